// The dual form (src/projection/dual.cpp): the paper's theorems as tests, on every bundled
// mechanism (issue 2 §3). Oracles: the identities themselves (Theorems 1–4, 2′), central
// differences along admissible motion on the constraint manifold (θ = ψ̇, eq. (84); Ḟ, eq. (83)),
// and a full crank turn through chart switches that must close the loop.
#include "orthomech/projection/dual.hpp"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <string>

#include "orthomech/analysis/mobility.hpp"
#include "orthomech/projection/primal.hpp"
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

// ---- dual form: holds on every mechanism, redundant or not ------------------------------------
TEST_P(Projection, Eq68_HSymmetricPositiveDefiniteAndEtFZero) {
  const Evaluated e(GetParam());
  const auto& d = e.ws->dual;
  EXPECT_LT(rel(d.H, d.H.transpose()), kIdentityTol);
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<MatX>(d.H).eigenvalues().minCoeff(), 0.0);
  EXPECT_LT((e.Et() * d.F).norm() / (1.0 + e.Et().norm() * d.F.norm()), kIdentityTol);
  EXPECT_EQ(numeric_rank(d.F), e.mob.dof);
}

TEST_P(Projection, Eq70_Theorem2Prime_AlphaFromDualIsTheMassOrthogonalProjection) {
  const Evaluated e(GetParam());
  const auto& d = e.ws->dual;
  const MatX I = MatX::Identity(e.model.n, e.model.n);
  EXPECT_LT(rel(d.alpha * d.alpha, d.alpha), kIdentityTol);                      // eq. (65), (28)
  EXPECT_LT(rel(d.alpha * d.F, d.F), kIdentityTol);                              // eq. (66)
  EXPECT_EQ(numeric_rank(d.alpha), e.mob.dof);                                   // eq. (66)
  EXPECT_LT(rel(d.alpha * e.A(), (d.alpha * e.A()).transpose()), kIdentityTol);  // eq. (67)
  EXPECT_LT(rel(d.psi, d.alpha * e.A()), kIdentityTol);                          // eq. (69)
  EXPECT_LT(rel(d.alpha + d.beta, I), kIdentityTol);                             // eq. (29)
  EXPECT_LT((d.alpha * d.beta).norm() / (1.0 + d.alpha.norm() * d.beta.norm()), kIdentityTol);
  EXPECT_LT((d.beta * d.alpha).norm() / (1.0 + d.alpha.norm() * d.beta.norm()), kIdentityTol);
  EXPECT_LT((e.Et() * d.alpha).norm() / (1.0 + e.Et().norm() * d.alpha.norm()),
            kIdentityTol);                                // eq. (30)
  EXPECT_LT(rel(e.Et() * d.beta, e.Et()), kIdentityTol);  // eq. (30)
  EXPECT_LT(rel(d.beta * d.beta, d.beta), kIdentityTol);  // eq. (28)
  EXPECT_EQ(numeric_rank(d.beta), e.mob.rank);            // eq. (39)
}

TEST_P(Projection, Eq35_Theorem1_MBetaSymmetricAndAlphaTMBetaZero) {
  const Evaluated e(GetParam());
  const auto& d = e.ws->dual;
  const MatX Mb = e.M() * d.beta;
  EXPECT_LT(rel(Mb, Mb.transpose()), kIdentityTol);  // eq. (35)
  EXPECT_LT((d.alpha.transpose() * e.M() * d.beta).norm() / (1.0 + e.M().norm()),
            kIdentityTol);  // eq. (34)
}

TEST_P(Projection, Eq71_72_DualMassAndInfluenceMatricesAndTheorem4) {
  const Evaluated e(GetParam());
  const auto& d = e.ws->dual;
  const MatX& M = e.M();
  const MatX& A = e.A();
  const MatX Maa = d.alpha.transpose() * M * d.alpha,
             Mbb = d.beta.transpose() * M * d.beta;  // eq. (49)
  const MatX Aaa = d.alpha * A * d.alpha.transpose(),
             Abb = d.beta * A * d.beta.transpose();      // eq. (55)
  EXPECT_LT(rel(Maa, M * d.psi * M), kIdentityTol);      // eq. (71)
  EXPECT_LT(rel(Mbb, M - M * d.psi * M), kIdentityTol);  // eq. (71)
  EXPECT_LT((d.alpha.transpose() * M * d.beta).norm() / (1.0 + M.norm()),
            kIdentityTol);                                       // eq. (71)
  EXPECT_LT(rel(Aaa, d.psi), kIdentityTol);                      // eq. (72)
  EXPECT_LT(rel(Abb, A - d.psi), kIdentityTol);                  // eq. (72)
  EXPECT_LT(rel(Aaa * Maa, d.alpha), kIdentityTol);              // eq. (58)
  EXPECT_LT(rel(Maa * Aaa, d.alpha.transpose()), kIdentityTol);  // eq. (58)
  EXPECT_LT(rel(Abb * Mbb, d.beta), kIdentityTol);               // eq. (59)
  EXPECT_LT(rel(Mbb * Abb, d.beta.transpose()), kIdentityTol);   // eq. (59)
}

TEST_P(Projection, Eq83_84_ThetaAndFdotAgainstDifferences) {
  Evaluated e(GetParam());
  Workspace probe(e.model, e.mob.rank);
  probe.dual.engine.set_chart(
      e.ws->dual.engine.chart());  // same chart: F(q(t)) one smooth function
  Workspace chart_ws(e.model, e.mob.rank);
  (void)evaluate_dual(e.model, e.state, chart_ws);
  State s = e.state;
  s.q = on_manifold(e.model, e.q, e.state.u, kFdStep, chart_ws);
  ASSERT_EQ(evaluate_dual(e.model, s, probe), ProjectionStatus::ok);
  const MatX psi_plus = probe.dual.psi, F_plus = probe.dual.F;
  s.q = on_manifold(e.model, e.q, e.state.u, -kFdStep, chart_ws);
  ASSERT_EQ(evaluate_dual(e.model, s, probe), ProjectionStatus::ok);
  ASSERT_EQ(probe.dual.engine.switch_count(), 0);
  const MatX psi_dot = (psi_plus - probe.dual.psi) / (2.0 * kFdStep);
  const MatX F_dot = (F_plus - probe.dual.F) / (2.0 * kFdStep);
  EXPECT_LT(rel(e.ws->dual.Fdot, F_dot), kFdTol) << "Ḟ (from Eᵀ Ḟ = −Dᵀ F) ≠ difference of F";
  EXPECT_LT(rel(e.ws->dual.theta, psi_dot), kFdTol) << "θ ≠ ψ̇ (eq. (84))";
  // Eq. (83) by definition, and the identity Eᵀ Ḟ = −Dᵀ F it rests on.
  const auto& d = e.ws->dual;
  EXPECT_LT(rel(d.Theta, d.Fdot * d.H.llt().solve(d.F.transpose())), kIdentityTol);
  EXPECT_LT(rel(e.Et() * d.Fdot, -e.ws->constraints.Dt * d.F), kIdentityTol);
  if (e.primal_ok) {  // eq. (85) with constant A: α̇ = θM; the primal gives α̇ = −β̇ = −Aω (82)
    EXPECT_LT(rel(d.theta * e.M(), -e.A() * e.ws->primal.omega), 1e-8);
  }
}

INSTANTIATE_TEST_SUITE_P(Bundled, Projection, ::testing::ValuesIn(kAll),
                         [](const auto& param_info) {
                           std::string s = param_info.param;
                           for (char& c : s) c = c == '-' ? '_' : c;
                           return s;
                         });

// ---- charts ------------------------------------------------------------------------------------
// A chart whose independent coordinate is the rocker angle fails at the rocker's limit positions;
// sweeping the crank through a full turn must switch charts there, keep Eᵀ F = 0, and bring the
// linkage back to where it started (same assembly mode).
TEST(Charts, SwitchAtRockerLimitsAndCloseTheLoopAfterOneTurn) {
  const Model model = test::load_bundled("crank-rocker");
  const VecX q0 = test::assembled_q(model);
  const Mobility mob = compute_mobility(model, q0);
  ASSERT_EQ(mob.dof, 1);
  Workspace ws(model, mob.rank);
  State s(model);
  s.q = q0;
  ASSERT_EQ(evaluate_dual(model, s, ws), ProjectionStatus::ok);
  // Force the rocker angle to be the independent coordinate.
  const int crank = model.find_body("crank"), rocker = model.find_body("rocker");
  ASSERT_GE(crank, 0);
  ASSERT_GE(rocker, 0);
  const int rocker_phi = model.bodies[static_cast<size_t>(rocker)].u_offset + 2;
  const int crank_phi = model.bodies[static_cast<size_t>(crank)].u_offset + 2;
  Chart c = ws.dual.engine.chart();
  auto& dep = c.dependent;
  const auto it = std::find(dep.begin(), dep.end(), rocker_phi);
  ASSERT_NE(it, dep.end()) << "rocker angle already independent";
  *it = c.independent[0];
  c.independent[0] = rocker_phi;
  std::sort(dep.begin(), dep.end());
  ws.dual.engine.set_chart(c);
  const double start = s.q(crank_phi);
  const int steps = 3600;
  const double h = 2.0 * M_PI / steps;
  for (int k = 0; k < steps; ++k) {
    s.t = k * h;
    ASSERT_EQ(evaluate_dual(model, s, ws), ProjectionStatus::ok) << "step " << k;
    ASSERT_LT((ws.constraints.Et * ws.dual.F).norm(), 1e-9) << "step " << k;
    // Unit crank speed: u = F v with (crank row of F) v = 1.
    const double rate = ws.dual.F(crank_phi, 0);
    ASSERT_GT(std::abs(rate), 1e-3) << "a crank-rocker has no dead point at its crank";
    // Midpoint predictor, then the chart corrector.
    const VecX u1 = ws.dual.F.col(0) / rate;
    State mid = s;
    mid.q += 0.5 * h * u1;
    ASSERT_EQ(evaluate_dual(model, mid, ws), ProjectionStatus::ok);
    s.q += h * ws.dual.F.col(0) / ws.dual.F(crank_phi, 0);
    const SolveResult r = correct_positions_in_chart(model, s.q, ws);
    ASSERT_EQ(r.status, SolveStatus::converged) << "step " << k << ": " << r.message;
  }
  EXPECT_GE(ws.dual.engine.switch_count(), 1)
      << "the rocker-angle chart must be left at a rocker limit";
  EXPECT_EQ(ws.dual.engine.switches().size(), static_cast<size_t>(ws.dual.engine.switch_count()));
  EXPECT_NEAR(s.q(crank_phi) - start, 2.0 * M_PI, 1e-3);  // crank held by the predictor only
  // Back to the start: every coordinate but the crank angle returns (same assembly mode).
  VecX back = s.q;
  back(crank_phi) -= 2.0 * M_PI;
  EXPECT_LT((back - q0).cwiseAbs().maxCoeff(), 1e-3);
}

}  // namespace
}  // namespace orthomech
