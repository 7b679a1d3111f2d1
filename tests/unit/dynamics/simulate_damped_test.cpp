// State-dependent loads in simulate: a bar pinned to the ground with a rotary spring-damper,
// under gravity. Oracles: the exact one-DOF equation J_O θ̈ = −m g l cos θ − k θ − c θ̇
// (integrated by RK4 in the test) and the energy balance T + V − W = const, where W is the
// damper's work accumulated by simulate independently of T and V.
#include <gtest/gtest.h>

#include <cmath>

#include "orthomech/dynamics/simulate.hpp"
#include "orthomech/io/mechanism_file.hpp"

namespace orthomech {
namespace {

constexpr double kM = 2.0, kI = 0.1, kL = 0.3, kK = 5.0, kC = 0.4, kG = 9.81;

const char* const kBar = R"(orthomech: 1
name: damped-bar
units: {length: m, angle: rad, mass: kg}
ground:
  points: {O: [0, 0]}
bodies:
  - {name: bar, mass: 2, inertia: 0.1, com: [0.3, 0], pose: [0, 0, 0], points: {O: [0, 0]}}
joints:
  - {name: O, type: revolute, connects: [ground.O, bar.O]}
loads:
  - {name: weight, type: gravity, g: [0, -9.81]}
  - {name: coil, type: rotary-spring-damper, bodies: [ground, bar], stiffness: 5, free_angle: 0, damping: 0.4}
measures:
  - {name: phi, type: angle, body: bar}
)";

double reduced_angle(double t_end) {
  const double J = kI + kM * kL * kL;
  auto acc = [&](double th, double w) {
    return (-kM * kG * kL * std::cos(th) - kK * th - kC * w) / J;
  };
  double th = 0.0, w = 0.0;
  const int steps = 200000;
  const double h = t_end / steps;
  for (int i = 0; i < steps; ++i) {
    const double k1t = w, k1w = acc(th, w);
    const double k2t = w + 0.5 * h * k1w, k2w = acc(th + 0.5 * h * k1t, w + 0.5 * h * k1w);
    const double k3t = w + 0.5 * h * k2w, k3w = acc(th + 0.5 * h * k2t, w + 0.5 * h * k2w);
    const double k4t = w + h * k3w, k4w = acc(th + h * k3t, w + h * k3w);
    th += h / 6.0 * (k1t + 2 * k2t + 2 * k3t + k4t);
    w += h / 6.0 * (k1w + 2 * k2w + 2 * k3w + k4w);
  }
  return th;
}

TEST(SimulateLoads, RotaryDamperAndGravity_AgainstOneDofEquationAndEnergyBalance) {
  const Model model = parse_mechanism(kBar, "damped-bar");
  for (DynamicsForm form : {DynamicsForm::dual, DynamicsForm::primal}) {
    SimulateOptions o;
    o.form = form;
    o.t_end = 5.0;
    o.rtol = 1e-11;
    o.atol = 1e-12;
    const SimulateResult r = simulate(model, o);
    ASSERT_EQ(r.status, SimulateStatus::completed) << r.message;
    EXPECT_NEAR(r.final.measures[0], reduced_angle(5.0), 1e-8);
    // The damper dissipated energy (W < 0) and the balance T + V − W holds.
    EXPECT_LT(r.final.work, -0.1);
    EXPECT_LT(r.energy_max_drift, 1e-9 * r.energy_scale);
  }
}

}  // namespace
}  // namespace orthomech
