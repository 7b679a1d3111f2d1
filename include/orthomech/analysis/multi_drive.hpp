#pragma once
// Several drivers (issue 13 item 3): a mechanism with m degrees of freedom driven by m drivers,
// each with its own time law, swept over time. At every position: the inputs, every driver's
// force or torque, every joint's reaction (minimum-norm multipliers with the determinate
// components named, as `cycle`), the measures and the energies. The kinetostatics is (C1)–(C4)
// of the single-driver cycle with the input row d replaced by the m rows D_s of the drivers'
// coordinates (compute_multi_driven, analysis/cycle.hpp).
#include <string>
#include <vector>

#include "orthomech/analysis/cycle.hpp"
#include "orthomech/model/model.hpp"

namespace orthomech {

struct MultiDriveOptions {
  std::vector<Driver> drivers;  // one per degree of freedom
  // End of the sweep (s); 0: one period of the slowest law (a constant-speed revolute: one
  // turn; a harmonic law: 1/f); a polynomial or prismatic constant-speed law has no period.
  double t_end = 0.0;
  int steps = 101;  // positions, t = 0 … t_end inclusive
};

enum class MultiDriveStatus { completed, invalid_request, stopped, failed };
[[nodiscard]] const char* to_string(MultiDriveStatus s);

struct MultiDriveResult {
  MultiDriveStatus status = MultiDriveStatus::failed;
  std::string message;
  std::vector<std::string> warnings;
  int dof = 0, rank = 0, redundant = 0;
  double t_end = 0.0;
  std::vector<ReactionComponent> components;
  std::vector<bool> determinate;  // per component: unique whatever the redundancy
  std::vector<MultiDrivenPoint> points;
};

// Start: the design position with every driven joint held at its law's value at t = 0
// (project_positions with locks). Each later position: predictor q ⊕ (u h + ½ u̇ h²), then the
// same projection with the inputs held at s(t); steps that fail or jump are halved. The sweep
// stops (status `stopped`) where the drivers cannot move the mechanism (D_s F singular: a
// singular position of the drivers) or E loses rank.
[[nodiscard]] MultiDriveResult run_multi_drive(const Model& model,
                                               const MultiDriveOptions& options);

}  // namespace orthomech
