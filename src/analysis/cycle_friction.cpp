#include "orthomech/analysis/cycle_friction.hpp"

#include <algorithm>
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

namespace orthomech {

FrictionSeries friction_series(const Model& model, const CycleResult& result, bool cyclic) {
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
  // ∫ P dt over consecutive reported positions (and from the last back to the first, one
  // period later, on a full cycle).
  std::size_t last = n;
  for (std::size_t k = 0; k < n; ++k) {
    if (!s.reported[k]) continue;
    if (last < n)
      s.dissipated +=
          0.5 * (s.power[last] + s.power[k]) * (result.points[k].time - result.points[last].time);
    last = k;
  }
  if (cyclic && n >= 3 && s.reported[0] && s.reported[n - 1]) {
    const double dt = result.points[1].time - result.points[0].time;
    s.dissipated += 0.5 * (s.power[n - 1] + s.power[0]) * dt;
  }
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
  return out;
}

}  // namespace orthomech
