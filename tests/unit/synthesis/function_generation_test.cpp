// Freudenstein function generation (src/synthesis/function_generation.cpp, (L9)–(L13)).
// Oracle: the closed-form circle-intersection positions of four_bar.cpp (calc_position), which
// never use Freudenstein's equation: pairs are sampled from a known linkage with it, and the
// synthesised linkage is checked with it.
#include "orthomech/synthesis/function_generation.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace orthomech::synthesis {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;
// Exact synthesis: a 3 × 3 solve and a few trigonometric evaluations (angles in radians).
constexpr double kExactAngle = 1e-12;
// Recovered lengths of ~100 mm links from a well-conditioned solve.
constexpr double kLength = 1e-10;

FourBar crank_rocker() {  // mechanisms/crank-rocker.yaml
  FourBar fb;
  fb.B0 = {70, 0};
  fb.a = 30;
  fb.b = 80;
  fb.c = 60;
  return fb;
}

std::vector<AnglePair> sample(const FourBar& fb, const std::vector<double>& phis) {
  std::vector<AnglePair> pairs;
  for (const double phi : phis) pairs.push_back({phi, calc_position(fb, phi).follower_angle});
  return pairs;
}

void expect_same_linkage(const FourBar& got, const FourBar& want) {
  EXPECT_NEAR(got.a, want.a, kLength);
  EXPECT_NEAR(got.b, want.b, kLength);
  EXPECT_NEAR(got.c, want.c, kLength);
  EXPECT_EQ(got.branch, want.branch);
}

TEST(FunctionGeneration, L11_ThreePairsRoundTripOfTheCrankRocker) {
  for (const int branch : {1, -1}) {
    FourBar fb = crank_rocker();
    fb.branch = branch;
    const auto pairs = sample(fb, {40 * kDeg, 100 * kDeg, 200 * kDeg});
    const FunctionSynthesisResult r = synthesize_function_generator(pairs, 70.0);
    ASSERT_EQ(r.status, SynthesisStatus::ok) << r.message;
    EXPECT_LT(r.max_output_error, kExactAngle);
    expect_same_linkage(r.linkage, fb);
    EXPECT_EQ(r.input_offset, 0.0);
    // The same linkage away from the precision points too.
    for (int k = 0; k < 36; ++k) {
      const double phi = k * 10 * kDeg;
      EXPECT_NEAR(calc_position(r.linkage, phi).follower_angle,
                  calc_position(fb, phi).follower_angle, kExactAngle);
    }
  }
}

TEST(FunctionGeneration, L10_FreudensteinCoefficientsOfTheCrankRocker) {
  // (L10) by hand: K1 = −70/60, K2 = −70/30, K3 = (30² − 80² + 60² + 70²)/(2·30·60).
  const auto pairs = sample(crank_rocker(), {10 * kDeg, 130 * kDeg, 250 * kDeg});
  const FunctionSynthesisResult r = synthesize_function_generator(pairs, 70.0);
  EXPECT_NEAR(r.K(0), -70.0 / 60.0, 1e-13);
  EXPECT_NEAR(r.K(1), -70.0 / 30.0, 1e-13);
  EXPECT_NEAR(r.K(2), (900.0 - 6400.0 + 3600.0 + 4900.0) / 3600.0, 1e-13);
}

TEST(FunctionGeneration, L12_LeastSquaresRecoversTheLinkage) {
  const FourBar fb = crank_rocker();
  std::vector<double> phis;
  for (int k = 0; k < 12; ++k) phis.push_back(k * 30 * kDeg + 0.1);
  const FunctionSynthesisResult r = synthesize_function_generator(sample(fb, phis), 70.0);
  ASSERT_EQ(r.status, SynthesisStatus::ok) << r.message;
  expect_same_linkage(r.linkage, fb);
  EXPECT_LT(r.max_output_error, kExactAngle);
}

TEST(FunctionGeneration, L10_NegativeCrankBecomesAnInputOffset) {
  // Pairs whose input is measured from the crank's opposite direction give a = −30.
  const FourBar fb = crank_rocker();
  std::vector<AnglePair> pairs = sample(fb, {20 * kDeg, 150 * kDeg, 300 * kDeg});
  for (AnglePair& p : pairs) p.phi -= kPi;
  const FunctionSynthesisResult r = synthesize_function_generator(pairs, 70.0);
  ASSERT_EQ(r.status, SynthesisStatus::ok) << r.message;
  EXPECT_DOUBLE_EQ(r.input_offset, kPi);
  expect_same_linkage(r.linkage, fb);
  EXPECT_LT(r.max_output_error, kExactAngle);
}

TEST(FunctionGeneration, L9_PairsOnBothBranchesAreABranchDefect) {
  // (L9) holds on both branches, so two open-branch pairs and one crossed-branch pair give the
  // crank-rocker's K exactly, but no single branch passes through all three.
  FourBar open = crank_rocker(), crossed = crank_rocker();
  crossed.branch = -1;
  std::vector<AnglePair> pairs = sample(open, {30 * kDeg, 140 * kDeg});
  pairs.push_back(sample(crossed, {260 * kDeg})[0]);
  const FunctionSynthesisResult r = synthesize_function_generator(pairs, 70.0);
  EXPECT_EQ(r.status, SynthesisStatus::branch_defect) << r.message;
  EXPECT_NE(r.message.find("different assembly branches"), std::string::npos) << r.message;
  expect_same_linkage(r.linkage, open);
}

TEST(FunctionGeneration, L13_ChebyshevSpacingAndALogarithmGenerator) {
  const std::vector<double> x = chebyshev_spacing(3, 1.0, 2.0);
  ASSERT_EQ(x.size(), 3U);
  EXPECT_NEAR(x[0], 1.5 - 0.5 * std::sqrt(3.0) / 2.0, 1e-15);
  EXPECT_NEAR(x[1], 1.5, 1e-15);
  EXPECT_NEAR(x[2], 1.5 + 0.5 * std::sqrt(3.0) / 2.0, 1e-15);
  // y = log10 x on [1, 2]; φ over 60° from 45°, ψ over 60° from 135° (a textbook-sized case).
  const AngleMap map{1.0, 2.0, 45 * kDeg, 60 * kDeg, 135 * kDeg, 60 * kDeg};
  const auto f = [](double v) { return std::log10(v); };
  const std::vector<AnglePair> pairs = map_to_angles(f, x, map);
  EXPECT_NEAR(pairs[1].psi, 135 * kDeg + std::log10(1.5) / std::log10(2.0) * 60 * kDeg, 1e-15);
  const FunctionSynthesisResult r = synthesize_function_generator(pairs, 1.0);
  ASSERT_NE(r.status, SynthesisStatus::no_linkage) << r.message;
  // Exact at the precision points (checked by circle intersection).
  for (const AnglePair& p : pairs) {
    const FourBarPosition pos = calc_position(r.linkage, p.phi + r.input_offset);
    ASSERT_TRUE(pos.assembles);
    EXPECT_NEAR(std::remainder(pos.follower_angle - r.output_offset - p.psi, 2 * kPi), 0.0,
                kExactAngle);
  }
}

TEST(FunctionGeneration, MisuseAndDegenerateData) {
  const auto two = sample(crank_rocker(), {0.1, 0.2});
  EXPECT_THROW((void)synthesize_function_generator(two, 70.0), std::invalid_argument);
  const auto three = sample(crank_rocker(), {0.1, 0.2, 0.3});
  EXPECT_THROW((void)synthesize_function_generator(three, 0.0), std::invalid_argument);
  const std::vector<AnglePair> same(3, AnglePair{0.3, 1.2});
  const FunctionSynthesisResult r = synthesize_function_generator(same, 70.0);
  EXPECT_EQ(r.status, SynthesisStatus::no_linkage);
  EXPECT_NE(r.message.find("rank-deficient"), std::string::npos) << r.message;
  try {
    (void)synthesize_function_generator(two, 70.0);
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("pairs"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace orthomech::synthesis
