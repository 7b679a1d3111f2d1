#pragma once
// `sweep --report FILE.html` (docs/cli.md "sweep", "The study report"): one self-contained HTML
// page that works offline — a scatter-plot matrix of each parameter against each reported metric,
// a histogram of each metric with its quantiles, the sensitivity bars of a Monte Carlo study, and
// the best variants, each with a click-through to its cycle (the drive and every measure versus
// the input). The figures are inline SVG drawn here; study_report_figures gives each one as a
// standalone SVG document for papers.
//
// The page's contract (the browser tests read it): `body[data-ready="yes"]` once its script ran
// and `window.reportErrors` lists the script errors met; the scatter matrix is `#scatter`, one
// `svg.panel[data-parameter][data-metric]` per pair with a `circle.point[data-variant]` per
// variant that has both values (class `best` too for a best variant); each histogram is
// `svg.histogram[data-metric]` with `rect.bin[data-count][data-low][data-high]` and, with
// quantiles, `line.quantile[data-quantile][data-value]`; each sensitivity chart
// `svg.sensitivity[data-metric]` with `rect.bar[data-parameter][data-effect]`; the best variants
// are rows `tr.variant[data-variant]` of `#best`; clicking one (or a best point) shows its
// `div.cycle[data-variant]` (display block; the others none), whose `svg.cycle-plot` holds a
// `polyline.series[data-name][data-min][data-max]` per series with one point per position; a
// search's convergence is `svg.convergence` with a `circle.evaluation[data-evaluation]
// [data-objective][data-feasible]` per evaluation with an objective and `polyline.best
// [data-final]` (the best feasible objective at the end). The
// data-* numbers are exact (the shortest text that reads back to the same double).
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "orthomech/io/study_db.hpp"
#include "orthomech/study/study.hpp"

namespace orthomech {

// One column of the table: a value per row (NaN: none).
struct StudyReportColumn {
  std::string name;
  std::vector<double> values;
};

// A metric's statistics over the study (Monte Carlo): quantiles and, per parameter, the
// least-squares coefficient (metric unit per parameter unit) with its 95 % interval.
struct StudyReportStatistics {
  double q05 = 0.0, q50 = 0.0, q95 = 0.0;
  struct Sensitivity {
    double coefficient = 0.0, low = 0.0, high = 0.0;
  };
  std::vector<std::optional<Sensitivity>> sensitivity;  // per parameter (none: it is constant)
};

// One evaluation of a search (optimize): its objective (NaN: none), whether it was feasible, and
// the best feasible objective so far (NaN: none yet).
struct ConvergencePoint {
  long evaluation = 0;
  double objective = 0.0;
  bool feasible = false;
  double best = 0.0;
};

struct StudyReport {
  std::string title;           // "examples/tolerance-study.yaml on mechanisms/crank-rocker.yaml"
  std::string kind;            // "grid", "monte-carlo", "optimize"
  std::string summary;         // the terminal summary, shown as is
  std::vector<long> variants;  // the rows' variant indices
  std::vector<StudyReportColumn> parameters;  // one per parameter, a value per row
  std::vector<StudyReportColumn> metrics;     // the reported metrics, a value per row
  // Per reported metric (Monte Carlo): the quantiles and sensitivities; empty otherwise.
  std::vector<StudyReportStatistics> statistics;
  std::string best_metric;                    // how the best variants are ranked ("" none)
  std::vector<long> best;                     // the best variants, best first
  std::vector<VariantCycle> cycles;           // the cycles of (some of) the best variants
  std::vector<ConvergencePoint> convergence;  // a search's evaluations (optimize), else empty
  std::string objective;                      // the objective's text ("drive.peak")
};

// What the study's rows give for a metric's summary: the values of the rows whose cycle
// completed (a stopped sweep's peaks are partial), except the design checks (validate.*,
// assemble.*), which every row has (a variant that does not assemble is part of the yield).
[[nodiscard]] std::vector<double> summarized_metric(const std::vector<StudyDatabase::Row>& rows,
                                                    size_t metric, const std::string& name);
// The `count` best rows by metric column `metric` (smallest first, or largest with `largest`),
// completed rows with a value only, ties in variant order.
[[nodiscard]] std::vector<const StudyDatabase::Row*> best_rows(
    const std::vector<StudyDatabase::Row>& rows, size_t metric, bool largest, long count);

// The report of a stored study: `metrics` the metrics to show (empty: the study's best metric and
// expressions, then the other metrics that vary over the rows (strokes M.range and the worst
// loop angles first), at most kDefaultReportMetrics in all); the best variants of a grid by its
// best metric with the cycles of the first `cycles` of them computed again (variant_cycle). Throws
// std::invalid_argument for a metric the study does not have (the message lists them).
inline constexpr size_t kDefaultReportMetrics = 8;
struct StudyReportRequest {
  std::string title, summary;
  std::vector<std::string> metrics;
  long cycles = 5;
  // A search (optimize): the best variants as given (the optimum first; a grid's come from its
  // best metric), its evaluations and its objective's text.
  std::vector<long> best;
  std::vector<ConvergencePoint> convergence;
  std::string objective;
};

// The convergence of a search as a standalone SVG document: every evaluation's objective (a
// point; feasible ones filled) and the best feasible objective so far (a step line).
[[nodiscard]] std::string convergence_svg(const StudyReport& report);
[[nodiscard]] StudyReport study_report_of(const Study& study, const StudyDatabase& db,
                                          const std::string& mechanism, const std::string& origin,
                                          const StudyReportRequest& request);

// The histogram of values (NaN left out): `bins` equal bins from the smallest to the largest
// value (one bin when they are equal), the largest value in the last bin. The page's bins.
struct HistogramBin {
  double low = 0.0, high = 0.0;
  long count = 0;
};
[[nodiscard]] std::vector<HistogramBin> histogram(const std::vector<double>& values, int bins);
// The bins of n values: ⌈log₂ n⌉ + 1 (Sturges), between 1 and 40.
[[nodiscard]] int histogram_bins(long n);

// The page. Throws std::invalid_argument when a column has not one value per row, or the
// statistics not one entry per metric (when given).
[[nodiscard]] std::string study_report_html(const StudyReport& report);

// The same figures as standalone SVG documents for papers: file name ("scatter.svg",
// "histogram-METRIC.svg", "sensitivity-METRIC.svg" with the metric's characters outside
// [A-Za-z0-9._-] as '_', and "convergence.svg" of a search) and text.
struct StudyFigure {
  std::string file, svg;
};
[[nodiscard]] std::vector<StudyFigure> study_report_figures(const StudyReport& report);

}  // namespace orthomech
