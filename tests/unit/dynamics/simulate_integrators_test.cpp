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
double oscillator_error(DynamicsForm form, Integrator integrator, double dt_out) {
  const Model model = parse_mechanism(kOscillator, "oscillator.yaml");
  SimulateOptions o;
  o.form = form;
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
  return worst;
}

// rtol 1e-10 on a motion of amplitude 0.3 m and size 1.3 m: a local error per step of ~1e-10
// of the state, accumulated over a few hundred to a few thousand steps (errors of a stable
// oscillator add up at most linearly), so every output within 1e-8 m; the cubic Hermite outputs
// that rkf78 had before measured ~1e-5 here.
constexpr double kOutputBound = 1e-8;

TEST(IntegratorOutputs, LinearOscillator_EveryOutputAtFullAccuracy) {
  for (const DynamicsForm form : {DynamicsForm::dual, DynamicsForm::primal})
    for (const Integrator i : kAll) {
      const char* f = form == DynamicsForm::dual ? " dual" : " primal";
      // dt_out = 0.01 s is shorter than the steps (outputs inside steps) …
      EXPECT_LT(oscillator_error(form, i, 0.01), kOutputBound) << to_string(i) << f;
      // … and 0.37 s longer than them (outputs between step ends, not on a step grid).
      EXPECT_LT(oscillator_error(form, i, 10.0 / 27.0), kOutputBound) << to_string(i) << f;
    }
}

// ---- IFToMM A01 pendulum against its exact solution, every integrator and both forms ------
// sin(θ/2) = k sn(K − √(g/L) t, k²), k = sin 45°, θ from the downward vertical; released at
// (−1, 0), so the mass is at (−sin θ, −cos θ) (tests/unit/dynamics/simulate_test.cpp has the same
// oracle checked against the published samples).
Vec2 pendulum_exact(double t) {
  const double k = std::sin(M_PI / 4.0);
  const double K = boost::math::ellint_1(k);
  const double theta = 2.0 * std::asin(k * boost::math::jacobi_sn(k, K - std::sqrt(9.81) * t));
  return {-std::sin(theta), -std::cos(theta)};
}

// 20 s (8.4 periods) at rtol = atol = 1e-10: a local error of ~1e-10 per step over 50 (Bulirsch–
// Stoer) to 12 000 (Rosenbrock) steps, and a phase error that grows faster than linearly with
// time (energy errors change the period): every output within 1e-6 m. Measured: 2e-10 … 1e-8
// for dopri5, rkf78, rosenbrock4 and Bulirsch–Stoer primal; 4e-7 for Bulirsch–Stoer dual, whose
// error control is the loosest of the four at equal rtol (docs/benchmarks.md).
constexpr double kPendulumBound = 1e-6;

TEST(IntegratorPendulum, A01ExactSolution_EveryIntegratorBothForms) {
  const Model model = test::load_bundled("pendulum");
  const size_t ix = static_cast<size_t>(model.find_measure("P1_x"));
  const size_t iy = static_cast<size_t>(model.find_measure("P1_y"));
  for (const DynamicsForm form : {DynamicsForm::dual, DynamicsForm::primal})
    for (const Integrator i : kAll) {
      SimulateOptions o;
      o.form = form;
      o.integrator = i;
      o.t_end = 20.0;
      o.rtol = o.atol = 1e-10;
      o.dt_out = 0.1;
      o.reactions = false;
      const SimulateResult r = simulate(model, o);
      ASSERT_EQ(r.status, SimulateStatus::completed) << to_string(i) << ": " << r.message;
      ASSERT_EQ(r.samples.size(), 201u);
      double worst = 0.0;
      for (const SimulationSample& s : r.samples) {
        const Vec2 exact = pendulum_exact(s.t);
        worst = std::max(worst, std::hypot(s.measures[ix] - exact.x(), s.measures[iy] - exact.y()));
      }
      EXPECT_LT(worst, kPendulumBound)
          << to_string(i) << (form == DynamicsForm::dual ? " dual" : " primal");
    }
}

// ---- The stiff spring-damper pair (mechanisms/stiff-spring-damper.yaml) ---------------------
// Its equations are linear (the file's comment): z = (y1, y2, ẏ1, ẏ2), ż = A z + b, so
// z(t) = z* + exp(A t) (z0 − z*) with z* = −A⁻¹ b; exp(A t) = V exp(Λ t) V⁻¹ from the
// eigen-decomposition of A (four distinct eigenvalues: −15980, −20.0, and a pair near ±10i).
struct StiffPair {
  Eigen::Matrix4d A;
  Eigen::Vector4d z_star, z0;
  Eigen::Matrix4cd V, V_inv;
  Eigen::Vector4cd lambda;

  StiffPair() {
    const double m = 5.0, k1 = 1000.0, l1 = 0.5, k = 8e5, c = 4e4, l0 = 0.5, g = 9.81;
    A.setZero();
    A(0, 2) = A(1, 3) = 1.0;
    A(2, 0) = (-k1 - k) / m, A(2, 1) = k / m, A(2, 2) = -c / m, A(2, 3) = c / m;
    A(3, 0) = k / m, A(3, 1) = -k / m, A(3, 2) = c / m, A(3, 3) = -c / m;
    const Eigen::Vector4d b(0.0, 0.0, (-k1 * l1 + k * l0) / m - g, -k * l0 / m - g);
    z_star = -A.partialPivLu().solve(b);
    z0 << -1.0, -1.51, 0.0, 0.0;  // released from rest at the design position
    const Eigen::EigenSolver<Eigen::Matrix4d> es(A);
    V = es.eigenvectors();
    V_inv = V.inverse();
    lambda = es.eigenvalues();
  }
  [[nodiscard]] Eigen::Vector4d at(double t) const {
    const Eigen::Vector4cd e = (lambda * t).array().exp().matrix();
    const Eigen::Vector4cd d =
        V * e.asDiagonal() * V_inv * (z0 - z_star).cast<std::complex<double>>();
    return z_star + d.real();
  }
};

// rtol 1e-6, atol 1e-9 over 2 s (3 periods of the soft mode, amplitude ~0.4 m): every output
// within 2e-5 m of the closed form (a few hundred steps at ~1e-6 relative each, measured below
// 1e-5 for both integrators).
constexpr double kStiffBound = 2e-5;

SimulateResult run_stiff(Integrator integrator) {
  SimulateOptions o;
  o.integrator = integrator;
  o.t_end = 2.0;
  o.rtol = 1e-6;
  o.atol = 1e-9;
  o.dt_out = 0.05;
  o.reactions = false;
  return simulate(test::load_bundled("stiff-spring-damper"), o);
}

double stiff_error(const Model& model, const SimulateResult& r) {
  const StiffPair pair;
  const size_t i1 = static_cast<size_t>(model.find_measure("sleeve_y"));
  const size_t i2 = static_cast<size_t>(model.find_measure("bob_y"));
  double worst = 0.0;
  for (const SimulationSample& s : r.samples) {
    const Eigen::Vector4d z = pair.at(s.t);
    worst = std::max({worst, std::abs(s.measures[i1] - z(0)), std::abs(s.measures[i2] - z(1))});
  }
  return worst;
}

TEST(IntegratorStiff, SpringDamperPair_ClosedForm_RosenbrockTakesFarFewerSteps) {
  const Model model = test::load_bundled("stiff-spring-damper");
  // The oracle itself: at t = 0 the design position at rest; z* is the static equilibrium
  // (soft spring carries both weights, stiff spring one).
  const StiffPair pair;
  EXPECT_NEAR((pair.at(0.0) - pair.z0).norm(), 0.0, 1e-12);
  EXPECT_NEAR(-pair.z_star(0) - 0.5, 2 * 5.0 * 9.81 / 1000.0, 1e-12);
  EXPECT_NEAR(pair.z_star(0) - pair.z_star(1) - 0.5, 5.0 * 9.81 / 8e5, 1e-12);

  const SimulateResult stiff = run_stiff(Integrator::rosenbrock4);
  ASSERT_EQ(stiff.status, SimulateStatus::completed) << stiff.message;
  EXPECT_LT(stiff_error(model, stiff), kStiffBound);
  const SimulateResult explicit_rk = run_stiff(Integrator::dopri5);
  ASSERT_EQ(explicit_rk.status, SimulateStatus::completed) << explicit_rk.message;
  EXPECT_LT(stiff_error(model, explicit_rk), kStiffBound);
  // Dormand–Prince is held by stability: |h λ| ≤ ~3.3 with λ = −15980 1/s, so at least
  // 2 s · 15980 / 3.3 ≈ 9700 steps whatever the tolerance; Rosenbrock (L-stable) by accuracy.
  EXPECT_GT(explicit_rk.steps, 9000);
  EXPECT_LT(10 * stiff.steps, explicit_rk.steps)
      << "rosenbrock4 " << stiff.steps << " steps, dopri5 " << explicit_rk.steps;
}

}  // namespace
}  // namespace orthomech
