#pragma once
// Design studies (docs/cli.md "sweep"): many variants of one mechanism file, each a set of `--set`
// changes (FileChange); per variant the metric blocks the study asks for, in the file's units —
// the cycle's summary, `validate`'s checks, `assemble`'s success and distance, the deviation of
// traced points' paths from the nominal design's — and over the study the best variants (grid)
// or the quantiles and sensitivities of every metric (Monte Carlo).
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "orthomech/study/measure_metrics.hpp"

namespace orthomech {

enum class StudyKind { grid, monte_carlo, optimize };

struct StudyParameter {
  std::string path;  // FileChange path: bodies.crank.points.A.0, a parameter name, …
  std::string name;  // column name (default: the path)
  enum class Law { values, normal, uniform, bounds } law = Law::values;
  std::vector<double> values;       // grid: the values in order
  double mean = 0.0;                // normal and uniform: the nominal value (default: the file's);
                                    // bounds (optimize): the start (default: the file's)
  double lower = 0.0, upper = 0.0;  // bounds: the design variable's box
  double sigma = 0.0;               // normal: standard deviation (0: always the mean)
  double tolerance = 0.0;           // uniform: mean ± tolerance
};

// What is computed per variant (the study file's `metrics:`; absent: the cycle alone).
struct StudyMetrics {
  bool cycle = true;      // the cycle summary (drive, reactions, power, angles, dead points)
  bool validate = false;  // validate_design_positions: one 0/1 column per check, and overall
  bool assemble = false;  // assemble(design pose): success 0/1 and the mass-metric distance
  std::vector<std::string> deviation;  // traced points "body.point" ("body.origin"): max and
                                       // RMS distance from the nominal design's path
  // The study file's `expressions:` (study/measure_metrics.hpp), columns after the blocks'.
  std::vector<MetricExpression> expressions;
  // Their `at(NAME, X)` (measure_at_requests), columns NAME@X after the cycle block's.
  std::vector<MeasureAt> at;
};

// The nominal design's traced paths (the file unchanged), computed once per study: the cycle's
// input at each position (SI) and the world path of each StudyMetrics::deviation point (m).
struct NominalPaths {
  bool available = false;  // false: the nominal cycle gave no positions (message says why)
  std::string message;
  std::vector<double> input;
  std::vector<std::vector<double>> x, y, z;  // per point, per position, m (z 0 when planar)
};

// An optimisation's goal (study: optimize; study/optimize.hpp). The objective and each
// constraint are expression columns of the variants: `objective` and `constraint.1`, … .
struct OptimizeConstraint {
  std::string text;  // the expression constrained
  enum class Kind { at_least, at_most, equal } kind = Kind::at_least;
  double bound = 0.0;
  double tolerance = 0.0;  // equal: |value − bound| ≤ tolerance
};
struct OptimizeGoal {
  std::string objective;  // the expression minimised (or maximised)
  bool maximize = false;
  std::vector<OptimizeConstraint> constraints;
  // cobyla: one local search from the start; isres: global, seeded; multistart: `starts` COBYLA
  // searches, the first from the start, the others from seeded points of the box, in parallel.
  enum class Algorithm { cobyla, isres, multistart } algorithm = Algorithm::cobyla;
  long starts = 8;          // multistart
  long evaluations = 200;   // the budget (multistart: of each search)
  double tolerance = 1e-4;  // a step below this share of every variable's span ends the search
};

struct Study {
  StudyKind kind = StudyKind::grid;
  long samples = 0;        // Monte Carlo: number of variants
  std::uint64_t seed = 1;  // Monte Carlo
  int steps = 0;           // positions per cycle (0: the mechanism file's analysis steps)
  // Several drivers (`drivers: [A, B]`, as `cycle --drivers`): each variant swept over time by
  // these drivers of the file (run_multi_drive) for t_end seconds (0: one period of the slowest
  // law), `steps` positions (0: 101); empty: the one driver's cycle.
  std::vector<std::string> drivers;
  double t_end = 0.0;
  std::vector<StudyParameter> parameters;
  std::string best_metric = "drive.peak";  // grid summary: ranked by this metric
  bool best_largest = false;               // … smallest first unless `order: max`
  int best_count = 5;
  StudyMetrics metrics;
  OptimizeGoal goal;  // study: optimize
  // The nominal paths of the deviation metrics (attach_nominal_paths); when empty, each variant
  // computes them itself (same values, twice the work).
  std::shared_ptr<const NominalPaths> nominal;
};

// Reads a study file. The nominal values of `normal` and `uniform` laws without a `mean` are read
// from the mechanism file's text (`mechanism`, named `mechanism_origin`). Throws InputError naming
// file:line:column and the element.
[[nodiscard]] Study load_study(const std::string& path, const std::string& mechanism,
                               const std::string& mechanism_origin);
[[nodiscard]] Study parse_study(const std::string& text, const std::string& origin,
                                const std::string& mechanism, const std::string& mechanism_origin);

// What makes a stored study the same study (`sweep --resume`, `optimize --resume`): the study
// file's text, with a Monte Carlo study's `samples` value (an optimize study's `evaluations`)
// written as N — a Monte Carlo study is extended by resuming it with more samples (variant k's
// draws depend only on the seed and k, so the first variants are the ones stored), a search by
// resuming it with a larger budget (its first evaluations are the ones stored). Throws InputError
// as parse_study for a text it cannot read.
[[nodiscard]] std::string study_identity(const std::string& text, const std::string& origin);

// The nominal design's paths of the study's deviation points (run_cycle of the unchanged file,
// the study's steps). Never throws for a numerical outcome (available = false, message).
[[nodiscard]] NominalPaths nominal_paths(const std::string& mechanism, const std::string& origin,
                                         const Study& study);
// Computes them once into study.nominal when the study asks for deviations (else leaves it).
void attach_nominal_paths(Study& study, const std::string& mechanism, const std::string& origin);

// The number of variants: the product of the grid's value counts, or the samples.
[[nodiscard]] long variant_count(const Study& study);
// The parameter values of variant `index` (0-based): the grid's mixed-radix digits (the last
// parameter fastest), or draws from the variant's own random stream (Boost.Random mt19937_64
// seeded from the study's seed and the index), so a variant's values depend on nothing else.
[[nodiscard]] std::vector<double> variant_values(const Study& study, long index);
// The FileChange text of a value: shortest decimal that reads back to the same double.
[[nodiscard]] std::string value_text(double value);

// The `--set` changes of a variant: each parameter's path and the value_text of its value.
struct FileChange;
[[nodiscard]] std::vector<FileChange> variant_changes(const Study& study,
                                                      const std::vector<double>& values);
// The driver a study sweeps: the file's `analysis: driver`, else its first (nullptr: none).
[[nodiscard]] const Driver* study_driver(const Model& model);

// One variant's outcome: status "completed", "stopped_at_dead_point", "failed" (the cycle could
// not be computed or stopped) or "invalid" (the changed file is not a valid mechanism); the
// cycle's message; metrics by name in the file's units (NaN where there is none). Without a cycle
// block (no cycle, no deviation) a valid file is "completed": failed checks are metrics (0).
struct VariantResult {
  long index = 0;
  std::vector<double> values;
  std::string status, message;
  std::vector<std::pair<std::string, double>> metrics;
  long positions = 0;  // positions of the variant's cycle (0: not run, or none computed)
};

// Evaluates one variant of the mechanism text (docs/cli.md "sweep": the metrics). `values` as
// variant_values. Never throws for a bad variant: it is a result with its status.
[[nodiscard]] VariantResult evaluate_variant(const std::string& mechanism,
                                             const std::string& origin, const Study& study,
                                             long index, const std::vector<double>& values);

// A variant's cycle (the study report's click-through): its input and, over its positions, the
// drive and every measure in the file's units (NaN where one is not reported). status and message
// as VariantResult's; no positions when the file is invalid or has no driver.
struct VariantCycle {
  long variant = 0;
  std::string status, message;
  std::string input_label;  // "input A0 [deg]"
  std::vector<double> input;
  struct Series {
    std::string name, unit;
    std::vector<double> values;
  };
  std::vector<Series> series;
};
[[nodiscard]] VariantCycle variant_cycle(const std::string& mechanism, const std::string& origin,
                                         const Study& study, long index,
                                         const std::vector<double>& values);

// Evaluates the variants in `pending` on `jobs` OpenMP threads (0: all cores), calling `done`
// with each result as it finishes, one call at a time (any order). Results do not depend on the
// number of threads.
void run_variants(const std::string& mechanism, const std::string& origin, const Study& study,
                  const std::vector<long>& pending, int jobs,
                  const std::function<void(const VariantResult&)>& done);

// ---- Summary ---------------------------------------------------------------------------------
struct MetricStatistics {
  std::string metric;
  long n = 0;  // variants with a value
  double mean = 0.0, stddev = 0.0, q05 = 0.0, q50 = 0.0, q95 = 0.0, min = 0.0, max = 0.0;
  // Least-squares fit metric ≈ b0 + Σ b_j x_j over the variants with a value: per parameter its
  // coefficient (metric unit per parameter unit), standard error and 95 % confidence interval
  // (Student's t with n − p − 1 degrees of freedom). Parameters that do not vary are left out
  // (nullopt); no fit when n ≤ p + 1.
  struct Sensitivity {
    double coefficient = 0.0, std_error = 0.0, low = 0.0, high = 0.0;
  };
  std::vector<std::optional<Sensitivity>> sensitivity;
};
// Quantiles (linear interpolation between order statistics, as numpy's default) and the linear
// fit. `values[k]` are the parameter values of row k, `metric[k]` its metric (NaN: left out).
[[nodiscard]] MetricStatistics metric_statistics(const std::string& name,
                                                 const std::vector<std::vector<double>>& values,
                                                 const std::vector<double>& metric);

}  // namespace orthomech
