// The contract of docs/cli.md ("The contract") on inputs a careful user gets wrong (issue 17):
// every command on every broken file of tests/data/invalid/ exits 2 with the file's place and
// nothing on stdout; every command on the degenerate mechanisms of tests/data/degenerate/ ends
// (no crash, no exit 4) with no NaN or inf printed; every number option refuses NaN, inf and
// out-of-range values with exit 2 naming the option, before any work (no hang).
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>
#include <vector>

#include "support/cli_runner.hpp"
#include "unit/analysis/large_mechanisms.hpp"

namespace orthomech {
namespace {

namespace fs = std::filesystem;
using test::CliResult;
using test::run_cli;

const fs::path kData = fs::path(ORTHOMECH_SOURCE_DIR) / "tests" / "data";
const std::string kCrankRocker = ORTHOMECH_SOURCE_DIR "/mechanisms/crank-rocker.yaml";
const std::string kPendulum = ORTHOMECH_SOURCE_DIR "/mechanisms/pendulum.yaml";

std::vector<std::string> yaml_files(const fs::path& dir) {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().extension() == ".yaml") out.push_back(e.path().string());
  std::sort(out.begin(), out.end());
  return out;
}

// "nan", "-nan", "inf", "-inf" as a printed number (not inside a word such as "info").
bool prints_non_finite(const std::string& text) {
  static const std::regex number(R"((^|[^A-Za-z_])-?(nan|inf)([^A-Za-z_]|$))", std::regex::icase);
  return std::regex_search(text, number);
}

// The commands with the options that make them short on these small files.
const std::vector<std::vector<std::string>> kCommands = {
    {"info"},
    {"assemble"},
    {"cycle", "--steps", "36"},
    {"crosscheck", "--samples", "3", "--t-end", "0.05"},
    {"simulate", "--t-end", "0.05"},
    {"validate", "--starts", "2"},
    {"render", "--out",
     (std::filesystem::temp_directory_path() /
      ("orthomech_robustness_" + std::to_string(::getpid()) + ".svg"))
         .string()},
};

std::vector<std::string> with_file(std::vector<std::string> command, const std::string& file) {
  command.insert(command.begin() + 1, file);
  return command;
}

std::string describe(const std::vector<std::string>& args) {
  std::string s = "orthomech";
  for (const auto& a : args) s += " " + a;
  return s;
}

// Every broken file, through the commands in turn (file k through command k mod 7; `info` on
// every file is Data/InvalidFile.CliInfo…): exit 2, the `# expect:` message's place
// (file:line:column) at the start of stderr, nothing on stdout. Every command reads its file
// through the same cli::load, so one command per file covers the reader; the rotation checks that
// no command does anything before or besides it (~75 processes, not ~450: the suite stays fast).
TEST(Robustness, EveryCommandRefusesTheInvalidFilesWithTheirPlace) {
  const auto files = yaml_files(kData / "invalid");
  ASSERT_GT(files.size(), 60u);
  static const std::regex place(R"(^# expect: [^:]+:([0-9]+):([0-9]+): error: )");
  for (size_t k = 0; k < files.size(); ++k) {
    const std::string& file = files[k];
    std::ifstream in(file);
    std::string first;
    std::getline(in, first);
    std::smatch m;
    ASSERT_TRUE(std::regex_search(first, m, place)) << file;
    const auto args = with_file(kCommands[k % kCommands.size()], file);
    const CliResult r = run_cli(args);
    EXPECT_EQ(r.status, 2) << describe(args) << "\n" << r.err;
    EXPECT_EQ(r.out, "") << describe(args);
    EXPECT_EQ(r.err.rfind(file + ":" + m[1].str() + ":" + m[2].str() + ": error: ", 0), 0u)
        << describe(args) << "\n"
        << r.err;
  }
}

struct Degenerate {
  const char* file;
  const char* command;
  int status;           // expected exit status
  const char* message;  // expected on stderr ("" = nothing in particular)
};

// Degenerate mechanisms that parse: each command ends with a documented status and its reason,
// never a signal, exit 4 or a NaN. The statuses are the documented ones (docs/cli.md): nothing to
// close is `unchanged` (0); crosscheck without joints or without DOF has nothing to compare (3);
// cycle needs DOF 1 (3) or stops at a dead point (1).
const Degenerate kDegenerate[] = {
    {"no-joints.yaml", "assemble", 0, ""},
    {"no-joints.yaml", "crosscheck", 3, "has no joints"},
    {"no-joints.yaml", "cycle", 2, "has no driver"},
    {"empty-joints.yaml", "assemble", 0, ""},
    {"empty-joints.yaml", "crosscheck", 3, "has no joints"},
    {"dof0-driven.yaml", "crosscheck", 3, "no degree of freedom"},
    {"dof0-driven.yaml", "cycle", 3, "1 DOF; this one has 0"},
    {"locked-driver.yaml", "cycle", 1, "dead point"},
    {"gear-own-carrier.yaml", "cycle", 3, "1 DOF; this one has 3"},
};

TEST(Robustness, DegenerateMechanismsEndWithAReason) {
  for (const Degenerate& d : kDegenerate) {
    const std::vector<std::string> args = {d.command, (kData / "degenerate" / d.file).string()};
    const CliResult r = run_cli(args);
    EXPECT_EQ(r.status, d.status) << describe(args) << "\n" << r.err;
    EXPECT_NE(r.err.find(d.message), std::string::npos) << describe(args) << "\n" << r.err;
  }
}

TEST(Robustness, EveryCommandOnEveryDegenerateMechanismEndsWithoutNaN) {
  for (const auto& file : yaml_files(kData / "degenerate")) {
    for (const auto& command : kCommands) {
      const auto args = with_file(command, file);
      const CliResult r = run_cli(args);
      EXPECT_TRUE(r.status >= 0 && r.status <= 3)
          << describe(args) << " ended with " << r.status << "\n"
          << r.err;
      EXPECT_FALSE(prints_non_finite(r.out)) << describe(args) << "\n" << r.out;
      if (r.status >= 2) {
        EXPECT_FALSE(r.err.empty()) << describe(args);
      }
    }
  }
}

// A distance measure between two points that coincide at every position: |d| = 0 and its rate 0
// at every position (closed form: both points are the pivot), not an internal error. Tolerance:
// the pivot closes to rounding (1e-15 m and 1e-15 m/s at a 1 m crank turning at 2π rad/s).
constexpr double kPivotClosure = 1e-12;
TEST(Robustness, DistanceMeasureOfCoincidentPointsIsZeroAlongTheCycle) {
  const CliResult r =
      run_cli({"cycle", (kData / "degenerate" / "coincident-distance.yaml").string(), "--steps",
               "12", "--json", "--positions"});
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["points"].size(), 12u);
  for (const auto& p : j["points"]) {
    EXPECT_NEAR(p["measures"]["gap"].get<double>(), 0.0, kPivotClosure);
    EXPECT_NEAR(p["measures"]["gap_rate"].get<double>(), 0.0, kPivotClosure);
  }
}

struct OptionCase {
  std::vector<std::string> args;
  const char* option;  // named in the message
};

// Number options: NaN, inf, out of range, trailing text and the limits shared with the file are
// command-line errors (exit 2 naming the option), found before any work: none of these may run
// (`--rtol nan` and `--dt-out 1e-300` used to run for ever).
TEST(Robustness, NumberOptionsRefuseNonFiniteAndOutOfRangeValues) {
  const std::string cr = kCrankRocker, pe = kPendulum;
  const std::vector<OptionCase> cases = {
      {{"simulate", pe, "--t-end", "nan"}, "--t-end"},
      {{"simulate", pe, "--t-end", "inf"}, "--t-end"},
      {{"simulate", pe, "--t-end", "-1"}, "--t-end"},
      {{"simulate", pe, "--t-end", "1", "--rtol", "nan"}, "--rtol"},
      {{"simulate", pe, "--t-end", "1", "--rtol", "0"}, "--rtol"},
      {{"simulate", pe, "--t-end", "1", "--atol", "inf"}, "--atol"},
      {{"simulate", pe, "--t-end", "1", "--dt-out", "1e-300"}, "--dt-out"},
      {{"simulate", pe, "--t-end", "1", "--dt-out", "nan"}, "--dt-out"},
      {{"simulate", pe, "--t-end", "1", "--max-step", "-inf"}, "--max-step"},
      {{"simulate", pe, "--t-end", "1", "--rate", "P1_x=1e308"}, "--rate"},
      {{"simulate", pe, "--t-end", "1", "--rate", "P1_x=nan"}, "--rate"},
      {{"simulate", pe, "--t-end", "1", "--rate", "P1_x=1x"}, "--rate"},
      {{"simulate", pe, "--t-end", "0.1", "--out", "/proc/orthomech-cannot-be-here"}, "--out"},
      {{"cycle", cr, "--speed", "nan"}, "--speed"},
      {{"cycle", cr, "--speed", "1e308"}, "--speed"},
      {{"cycle", cr, "--speed", "0rpm"}, "--speed"},
      {{"cycle", cr, "--steps", "1000000"}, "--steps"},
      {{"cycle", cr, "--from", "1e300deg"}, "--from"},
      {{"cycle", cr, "--from", "0", "--to", "inf"}, "--to"},
      {{"assemble", cr, "--velocity", "crank=nan,0,0"}, "--velocity"},
      {{"assemble", cr, "--velocity", "crank=1e300,0,0"}, "--velocity"},
      {{"assemble", cr, "--lock", "A0=1e300deg"}, "--lock"},
      {{"assemble", cr, "--lock", "A0=nan"}, "--lock"},
      {{"assemble", cr, "--tolerance", "inf"}, "--tolerance"},
      {{"crosscheck", cr, "--t-end", "nan"}, "--t-end"},
      {{"crosscheck", cr, "--tolerance", "nan"}, "--tolerance"},
      {{"crosscheck", cr, "--samples", "0"}, "--samples"},
      {{"validate", cr, "--min-transmission", "nan"}, "--min-transmission"},
      {{"validate", cr, "--starts", "-1"}, "--starts"},
  };
  for (const OptionCase& c : cases) {
    const CliResult r = run_cli(c.args);
    EXPECT_EQ(r.status, 2) << describe(c.args) << "\n" << r.err;
    EXPECT_EQ(r.out, "") << describe(c.args);
    EXPECT_NE(r.err.find(c.option), std::string::npos) << describe(c.args) << "\n" << r.err;
  }
}

// A driver problem found by `cycle` (not by the reader) in a driver taken from the file carries
// the driver's place: file:line:column of its list item.
TEST(Robustness, CycleDriverProblemFromTheFileNamesTheDriversLine) {
  const fs::path file = fs::temp_directory_path() / "orthomech-robustness-polynomial.yaml";
  std::ofstream(file) << "orthomech: 1\n"
                         "bodies:\n"
                         "  - {name: crank, mass: 1, inertia: 0.1, pose: [0, 0, 0]}\n"
                         "joints:\n"
                         "  - {name: O, type: revolute, connects: [ground.origin, crank.origin]}\n"
                         "drivers:\n"
                         "  - {name: ramp, joint: O, profile: polynomial, coefficients: [0, 1]}\n";
  const CliResult r = run_cli({"cycle", file.string()});
  fs::remove(file);
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err.rfind(file.string() + ":7:5: error: driver 'ramp': a polynomial driver", 0), 0u)
      << r.err;
  EXPECT_EQ(r.out, "");
}

// A model too large for a command's dense n × n matrices (IFToMM A02 at N = 1000: 2001 bodies,
// n = 6003, 5.48 GB of them) is refused with exit 2 naming the file and its sizes, before anything
// is allocated (the system would otherwise kill the process): `crosscheck --method dense`. info,
// assemble and the default crosscheck (the probe comparison from n = 300), on sparse matrices,
// run.
TEST(Robustness, ModelTooLargeForDenseMatricesIsBadInputNotACrash) {
  const test::TempDir dir("orthomech_large_");
  const fs::path file = dir.path / "n-four-bar-1000.yaml";
  std::ofstream(file) << test::n_four_bar_yaml(1000, 0.5);
  const CliResult r = run_cli({"crosscheck", file.string(), "--method", "dense"});
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_NE(r.err.find(file.string() + ": 6003 velocity components"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("dense n × n matrices"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--method probes"), std::string::npos) << r.err;
  EXPECT_TRUE(r.out.empty());
  const CliResult probes =
      run_cli({"crosscheck", file.string(), "--samples", "2", "--t-end", "0.02", "--json"});
  ASSERT_EQ(probes.status, 0) << probes.err;
  EXPECT_EQ(nlohmann::json::parse(probes.out)["method"], "probes");
  const CliResult info = run_cli({"info", file.string(), "--json"});
  ASSERT_EQ(info.status, 0) << info.err;
  EXPECT_EQ(nlohmann::json::parse(info.out)["dof"], 1);
  // assemble projects the velocities on the sparse path (issue 18 item 2): no limit; the design
  // pose closes, and u₀ = 1 m/s of link0 along x leaves an admissible u with less energy.
  const CliResult a = run_cli({"assemble", file.string(), "--velocity", "link0=1,0,0", "--json"});
  ASSERT_EQ(a.status, 0) << a.err;
  const auto j = nlohmann::json::parse(a.out);
  EXPECT_EQ(j["status"], "unchanged");
  EXPECT_NEAR(j["velocities"]["kinetic_initial"].get<double>(), 0.5, 1e-12);
  EXPECT_GT(j["velocities"]["kinetic"].get<double>(), 0.0);
  EXPECT_LT(j["velocities"]["kinetic"].get<double>(), 0.5);
}

}  // namespace
}  // namespace orthomech
