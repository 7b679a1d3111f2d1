// The synthesis task reader (synthesis/task.hpp): the targets in SI, the defaults, and every
// mistake refused at its file:line with the element's name (house style, "Errors").
#include "orthomech/synthesis/task.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

#include "orthomech/error.hpp"

namespace orthomech::synthesis {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

TEST(SynthesisTask, ReadsAPathTaskInItsUnits) {
  const SynthesisTask t = parse_synthesis_task(
      "orthomech-synthesis: 1\n"
      "name: p\n"
      "units: {length: mm, angle: deg}\n"
      "task: path\n"
      "points: [[1, 2], [3, 4], [5, 7]]\n"
      "crank_angles: [0, 90, 180]\n"
      "fixed_pivot: [10, 0]\n"
      "require: {crank_rocker: true, min_transmission: 40}\n"
      "mechanism: {mass_per_length: 0.002, speed: 120 rpm}\n",
      "p.yaml");
  EXPECT_EQ(t.kind, TaskKind::path);
  EXPECT_EQ(t.timing, TaskTiming::prescribed);  // crank angles given: prescribed by default
  ASSERT_EQ(t.positions.size(), 3u);
  EXPECT_DOUBLE_EQ(t.positions[2].y(), 7e-3);
  EXPECT_DOUBLE_EQ(t.inputs[1], 90 * kDeg);
  EXPECT_DOUBLE_EQ(t.fixed_pivot->x(), 10e-3);
  EXPECT_TRUE(t.crank_rocker);
  EXPECT_DOUBLE_EQ(t.min_transmission, 40 * kDeg);
  EXPECT_DOUBLE_EQ(t.mass_per_length, 2.0);  // 0.002 kg/mm
  EXPECT_NEAR(t.speed, 4 * std::numbers::pi, 1e-12);
}

// An RSSR function task: the axes' points in the task's length unit, directions and references
// as given (unit-free), the pairs in its angle unit.
TEST(SynthesisTask, ReadsAnRssrTaskInItsUnits) {
  const SynthesisTask t =
      load_synthesis_task(std::string(ORTHOMECH_SOURCE_DIR) + "/examples/synthesis-rssr.yaml");
  EXPECT_EQ(t.kind, TaskKind::function);
  EXPECT_EQ(t.linkage, TaskLinkage::rssr);
  EXPECT_LT((t.input_axis.point - Vec3::Zero()).norm(), 1e-15);
  EXPECT_LT((t.output_axis.point - Vec3(0.3, 0.05, 0.2)).norm(), 1e-15);
  EXPECT_LT((t.output_axis.direction - Vec3::UnitX()).norm(), 1e-15);
  ASSERT_TRUE(t.output_axis.reference.has_value());
  EXPECT_LT((*t.output_axis.reference - Vec3::UnitY()).norm(), 1e-15);
  ASSERT_EQ(t.inputs.size(), 8u);
  EXPECT_NEAR(t.inputs[1], 45 * kDeg, 1e-15);
  EXPECT_NEAR(t.outputs[6], -9.347043474587 * kDeg, 1e-15);
  EXPECT_DOUBLE_EQ(t.min_transmission, 20 * kDeg);
}

TEST(SynthesisTask, KinetostaticRankings) {
  for (const char* key : {"drive_torque", "pin_force"}) {
    const SynthesisTask t = parse_synthesis_task(
        std::string("orthomech-synthesis: 1\ntask: path\npoints: [[0, 0], [1, 0], [2, 1]]\n"
                    "rank_by: ") +
            key + "\n",
        "t.yaml");
    EXPECT_EQ(t.rank_by, key);
  }
}

// Each mistake: its line and the words a user needs.
TEST(SynthesisTask, MistakesNameTheirLine) {
  struct Case {
    const char* text;
    int line;
    const char* words;
  };
  const Case cases[] = {
      {"task: motion\n", 1, "orthomech-synthesis: 1"},
      {"orthomech-synthesis: 1\ntask: motion\nposes: [[0, 0, 0], [1, 0, 0]]\n", 3,
       "2 poses need the crank's moving pivot"},
      {"orthomech-synthesis: 1\ntask: path\npoints: [[0, 0], [1, 0], [2, 1]]\nposes: []\n", 4,
       "does not belong to a path task"},
      {"orthomech-synthesis: 1\ntask: dance\n", 2, "unknown task 'dance'"},
      {"orthomech-synthesis: 1\ntask: path\npoints: [[0, 0], [1, 0], [2, 1]]\n"
       "crank_angles: [0, 1]\n",
       4, "one crank angle per point (3)"},
      {"orthomech-synthesis: 1\ntask: function\npairs: [[0, 1], [1, 2], [2, 3]]\n", 1,
       "ground length"},
      {"orthomech-synthesis: 1\ntask: path\npoints: [[0, 0], [1, .nan], [2, 1]]\n", 3,
       "finite number"},
      {"orthomech-synthesis: 1\ntask: path\npoints: [[0, 0], [1, 0], [2, 1]]\nrank_by: cost\n", 4,
       "rank_by"},
      {"orthomech-synthesis: 1\ntask: path\npoints: [[0, 0], [1, 0], [2, 1]]\nspeed: 3\n", 4,
       "unknown key 'speed'"},
      {"orthomech-synthesis: 1\ntask: path\npoints: &a [*a]\n", 3, "alias"},
      // An RSSR (linkage: rssr): a function task with its two axes.
      {"orthomech-synthesis: 1\ntask: path\nlinkage: rssr\npoints: [[0, 0], [1, 0], [2, 1]]\n", 3,
       "function generator (task: function) only"},
      {"orthomech-synthesis: 1\ntask: function\nlinkage: rssr\npairs: [[0, 1], [1, 2], [2, 3]]\n",
       1, "needs `axes:"},
      {"orthomech-synthesis: 1\ntask: function\nlinkage: rssr\npairs: [[0, 1], [1, 2], [2, 3]]\n"
       "axes: {input: {point: [0, 0, 0], direction: [0, 0, 1]}}\n",
       5, "expected `output:"},
      {"orthomech-synthesis: 1\ntask: function\nlinkage: rssr\npairs: [[0, 1], [1, 2], [2, 3]]\n"
       "axes:\n  input: {point: [0, 0, 0], direction: [0, 0, 1], ref: [0, 0, 2]}\n"
       "  output: {point: [1, 0, 0], direction: [1, 0, 0]}\n",
       6, "parallel to the axis' direction"},
      {"orthomech-synthesis: 1\ntask: function\nlinkage: rssr\npairs: [[0, 1], [1, 2], [2, 3]]\n"
       "axes:\n  input: {point: [0, 0, 0], direction: [0, 0, 0]}\n"
       "  output: {point: [1, 0, 0], direction: [1, 0, 0]}\n",
       6, "zero vector"},
      {"orthomech-synthesis: 1\ntask: function\npairs: [[0, 1], [1, 2], [2, 3]]\nground: 1\n"
       "held: {a: [0, 0, 0]}\n",
       5, "belongs to an RSSR function task"},
  };
  for (const Case& c : cases) {
    try {
      (void)parse_synthesis_task(c.text, "t.yaml");
      ADD_FAILURE() << "accepted: " << c.text;
    } catch (const InputError& e) {
      EXPECT_EQ(e.where().file, "t.yaml");
      EXPECT_EQ(e.where().line, c.line) << e.what();
      EXPECT_NE(std::string(e.what()).find(c.words), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace orthomech::synthesis
