#include "orthomech/analysis/cycle_friction.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace orthomech {

namespace {

// ∫ P dt over consecutive reported positions (and from the last back to the first, one period
// later, on a full cycle).
double sweep_integral(const CycleResult& result, const std::vector<bool>& reported,
                      const std::vector<double>& P, bool cyclic) {
  const std::size_t n = result.points.size();
  double sum = 0.0;
  std::size_t last = n;
  for (std::size_t k = 0; k < n; ++k) {
    if (!reported[k]) continue;
    if (last < n)
      sum += 0.5 * (P[last] + P[k]) * (result.points[k].time - result.points[last].time);
    last = k;
  }
  if (cyclic && n >= 3 && reported[0] && reported[n - 1])
    sum += 0.5 * (P[n - 1] + P[0]) * (result.points[1].time - result.points[0].time);
  return sum;
}

// The least dissipation at every reported position (FrictionSeries::LowerBound).
FrictionSeries::LowerBound lower_bound(const Model& model, const CycleResult& result,
                                       int driver_joint, const FrictionSeries& s, bool cyclic) {
  FrictionSeries::LowerBound b;
  b.computed = true;
  const std::size_t n = result.points.size();
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  b.drive.assign(n, nan);
  b.power.assign(n, nan);
  std::vector<double> work_rate(n, nan);
  b.reported.assign(n, false);
  for (std::size_t k = 0; k < n; ++k) {
    const DrivenPointView p = result.points[k];
    // (A bridged position's values are interpolated on the branch: they fix no equation of
    // motion to split.)
    if (!s.reported[k] || p.bridge >= 0) continue;
    b.reported[k] = true;
    const DissipationBound one =
        least_dissipation(model, s.pins, driver_joint, p.q, p.u, p.lambda, p.drive);
    if (!one.solved) {
      ++b.unsolved;
      continue;
    }
    b.drive[k] = one.drive;
    b.power[k] = one.power;
    work_rate[k] = one.drive * p.input_rate;
  }
  b.dissipated = b.unsolved ? nan : sweep_integral(result, b.reported, b.power, cyclic);
  b.drive_work = b.unsolved ? nan : sweep_integral(result, b.reported, work_rate, cyclic);
  return b;
}

}  // namespace

FrictionSeries friction_series(const Model& model, const CycleResult& result, int driver_joint,
                               bool cyclic) {
  FrictionSeries s;
  s.pins = friction_pins(model);
  if (s.pins.empty()) return s;
  const std::size_t n = result.points.size();
  s.moment.assign(s.pins.size(), std::vector<double>(n, 0.0));
  s.power.assign(n, 0.0);
  s.reported.assign(n, false);
  s.determinate.assign(s.pins.size(), true);
  for (std::size_t c = 0; c < result.components.size(); ++c)
    for (std::size_t i = 0; i < s.pins.size(); ++i)
      if (result.components[c].joint == s.pins[i].joint && !result.determinate.empty() &&
          !result.determinate[c])
        s.determinate[i] = false;
  std::vector<double> m;
  for (std::size_t k = 0; k < n; ++k) {
    const DrivenPointView p = result.points[k];
    if (!drive_reported(p)) continue;
    s.reported[k] = true;
    s.power[k] = friction_moments(s.pins, p.u, p.lambda, m);
    for (std::size_t i = 0; i < s.pins.size(); ++i) s.moment[i][k] = m[i];
    if (p.friction_iterations < 0) s.converged = false;
    s.iterations_max = std::max(s.iterations_max, p.friction_iterations);
  }
  auto integral = [&](const std::vector<double>& P) {
    return sweep_integral(result, s.reported, P, cyclic);
  };
  s.dissipated = integral(s.power);
  // The drive's power τ ṡ with and without friction.
  std::vector<double> with(n, 0.0), without(n, 0.0);
  for (std::size_t k = 0; k < n; ++k) {
    const DrivenPointView p = result.points[k];
    with[k] = p.drive * p.input_rate;
    without[k] = p.drive_frictionless * p.input_rate;
  }
  s.drive_work = integral(with);
  s.drive_work_frictionless = integral(without);
  // (W₀ at rounding level, against W: no net work taken by the loads.)
  s.efficiency = s.drive_work_frictionless > 1e-9 * std::abs(s.drive_work) && s.drive_work > 0.0
                     ? s.drive_work_frictionless / s.drive_work
                     : std::numeric_limits<double>::quiet_NaN();
  if (std::find(s.determinate.begin(), s.determinate.end(), false) != s.determinate.end())
    s.bound = lower_bound(model, result, driver_joint, s, cyclic);
  return s;
}

std::vector<SeriesSummary> summarize_friction(const Model& model, const CycleResult& result,
                                              const FrictionSeries& series,
                                              const std::string& drive_unit) {
  std::vector<SeriesSummary> out;
  if (series.pins.empty()) return out;
  const std::size_t n = result.points.size();
  std::vector<double> v(n);
  for (std::size_t k = 0; k < n; ++k) v[k] = result.points[k].drive_frictionless;
  out.push_back(summarize_values(result, "drive without friction", drive_unit, v, series.reported));
  for (std::size_t i = 0; i < series.pins.size(); ++i) {
    SeriesSummary s = summarize_values(
        result,
        model.joints[static_cast<std::size_t>(series.pins[i].joint)].name + " friction moment",
        "N*m", series.moment[i], series.reported);
    s.determinate = series.determinate[i];
    out.push_back(std::move(s));
  }
  out.push_back(summarize_values(result, "friction power", "W", series.power, series.reported));
  if (series.bound.computed) {
    std::vector<bool> solved(n);
    for (std::size_t k = 0; k < n; ++k)
      solved[k] = series.bound.reported[k] && std::isfinite(series.bound.drive[k]);
    out.push_back(summarize_values(result, "drive at least friction", drive_unit,
                                   series.bound.drive, solved));
    out.push_back(
        summarize_values(result, "least friction power", "W", series.bound.power, solved));
  }
  return out;
}

}  // namespace orthomech
