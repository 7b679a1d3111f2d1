// A synthesis task from its targets to validated candidates (synthesis/synthesize.hpp): round
// trips that recover a known four-bar (mechanisms/crank-rocker.yaml: ground 70, crank 30,
// coupler 80, rocker 60 mm, coupler point [40, 20]), each accepted candidate's file read back and
// validated independently here, and defective candidates rejected with their reasons.
#include "orthomech/synthesis/synthesize.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "orthomech/analysis/validate.hpp"
#include "orthomech/io/mechanism_file.hpp"

namespace orthomech::synthesis {
namespace {

constexpr double kMm = 1e-3;
// The example tasks' targets are closed-form values rounded to 1e-12 mm: a recovered linkage's
// lengths agree to ~1e-12 of their size; 1e-9 mm leaves room for the Burmester polish.
constexpr double kRecovered = 1e-9 * kMm;

std::string example(const std::string& name) {
  return std::string(ORTHOMECH_SOURCE_DIR) + "/examples/" + name;
}

bool is_crank_rocker_of_the_file(const FourBar& fb) {
  return std::abs((fb.B0 - fb.A0).norm() - 70 * kMm) < kRecovered &&
         std::abs(fb.a - 30 * kMm) < kRecovered && std::abs(fb.b - 80 * kMm) < kRecovered &&
         std::abs(fb.c - 60 * kMm) < kRecovered;
}

// Every accepted candidate's file, read back, passes validate (its own assembly solve, with the
// targets as design positions, at the task's transmission bound) and meets each target.
void expect_files_validate(const SynthesisResult& r, const SynthesisTask& task) {
  ValidateOptions vo;
  vo.min_transmission = task.min_transmission;
  for (const SynthesisCandidate& c : r.accepted) {
    const Model model = parse_mechanism(c.file_text, c.name + ".yaml");
    const ValidationReport report = validate_design_positions(model, vo);
    EXPECT_TRUE(report.pass()) << c.name;
    ASSERT_EQ(report.positions.size(), c.crank_angles.size());
    for (const PositionReport& p : report.positions) {
      ASSERT_TRUE(p.target_error.has_value()) << p.name;
      EXPECT_LE(*p.target_error, r.tolerance) << p.name;
    }
  }
}

TEST(Synthesize, FivePosesGiveBackTheCrankRocker) {
  const SynthesisTask task = load_synthesis_task(example("synthesis-motion.yaml"));
  const SynthesisResult r = run_synthesis(task);
  ASSERT_FALSE(r.accepted.empty()) << r.message;
  EXPECT_TRUE(std::any_of(r.accepted.begin(), r.accepted.end(), [](const auto& c) {
    return is_crank_rocker_of_the_file(std::get<FourBar>(c.linkage));
  }));
  for (const SynthesisCandidate& c : r.accepted) {
    EXPECT_LE(c.max_distance, 1e-10 * kMm) << c.name;
    EXPECT_LE(c.max_angle_error, 1e-10) << c.name;
  }
  expect_files_validate(r, task);
}

TEST(Synthesize, TimedPathGivesBackAFourBarThroughThePoints) {
  SynthesisTask task = load_synthesis_task(example("synthesis-path.yaml"));
  task.starts = 60;
  const SynthesisResult r = run_synthesis(task);
  ASSERT_FALSE(r.accepted.empty()) << r.message;
  EXPECT_LE(r.accepted.front().max_distance, 1e-10 * kMm);
  for (const SynthesisCandidate& c : r.accepted) EXPECT_EQ(c.grashof, GrashofType::crank_rocker);
  expect_files_validate(r, task);
}

// Freudenstein through the rocker angles of the crank-rocker at crank 60°, 150°, 270° (closed
// form, 1e-12 deg): the linkage and its output angles to 1e-12 (through calc_position, not
// Freudenstein's equation).
TEST(Synthesize, ThreePairsGiveBackTheCrankRocker) {
  const SynthesisTask task = parse_synthesis_task(
      "orthomech-synthesis: 1\ntask: function\nground: 70\n"
      "pairs: [[60, 71.797553609615], [150, 115.823166144399], [270, 132.362157995438]]\n",
      "fn.yaml");
  const SynthesisResult r = run_synthesis(task);
  ASSERT_EQ(r.accepted.size(), 1u) << r.message;
  EXPECT_NEAR(std::get<FourBar>(r.accepted[0].linkage).a, 30 * kMm, 1e-10 * kMm);
  EXPECT_NEAR(std::get<FourBar>(r.accepted[0].linkage).c, 60 * kMm, 1e-10 * kMm);
  EXPECT_LE(r.accepted[0].max_angle_error, 1e-12);
  expect_files_validate(r, task);
}

// Never a defective candidate: the same five poses in another order (an order defect: the crank
// cannot reach them in the order given within a turn), and a transmission bound the only
// four-bar misses, leave nothing accepted and say why.
TEST(Synthesize, DefectiveCandidatesAreRejectedWithTheReason) {
  SynthesisTask task = load_synthesis_task(example("synthesis-motion.yaml"));
  std::swap(task.positions[1], task.positions[2]);
  std::swap(task.angles[1], task.angles[2]);
  const SynthesisResult scrambled = run_synthesis(task);
  EXPECT_TRUE(scrambled.accepted.empty());
  ASSERT_FALSE(scrambled.rejected.empty());
  for (const SynthesisCandidate& c : scrambled.rejected) {
    std::string all;
    for (const auto& why : c.rejections) all += why + "\n";
    EXPECT_NE(all.find("order"), std::string::npos) << all;
  }
  SynthesisTask strict = load_synthesis_task(example("synthesis-motion.yaml"));
  strict.min_transmission = 60 * std::numbers::pi / 180;
  const SynthesisResult r = run_synthesis(strict);
  EXPECT_TRUE(r.accepted.empty());
  ASSERT_FALSE(r.rejected.empty());
  EXPECT_NE(r.rejected[0].rejections.front().find("transmission"), std::string::npos)
      << r.rejected[0].rejections.front();
}

// examples/synthesis-rssr.yaml: eight pairs sampled from the skew RSSR a = (100, 0, 0),
// b = (200, 0, 0), L = 420 mm (axes: z through the origin, x through (300, 50, 200) mm) on its
// branch -1; the task's pipeline gives it back, and its spatial file validates and runs `cycle`.
TEST(Synthesize, RssrTaskGivesBackTheSkewRssr) {
  const SynthesisTask task = load_synthesis_task(example("synthesis-rssr.yaml"));
  ASSERT_EQ(task.linkage, TaskLinkage::rssr);
  const SynthesisResult r = run_synthesis(task);
  ASSERT_EQ(r.accepted.size(), 1u) << r.message;
  const auto& lk = std::get<Rssr>(r.accepted[0].linkage);
  // Targets rounded to 1e-12 deg: the least-squares design within 1e-9 m of the source.
  EXPECT_LT((lk.a - Vec3(0.1, 0.0, 0.0)).norm(), 1e-9);
  EXPECT_LT((lk.b - Vec3(0.2, 0.0, 0.0)).norm(), 1e-9);
  EXPECT_NEAR(lk.coupler, 0.42, 1e-9);
  EXPECT_EQ(lk.branch, -1);
  EXPECT_LT(r.accepted[0].max_angle_error, 1e-10);
  EXPECT_LT(r.accepted[0].max_distance, 1e-10 * kMm);
  ASSERT_TRUE(r.accepted[0].cycle.has_value());
  EXPECT_GT(r.accepted[0].cycle->peak_drive, 0.0);
  expect_files_validate(r, task);
}

// The worst transmission angle of an RSSR candidate is asin of the Sutherland–Roth index of the
// closed form (rssr.hpp); validate computes that index on the file's own assembled positions.
// At every design position the two agree, and the worst over the motion is at most the targets'.
TEST(Synthesize, RssrTransmissionIsTheIndexValidateComputes) {
  const SynthesisTask task = load_synthesis_task(example("synthesis-rssr.yaml"));
  const SynthesisResult r = run_synthesis(task);
  ASSERT_EQ(r.accepted.size(), 1u) << r.message;
  const SynthesisCandidate& c = r.accepted[0];
  const auto& lk = std::get<Rssr>(c.linkage);
  ValidateOptions vo;
  vo.min_transmission = task.min_transmission;
  const ValidationReport report =
      validate_design_positions(parse_mechanism(c.file_text, "c.yaml"), vo);
  ASSERT_EQ(report.positions.size(), task.inputs.size());
  double lowest = 1.0;
  for (size_t j = 0; j < task.inputs.size(); ++j) {
    const auto& loops = report.positions[j].spatial_loops;
    ASSERT_EQ(loops.size(), 1u) << report.positions[j].name;
    const double closed = transmission_index(lk, calc_position(lk, c.crank_angles[j]));
    EXPECT_NEAR(loops[0].index, closed, 1e-9) << report.positions[j].name;
    lowest = std::min(lowest, loops[0].index);
  }
  EXPECT_LE(c.worst_transmission, std::asin(lowest) + 1e-12);
  EXPECT_GE(c.worst_transmission, task.min_transmission);
}

// Axes that intersect (mechanisms/rssr.yaml's: z through the origin, x through (300, 0, 200) mm)
// are refused with the reason: the rocker's pin at their common point closes the loop at every
// input, an exact solution of (L54) that hides the linkage.
TEST(Synthesize, RssrWithIntersectingAxesIsRefusedWithTheReason) {
  SynthesisTask task = load_synthesis_task(example("synthesis-rssr.yaml"));
  task.output_axis.point = Vec3(0.3, 0.0, 0.2);
  const SynthesisResult r = run_synthesis(task);
  EXPECT_EQ(r.status, SynthesisStatus::no_linkage);
  EXPECT_TRUE(r.accepted.empty());
  EXPECT_NE(r.message.find("axes intersect"), std::string::npos) << r.message;
}

}  // namespace
}  // namespace orthomech::synthesis
