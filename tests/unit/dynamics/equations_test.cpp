// A free system with configuration-dependent M(q) run through the same engine as the mechanism
// files: Andrews' squeezer in the test set's relative coordinates (tests/support/
// andrews_relative.hpp) as a Model (model/general_system.hpp), which exercises every Ṁ term of
// eqs. (91) and (99) (Ṁ = 0 for the mechanism files' absolute coordinates). Oracles: the
// published values (references.md §1), central differences, and the dual form against the
// primal (and the built-in crosscheck's identities).
#include "orthomech/dynamics/equations.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "orthomech/analysis/mobility.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/dynamics/crosscheck.hpp"
#include "orthomech/dynamics/simulate.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/model/general_system.hpp"
#include "orthomech/projection/workspace.hpp"
#include "support/andrews_reference.hpp"
#include "support/andrews_relative.hpp"

namespace orthomech {
namespace {

// The published reference at t = 0.03 s (references.md §1).
constexpr const auto& kQ = test::andrews::kAnglesT003;
constexpr const auto& kU = test::andrews::kRatesT003;
constexpr const auto& kLambda = test::andrews::kLambdaT003;

// An admissible moving state: the state of the motion at t = 0.01 s, from the engine (every Ṁ
// entry is then non-zero: Θ, Φ, Ω and their rates are).
State moving_state(const Model& model) {
  SimulateOptions o;
  o.t_end = 0.01;
  o.record_samples = false;
  const SimulateResult r = simulate(model, o);
  EXPECT_EQ(r.status, SimulateStatus::completed) << r.message;
  State s(model);
  s.t = r.final.t;
  s.q = r.final.q;
  s.u = r.final.u;
  return s;
}

TEST(GeneralSystem, ModelHasTheSystemsSizesAndNames) {
  const Model m = test::andrews_relative();
  EXPECT_EQ(m.n, 7);
  EXPECT_EQ(m.nq, 7);
  EXPECT_EQ(m.nc, 6);
  EXPECT_FALSE(mass_matrix_is_constant(m));
  EXPECT_EQ(m.constraint_row_name(5), "constraint 'g6'");
  const Mobility mob = compute_mobility(m, m.design_q());
  EXPECT_EQ(mob.rank, 6);
  EXPECT_EQ(mob.dof, 1);
  GeneralSystem incomplete = test::andrews_relative_system();
  incomplete.jacobian_rate = nullptr;
  EXPECT_THROW((void)make_general_model("x", incomplete), std::invalid_argument);
}

TEST(GeneralSystem, AndrewsRelative_MassRateAgainstCentralDifferences) {
  const Model m = test::andrews_relative();
  State s = moving_state(m);
  s.u += VecX::LinSpaced(7, 1.0, 7.0);  // every coordinate moves (Ṁ is a property of M alone)
  MatX Md(7, 7), Mp(7, 7), Mm(7, 7);
  compute_mass_matrix_rate(m, s.q, s.u, Md);
  const double h = 1e-5 / s.u.cwiseAbs().maxCoeff();  // a step of 1e-5 rad along u
  compute_mass_matrix(m, s.q + h * s.u, Mp);
  compute_mass_matrix(m, s.q - h * s.u, Mm);
  // Central differences: truncation ~ (1e-5)² relative, rounding ~ 1e-16/1e-5.
  EXPECT_LT(((Mp - Mm) / (2 * h) - Md).cwiseAbs().maxCoeff(), 1e-8 * Md.cwiseAbs().maxCoeff());
  EXPECT_GT(Md.cwiseAbs().maxCoeff(), 0.0);
}

// Dᵀ = Ėᵀ (eq. (76)) through compute_constraints against central differences of Eᵀ along u.
TEST(GeneralSystem, AndrewsRelative_JacobianRateAgainstCentralDifferences) {
  const Model m = test::andrews_relative();
  const State s = moving_state(m);
  ConstraintWorkspace c(m);
  compute_constraints(m, s, c);
  MatX Ep(6, 7), Em(6, 7);
  const double h = 1e-5 / s.u.cwiseAbs().maxCoeff();
  compute_constraint_jacobian(m, s.q + h * s.u, Ep);
  compute_constraint_jacobian(m, s.q - h * s.u, Em);
  const MatX fd = (Ep - Em) / (2 * h);
  EXPECT_LT((fd - c.Dt).cwiseAbs().maxCoeff(), 1e-6 * c.Dt.cwiseAbs().maxCoeff());
  EXPECT_LT((fd * s.u - c.Dtu).cwiseAbs().maxCoeff(), 1e-6 * c.Dtu.cwiseAbs().maxCoeff());
  ConstraintWorkspace rate_only(m);  // the row-by-row entry point gives the same Dᵀu
  compute_constraint_rate(m, s, rate_only);
  EXPECT_LT((rate_only.Dtu - c.Dtu).cwiseAbs().maxCoeff(), 1e-14 * c.Dtu.cwiseAbs().maxCoeff());
  EXPECT_LT((c.Et * s.u).cwiseAbs().maxCoeff(),
            1e-9 * c.Et.cwiseAbs().maxCoeff() * s.u.cwiseAbs().maxCoeff());  // admissible
}

// Eqs. (91), (99) with Ṁ ≠ 0 through the projection workspace: the primal form
// (αᵀQ̂ − Ωu + βᵀṀu) equals the dual form (H v̇ = Fᵀ(Q̂ − Ṁu − M Ḟ v)), and R = −βᵀQ̂ − ωu +
// Ṁ_βα u equals ṗ − Q̂; and the Ṁ terms matter (dropping them changes the acceleration by far
// more than the tolerance).
TEST(GeneralSystem, Eq91_Eq99_WithMdot_PrimalEqualsDual) {
  const Model m = test::andrews_relative();
  const State s = moving_state(m);
  Workspace wp(m, 6), wd(m, 6);
  DynamicsPoint p(m), d(m);
  ASSERT_EQ(compute_primal_dynamics(m, s, wp, p), ProjectionStatus::ok);
  ASSERT_EQ(compute_dual_dynamics(m, s, wd, d), ProjectionStatus::ok);
  const double scale = p.udot.cwiseAbs().maxCoeff();
  EXPECT_LT((p.udot - d.udot).cwiseAbs().maxCoeff(), 1e-10 * scale);
  EXPECT_LT((p.R - d.R).cwiseAbs().maxCoeff(), 1e-10 * p.R.cwiseAbs().maxCoeff());
  EXPECT_LT((p.lambda - d.lambda).cwiseAbs().maxCoeff(), 1e-10 * p.lambda.cwiseAbs().maxCoeff());
  // Without the Ṁ terms of eq. (99) (βᵀṀu) the acceleration is wrong.
  GeneralSystem no_mdot = test::andrews_relative_system();
  no_mdot.mass_rate = [](const VecX&, const VecX&, MatX& Md) { Md.setZero(7, 7); };
  const Model wrong_model = make_general_model("no-Mdot", no_mdot);
  Workspace ww(wrong_model, 6);
  DynamicsPoint wrong(wrong_model);
  ASSERT_EQ(compute_primal_dynamics(wrong_model, s, ww, wrong), ProjectionStatus::ok);
  EXPECT_GT((wrong.udot - p.udot).cwiseAbs().maxCoeff(), 1e-3 * scale);
}

// Eqs. (81)–(82) with Ṁ ≠ 0: α̇ = −β̇ = −Aω + A Ṁ_αβ (Ṁ_αβ = αᵀṀβ), against central
// differences of α(q) (eq. (44)) along u; and the Ṁ term is needed (−Aω alone is off).
TEST(GeneralSystem, Eq81_Eq82_AlphaRateWithMdotAgainstCentralDifferences) {
  const Model m = test::andrews_relative();
  const State s = moving_state(m);
  Workspace w(m, 6);
  DynamicsPoint p(m);
  ASSERT_EQ(compute_primal_dynamics(m, s, w, p), ProjectionStatus::ok);
  const MatX& A = w.free.A;
  const MatX alpha = w.primal.alpha, beta = w.primal.beta, omega = w.primal.omega;
  const MatX Mdot = w.free.Mdot;
  const MatX predicted = -A * omega + A * alpha.transpose() * Mdot * beta;  // eq. (82)
  const double h = 1e-6 / s.u.cwiseAbs().maxCoeff();
  MatX a_plus, a_minus;
  for (const double sign : {1.0, -1.0}) {
    State x = s;
    x.q = s.q + sign * h * s.u;
    Workspace wx(m, 6);
    DynamicsPoint px(m);
    ASSERT_EQ(compute_primal_dynamics(m, x, wx, px), ProjectionStatus::ok);
    (sign > 0 ? a_plus : a_minus) = wx.primal.alpha;
  }
  const MatX fd = (a_plus - a_minus) / (2 * h);
  const double scale = fd.cwiseAbs().maxCoeff();
  EXPECT_LT((fd - predicted).cwiseAbs().maxCoeff(), 1e-6 * scale);  // measured 6.2e-9
  EXPECT_GT((fd + A * omega).cwiseAbs().maxCoeff(), 1e-2 * scale);  // Ṁ_αβ matters: 0.12
}

// Published accelerations and multipliers at t = 0 (velocities 0), both forms.
TEST(GeneralSystem, AndrewsRelative_InitialAccelerationsAndMultipliers) {
  const Model m = test::andrews_relative();
  State s(m);
  s.q = test::andrews_q0();
  Workspace wp(m, 6), wd(m, 6);
  DynamicsPoint p(m), d(m);
  ASSERT_EQ(compute_primal_dynamics(m, s, wp, p), ProjectionStatus::ok);
  ASSERT_EQ(compute_dual_dynamics(m, s, wd, d), ProjectionStatus::ok);
  for (const DynamicsPoint* x : {&p, &d}) {
    EXPECT_NEAR(x->udot(0), 14222.4439199541138705911625887, 1e-9 * 14222.4);
    EXPECT_NEAR(x->udot(1), -10666.8329399655854029433719415, 1e-9 * 10666.8);
    for (int k = 2; k < 7; ++k) EXPECT_NEAR(x->udot(k), 0.0, 1e-7);
    EXPECT_NEAR(-x->lambda(0), 98.5668703962410896057654982170, 1e-10 * 98.6);
    EXPECT_NEAR(-x->lambda(1), -6.12268834425566265503114393122, 1e-10 * 6.2);
    for (int k = 2; k < 6; ++k) EXPECT_NEAR(x->lambda(k), 0.0, 1e-9);
  }
}

class AndrewsRelative : public ::testing::TestWithParam<DynamicsForm> {};

// The published state at t = 0.03 s from simulate (angles 1e-8, rates 1e-5, multipliers 1e-4
// relative), and the energy balance T − W (all of Q̂ is counted as work for a general system).
TEST_P(AndrewsRelative, StateAt3ms) {
  const Model m = test::andrews_relative();
  SimulateOptions o = test::andrews::reference_run(GetParam());
  o.record_samples = false;
  const SimulateResult r = simulate(m, o);
  ASSERT_EQ(r.status, SimulateStatus::completed) << r.message;
  EXPECT_NEAR(r.final.t, 0.03, 1e-15);
  for (int k = 0; k < 7; ++k) {
    const auto K = static_cast<size_t>(k);
    EXPECT_NEAR(r.final.q(k), kQ[K], 1e-8 * std::abs(kQ[K])) << k;
    EXPECT_NEAR(r.final.u(k), kU[K], 1e-5 * std::abs(kU[K])) << k;
  }
  for (int k = 0; k < 6; ++k) {
    const auto K = static_cast<size_t>(k);
    EXPECT_NEAR(-r.final.lambda(k), kLambda[K], 1e-4 * std::abs(kLambda[K])) << k;
  }
  EXPECT_LT(r.max_constraint_residual, 1e-10);
  EXPECT_LT(r.energy_max_drift, 1e-9 * r.energy_scale);  // measured 9e-12 (dual), 3e-12
}
INSTANTIATE_TEST_SUITE_P(Forms, AndrewsRelative,
                         ::testing::Values(DynamicsForm::dual, DynamicsForm::primal),
                         [](const auto& param_info) {
                           return std::string(
                               param_info.param == DynamicsForm::primal ? "Primal_Eq99" : "Dual");
                         });

// The built-in crosscheck on the M(q) system: dual = primal and every identity, including
// θM = −Aω (eqs. (82), (85)), which holds with Ṁ ≠ 0 because the Ṁ terms of (82) and (85)
// are equal (ψ Ṁ β = A αᵀ Ṁ β since ψ = A αᵀ).
TEST(GeneralSystem, AndrewsRelative_CrosscheckPasses) {
  const Model m = test::andrews_relative();
  CrosscheckOptions o;
  o.t_end = 0.02;
  o.samples = 6;
  o.tolerance = 1e-10;  // measured: ≤ 1.9e-14 on every item
  const CrosscheckResult r = run_crosscheck(m, o);
  EXPECT_TRUE(r.pass) << r.message;
  EXPECT_TRUE(r.primal_checked);
  bool theta_checked = false;
  for (const CrosscheckItem& it : r.items) {
    EXPECT_TRUE(it.pass) << it.name << ": " << it.max_relative;
    if (it.name.find("theta M") != std::string::npos) theta_checked = true;
  }
  EXPECT_TRUE(theta_checked);
}

}  // namespace
}  // namespace orthomech
