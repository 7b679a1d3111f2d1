// Position projection (src/analysis/positions.cpp): Gauss–Newton in the mass metric onto
// f(q) = 0. Oracles: for a particle on a rod every step is along the rod, so the result is the
// radial projection onto the circle (closed form); with a joint locked, the four-bar's loop
// written here (the crank-rocker's 30/80/60 mm links on a 70 mm ground, pins on the bodies' x
// axes) and the locked angle; a loop that cannot close is reported, not thrown.
#include "orthomech/analysis/positions.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "orthomech/io/mechanism_file.hpp"
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

}  // namespace
}  // namespace orthomech
