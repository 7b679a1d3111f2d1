// Closed-form four-bar and slider-crank positions (src/synthesis/four_bar.cpp, (L1)–(L8)).
// Oracles: the reference values of mechanisms/crank-rocker.yaml, double-rocker.yaml and
// slider-crank.yaml (computed by scripts/gen_mechanisms.py, written in their comment blocks);
// the loop-closure lengths; the Grashof inequalities written out by hand for each case.
#include "orthomech/synthesis/four_bar.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace orthomech::synthesis {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;
// The yaml files round their reference values to 1e-6 (mm, deg).
constexpr double kFileRounding = 1e-6;
// Round-off of a few trigonometric evaluations on 100 mm links.
constexpr double kRoundoff = 1e-11;

FourBar crank_rocker() {  // mechanisms/crank-rocker.yaml
  FourBar fb;
  fb.A0 = {0, 0};
  fb.B0 = {70, 0};
  fb.a = 30;
  fb.b = 80;
  fb.c = 60;
  fb.coupler_point = {40, 20};
  fb.branch = 1;
  return fb;
}

TEST(FourBar, L1L5_DesignPositionsOfTheCrankRockerFile) {
  const FourBar fb = crank_rocker();
  // design_positions p1..p3 of mechanisms/crank-rocker.yaml (open circuit).
  const FourBarPosition p1 = calc_position(fb, 60 * kDeg);
  ASSERT_TRUE(p1.assembles);
  EXPECT_NEAR(p1.P.x(), 44.117074, kFileRounding);
  EXPECT_NEAR(p1.P.y(), 59.924775, kFileRounding);
  EXPECT_NEAR(p1.coupler_angle / kDeg, 22.812053, kFileRounding);
  EXPECT_NEAR(p1.follower_angle / kDeg, 71.79755360961532, kRoundoff);
  const FourBarPosition p2 = calc_position(fb, 150 * kDeg);
  EXPECT_NEAR(p2.P.x(), -0.810374, kFileRounding);
  EXPECT_NEAR(p2.P.y(), 51.965546, kFileRounding);
  const FourBarPosition p3 = calc_position(fb, 270 * kDeg);
  EXPECT_NEAR(p3.P.x(), -3.797943, kFileRounding);
  EXPECT_NEAR(p3.P.y(), 14.559798, kFileRounding);
}

TEST(FourBar, L5_TransmissionAngleExtremesOfTheCrankRocker) {
  const FourBar fb = crank_rocker();
  EXPECT_NEAR(calc_position(fb, 0.0).transmission_angle / kDeg, 28.955024, kFileRounding);
  EXPECT_NEAR(calc_position(fb, kPi).transmission_angle / kDeg, 90.0, kFileRounding);
  // The extended limit position: rocker at 64.623066 deg when the crank is at 29.526265 deg.
  EXPECT_NEAR(calc_position(fb, 29.526265 * kDeg).follower_angle / kDeg, 64.623066, 1e-5);
}

TEST(FourBar, L4_LoopClosesOnBothBranchesAndBranchesMirror) {
  const FourBar fb = crank_rocker();
  for (int k = 0; k < 36; ++k) {
    const double theta = k * 10 * kDeg;
    for (const int br : {1, -1}) {
      const FourBarPosition p = calc_position(fb, theta, br);
      ASSERT_TRUE(p.assembles);
      EXPECT_NEAR((p.A - fb.A0).norm(), fb.a, kRoundoff);
      EXPECT_NEAR((p.B - p.A).norm(), fb.b, kRoundoff);
      EXPECT_NEAR((p.B - fb.B0).norm(), fb.c, kRoundoff);
      // Side of B relative to A→B0 is the branch sign (cross product).
      const Eigen::Vector2d u = fb.B0 - p.A, w = p.B - p.A;
      EXPECT_GT(br * (u.x() * w.y() - u.y() * w.x()), 0.0);
    }
  }
}

TEST(FourBar, L6_GrashofTypes) {
  FourBar fb = crank_rocker();
  EXPECT_EQ(classify_grashof(fb), GrashofType::crank_rocker);
  // Drag link: ground shortest (d = 20; 20 + 80 < 30 + 75).
  fb.B0 = {20, 0};
  fb.a = 30;
  fb.b = 80;
  fb.c = 75;
  EXPECT_EQ(classify_grashof(fb), GrashofType::double_crank);
  // Rocker-crank: follower shortest (c = 20; 20 + 80 < 60 + 70).
  fb.B0 = {70, 0};
  fb.a = 60;
  fb.c = 20;
  EXPECT_EQ(classify_grashof(fb), GrashofType::rocker_crank);
  // Grashof double-rocker: coupler shortest (b = 20; 20 + 80 < 60 + 70 with d = 80).
  fb.B0 = {80, 0};
  fb.a = 60;
  fb.b = 20;
  fb.c = 70;
  EXPECT_EQ(classify_grashof(fb), GrashofType::grashof_double_rocker);
  // mechanisms/double-rocker.yaml: 40 + 100 > 60 + 65.
  fb.B0 = {100, 0};
  fb.a = 60;
  fb.b = 40;
  fb.c = 65;
  EXPECT_EQ(classify_grashof(fb), GrashofType::triple_rocker);
  // Parallelogram: s + l = p + q.
  fb.B0 = {70, 0};
  fb.a = 30;
  fb.b = 70;
  fb.c = 30;
  EXPECT_EQ(classify_grashof(fb), GrashofType::change_point);
  EXPECT_STREQ(to_string(GrashofType::triple_rocker), "non-Grashof triple-rocker");
}

TEST(FourBar, L7_CrankRangeOfTheTripleRockerFile) {
  // mechanisms/double-rocker.yaml: the input oscillates within ±77.608916 deg.
  FourBar fb;
  fb.B0 = {100, 0};
  fb.a = 60;
  fb.b = 40;
  fb.c = 65;
  const CrankRange r = calc_crank_range(fb);
  EXPECT_FALSE(r.full_turn);
  ASSERT_EQ(r.count, 1);
  EXPECT_NEAR(r.intervals[0][1] / kDeg, 77.608916, kFileRounding);
  EXPECT_NEAR(r.intervals[0][0] / kDeg, -77.608916, kFileRounding);
  // Just inside assembles with zero gap, just outside does not.
  EXPECT_TRUE(calc_position(fb, r.intervals[0][1] - 1e-9).assembles);
  const FourBarPosition out = calc_position(fb, r.intervals[0][1] + 1e-3);
  EXPECT_FALSE(out.assembles);
  EXPECT_GT(out.closure_gap, 0.0);
  EXPECT_TRUE(calc_crank_range(crank_rocker()).full_turn);
}

TEST(FourBar, L7_RockerCrankHasTwoSymmetricIntervals) {
  FourBar fb;  // rocker-crank of L6: both limits active
  fb.B0 = {70, 0};
  fb.a = 60;
  fb.b = 80;
  fb.c = 20;
  const CrankRange r = calc_crank_range(fb);
  ASSERT_EQ(r.count, 2);
  // At each end the diagonal |AB0| is b − c or b + c: the gap vanishes there.
  for (const auto& iv : r.intervals)
    for (const double theta : iv) {
      const double e = (fb.B0 - fb.a * Vec2(std::cos(theta), std::sin(theta))).norm();
      EXPECT_TRUE(std::abs(e - (fb.b + fb.c)) < 1e-9 || std::abs(e - (fb.b - fb.c)) < 1e-9);
    }
  EXPECT_TRUE(calc_position(fb, 0.5 * (r.intervals[0][0] + r.intervals[0][1])).assembles);
  EXPECT_FALSE(calc_position(fb, 0.0).assembles);  // between the intervals
}

TEST(SliderCrank, L8_PistonPositionsOfTheSliderCrankFile) {
  SliderCrank sc;  // mechanisms/slider-crank.yaml: r = 50, l = 200, in line
  sc.r = 50;
  sc.l = 200;
  EXPECT_NEAR(calc_position(sc, 45 * kDeg).s, 232.20553590962265, kRoundoff);
  EXPECT_NEAR(calc_position(sc, 0.0).s, 250.0, kRoundoff);
  EXPECT_NEAR(calc_position(sc, kPi).s, 150.0, kRoundoff);
  // An offset line at 30°: the coupler keeps its length and B stays on the line.
  sc.offset = 20;
  sc.line_angle = 30 * kDeg;
  const SliderCrankPosition p = calc_position(sc, 1.0);
  ASSERT_TRUE(p.assembles);
  EXPECT_NEAR((p.B - p.A).norm(), sc.l, kRoundoff);
  const Vec2 n(-std::sin(sc.line_angle), std::cos(sc.line_angle));
  EXPECT_NEAR((p.B - sc.O).dot(n), sc.offset, kRoundoff);
}

}  // namespace
}  // namespace orthomech::synthesis
