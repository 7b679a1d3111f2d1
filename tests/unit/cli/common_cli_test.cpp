// What every command shares (cli/common.cpp; docs/cli.md): the log level (-v/--verbose and
// -q/--quiet before or after the command: debug messages on stderr, never on stdout), the
// `--units file|si` choice, and --set changes that are not PATH=VALUE. The topic files
// common_<topic>_cli_test.cpp check the shared behaviour across the commands.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "support/cli_runner.hpp"

namespace orthomech {
namespace {

using test::CliResult;
using test::run_cli;

TEST(CommonCli, VerboseLogsTheFileReadOnStderrOnly) {
  const std::string file = test::bundled_file("crank-rocker");
  const std::string reading = "debug: reading " + file;
  for (const auto& args : {std::vector<std::string>{"-v", "info", file},
                           std::vector<std::string>{"info", file, "--verbose"}}) {
    const CliResult r = run_cli(args);
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.err.find(reading), std::string::npos) << r.err;
    EXPECT_EQ(r.out.find("debug:"), std::string::npos) << r.out;
  }
  const CliResult plain = run_cli({"info", file});
  ASSERT_EQ(plain.status, 0) << plain.err;
  EXPECT_EQ(plain.err.find("debug:"), std::string::npos) << plain.err;
  // The same results whatever the log level.
  EXPECT_EQ(run_cli({"-q", "info", file}).out, plain.out);
  EXPECT_EQ(run_cli({"info", file, "-v"}).out, plain.out);
}

TEST(CommonCli, UnitsAreFileOrSi) {
  const std::string file = test::bundled_file("crank-rocker");
  const CliResult si = run_cli({"info", file, "--units", "si", "--json"});
  EXPECT_EQ(si.status, 0) << si.err;
  const CliResult bad = run_cli({"info", file, "--units", "imperial"});
  EXPECT_EQ(bad.status, 2);
  EXPECT_NE(bad.err.find("--units"), std::string::npos) << bad.err;
  EXPECT_EQ(bad.out, "");
}

TEST(CommonCli, SetWithoutAnEqualsSignIsBadInput) {
  const CliResult r =
      run_cli({"info", test::bundled_file("crank-rocker"), "--set", "joints.A0.length"});
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--set"), std::string::npos) << r.err;
  EXPECT_EQ(r.out, "");
}

}  // namespace
}  // namespace orthomech
