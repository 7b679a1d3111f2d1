// Motion generation for 2, 3 and 4 poses with given pivots (src/synthesis/motion_few_poses.cpp,
// docs/synthesis.md (L26)–(L32)) and its task keys and pipeline (task.cpp, synthesize.cpp).
// Oracles: poses sampled from the crank-rocker of mechanisms/crank-rocker.yaml (ground A0 = (0, 0),
// B0 = (70, 0) mm, crank 30, coupler 80, rocker 60, P = (40, 20)) by calc_position (its pivots
// and lengths are the answer); the perpendicular-bisector projection written out here; every
// candidate's poses re-evaluated by calc_position at its crank angles (the circle intersection of
// four_bar.cpp, never the synthesis' own residual).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <stdexcept>
#include <string>

#include "orthomech/error.hpp"
#include "orthomech/synthesis/motion_generation.hpp"
#include "orthomech/synthesis/synthesize.hpp"
#include "orthomech/synthesis/task.hpp"

namespace orthomech::synthesis {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;
// Pivots and lengths (mm) recovered from exact poses by closed forms and Newton.
constexpr double kLength = 1e-10;
// Pose residuals (mm, rad) of a candidate through calc_position.
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

std::vector<Pose> sample_poses(const std::vector<double>& crank_deg) {
  std::vector<Pose> poses;
  for (const double t : crank_deg) {
    const FourBarPosition p = calc_position(crank_rocker(), t * kDeg);
    poses.push_back({p.P, p.frame_angle});
  }
  return poses;
}

// The crank-rocker's moving pivots A and B in the world at crank angle θ (the first pose).
Vec2 world_A(double deg) { return calc_position(crank_rocker(), deg * kDeg).A; }
Vec2 world_B(double deg) { return calc_position(crank_rocker(), deg * kDeg).B; }

void expect_is_crank_rocker(const FourBar& fb) {
  const FourBar want = crank_rocker();
  EXPECT_NEAR((fb.A0 - want.A0).norm(), 0.0, kLength);
  EXPECT_NEAR((fb.B0 - want.B0).norm(), 0.0, kLength);
  EXPECT_NEAR(fb.a, want.a, kLength);
  EXPECT_NEAR(fb.b, want.b, kLength);
  EXPECT_NEAR(fb.c, want.c, kLength);
  EXPECT_NEAR((fb.coupler_point - want.coupler_point).norm(), 0.0, kLength);
  EXPECT_NEAR(std::remainder(fb.coupler_frame_angle, 2 * kPi), 0.0, kLength);
  EXPECT_EQ(fb.branch, want.branch);
}

// Independent check of a candidate: calc_position at its crank angles carries the coupler frame
// into every pose.
void expect_meets_poses(const MotionCandidate& c, const std::vector<Pose>& poses) {
  ASSERT_EQ(c.crank_angles.size(), poses.size());
  for (std::size_t j = 0; j < poses.size(); ++j) {
    const FourBarPosition p = calc_position(c.linkage, c.crank_angles[j]);
    EXPECT_TRUE(p.assembles) << "pose " << j + 1;
    EXPECT_LT((p.P - poses[j].position).norm(), kPose) << "pose " << j + 1;
    EXPECT_LT(std::abs(std::remainder(p.frame_angle - poses[j].angle, 2 * kPi)), kPose)
        << "pose " << j + 1;
  }
}

const std::vector<double> kThree{60, 150, 270};

TEST(MotionFewPoses, L28_ThreePosesFixedPivotsGiveBackTheCrankRocker) {
  const MotionSynthesisResult r =
      synthesize_motion_few_poses(sample_poses(kThree), {Vec2(0, 0), {}}, {Vec2(70, 0), {}});
  ASSERT_EQ(r.status, SynthesisStatus::ok) << r.message;
  ASSERT_EQ(r.candidates.size(), 1u);
  expect_is_crank_rocker(r.candidates[0].linkage);
  expect_meets_poses(r.candidates[0], sample_poses(kThree));
}

TEST(MotionFewPoses, L26_L28_ThreePosesMovingPivotsGiveBackTheCrankRocker) {
  const MotionSynthesisResult r =
      synthesize_motion_few_poses(sample_poses(kThree), {{}, world_A(60)}, {{}, world_B(60)});
  ASSERT_EQ(r.status, SynthesisStatus::ok) << r.message;
  ASSERT_EQ(r.candidates.size(), 1u);
  expect_is_crank_rocker(r.candidates[0].linkage);
}

TEST(MotionFewPoses, L28_ThreePosesMixedGiveBackTheCrankRocker) {
  const MotionSynthesisResult r =
      synthesize_motion_few_poses(sample_poses(kThree), {Vec2(0, 0), {}}, {{}, world_B(60)});
  ASSERT_EQ(r.status, SynthesisStatus::ok) << r.message;
  ASSERT_EQ(r.candidates.size(), 1u);
  expect_is_crank_rocker(r.candidates[0].linkage);
  EXPECT_FALSE(r.candidates[0].branch_defect);
}

TEST(MotionFewPoses, L27_TwoPosesTrueGuessesGiveBackTheCrankRocker) {
  const MotionSynthesisResult r = synthesize_motion_few_poses(
      sample_poses({60, 200}), {Vec2(0, 0), world_A(60)}, {Vec2(70, 0), world_B(60)});
  ASSERT_EQ(r.status, SynthesisStatus::ok) << r.message;
  ASSERT_EQ(r.candidates.size(), 1u);
  expect_is_crank_rocker(r.candidates[0].linkage);
}

// A guess off the bisector moves to its foot on the bisector of B's two positions (written out
// here from calc_position's B, not from the body frame).
TEST(MotionFewPoses, L27_TwoPosesGuessIsProjectedOntoTheBisector) {
  const Vec2 guess(80, 15);
  const MotionSynthesisResult r = synthesize_motion_few_poses(
      sample_poses({60, 200}), {Vec2(0, 0), world_A(60)}, {guess, world_B(60)});
  ASSERT_EQ(r.status, SynthesisStatus::ok) << r.message;
  ASSERT_EQ(r.candidates.size(), 1u);
  const Vec2 Z1 = world_B(60), Z2 = world_B(200);
  const Vec2 M = 0.5 * (Z1 + Z2);
  const Vec2 d = Z2 - Z1;
  const Vec2 u = Vec2(-d.y(), d.x()).normalized();
  const Vec2 want = M + (guess - M).dot(u) * u;
  EXPECT_NEAR((r.candidates[0].linkage.B0 - want).norm(), 0.0, kLength);
  EXPECT_GT((want - guess).norm(), 1.0);  // the guess really was off the bisector
  EXPECT_NEAR((r.candidates[0].linkage.A0 - Vec2(0, 0)).norm(), 0.0, kLength);
  EXPECT_NEAR(r.candidates[0].linkage.a, 30.0, kLength);
  expect_meets_poses(r.candidates[0], sample_poses({60, 200}));
}

const std::vector<double> kFour{60, 100, 150, 270};

// The crank-rocker's pivots lie on the sampled centre-point curve (the nearest of 180 rays'
// points: below 0.5 mm, measured 3e-14 and 0.22 mm), and every candidate of the free search meets
// its 4 poses.
TEST(MotionFewPoses, L31_FourPosesCandidatesMeetThePoses) {
  const std::vector<Pose> poses = sample_poses(kFour);
  const CentrePointCurve curve = sample_centre_point_curve(poses, 180);
  ASSERT_EQ(curve.status, SynthesisStatus::ok) << curve.message;
  for (const Vec2& m0 : {Vec2(0, 0), Vec2(70, 0)}) {
    double nearest = HUGE_VAL;
    for (const Dyad& d : curve.points) nearest = std::min(nearest, (d.fixed_pivot - m0).norm());
    EXPECT_LT(nearest, 0.5) << m0.transpose();  // measured: A0 3e-14 mm, B0 0.22 mm
  }
  const MotionSynthesisResult r = synthesize_motion_few_poses(poses, {}, {});
  ASSERT_EQ(r.status, SynthesisStatus::ok) << r.message;
  ASSERT_GE(r.candidates.size(), 1u);
  EXPECT_LE(r.candidates.size(), 6u);
  // (L31) ranks them by the worst transmission angle over the motion through the poses: the
  // oracle samples calc_position every 0.05° over that motion (the shorter turning sense) here.
  double previous = HUGE_VAL;
  for (const MotionCandidate& c : r.candidates) {
    EXPECT_FALSE(c.branch_defect);
    expect_meets_poses(c, poses);
    double ccw = 0.0;
    for (std::size_t j = 1; j < c.crank_angles.size(); ++j)
      ccw += std::fmod(std::fmod(c.crank_angles[j] - c.crank_angles[j - 1], 2 * kPi) + 2 * kPi,
                       2 * kPi);
    const double turn = ccw <= 3 * 2 * kPi - ccw ? ccw : ccw - 3 * 2 * kPi;  // 3 steps
    double worst = kPi / 2;
    for (double t = 0; t <= 1.0; t += 0.05 * kDeg / std::abs(turn)) {
      const FourBarPosition p = calc_position(c.linkage, c.crank_angles[0] + t * turn);
      ASSERT_TRUE(p.assembles);
      worst = std::min({worst, p.transmission_angle, kPi - p.transmission_angle});
    }
    EXPECT_LE(worst, previous + 1e-3);  // sampled 0.05° apart: within 1e-3 rad of the closed form
    previous = worst;
  }
}

// (L29), (L30): the true fixed pivot of the crank and the true moving pivot of the follower lie
// on their curves; given, they give back the crank-rocker.
TEST(MotionFewPoses, L29_L30_FourPosesGivenPivotsOnTheirCurves) {
  const std::vector<Pose> poses = sample_poses(kFour);
  const MotionSynthesisResult r =
      synthesize_motion_few_poses(poses, {Vec2(0, 0), {}}, {{}, world_B(60)});
  ASSERT_EQ(r.status, SynthesisStatus::ok) << r.message;
  ASSERT_EQ(r.candidates.size(), 1u);
  expect_is_crank_rocker(r.candidates[0].linkage);
  expect_meets_poses(r.candidates[0], poses);
  // One given, the other from the curve: every candidate meets the poses.
  const MotionSynthesisResult half = synthesize_motion_few_poses(poses, {Vec2(0, 0), {}}, {});
  ASSERT_EQ(half.status, SynthesisStatus::ok) << half.message;
  for (const MotionCandidate& c : half.candidates) {
    EXPECT_NEAR((c.linkage.A0 - Vec2(0, 0)).norm(), 0.0, kLength);
    expect_meets_poses(c, poses);
  }
}

// A fixed pivot off the curve is refused with its distance; the oracle: the distance to the
// nearest point of a dense sample of the curve (3600 rays).
TEST(MotionFewPoses, L29_FourPosesPivotOffTheCurveIsRefused) {
  const std::vector<Pose> poses = sample_poses(kFour);
  const Vec2 off(3, 4);
  const MotionSynthesisResult r = synthesize_motion_few_poses(poses, {off, {}}, {});
  EXPECT_EQ(r.status, SynthesisStatus::no_linkage);
  EXPECT_TRUE(r.candidates.empty());
  const auto at = r.message.find(" is ");
  ASSERT_NE(at, std::string::npos) << r.message;
  EXPECT_NE(r.message.find("the crank's fixed pivot"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("from the centre-point curve"), std::string::npos) << r.message;
  const double reported = std::stod(r.message.substr(at + 4));
  double nearest = HUGE_VAL;
  for (const Dyad& d : sample_centre_point_curve(poses, 3600).points)
    nearest = std::min(nearest, (d.fixed_pivot - off).norm());
  EXPECT_GT(reported, 0.1);
  EXPECT_NEAR(reported, nearest, 0.05 * nearest) << r.message;
}

TEST(MotionFewPoses, MisuseNamesTheDyad) {
  try {
    (void)synthesize_motion_few_poses(sample_poses(kThree), {Vec2(0, 0), {}}, {});
    ADD_FAILURE() << "accepted a follower without pivots";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("the follower needs exactly one pivot"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW((void)synthesize_motion_few_poses(sample_poses({0, 60, 130, 210, 300}),
                                                 {Vec2(0, 0), {}}, {Vec2(70, 0), {}}),
               std::invalid_argument);
  EXPECT_THROW((void)synthesize_motion_few_poses(sample_poses({60, 200}), {{}, world_A(60)},
                                                 {Vec2(70, 0), world_B(60)}),
               std::invalid_argument);
}

// ---- The task file and the pipeline -------------------------------------------------------------

std::string poses_yaml(const std::vector<double>& crank_deg) {
  std::string s = "poses:\n";
  for (const Pose& p : sample_poses(crank_deg)) {
    char b[160];
    std::snprintf(b, sizeof b, "  - [%.17g, %.17g, %.17g]\n", p.position.x(), p.position.y(),
                  p.angle / kDeg);
    s += b;
  }
  return s;
}

// check_closed_form's max_distance and max_angle_error (calc_position at the candidate's crank
// angles against the task's poses) for every accepted candidate.
void expect_accepted_meet_poses(const SynthesisResult& r) {
  ASSERT_FALSE(r.accepted.empty()) << r.message;
  for (const SynthesisCandidate& c : r.accepted) {
    EXPECT_LE(c.max_distance, 1e-9) << c.name << " " << c.method;
    EXPECT_LE(c.max_angle_error, 1e-9) << c.name << " " << c.method;
  }
}

TEST(MotionFewPoses, PipelineThreePosesFixedPivots) {
  const SynthesisTask task =
      parse_synthesis_task("orthomech-synthesis: 1\ntask: motion\n" + poses_yaml(kThree) +
                               "crank: {fixed_pivot: [0, 0]}\nfollower: {fixed_pivot: [70, 0]}\n",
                           "m3.yaml");
  ASSERT_TRUE(task.crank.fixed_pivot.has_value());
  EXPECT_DOUBLE_EQ(task.follower.fixed_pivot->x(), 70e-3);
  const SynthesisResult r = run_synthesis(task);
  expect_accepted_meet_poses(r);
  ASSERT_EQ(r.accepted.size(), 1u);
  EXPECT_NEAR(std::get<FourBar>(r.accepted[0].linkage).b, 80e-3, 1e-12);
  EXPECT_NE(r.accepted[0].method.find("3 poses, crank's fixed pivot given"), std::string::npos)
      << r.accepted[0].method;
}

// examples/synthesis-motion-3.yaml: its poses are the crank-rocker's rounded to 1e-12 mm, so
// the one candidate is the crank-rocker to ~1e-12 of its size (1e-9 mm bound).
TEST(MotionFewPoses, ExampleThreePoseTaskGivesBackTheCrankRocker) {
  const SynthesisTask task =
      load_synthesis_task(std::string(ORTHOMECH_SOURCE_DIR) + "/examples/synthesis-motion-3.yaml");
  const SynthesisResult r = run_synthesis(task);
  ASSERT_EQ(r.accepted.size(), 1u) << r.message;
  const FourBar& fb = std::get<FourBar>(r.accepted[0].linkage);
  constexpr double kRounded = 1e-9 * 1e-3;  // m
  EXPECT_NEAR(fb.a, 30e-3, kRounded);
  EXPECT_NEAR(fb.b, 80e-3, kRounded);
  EXPECT_NEAR(fb.c, 60e-3, kRounded);
  EXPECT_NEAR((fb.B0 - Vec2(70e-3, 0)).norm(), 0.0, kRounded);
  EXPECT_NEAR((fb.coupler_point - Vec2(40e-3, 20e-3)).norm(), 0.0, kRounded);
  EXPECT_LE(r.accepted[0].max_distance, kRounded);
}

TEST(MotionFewPoses, PipelineFourPosesFree) {
  const SynthesisTask task =
      parse_synthesis_task("orthomech-synthesis: 1\ntask: motion\n" + poses_yaml(kFour), "m4.yaml");
  const SynthesisResult r = run_synthesis(task);
  expect_accepted_meet_poses(r);
  EXPECT_LE(r.accepted.size() + r.rejected.size(), 6u);
}

TEST(MotionFewPoses, TaskErrorsNameTheirLine) {
  struct Case {
    std::string text;
    int line;
    const char* words;
  };
  const std::string head = "orthomech-synthesis: 1\ntask: motion\n";
  const Case cases[] = {
      // 3 poses, no pivots: at the poses' value (its first row, line 4), naming the key to add.
      {head + poses_yaml(kThree), 4, "3 poses need exactly one of the crank's pivots"},
      {head + poses_yaml(kThree) + "crank: {fixed_pivot: [0, 0]}\n", 4, "the follower's pivots"},
      // 5 poses with a pivot: at the key.
      {head + poses_yaml({60, 100, 150, 200, 270}) + "crank: {fixed_pivot: [0, 0]}\n", 9,
       "no pivot can be given"},
      {head + poses_yaml({60, 200}) + "crank: {fixed_pivot: [0, 0]}\nfollower: {}\n", 6,
       "2 poses need the crank's moving pivot"},
      {head + poses_yaml(kThree) + "crank: {fixed_pivot: [0, 0], hinge: 1}\n", 7,
       "unknown key 'hinge'"},
      {head + poses_yaml(kFour) + "crank: {fixed_pivot: [0, 0], moving_pivot: [1, 2]}\n", 8,
       "4 poses take at most one"},
      {head + "poses: [[0, 0, 0]]\n", 3, "2 to 1000"},
      {"orthomech-synthesis: 1\ntask: path\npoints: [[0, 0], [1, 0], [2, 1]]\n"
       "crank: {fixed_pivot: [0, 0]}\n",
       4, "does not belong to a path task"},
  };
  for (const Case& c : cases) {
    try {
      (void)parse_synthesis_task(c.text, "t.yaml");
      ADD_FAILURE() << "accepted: " << c.text;
    } catch (const InputError& e) {
      EXPECT_EQ(e.where().line, c.line) << e.what();
      EXPECT_NE(std::string(e.what()).find(c.words), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace orthomech::synthesis
