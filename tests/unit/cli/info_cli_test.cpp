// `info` (cli/info.cpp; docs/cli.md): mobility in table and JSON form on small inline
// mechanisms (a four-bar, parallel cranks with a redundant equation, a free body), and its bad
// inputs (exit 2).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "support/cli_runner.hpp"

namespace orthomech {
namespace {

namespace fs = std::filesystem;

fs::path temp_base() {
  static int counter = 0;
  return fs::temp_directory_path() /
         ("orthomech_cli_file_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
}

using test::CliResult;
using test::run_cli;

// A mechanism file in the temporary directory, removed at the end of the test.
class TempMechanism {
 public:
  explicit TempMechanism(const std::string& text) : path_(temp_base().string() + ".yaml") {
    std::ofstream(path_) << text;
  }
  ~TempMechanism() {
    std::error_code ec;
    fs::remove(path_, ec);
  }
  TempMechanism(const TempMechanism&) = delete;
  TempMechanism& operator=(const TempMechanism&) = delete;
  [[nodiscard]] std::string path() const { return path_.string(); }

 private:
  fs::path path_;
};

// A four-bar drawn exactly assembled (SI units): ground pivots A0 (0, 0) and B0 (10, 0); crank
// A0 → A (3, 4); coupler A → B (10, 3); rocker B0 → B. Every body frame is parallel to the world,
// so the body-frame points are world offsets from the pose.
// 3 bodies × 3 = 9 coordinates, 4 revolutes × 2 = 8 equations, DOF = Grübler = 1.
const char* const kFourBar = R"(orthomech: 1
name: four-bar
description: a crank-rocker for the CLI tests
ground:
  points: {A0: [0, 0], B0: [10, 0]}
bodies:
  - {name: crank, mass: 1, inertia: 0.1, com: [1.5, 2], pose: [0, 0, 0], points: {A0: [0, 0], A: [3, 4]}}
  - {name: coupler, mass: 2, inertia: 0.2, com: [3.5, -0.5], pose: [3, 4, 0], points: {A: [0, 0], B: [7, -1]}}
  - {name: rocker, mass: 1, inertia: 0.1, com: [0, 1.5], pose: [10, 0, 0], points: {B0: [0, 0], B: [0, 3]}}
joints:
  - {name: A0, type: revolute, connects: [ground.A0, crank.A0]}
  - {name: A, type: revolute, connects: [crank.A, coupler.A]}
  - {name: B, type: revolute, connects: [coupler.B, rocker.B]}
  - {name: B0, type: revolute, connects: [rocker.B0, ground.B0]}
measures:
  - {name: crank_angle, type: joint, joint: A0}
)";

// A parallelogram (cranks of length 3 at x = 0 and x = 4, coupler of length 4) with a third,
// equal crank at x = 2: 4 bodies × 3 = 12 coordinates, 6 revolutes × 2 = 12 equations, so the
// Grübler count is 0, but one equation is redundant and the mechanism moves: DOF 1.
const char* const kParallelCranks = R"(orthomech: 1
name: parallel-cranks
ground:
  points: {A0: [0, 0], B0: [4, 0], C0: [2, 0]}
bodies:
  - {name: crank1, mass: 1, inertia: 0.1, com: [0, 1.5], pose: [0, 0, 0], points: {O: [0, 0], P: [0, 3]}}
  - {name: crank2, mass: 1, inertia: 0.1, com: [0, 1.5], pose: [4, 0, 0], points: {O: [0, 0], P: [0, 3]}}
  - {name: crank3, mass: 1, inertia: 0.1, com: [0, 1.5], pose: [2, 0, 0], points: {O: [0, 0], P: [0, 3]}}
  - {name: coupler, mass: 2, inertia: 0.3, com: [2, 0], pose: [0, 3, 0], points: {A: [0, 0], B: [4, 0], C: [2, 0]}}
joints:
  - {name: A0, type: revolute, connects: [ground.A0, crank1.O]}
  - {name: B0, type: revolute, connects: [ground.B0, crank2.O]}
  - {name: C0, type: revolute, connects: [ground.C0, crank3.O]}
  - {name: A, type: revolute, connects: [crank1.P, coupler.A]}
  - {name: B, type: revolute, connects: [crank2.P, coupler.B]}
  - {name: C, type: revolute, connects: [crank3.P, coupler.C]}
)";

::testing::AssertionResult parses_as_json(const std::string& text, nlohmann::json& out) {
  try {
    out = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    return ::testing::AssertionFailure() << "stdout is not JSON (" << e.what() << "):\n" << text;
  }
  return ::testing::AssertionSuccess();
}

void expect_mobility_keys(const nlohmann::json& j) {
  for (const char* key : {"coordinates", "constraints", "rank", "dof", "grubler"}) {
    ASSERT_TRUE(j.contains(key)) << key;
    EXPECT_TRUE(j[key].is_number_integer()) << key << " = " << j[key];
  }
  ASSERT_TRUE(j.contains("redundant"));
  EXPECT_TRUE(j["redundant"].is_array()) << j["redundant"];
}

TEST(Cli, InfoHelpExitsZero) {
  const CliResult r = run_cli({"info", "--help"});
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("--json"), std::string::npos) << r.out;
}

TEST(Cli, InfoWithoutFileIsBadInput) {
  const CliResult r = run_cli({"info"});
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_EQ(r.out, "");
}

TEST(Cli, InfoOnMissingFileIsBadInput) {
  const std::string missing = (fs::temp_directory_path() / "orthomech_no_such_file.yaml").string();
  ASSERT_FALSE(fs::exists(missing));
  const CliResult r = run_cli({"info", missing});
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_EQ(r.out, "");
  EXPECT_NE(r.err.find("cannot open"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(missing), std::string::npos) << "the message names the file: " << r.err;
  EXPECT_EQ(r.err.find("internal error"), std::string::npos) << r.err;
}

TEST(Cli, InfoJsonFourBar) {
  const TempMechanism file(kFourBar);
  const CliResult r = run_cli({"info", file.path(), "--json"});
  ASSERT_EQ(r.status, 0) << r.err;
  nlohmann::json j;
  ASSERT_TRUE(parses_as_json(r.out, j));
  expect_mobility_keys(j);
  if (HasFatalFailure()) return;
  EXPECT_EQ(j["coordinates"].get<int>(), 9);
  EXPECT_EQ(j["constraints"].get<int>(), 8);
  EXPECT_EQ(j["rank"].get<int>(), 8);
  EXPECT_EQ(j["dof"].get<int>(), 1);
  EXPECT_EQ(j["grubler"].get<int>(), 1);
  EXPECT_TRUE(j["redundant"].empty()) << j["redundant"];
}

TEST(Cli, InfoJsonParallelCranksHasOneRedundantEquation) {
  const TempMechanism file(kParallelCranks);
  const CliResult r = run_cli({"info", file.path(), "--json"});
  ASSERT_EQ(r.status, 0) << r.err;
  nlohmann::json j;
  ASSERT_TRUE(parses_as_json(r.out, j));
  expect_mobility_keys(j);
  if (HasFatalFailure()) return;
  EXPECT_EQ(j["coordinates"].get<int>(), 12);
  EXPECT_EQ(j["constraints"].get<int>(), 12);
  EXPECT_EQ(j["rank"].get<int>(), 11);
  EXPECT_EQ(j["grubler"].get<int>(), 0);
  EXPECT_EQ(j["dof"].get<int>(), 1);
  ASSERT_EQ(j["redundant"].size(), 1u) << j["redundant"];
  ASSERT_TRUE(j["redundant"][0].is_string()) << j["redundant"];
  const std::string entry = j["redundant"][0].get<std::string>();
  EXPECT_TRUE(std::regex_match(entry, std::regex("joint '.+', (x|y)"))) << entry;
}

TEST(Cli, InfoTable) {
  const TempMechanism file(kFourBar);
  const CliResult r = run_cli({"info", file.path()});
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("DOF"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("four-bar"), std::string::npos) << r.out;
}

// Formerly known bugs, fixed.
// A directory is not a readable mechanism file: bad input (2), not an internal error (4).
TEST(Cli, InfoOnADirectoryIsBadInput) {
  const CliResult r = run_cli({"info", fs::temp_directory_path().string()});
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_EQ(r.out, "");
  EXPECT_EQ(r.err.find("internal error"), std::string::npos) << r.err;
}

// `joints` is optional (docs/file-format.md): a free body has 3 DOF and no constraints.
TEST(Cli, InfoOnAMechanismWithoutJoints) {
  const TempMechanism file(R"(orthomech: 1
bodies:
  - {name: puck, mass: 1, inertia: 0.1, pose: [0, 0, 0]}
)");
  const CliResult r = run_cli({"info", file.path(), "--json"});
  ASSERT_EQ(r.status, 0) << r.err;
  nlohmann::json j;
  ASSERT_TRUE(parses_as_json(r.out, j));
  EXPECT_EQ(j["constraints"], 0);
  EXPECT_EQ(j["dof"], 3);
  EXPECT_EQ(j["grubler"], 3);
}

}  // namespace
}  // namespace orthomech
