// Position projection (src/analysis/positions.cpp): Gauss–Newton in the mass metric onto
// f(q) = 0. Oracles: for a particle on a rod every step is along the rod, so the result is the
// radial projection onto the circle (closed form); with a joint locked, the four-bar's loop
// written here (the crank-rocker's 30/80/60 mm links on a 70 mm ground, pins on the bodies' x
// axes) and the locked angle; a loop that cannot close is reported, not thrown; Bennett's
// linkage (3 redundant equations) locked from a start off the manifold, against its closure
// θ3 = −θ1, θ4 = −θ2, tan(θ1/2) tan(θ2/2) = sin((β+α)/2)/sin((β−α)/2) (docs/spatial.md §4.2).
#include "orthomech/analysis/positions.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "orthomech/analysis/assembly.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/model/measures.hpp"
#include "support/fixtures.hpp"
#include "support/short_four_bar.hpp"

namespace orthomech {
namespace {

TEST(Positions, ParticleOnARodProjectsRadially) {
  const Model model = test::load_bundled("pendulum");
  for (const Vec2& start : {Vec2(-1.2, 0.3), Vec2(0.4, -0.1), Vec2(0.0, 2.0)}) {
    VecX q(2);
    q << start.x(), start.y();
    const SolveResult r = project_positions(model, q);
    ASSERT_EQ(r.status, SolveStatus::converged) << r.message;
    EXPECT_LE(r.residual, 1e-12);
    const Vec2 expected = start / start.norm();
    EXPECT_NEAR(q(0), expected.x(), 1e-12);
    EXPECT_NEAR(q(1), expected.y(), 1e-12);
  }
}

TEST(Positions, LockedJointHoldsItsAngleAndTheLoopCloses) {
  const Model model = test::load_bundled("crank-rocker");
  const int crank = model.find_body("crank"), coupler = model.find_body("coupler"),
            rocker = model.find_body("rocker");
  ASSERT_GE(crank, 0);
  const auto& bc = model.bodies[static_cast<size_t>(crank)];
  const auto& bk = model.bodies[static_cast<size_t>(coupler)];
  const auto& br = model.bodies[static_cast<size_t>(rocker)];
  for (const double theta : {0.3, 1.0, 2.5, -2.0}) {
    VecX q = model.design_q();
    PositionOptions options;
    options.locked_joint = 0;  // A0: the crank's angle from the ground
    options.locked_value = theta;
    const SolveResult r = project_positions(model, q, options);
    ASSERT_EQ(r.status, SolveStatus::converged) << theta << ": " << r.message;
    EXPECT_NEAR(q(bc.q_offset + 2), theta, 1e-12);
    const auto e = [](double a) { return Vec2(std::cos(a), std::sin(a)); };
    const auto com = [&](const Body& b) { return Vec2(q(b.q_offset), q(b.q_offset + 1)); };
    const double phi_c = q(bk.q_offset + 2), phi_r = q(br.q_offset + 2);
    const Vec2 A0(0, 0), B0(0.07, 0);
    const Vec2 A = A0 + 0.03 * e(theta), B = B0 + 0.06 * e(phi_r);
    EXPECT_LT((com(bc) - (A0 + 0.015 * e(theta))).norm(), 1e-11) << theta;
    EXPECT_LT((com(bk) - (A + 0.04 * e(phi_c))).norm(), 1e-11) << theta;
    EXPECT_LT((com(br) - (B0 + 0.03 * e(phi_r))).norm(), 1e-11) << theta;
    EXPECT_LT((A + 0.08 * e(phi_c) - B).norm(), 1e-11) << theta;
  }
}

// Links 1 + 2 + 3 m on a 10 m ground cannot close: a status with the residual, no exception.
TEST(Positions, ALoopThatCannotCloseIsReported) {
  const Model model = parse_mechanism(test::kShortFourBar, "short.yaml");
  VecX q = model.design_q();
  const SolveResult r = project_positions(model, q);
  EXPECT_NE(r.status, SolveStatus::converged);
  // The gap is 4 m along x, shared among the 4 joints: some |f_k| ≥ 1 m.
  EXPECT_GE(r.residual, 1.0 - 1e-9);
  EXPECT_FALSE(r.message.empty());
}

// Off the manifold the 3 redundant rows of Bennett's linkage regain rank: the rows independent
// at the start are not those independent at the solution. The start is the design pose moved
// along a random velocity (q ⊕ du, so the quaternions stay unit), the input J1 locked elsewhere.
TEST(Positions, BennettLockedFromOffTheManifoldMeetsItsClosure) {
  const Model model = test::load_bundled("bennett");
  constexpr double kPi = std::numbers::pi, kDeg = kPi / 180.0;
  const double a = 30 * kDeg, b = 60 * kDeg;
  const double k = std::sin((b + a) / 2) / std::sin((b - a) / 2);
  const auto wrap = [](double x) { return std::remainder(x, 2 * kPi); };
  const int j1 = model.find_joint("J1"), j2 = model.find_joint("J2"), j3 = model.find_joint("J3"),
            j4 = model.find_joint("J4");
  std::mt19937 rng(12);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  int cases = 0;
  for (const double size : {1e-3, 1e-2, 5e-2})
    for (const double deg : {20.0, 60.0, 75.0, 90.0, 140.0, -100.0}) {
      VecX q = model.design_q();
      VecX du(model.n);
      for (Eigen::Index i = 0; i < du.size(); ++i) du(i) = size * uniform(rng);
      integrate_positions(model, q, du, 1.0);
      VecX f(model.nc);
      compute_constraint_residual(model, q, f);
      ASSERT_GT(f.cwiseAbs().maxCoeff(), 0.1 * size) << "the start is off the manifold";
      PositionOptions options;
      options.locks.push_back({j1, deg * kDeg});
      const SolveResult r = project_positions(model, q, options);
      ASSERT_EQ(r.status, SolveStatus::converged) << size << " " << deg << ": " << r.message;
      compute_constraint_residual(model, q, f);
      EXPECT_LT(f.cwiseAbs().maxCoeff(), 1e-10) << size << " " << deg;
      const double t1 = joint_coordinate(model, j1, q), t2 = joint_coordinate(model, j2, q);
      EXPECT_NEAR(wrap(t1 - deg * kDeg), 0.0, 1e-10) << size << " " << deg;
      // tan(θ1/2) tan(θ2/2) = k without poles.
      EXPECT_NEAR(std::sin(t1 / 2) * std::sin(t2 / 2) - k * std::cos(t1 / 2) * std::cos(t2 / 2),
                  0.0, 1e-10)
          << size << " " << deg;
      EXPECT_NEAR(wrap(joint_coordinate(model, j3, q) + t1), 0.0, 1e-10) << size << " " << deg;
      EXPECT_NEAR(wrap(joint_coordinate(model, j4, q) + t2), 0.0, 1e-10) << size << " " << deg;
      ++cases;
    }
  EXPECT_EQ(cases, 18);
}

}  // namespace
}  // namespace orthomech
