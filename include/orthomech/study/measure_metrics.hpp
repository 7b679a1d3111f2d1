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
//     min_at, max_at, time_ratio, and the file's arithmetic (muparser: + − * / ^, sqrt, abs,
//     min(a, b), …, pi). `range(rocker_angle) - 75`.
#include <string>
#include <utility>
#include <vector>

#include "orthomech/analysis/cycle.hpp"
#include "orthomech/analysis/cycle_metrics.hpp"
#include "orthomech/model/model.hpp"

namespace orthomech {

using MetricColumns = std::vector<std::pair<std::string, double>>;

// The columns of the strokes and measures of a cycle (`metrics` its compute_cycle_metrics),
// appended to `out`.
void measure_metrics(const Model& model, const CycleResult& c, const CycleMetrics& metrics,
                     int driver_joint, MetricColumns& out);

// The suffixes of the columns measure_metrics writes (".min", …).
[[nodiscard]] const std::vector<std::string>& measure_metric_suffixes();

// A named expression of the metric columns (the study file's `expressions:`).
struct MetricExpression {
  std::string name, text;
};

// The value of an expression over the columns (a NaN column gives NaN). Throws
// std::invalid_argument saying what is wrong: an unknown name (listing the columns), f(NAME)
// without the column NAME.f, bad syntax.
[[nodiscard]] double evaluate_metric_expression(const std::string& text,
                                                const MetricColumns& columns);

}  // namespace orthomech
