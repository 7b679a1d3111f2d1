// IFToMM benchmarks A01 (simple pendulum) and A02 (N four-bar through its singular positions)
// (IFToMM Library of Computational Benchmark Problems; González, Dopico, Lugrís, Cuadrado,
// Multibody System Dynamics 16, 2006; /work/shared/references.md §2–3).
#include "orthomech/dynamics/simulate.hpp"

#include <gtest/gtest.h>

#include <boost/math/special_functions/ellint_1.hpp>
#include <boost/math/special_functions/jacobi_elliptic.hpp>
#include <cmath>
#include <string>

#include "orthomech/model/free_system.hpp"
#include "support/fixtures.hpp"

namespace orthomech {
namespace {

constexpr double kG = 9.81;

// ---- A01: exact solution sin(θ/2) = k sn(K − √(g/L) t, k²), k = sin 45°, θ from the downward
// vertical; released at x = −1, y = 0, so the mass is at (−sin θ, −cos θ) with θ(0) = 90°.
Vec2 pendulum_exact(double t) {
  const double k = std::sin(M_PI / 4.0);
  const double K = boost::math::ellint_1(k);
  const double sn = boost::math::jacobi_sn(k, K - std::sqrt(kG) * t);
  const double theta = 2.0 * std::asin(k * sn);
  return {-std::sin(theta), -std::cos(theta)};
}

TEST(IftommA01, ExactSolutionReproducesThePublishedSamples) {
  // The oracle itself against the published 6-digit samples (t = 0.5 s and 1.0 s).
  EXPECT_NEAR(pendulum_exact(0.5).x(), -0.391049, 1e-6);
  EXPECT_NEAR(pendulum_exact(0.5).y(), -0.920370, 1e-6);
  EXPECT_NEAR(pendulum_exact(1.0).x(), 0.986292, 1e-6);
  EXPECT_NEAR(pendulum_exact(1.0).y(), -0.165011, 1e-6);
  // Period (published): 4K/√(g/L).
  EXPECT_NEAR(4.0 * boost::math::ellint_1(std::sin(M_PI / 4.0)) / std::sqrt(kG),
              2.36784194757623744930329503724, 1e-13);
}

void run_pendulum(DynamicsForm form, Integrator integrator) {
  const Model model = test::load_bundled("pendulum");
  SimulateOptions o;
  o.form = form;
  o.integrator = integrator;
  o.t_end = 2000.0;
  o.rtol = 1e-13;
  o.atol = 1e-13;
  o.dt_out = 0.5;
  o.reactions = false;
  const SimulateResult r = simulate(model, o);
  ASSERT_EQ(r.status, SimulateStatus::completed) << r.message;
  const int ix = model.find_measure("P1_x"), iy = model.find_measure("P1_y");
  // Position against the exact solution all along the 2000 s (≈ 845 periods): the phase error
  // grows linearly; 1e-5 m at 2000 s is a period error below 1e-8 relative (2000 s × ω ≈ 6000
  // rad of phase).
  double worst = 0.0;
  for (const auto& s : r.samples) {
    const Vec2 exact = pendulum_exact(s.t);
    worst = std::max(worst, std::hypot(s.measures[static_cast<size_t>(ix)] - exact.x(),
                                       s.measures[static_cast<size_t>(iy)] - exact.y()));
  }
  EXPECT_LT(worst, 1e-5);
  EXPECT_NEAR(r.final.t, 2000.0, 1e-9);
  // Energy T + V = 0 (V = m g y): drift below 1e-8 of m g L.
  EXPECT_NEAR(r.energy_initial, 0.0, 1e-12);
  EXPECT_LT(r.energy_max_drift, 1e-8 * kG);
}

TEST(IftommA01, Pendulum2000s_Dual_Fehlberg78) {
  run_pendulum(DynamicsForm::dual, Integrator::rkf78);
}
TEST(IftommA01, Pendulum2000s_Primal_Fehlberg78) {
  run_pendulum(DynamicsForm::primal, Integrator::rkf78);
}

// ---- A02: on the parallelogram branch every link turns by the same angle θ (body angle of
// link k, π/2 at the start) and every coupler translates with the link tips. Kinetic energy
// ½ I θ̇² with I = (N+1)·mL²/3 + N·m L², potential g m ((N+1) L/2 + N L) sin θ, so
//   I θ̈ = −g ((N+1)/2 + N) cos θ,  θ(0) = π/2, θ̇(0) = −1 (B0 moves at ẋ = 1 m/s).
// Oracle: this scalar ODE by classical RK4 with a tiny step (independent of the library).
struct Reduced {
  double theta, omega;
};
Reduced reduced_four_bar(int N, double t_end) {
  const double I = (N + 1) / 3.0 + N, c = kG * ((N + 1) / 2.0 + N);
  auto acc = [&](double th) { return -c * std::cos(th) / I; };
  Reduced s{M_PI / 2.0, -1.0};
  const int steps = static_cast<int>(std::ceil(t_end / 2e-5));
  const double h = t_end / steps;
  for (int i = 0; i < steps; ++i) {
    const double k1t = s.omega, k1w = acc(s.theta);
    const double k2t = s.omega + 0.5 * h * k1w, k2w = acc(s.theta + 0.5 * h * k1t);
    const double k3t = s.omega + 0.5 * h * k2w, k3w = acc(s.theta + 0.5 * h * k2t);
    const double k4t = s.omega + h * k3w, k4w = acc(s.theta + h * k3t);
    s.theta += h / 6.0 * (k1t + 2 * k2t + 2 * k3t + k4t);
    s.omega += h / 6.0 * (k1w + 2 * k2w + 2 * k3w + k4w);
  }
  return s;
}

void run_four_bar(int N, double t_end, double rtol, double position_tol) {
  const Model model = test::load_bundled("n-four-bar-" + std::to_string(N));
  SimulateOptions o;
  o.t_end = t_end;
  o.rtol = rtol;
  o.atol = 1e-12;
  o.dt_out = t_end;
  o.reactions = false;
  o.initial_rates = {{model.find_measure("B0_x"), 1.0}};
  const SimulateResult r = simulate(model, o);
  ASSERT_EQ(r.status, SimulateStatus::completed) << r.message;
  // The initial state is the published one: T0 = (N+1)/6 + N/2, V0 = g((N+1)/2 + N).
  EXPECT_NEAR(r.samples.front().kinetic, (N + 1) / 6.0 + N / 2.0, 1e-12);
  // Energy conserved to 1e-6 relative (issue 5) through all the change points.
  EXPECT_LT(r.energy_max_drift, 1e-6 * std::abs(r.energy_initial));
  // Still on the parallelogram branch: every link parallel to link0, every coupler horizontal.
  const VecX& q = r.final.q;
  const double th0 = body_angle(model, model.find_body("link0"), q);
  for (int k = 0; k <= N; ++k) {
    const double th = body_angle(model, model.find_body("link" + std::to_string(k)), q);
    EXPECT_NEAR(std::remainder(th - th0, 2 * M_PI), 0.0, 1e-6) << "link" << k;
  }
  for (int k = 0; k < N; ++k)
    EXPECT_NEAR(std::remainder(body_angle(model, model.find_body("coupler" + std::to_string(k)), q),
                               2 * M_PI),
                0.0, 1e-6)
        << "coupler" << k;
  // B0 against the reduced ODE.
  const Reduced ref = reduced_four_bar(N, t_end);
  const size_t ix = static_cast<size_t>(model.find_measure("B0_x"));
  const size_t iy = static_cast<size_t>(model.find_measure("B0_y"));
  EXPECT_NEAR(r.final.measures[ix], std::cos(ref.theta), position_tol);
  EXPECT_NEAR(r.final.measures[iy], std::sin(ref.theta), position_tol);
  EXPECT_NEAR(body_angular_velocity(model, model.find_body("link0"), r.final.u), ref.omega,
              position_tol * std::max(1.0, std::abs(ref.omega)));
  EXPECT_GT(r.chart_switches.size(), 0u);  // it did pass change points
}

TEST(IftommA02, NFourBar2_10s_ThroughSingularPositions) { run_four_bar(2, 10.0, 1e-10, 1e-6); }
TEST(IftommA02, NFourBar40_20s_ThroughSingularPositions) { run_four_bar(40, 20.0, 1e-8, 1e-4); }

}  // namespace
}  // namespace orthomech

namespace orthomech {
namespace {

// The primal form on mechanisms where G = EᵀAE is singular from the start (redundant rows: the
// triple-crank, Bennett; a spatial loop) or becomes so: a stop with a status and a message, never
// a crash, and every sample (and the final one) a whole state of the model.
TEST(SimulatePrimal, SingularStartOrRedundancyStopsWithWholeSamples) {
  for (const char* name : {"triple-crank", "bennett", "hooke-joint", "crank-rocker-3d"}) {
    const Model model = test::load_bundled(name);
    SimulateOptions o;
    o.t_end = 1.0;
    o.form = DynamicsForm::primal;
    const SimulateResult r = simulate(model, o);
    for (const SimulationSample& s : r.samples) {
      ASSERT_EQ(s.q.size(), model.nq) << name << " at t = " << s.t;
      ASSERT_EQ(s.u.size(), model.n) << name << " at t = " << s.t;
    }
    if (r.status != SimulateStatus::completed) {
      EXPECT_FALSE(r.message.empty()) << name;
    }
    EXPECT_EQ(r.final.q.size(), model.nq) << name << ": " << r.message;
  }
}

}  // namespace
}  // namespace orthomech
