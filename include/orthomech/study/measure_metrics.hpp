#pragma once
// Study metrics of every measure and stroke, and expressions of metrics (issue 51 item 1;
// docs/cli.md "sweep": Metrics). In the mechanism file's units, as every study column.
//   - per stroke of compute_cycle_metrics (a prismatic joint, a position measure, a tracer
//     point's x or y): NAME.min, NAME.max, NAME.range (the stroke), NAME.min_at and NAME.max_at
//     (the input, in the driver's unit, at the extreme; parabola-refined as the extremes) and
//     NAME.time_ratio (forward/return; NaN unless a full cycle with one maximum per cycle);
//   - per measure (any derivative; the input itself excepted): the same from its samples where
//     it is not a stroke (a rate, a series constant up to noise), and NAME.rms = √(Σ y_k² / m);
//   - a series whose column would be a column already (a measure named `transmission` beside
//     the loops' transmission.min) has its columns as measure.NAME.min, … ;
//   - an expression of the columns: a column by its name (drive.peak, A.|F|.peak,
//     transmission.min), `f(NAME)` for the column NAME.f with f one of range, min, max, rms,
//     min_at, max_at, time_ratio, `at(NAME, X)` for measure NAME at the input X (the driver's
//     unit of the file; a column NAME@X), and the file's arithmetic (muparser: + − * / ^, sqrt,
//     abs, min(a, b), …, pi), numbers with a unit in the file's unit of their kind (75deg, 0.5 m).
//     `range(rocker_angle) - 75deg`, `at(rocker_angle, 90) - 120`.
#include <string>
#include <utility>
#include <vector>

#include "orthomech/analysis/cycle.hpp"
#include "orthomech/analysis/cycle_metrics.hpp"
#include "orthomech/io/units.hpp"
#include "orthomech/model/model.hpp"

namespace orthomech {

using MetricColumns = std::vector<std::pair<std::string, double>>;

// The columns of the strokes and measures of a cycle (`metrics` its compute_cycle_metrics),
// appended to `out`.
void measure_metrics(const Model& model, const CycleResult& c, const CycleMetrics& metrics,
                     int driver_joint, MetricColumns& out);

// The same columns of a sweep by several drivers (study with `drivers:`): per measure NAME.min,
// .max, .range, .rms from its samples and .min_at, .max_at the time of the extreme (the file's
// time unit: there is no one input); .time_ratio NaN.
struct MultiDriveResult;
void multi_drive_measure_metrics(const Model& model, const MultiDriveResult& r, MetricColumns& out);

// The suffixes of the columns measure_metrics writes (".min", …).
[[nodiscard]] const std::vector<std::string>& measure_metric_suffixes();

// A named expression of the metric columns (the study file's `expressions:`).
struct MetricExpression {
  std::string name, text;
};

// A measure's value at an input, asked for by `at(NAME, X)` in an expression: the column
// NAME@X (X its shortest decimal text), in the measure's unit of the file.
struct MeasureAt {
  std::string measure;
  double input = 0.0;  // in `unit`, or the driver's unit of the file when none (deg, mm)
  std::string unit;    // as written: at(rocker_angle, 1.5rad) ("" none)
  std::string column;  // "rocker_angle@90", "rocker_angle@1.5rad"
};
// Every `at(NAME, X)` of the expressions, each once, in order of appearance. Throws
// std::invalid_argument for an `at(` whose arguments are not a name and a number.
[[nodiscard]] std::vector<MeasureAt> measure_at_requests(
    const std::vector<MetricExpression>& expressions);
// The columns of the requests over a cycle: measure NAME at input X by the cubic through the
// four positions around X (Lagrange; an error of order h⁴ in the step h of the input), a
// revolute driver's X taken up to whole turns into the swept inputs; NaN when X is outside them
// or NAME is reported at fewer than four positions. A request for what is not a measure of the
// model gives no column (the expression then names it as unknown).
void measure_at_metrics(const Model& model, const CycleResult& c, int driver_joint,
                        const std::vector<MeasureAt>& requests, MetricColumns& out);

// The value of an expression over the columns (a NaN column gives NaN). A number written with a
// base unit of the file format (75deg, 0.5 m, 2kN: io/units.hpp base_unit) is that quantity in
// the file's unit of its kind (`units`: the mechanism's; a unit without them is an error). Throws
// std::invalid_argument saying what is wrong: an unknown name (listing the columns), f(NAME)
// without the column NAME.f, bad syntax.
[[nodiscard]] double evaluate_metric_expression(const std::string& text,
                                                const MetricColumns& columns,
                                                const UnitSystem* units = nullptr);

}  // namespace orthomech
