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

}  // namespace
}  // namespace orthomech::synthesis
