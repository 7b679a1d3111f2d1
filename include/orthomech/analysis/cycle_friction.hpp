#pragma once
/// @file
/// The pins' friction over a sweep of `cycle` (analysis/friction.hpp gives the moments at one
/// position): per position and pin, the energy dissipated, the summaries.
#include <string>
#include <vector>

#include "orthomech/analysis/cycle.hpp"
#include "orthomech/analysis/friction.hpp"
#include "orthomech/analysis/friction_bound.hpp"
#include "orthomech/model/model.hpp"

namespace orthomech {

/// The friction over a sweep: each pin's moment and the power dissipated at every position
/// (reported where the position's drive is, drive_reported), whether each pin's force is
/// determinate (all its reaction components are), the energy dissipated over the sweep
/// (trapezoid rule in time, closed round the period when `cyclic`), and the fixed point's
/// iterations (the most taken; converged false when a reported position did not converge).
struct FrictionSeries {
  std::vector<FrictionPin> pins;
  std::vector<std::vector<double>> moment;  // [pin][position], N·m on the second body
  std::vector<double> power;                // W
  std::vector<bool> reported;
  std::vector<bool> determinate;  // per pin
  double dissipated = 0.0;        // J
  // The drive's net work over the sweep with and without friction (∫ τ ṡ dt, the same rule), J,
  // and the mechanical efficiency η = W₀ / W: the share of the drive's work that is not lost in
  // the pins (NaN where W₀ ≤ 0: a sweep whose loads take no net work has no efficiency).
  double drive_work = 0.0, drive_work_frictionless = 0.0;
  double efficiency = 0.0;
  int iterations_max = 0;
  bool converged = true;
  // Where some pin's force is not determined (redundant constraints): the least dissipation over
  // every admissible split of the redundant reactions at each reported position
  // (least_dissipation) but those bridged next to a change point (their values are interpolated
  // on the branch, and the minimum-norm forces diverge there), and over those positions the least
  // energy dissipated and the least net work of the drive (the splits at different positions are
  // independent, so the sum of the least values is the least sum). NaN where not reported or not
  // solved (`unsolved` counts them; the sweep's values are then NaN too).
  struct LowerBound {
    bool computed = false;
    std::vector<bool> reported;                 // per position
    std::vector<double> drive, power;           // per position: the drive (N·m or N) and power (W)
    double dissipated = 0.0, drive_work = 0.0;  // J
    int unsolved = 0;
  } bound;
};
// `driver_joint`: the driven joint of the sweep (the bound's equation of motion).
[[nodiscard]] FrictionSeries friction_series(const Model& model, const CycleResult& result,
                                             int driver_joint, bool cyclic);

/// Their summaries (summarize_values): "drive without friction" (`drive_unit`), each pin's
/// "<joint> friction moment" (N*m) and "friction power" (W). Empty without friction.
[[nodiscard]] std::vector<SeriesSummary> summarize_friction(const Model& model,
                                                            const CycleResult& result,
                                                            const FrictionSeries& series,
                                                            const std::string& drive_unit);

}  // namespace orthomech
