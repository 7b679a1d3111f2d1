// A free system with configuration-dependent M(q): Andrews' squeezer in the test set's relative
// coordinates (tests/support/andrews_relative.hpp), which exercises every Ṁ term of eqs. (91)
// and (99) (Ṁ = 0 for the mechanism files' absolute coordinates). Oracles: the published
// values (references.md §1), central differences, and the dual form against the primal.
#include "orthomech/dynamics/general.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <random>

#include "support/andrews_reference.hpp"
#include "support/andrews_relative.hpp"

namespace orthomech {
namespace {

// The published reference at t = 0.03 s (references.md §1).
constexpr const auto& kQ = test::andrews::kAnglesT003;
constexpr const auto& kU = test::andrews::kRatesT003;
constexpr const auto& kLambda = test::andrews::kLambdaT003;

// An admissible moving state: the state of the motion at t = 0.01 s (every Ṁ entry is then
// non-zero: Θ, Φ, Ω and their rates are).
void moving_state(const GeneralSystem& s, VecX& q, VecX& v) {
  GeneralSimulateOptions o;
  o.t_end = 0.01;
  const GeneralSimulateResult r = simulate_general(s, test::andrews_q0(), VecX::Zero(7), o);
  ASSERT_TRUE(r.completed) << r.message;
  q = r.q;
  v = r.u;
}

TEST(GeneralSystem, AndrewsRelative_MassRateAgainstCentralDifferences) {
  const GeneralSystem s = test::andrews_relative();
  VecX q, v;
  moving_state(s, q, v);
  v += VecX::LinSpaced(7, 1.0, 7.0);  // every coordinate moves (Ṁ is a property of M alone)
  MatX Md, Mp, Mm;
  s.mass_rate(q, v, Md);
  const double h = 1e-5 / v.cwiseAbs().maxCoeff();  // a step of 1e-5 rad along v
  s.mass(q + h * v, Mp);
  s.mass(q - h * v, Mm);
  // Central differences: truncation ~ (1e-5)² relative, rounding ~ 1e-16/1e-5.
  EXPECT_LT(((Mp - Mm) / (2 * h) - Md).cwiseAbs().maxCoeff(), 1e-8 * Md.cwiseAbs().maxCoeff());
  EXPECT_GT(Md.cwiseAbs().maxCoeff(), 0.0);
}

TEST(GeneralSystem, AndrewsRelative_ConvectiveTermAgainstCentralDifferences) {
  const GeneralSystem s = test::andrews_relative();
  VecX q, v;
  moving_state(s, q, v);
  MatX Ep, Em;
  VecX Dtu;
  const double h = 1e-5 / v.cwiseAbs().maxCoeff();
  s.jacobian(q + h * v, Ep);
  s.jacobian(q - h * v, Em);
  s.convective(q, v, Dtu);
  const VecX fd = (Ep - Em) / (2 * h) * v;
  EXPECT_LT((fd - Dtu).cwiseAbs().maxCoeff(), 1e-6 * Dtu.cwiseAbs().maxCoeff());
}

// Eqs. (91), (99) with Ṁ ≠ 0: the primal form (αᵀQ̂ − Ωu + βᵀṀu) equals the dual form
// (H v̇ = Fᵀ(Q̂ − Ṁu − M w)), and R = −βᵀQ̂ − ωu + Ṁ_βα u equals ṗ − Q̂; and the Ṁ terms matter
// (dropping them changes the acceleration by far more than the tolerance).
TEST(GeneralSystem, Eq91_Eq99_WithMdot_PrimalEqualsDual) {
  const GeneralSystem s = test::andrews_relative();
  VecX q, v;
  moving_state(s, q, v);
  GeneralDynamics p, d;
  ASSERT_TRUE(compute_general_primal(s, q, v, 0.0, p));
  ASSERT_TRUE(compute_general_dual(s, q, v, 0.0, d));
  const double scale = p.udot.cwiseAbs().maxCoeff();
  EXPECT_LT((p.udot - d.udot).cwiseAbs().maxCoeff(), 1e-10 * scale);
  EXPECT_LT((p.R - d.R).cwiseAbs().maxCoeff(), 1e-10 * p.R.cwiseAbs().maxCoeff());
  EXPECT_LT((p.lambda - d.lambda).cwiseAbs().maxCoeff(), 1e-10 * p.lambda.cwiseAbs().maxCoeff());
  // Without the Ṁ terms of eq. (99) (βᵀṀu) the acceleration is wrong.
  GeneralSystem no_mdot = s;
  no_mdot.mass_rate = [](const VecX&, const VecX&, MatX& Md) { Md.setZero(7, 7); };
  GeneralDynamics wrong;
  ASSERT_TRUE(compute_general_primal(no_mdot, q, v, 0.0, wrong));
  EXPECT_GT((wrong.udot - p.udot).cwiseAbs().maxCoeff(), 1e-3 * scale);
}

// Published accelerations and multipliers at t = 0 (velocities 0).
TEST(GeneralSystem, AndrewsRelative_InitialAccelerationsAndMultipliers) {
  const GeneralSystem s = test::andrews_relative();
  GeneralDynamics p;
  ASSERT_TRUE(compute_general_primal(s, test::andrews_q0(), VecX::Zero(7), 0.0, p));
  EXPECT_NEAR(p.udot(0), 14222.4439199541138705911625887, 1e-9 * 14222.4);
  EXPECT_NEAR(p.udot(1), -10666.8329399655854029433719415, 1e-9 * 10666.8);
  for (int k = 2; k < 7; ++k) EXPECT_NEAR(p.udot(k), 0.0, 1e-7);
  EXPECT_NEAR(-p.lambda(0), 98.5668703962410896057654982170, 1e-10 * 98.6);
  EXPECT_NEAR(-p.lambda(1), -6.12268834425566265503114393122, 1e-10 * 6.2);
  for (int k = 2; k < 6; ++k) EXPECT_NEAR(p.lambda(k), 0.0, 1e-9);
}

class AndrewsRelative : public ::testing::TestWithParam<bool> {};

// The published state at t = 0.03 s (angles 1e-8, rates 1e-5, multipliers 1e-4 relative).
TEST_P(AndrewsRelative, StateAt3ms) {
  const GeneralSystem s = test::andrews_relative();
  GeneralSimulateOptions o;
  o.primal = GetParam();
  o.t_end = 0.03;
  o.rtol = 1e-10;
  o.atol = 1e-12;
  const GeneralSimulateResult r = simulate_general(s, test::andrews_q0(), VecX::Zero(7), o);
  ASSERT_TRUE(r.completed) << r.message;
  EXPECT_NEAR(r.t, 0.03, 1e-15);
  for (int k = 0; k < 7; ++k) {
    const auto K = static_cast<size_t>(k);
    EXPECT_NEAR(r.q(k), kQ[K], 1e-8 * std::abs(kQ[K])) << k;
    EXPECT_NEAR(r.u(k), kU[K], 1e-5 * std::abs(kU[K])) << k;
  }
  for (int k = 0; k < 6; ++k) {
    const auto K = static_cast<size_t>(k);
    EXPECT_NEAR(-r.final.lambda(k), kLambda[K], 1e-4 * std::abs(kLambda[K])) << k;
  }
}
INSTANTIATE_TEST_SUITE_P(Forms, AndrewsRelative, ::testing::Values(false, true),
                         [](const auto& param_info) {
                           return std::string(param_info.param ? "Primal_Eq99" : "Dual");
                         });

}  // namespace
}  // namespace orthomech
