// `orthomech assemble` (cli/assemble.cpp; docs/cli.md): exit codes, JSON keys, --write.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>

#include "support/cli_runner.hpp"
#include "support/fixtures.hpp"
#include "support/short_four_bar.hpp"

namespace orthomech {
namespace {

namespace fs = std::filesystem;
using test::run_cli;

fs::path temp_path(const std::string& leaf) {
  static int counter = 0;
  return fs::temp_directory_path() / ("orthomech_asm_" + std::to_string(::getpid()) + "_" +
                                      std::to_string(counter++) + "_" + leaf);
}

// Crank-rocker of the CLI tests drawn slightly off (coupler 3° and rocker 2° off).
const char* const kRoughFourBar = R"(orthomech: 1
name: rough
units: {length: m, angle: deg}
ground:
  points: {A0: [0, 0], B0: [10, 0]}
bodies:
  - {name: crank, mass: 1, inertia: 0.1, pose: [0, 0, 53.13010235415598], points: {A0: [0, 0], A: [5, 0]}}
  - {name: coupler, mass: 2, inertia: 0.2, pose: [3, 4, -5], points: {A: [0, 0], B: [7.0710678118654755, 0]}}
  - {name: rocker, mass: 1, inertia: 0.1, pose: [10, 0, 92], points: {B0: [0, 0], B: [3, 0]}}
joints:
  - {name: A0, type: revolute, connects: [ground.A0, crank.A0]}
  - {name: A, type: revolute, connects: [crank.A, coupler.A]}
  - {name: B, type: revolute, connects: [coupler.B, rocker.B]}
  - {name: B0, type: revolute, connects: [rocker.B0, ground.B0]}
measures:
  - {name: crank_angle, type: joint, joint: A0}
)";

std::string write_temp(const std::string& text, const std::string& leaf) {
  const fs::path p = temp_path(leaf);
  std::ofstream(p) << text;
  return p.string();
}

TEST(AssembleCli, Json_StatusAndMeasures_LockedCrank) {
  const std::string file = write_temp(kRoughFourBar, "rough.yaml");
  const auto r = run_cli({"assemble", file, "--json", "--lock", "A0=53.13010235415598deg"});
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["status"], "assembled");
  // In the file's angle unit (deg): the locked value itself.
  EXPECT_EQ(j["units"]["angle"], "deg");
  EXPECT_NEAR(j["measures"]["crank_angle"].get<double>(), 53.13010235415598, 1e-10);
  EXPECT_LE(j["residual_length"].get<double>(), 1e-12);  // m
  EXPECT_LE(j["residual_angle"].get<double>(), 1e-10);   // deg
  EXPECT_EQ(j["bodies"].size(), 3u);
  EXPECT_EQ(j["joints"].size(), 4u);
  EXPECT_TRUE(j["velocities"].contains("kinetic_removed"));
  fs::remove(file);
}

TEST(AssembleCli, CannotClose_Exit3_NamesJointsAndGap) {
  const std::string file = write_temp(test::kShortFourBar, "short.yaml");
  const auto r = run_cli({"assemble", file});
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(r.err.find("cannot close"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("joint 'B0'"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("total gap 4 m"), std::string::npos) << r.err;  // the file's unit (m)
  const auto rj = run_cli({"assemble", file, "--json"});
  EXPECT_EQ(rj.status, 3);
  const auto j = nlohmann::json::parse(rj.out);
  EXPECT_EQ(j["status"], "cannot close");
  EXPECT_NEAR(j["total_gap"].get<double>(), 4.0, 1e-6);
  fs::remove(file);
}

TEST(AssembleCli, Write_SavesAssembledFile_InputUntouched_InPlace) {
  const std::string file = write_temp(kRoughFourBar, "rough.yaml");
  const std::string out = temp_path("out.yaml").string();
  const auto r = run_cli({"assemble", file, "--write", out});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(test::read_text(file), kRoughFourBar);  // never overwritten without --in-place
  // The written file is assembled: assembling it again changes nothing.
  const auto again = run_cli({"assemble", out, "--json"});
  ASSERT_EQ(again.status, 0) << again.err;
  EXPECT_EQ(nlohmann::json::parse(again.out)["status"], "unchanged");
  EXPECT_NE(test::read_text(out).find("units: {length: m, angle: deg}"), std::string::npos);
  // --write onto the input is refused; --in-place does it.
  EXPECT_EQ(run_cli({"assemble", file, "--write", file}).status, 2);
  EXPECT_EQ(test::read_text(file), kRoughFourBar);
  ASSERT_EQ(run_cli({"assemble", file, "--in-place"}).status, 0);
  EXPECT_NE(test::read_text(file), kRoughFourBar);
  EXPECT_EQ(nlohmann::json::parse(run_cli({"assemble", file, "--json"}).out)["status"],
            "unchanged");
  fs::remove(file);
  fs::remove(out);
}

// --in-place through a symbolic link writes the file it names; the link stays a link
// (io/file_writer.hpp).
TEST(AssembleCli, InPlace_ThroughSymlink_LinkStaysALink) {
  const std::string file = write_temp(kRoughFourBar, "real.yaml");
  const std::string link = temp_path("link.yaml").string();
  fs::create_symlink(file, link);
  const auto r = run_cli({"assemble", link, "--in-place"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(fs::is_symlink(fs::symlink_status(link)));
  EXPECT_EQ(fs::read_symlink(link), file);
  EXPECT_NE(test::read_text(file), kRoughFourBar);
  EXPECT_EQ(nlohmann::json::parse(run_cli({"assemble", file, "--json"}).out)["status"],
            "unchanged");
  fs::remove(link);
  fs::remove(file);
}

// kRoughFourBar with parameters: the crank's angle, the coupler's frame origin (at the crank's
// A = (5 cos 53.13°, 5 sin 53.13°) = (3, 4), which the locked crank keeps) and the rocker's (at
// B0) are expressions the assembly does not move; the coupler's angle -L/2 = -5° it moves.
const char* const kParametricFourBar = R"(orthomech: 1
name: rough-parametric
units: {length: m, angle: deg}
parameters: {L: 10, crank_angle: 53.13010235415598}
ground:
  points: {A0: [0, 0], B0: [L, 0]}
bodies:
  - {name: crank, mass: 1, inertia: 0.1, pose: [0, 0, crank_angle], points: {A0: [0, 0], A: [5, 0]}}
  - {name: coupler, mass: 2, inertia: 0.2, pose: [L - 7, 4, -L/2], points: {A: [0, 0], B: [7.0710678118654755, 0]}}
  - {name: rocker, mass: 1, inertia: 0.1, pose: [L, 0, 92], points: {B0: [0, 0], B: [3, 0]}}
joints:
  - {name: A0, type: revolute, connects: [ground.A0, crank.A0]}
  - {name: A, type: revolute, connects: [crank.A, coupler.A]}
  - {name: B, type: revolute, connects: [coupler.B, rocker.B]}
  - {name: B0, type: revolute, connects: [rocker.B0, ground.B0]}
)";

// --write keeps the text of an expression whose value the assembly did not change, writes a
// number for one it changed and says so on stderr; the written file is assembled.
TEST(AssembleCli, Write_KeepsUnmovedExpressions_ReplacesMovedOnes) {
  const std::string file = write_temp(kParametricFourBar, "parametric.yaml");
  const std::string out = temp_path("parametric-out.yaml").string();
  const auto r = run_cli({"assemble", file, "--write", out, "--lock", "A0=53.13010235415598deg"});
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string text = test::read_text(out);
  EXPECT_NE(text.find("pose: [0, 0, crank_angle]"), std::string::npos) << text;
  EXPECT_NE(text.find("pose: [L - 7, 4, "), std::string::npos) << text;
  EXPECT_EQ(text.find("-L/2"), std::string::npos) << text;
  EXPECT_NE(text.find("pose: [L, 0, "), std::string::npos) << text;
  EXPECT_EQ(text.find("pose: [L, 0, 92]"), std::string::npos) << text;  // the rocker turned
  EXPECT_NE(r.err.find("body 'coupler': pose angle: the expression '-L/2' is now -"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find("'L - 7'"), std::string::npos) << r.err;
  const auto again = run_cli({"assemble", out, "--json"});
  ASSERT_EQ(again.status, 0) << again.err;
  EXPECT_EQ(nlohmann::json::parse(again.out)["status"], "unchanged");
  fs::remove(file);
  fs::remove(out);
}

TEST(AssembleCli, BadLock_Exit2) {
  const std::string file = test::source_path("mechanisms/crank-rocker.yaml");
  const auto r = run_cli({"assemble", file, "--lock", "nope=3"});
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("joint 'nope' is not defined"), std::string::npos) << r.err;
  EXPECT_EQ(run_cli({"assemble", file, "--lock", "A0=3furlongs"}).status, 2);
  // Unwritable output: exit 2 with the reason, nothing written.
  const auto w = run_cli({"assemble", file, "--write", "/nonexistent-dir/out.yaml"});
  EXPECT_EQ(w.status, 2);
  EXPECT_NE(w.err.find("cannot write"), std::string::npos) << w.err;
}

}  // namespace
}  // namespace orthomech
