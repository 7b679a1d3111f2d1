// Burmester motion generation (src/synthesis/motion_generation.cpp, (L14)–(L20)).
// Oracles: poses sampled from the known crank-rocker of mechanisms/crank-rocker.yaml (its pivots
// are the answer); the closed-form positions of four_bar.cpp (calc_position, circle
// intersection), which check that every candidate carries its coupler frame through every pose;
// the constant-radius condition of each dyad.
#include "orthomech/synthesis/motion_generation.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>

namespace orthomech::synthesis {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
// Pivots and lengths of ~100 mm found by direct solves and Newton polishing.
constexpr double kLength = 1e-10;
// Pose residuals (mm, rad) of synthesised candidates through calc_position.
constexpr double kPose = 1e-10;

FourBar crank_rocker() {  // mechanisms/crank-rocker.yaml
  FourBar fb;
  fb.B0 = {70, 0};
  fb.a = 30;
  fb.b = 80;
  fb.c = 60;
  fb.coupler_point = {40, 20};
  return fb;
}

std::vector<Pose> sample_poses(const FourBar& fb, const std::vector<double>& crank_deg) {
  std::vector<Pose> poses;
  for (const double t : crank_deg) {
    const FourBarPosition p = calc_position(fb, t * kDeg);
    poses.push_back({p.P, p.frame_angle});
  }
  return poses;
}

// The crank-rocker's moving pivots in the pose frame (at P, x along A→B): A and B.
const Vec2 kZA(-40, -20), kZB(40, -20);

void expect_is_crank_rocker(const FourBar& fb) {
  const FourBar want = crank_rocker();
  EXPECT_NEAR((fb.A0 - want.A0).norm(), 0.0, kLength);
  EXPECT_NEAR((fb.B0 - want.B0).norm(), 0.0, kLength);
  EXPECT_NEAR(fb.a, want.a, kLength);
  EXPECT_NEAR(fb.b, want.b, kLength);
  EXPECT_NEAR(fb.c, want.c, kLength);
  EXPECT_NEAR((fb.coupler_point - want.coupler_point).norm(), 0.0, kLength);
  EXPECT_NEAR(std::remainder(fb.coupler_frame_angle, 2 * std::numbers::pi), 0.0, kLength);
  EXPECT_EQ(fb.branch, want.branch);
}

bool is_crank_rocker(const FourBar& fb) {
  const FourBar want = crank_rocker();
  return (fb.A0 - want.A0).norm() < kLength && (fb.B0 - want.B0).norm() < kLength &&
         std::abs(fb.b - want.b) < kLength;
}

TEST(MotionGeneration, L15_ThreePosesCentreAndCirclePoints) {
  const std::vector<Pose> poses = sample_poses(crank_rocker(), {10, 120, 250});
  const ConjugatePivot m = calc_centre_point(poses, kZA);
  ASSERT_EQ(m.status, SynthesisStatus::ok) << m.message;
  EXPECT_NEAR((m.point - Vec2(0, 0)).norm(), 0.0, kLength);
  EXPECT_TRUE(m.direction.isZero());
  const ConjugatePivot z = calc_circle_point(poses, Vec2(70, 0));
  ASSERT_EQ(z.status, SynthesisStatus::ok) << z.message;
  EXPECT_NEAR((z.point - kZB).norm(), 0.0, kLength);
}

TEST(MotionGeneration, L15_TwoPosesGiveTheBisector) {
  const std::vector<Pose> poses = sample_poses(crank_rocker(), {30, 200});
  const ConjugatePivot m = calc_centre_point(poses, kZB);
  ASSERT_EQ(m.status, SynthesisStatus::ok) << m.message;
  // B0 lies on the line of solutions.
  const Vec2 w = Vec2(70, 0) - m.point;
  EXPECT_NEAR(w.x() * m.direction.y() - w.y() * m.direction.x(), 0.0, kLength);
  EXPECT_NEAR(m.direction.norm(), 1.0, 1e-15);
}

TEST(MotionGeneration, L15_DegenerateThreePoses) {
  // Pure translations along x: a moving pivot's positions are collinear.
  const std::vector<Pose> poses{{{0, 0}, 0.0}, {{1, 0}, 0.0}, {{2, 0}, 0.0}};
  const ConjugatePivot m = calc_centre_point(poses, Vec2(0.3, 0.4));
  EXPECT_EQ(m.status, SynthesisStatus::no_linkage);
  EXPECT_NE(m.message.find("collinear"), std::string::npos) << m.message;
  EXPECT_THROW((void)calc_centre_point({poses[0]}, Vec2::Zero()), std::invalid_argument);
}

TEST(MotionGeneration, L16_CentrePointCurvePointsSatisfyTheFourPoses) {
  const std::vector<Pose> poses = sample_poses(crank_rocker(), {0, 70, 160, 280});
  const CentrePointCurve curve = sample_centre_point_curve(poses, 180);
  ASSERT_EQ(curve.status, SynthesisStatus::ok) << curve.message;
  ASSERT_GT(curve.points.size(), 100U);
  for (const Dyad& d : curve.points) {
    // Independent check: the moving pivot's four positions are equidistant from the centre.
    double lo = HUGE_VAL, hi = 0.0;
    for (const Pose& p : poses) {
      const Eigen::Matrix2d R = Eigen::Rotation2Dd(p.angle).toRotationMatrix();
      const double r = (p.position + R * d.moving_pivot - d.fixed_pivot).norm();
      lo = std::min(lo, r);
      hi = std::max(hi, r);
    }
    EXPECT_LT(hi - lo, 1e-8 * std::max(1.0, hi)) << d.fixed_pivot.transpose();
  }
  // The crank-rocker's own pivots are on the curve: their circle points from 3 poses satisfy
  // the fourth, and the curve passes close to them.
  for (const Vec2& m0 : {Vec2(0, 0), Vec2(70, 0)}) {
    double nearest = HUGE_VAL;
    for (const Dyad& d : curve.points) nearest = std::min(nearest, (d.fixed_pivot - m0).norm());
    EXPECT_LT(nearest, 5.0);
  }
}

TEST(MotionGeneration, L16_TranslationsOnlyAndMisuse) {
  const std::vector<Pose> shifted{{{0, 0}, 0.3}, {{1, 0}, 0.3}, {{2, 1}, 0.3}, {{0, 3}, 0.3}};
  const CentrePointCurve curve = sample_centre_point_curve(shifted);
  EXPECT_EQ(curve.status, SynthesisStatus::no_linkage);
  EXPECT_NE(curve.message.find("translations"), std::string::npos) << curve.message;
  EXPECT_THROW((void)sample_centre_point_curve({shifted[0], shifted[1], shifted[2]}),
               std::invalid_argument);
  EXPECT_THROW((void)sample_centre_point_curve(shifted, 0), std::invalid_argument);
}

TEST(MotionGeneration, L17_FivePosesFindTheCrankRocker) {
  const std::vector<Pose> poses = sample_poses(crank_rocker(), {0, 60, 130, 210, 300});
  const MotionSynthesisResult r = synthesize_motion_generator(poses);
  ASSERT_EQ(r.status, SynthesisStatus::ok) << r.message;
  EXPECT_GE(r.dyads.size(), 2U);
  EXPECT_LE(r.dyads.size(), 4U);
  int found = 0;
  for (const MotionCandidate& c : r.candidates) {
    // Every candidate passes through every pose (calc_position's circle intersection).
    EXPECT_LT(c.max_position_error, kPose);
    EXPECT_LT(c.max_angle_error, kPose);
    ASSERT_EQ(c.crank_angles.size(), poses.size());
    if (is_crank_rocker(c.linkage)) {
      ++found;
      expect_is_crank_rocker(c.linkage);
      EXPECT_FALSE(c.branch_defect);
      for (std::size_t j = 0; j < poses.size(); ++j)
        EXPECT_NEAR(
            std::remainder(c.crank_angles[j] - std::vector<double>{0, 60, 130, 210, 300}[j] * kDeg,
                           2 * std::numbers::pi),
            0.0, kLength);
    }
  }
  EXPECT_EQ(found, 1);
  for (const Dyad& d : r.dyads) EXPECT_LT(d.residual, kLength);
}

// 100 random sets of 5 crank angles (fixed seed): the crank-rocker is always among the
// candidates and every candidate passes through every pose. Nearly coincident poses (two crank
// angles a degree apart) cost digits, hence the looser bound than kPose.
TEST(MotionGeneration, L17_RandomFivePoseSetsAlwaysContainTheCrankRocker) {
  constexpr double kIllConditioned = 1e-7;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> angle(0.0, 360.0);
  for (int trial = 0; trial < 100; ++trial) {
    std::vector<double> crank;
    for (int k = 0; k < 5; ++k) crank.push_back(angle(rng));
    const MotionSynthesisResult r =
        synthesize_motion_generator(sample_poses(crank_rocker(), crank));
    ASSERT_EQ(r.status, SynthesisStatus::ok) << r.message;
    EXPECT_LE(r.dyads.size(), 4U) << "trial " << trial;
    bool found = false;
    for (const MotionCandidate& c : r.candidates) {
      EXPECT_LT(c.max_position_error, kIllConditioned) << "trial " << trial;
      found = found || ((c.linkage.A0 - Vec2(0, 0)).norm() < kIllConditioned &&
                        (c.linkage.B0 - Vec2(70, 0)).norm() < kIllConditioned &&
                        std::abs(c.linkage.b - 80.0) < kIllConditioned);
    }
    EXPECT_TRUE(found) << "trial " << trial;
  }
}

TEST(MotionGeneration, L18_LeastSquaresOnSixExactPosesFindsTheCrankRocker) {
  const std::vector<Pose> poses = sample_poses(crank_rocker(), {0, 50, 110, 170, 240, 310});
  MotionSynthesisOptions opt;
  opt.seed = 3;
  const MotionSynthesisResult r = synthesize_motion_generator(poses, opt);
  ASSERT_EQ(r.status, SynthesisStatus::ok) << r.message;
  int found = 0;
  for (const MotionCandidate& c : r.candidates)
    if (is_crank_rocker(c.linkage)) {
      ++found;
      expect_is_crank_rocker(c.linkage);
      EXPECT_LT(c.max_position_error, kPose);
    }
  EXPECT_EQ(found, 1);
}

TEST(MotionGeneration, L19_FindPoseOnTheKnownLinkage) {
  const FourBar fb = crank_rocker();
  for (const double t : {15.0, 100.0, 275.0}) {
    const Pose pose = sample_poses(fb, {t})[0];
    const PoseMatch m = find_pose(fb, pose);
    EXPECT_TRUE(m.assembles);
    EXPECT_EQ(m.branch, 1);
    EXPECT_NEAR(std::remainder(m.crank_angle - t * kDeg, 2 * std::numbers::pi), 0.0, 1e-12);
    EXPECT_LT(m.position_error, 1e-12);
    // The other branch's pose is found on branch −1.
    const FourBarPosition q = calc_position(fb, t * kDeg, -1);
    EXPECT_EQ(find_pose(fb, Pose{q.P, q.frame_angle}).branch, -1);
  }
  EXPECT_THROW((void)synthesize_motion_generator(sample_poses(fb, {0, 1, 2, 3})),
               std::invalid_argument);
}

}  // namespace
}  // namespace orthomech::synthesis
