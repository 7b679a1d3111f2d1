// The primal form (src/projection/primal.cpp): its projections equal the dual ones where G is
// regular (eqs. (42)–(44), (56), (57), (60), (103)), ω = π̇ by central differences on the
// manifold (eq. (79)); the Projection suite is instantiated in dual_test.cpp.
#include "orthomech/projection/primal.hpp"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <string>

#include "orthomech/analysis/mobility.hpp"
#include "orthomech/projection/dual.hpp"
#include "support/fixtures.hpp"
#include "support/projection_fixture.hpp"

namespace orthomech {
namespace {

using test::Evaluated;
using test::kAll;
using test::kFdStep;
using test::kFdTol;
using test::kIdentityTol;
using test::numeric_rank;
using test::on_manifold;
using test::Projection;
using test::rel;

// ---- primal form: only where G is regular ------------------------------------------------------
TEST_P(Projection, Eq42_44_PrimalProjectionsEqualDualOnes) {
  const Evaluated e(GetParam());
  if (e.mob.rank < e.model.nc) {
    // Redundant constraints: G = EᵀAE is singular and the primal form must say so.
    EXPECT_FALSE(e.primal_ok);
    EXPECT_EQ(e.ws->primal.status, ProjectionStatus::singular_G);
    return;  // the primal form rightly produces no numbers here
  }
  ASSERT_TRUE(e.primal_ok);
  const auto& p = e.ws->primal;
  const auto& d = e.ws->dual;
  EXPECT_LT(rel(p.G, p.G.transpose()), kIdentityTol);  // eq. (42)
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<MatX>(p.G).eigenvalues().minCoeff(), 0.0);
  EXPECT_LT(rel(p.pi, e.M() * p.beta), kIdentityTol);       // eq. (43)
  EXPECT_LT(rel(p.pi * e.A() * p.pi, p.pi), kIdentityTol);  // eq. (60)
  EXPECT_LT(rel(p.alpha, d.alpha), kIdentityTol) << "primal α ≠ dual α";
  EXPECT_LT(rel(p.beta, d.beta), kIdentityTol) << "primal β ≠ dual β";
  const MatX& M = e.M();
  const MatX& A = e.A();
  EXPECT_LT(rel(p.alpha.transpose() * M * p.alpha, M - p.pi), kIdentityTol);          // eq. (56)
  EXPECT_LT(rel(p.beta.transpose() * M * p.beta, p.pi), kIdentityTol);                // eq. (56)
  EXPECT_LT(rel(p.alpha * A * p.alpha.transpose(), A - A * p.pi * A), kIdentityTol);  // eq. (57)
  EXPECT_LT(rel(p.beta * A * p.beta.transpose(), A * p.pi * A), kIdentityTol);        // eq. (57)
  EXPECT_LT((p.Omega.transpose() * p.alpha).norm() / (1.0 + p.Omega.norm() * p.alpha.norm()),
            kIdentityTol);  // eq. (103)
}

TEST_P(Projection, Eq79_OmegaEqualsTimeDerivativeOfPi) {
  Evaluated e(GetParam());
  if (!e.primal_ok) GTEST_SKIP() << "redundant constraints: no primal form";
  Workspace probe(e.model, e.mob.rank);
  Workspace chart_ws(e.model, e.mob.rank);
  (void)evaluate_dual(e.model, e.state, chart_ws);
  State s = e.state;
  s.q = on_manifold(e.model, e.q, e.state.u, kFdStep, chart_ws);
  ASSERT_EQ(evaluate_primal(e.model, s, probe), ProjectionStatus::ok);
  const MatX pi_plus = probe.primal.pi;
  s.q = on_manifold(e.model, e.q, e.state.u, -kFdStep, chart_ws);
  ASSERT_EQ(evaluate_primal(e.model, s, probe), ProjectionStatus::ok);
  const MatX pi_dot = (pi_plus - probe.primal.pi) / (2.0 * kFdStep);
  EXPECT_LT(rel(e.ws->primal.omega, pi_dot), kFdTol) << "ω ≠ π̇";
}

}  // namespace
}  // namespace orthomech
