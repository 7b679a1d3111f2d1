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
