// Andrews' squeezing mechanism against the published reference (Test Set for IVP Solvers,
// Univ. Bari, Mazzia & Magherini, problem `andrews`; Hairer & Wanner, Solving ODEs II, §VII.7;
// /work/shared/references.md §1), from mechanisms/andrews-squeezer.yaml (absolute coordinates).
// Our multipliers are minus the published ones (file comment of andrews-squeezer.yaml).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <string>

#include "orthomech/dynamics/simulate.hpp"
#include "orthomech/model/free_system.hpp"
#include "support/andrews_reference.hpp"
#include "support/fixtures.hpp"

namespace orthomech {
namespace {

// The published reference (references.md §1), shared with the benchmarks.
using test::andrews::kAngleTol;
using test::andrews::kLambdaTol;
using test::andrews::kRateTol;
constexpr const auto& kAngles = test::andrews::kAnglesT003;
constexpr const auto& kRates = test::andrews::kRatesT003;
constexpr const auto& kLambda = test::andrews::kLambdaT003;
constexpr const auto& names = test::andrews::kNames;

// The published angles from the bodies: β = φ1, Θ = φ2 − φ1, γ = φ3, Φ = φ4 − φ5, δ = φ5,
// Ω = φ6 − φ7, ε = φ7 (the measures of the file do the same for positions).
std::array<double, 7> published_rates(const Model& m, const VecX& u) {
  auto w = [&](const char* b) { return body_angular_velocity(m, m.find_body(b), u); };
  return {w("K1"), w("K2") - w("K1"), w("K3"), w("K4") - w("K5"),
          w("K5"), w("K6") - w("K7"), w("K7")};
}

// Published λ1…λ6 from ours: E23 = −(λ1, λ2), E24 = −(λ3, λ4), E26 = −(λ5, λ6).
std::array<double, 6> published_lambda(const Model& m, const VecX& lambda) {
  std::array<double, 6> out{};
  const char* joints[] = {"E23", "E24", "E26"};
  for (int k = 0; k < 3; ++k) {
    const int r = m.joints[static_cast<size_t>(m.find_joint(joints[k]))].row_offset;
    out[static_cast<size_t>(2 * k)] = -lambda(r);
    out[static_cast<size_t>(2 * k + 1)] = -lambda(r + 1);
  }
  return out;
}

void expect_reference(const Model& model, const SimulateResult& res) {
  ASSERT_EQ(res.status, SimulateStatus::completed) << res.message;
  EXPECT_NEAR(res.final.t, 0.03, 1e-15);
  for (size_t k = 0; k < 7; ++k) {
    const double got = res.final.measures[static_cast<size_t>(model.find_measure(names[k]))];
    EXPECT_NEAR(got, kAngles[k], kAngleTol * std::abs(kAngles[k])) << names[k];
  }
  const auto rates = published_rates(model, res.final.u);
  for (size_t k = 0; k < 7; ++k)
    EXPECT_NEAR(rates[k], kRates[k], kRateTol * std::abs(kRates[k])) << names[k] << " rate";
  const auto lambda = published_lambda(model, res.final.lambda);
  for (size_t k = 0; k < 6; ++k)
    EXPECT_NEAR(lambda[k], kLambda[k], kLambdaTol * std::abs(kLambda[k])) << "lambda" << k + 1;
  // Energy T + V − W (W: work of the driving torque) is conserved: relative 1e-8 of its scale.
  EXPECT_LT(res.energy_max_drift, 1e-8 * res.energy_scale);
  EXPECT_LT(res.max_constraint_residual, 1e-9);
}

TEST(AndrewsReference, Dual_Dopri5_StateAt3ms) {
  const Model model = test::load_bundled("andrews-squeezer");
  const SimulateResult res = simulate(model, test::andrews::reference_run(DynamicsForm::dual));
  expect_reference(model, res);
}

TEST(AndrewsReference, Primal_Eq99_Dopri5_StateAt3ms) {
  const Model model = test::load_bundled("andrews-squeezer");
  const SimulateResult res = simulate(model, test::andrews::reference_run(DynamicsForm::primal));
  expect_reference(model, res);
  EXPECT_LT(res.max_invariant_J, 1e-6);  // eq. (105): J stays ~0 between projections
}

TEST(AndrewsReference, Dual_Fehlberg78_StateAt3ms) {
  const Model model = test::load_bundled("andrews-squeezer");
  const SimulateResult res =
      simulate(model, test::andrews::reference_run(DynamicsForm::dual, Integrator::rkf78));
  expect_reference(model, res);
}

// Accelerations and multipliers at t = 0 (published, exact to the digits printed).
TEST(AndrewsReference, InitialAccelerationsAndMultipliers) {
  const Model model = test::load_bundled("andrews-squeezer");
  for (DynamicsForm form : {DynamicsForm::dual, DynamicsForm::primal}) {
    SimulateOptions o = test::andrews::reference_run(form);
    o.t_end = 1e-6;
    o.dt_out = 1e-6;
    const SimulateResult res = simulate(model, o);
    ASSERT_EQ(res.status, SimulateStatus::completed) << res.message;
    ASSERT_FALSE(res.samples.empty());
    const SimulationSample& s0 = res.samples.front();
    EXPECT_EQ(s0.t, 0.0);
    const auto acc = published_rates(model, s0.udot);
    EXPECT_NEAR(acc[0], 14222.4439199541138705911625887, 1e-9 * 14222.4);
    EXPECT_NEAR(acc[1], -10666.8329399655854029433719415, 1e-9 * 10666.8);
    for (size_t k = 2; k < 7; ++k) EXPECT_NEAR(acc[k], 0.0, 1e-7);
    const auto lambda = published_lambda(model, s0.lambda);
    EXPECT_NEAR(lambda[0], 98.5668703962410896057654982170, 1e-10 * 98.6);
    EXPECT_NEAR(lambda[1], -6.12268834425566265503114393122, 1e-10 * 6.1);
    for (size_t k = 2; k < 6; ++k) EXPECT_NEAR(lambda[k], 0.0, 1e-9);
  }
}

}  // namespace
}  // namespace orthomech
