#pragma once
// Andrews' squeezing mechanism for the tests and the benchmarks: the published values
// (support/andrews_published.hpp), the measures that give them, the test set's run. Header-only.
#include <array>
#include <cmath>

#include "orthomech/dynamics/simulate.hpp"
#include "orthomech/model/model.hpp"
#include "support/andrews_published.hpp"

namespace orthomech::test::andrews {

// The measures of mechanisms/andrews-squeezer.yaml that give the published angles, in order.
inline constexpr std::array<const char*, 7> kNames = {"beta",  "Theta", "gamma",  "Phi",
                                                      "delta", "Omega", "epsilon"};

// The test set's run: t = 0 … 0.03 s at rtol 1e-10, atol 1e-12, one output at the end.
inline SimulateOptions reference_run(DynamicsForm form,
                                     Integrator integrator = Integrator::dopri5) {
  SimulateOptions o;
  o.form = form;
  o.integrator = integrator;
  o.t_end = 0.03;
  o.rtol = 1e-10;
  o.atol = 1e-12;
  o.dt_out = 0.03;
  return o;
}

// "Rough angles": every design pose of the file rounded, angles to 0.1 rad and positions to 1 mm
// (the starting guess of the assembly test and benchmark).
inline void round_design_poses(Model& m) {
  for (Body& b : m.bodies) {
    b.design_pose.x() = std::round(b.design_pose.x() * 1e3) / 1e3;
    b.design_pose.y() = std::round(b.design_pose.y() * 1e3) / 1e3;
    b.design_pose.z() = std::round(b.design_pose.z() * 10.0) / 10.0;
  }
}

}  // namespace orthomech::test::andrews
