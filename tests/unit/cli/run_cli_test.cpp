// The command line (cli/run.cpp, run by the executable cli/main.cpp; docs/cli.md): exit codes (0
// ok, 2 bad input or command line), --version against CMakeLists.txt and the configured git
// revision,
// --help.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include "orthomech/version.hpp"
#include "support/cli_runner.hpp"

namespace orthomech {
namespace {

using test::CliResult;
using test::run_cli;

TEST(Cli, VersionPrintsNameAndVersion) {
  const CliResult r = run_cli({"--version"});
  EXPECT_EQ(r.status, 0) << r.err;
  // The one place the version is written: project(VERSION) of CMakeLists.txt.
  std::ifstream cmake(std::string(ORTHOMECH_SOURCE_DIR) + "/CMakeLists.txt");
  std::stringstream text;
  text << cmake.rdbuf();
  std::smatch project;
  const std::string cmake_text = text.str();
  ASSERT_TRUE(std::regex_search(cmake_text, project,
                                std::regex(R"(project\(orthomech VERSION ([0-9.]+))")));
  EXPECT_EQ(project[1].str(), ORTHOMECH_VERSION);
  // "orthomech 0.1.0 (git 0123456789)" in a git checkout, "orthomech 0.1.0" without .git: the
  // revision CMake found at configure time (cmake/git_revision.cmake).
  std::ifstream header(ORTHOMECH_GIT_REVISION_HEADER);
  std::stringstream header_text;
  header_text << header.rdbuf();
  const std::string generated = header_text.str();
  std::smatch define;
  ASSERT_TRUE(std::regex_search(generated, define,
                                std::regex(R"re(#define ORTHOMECH_GIT_REVISION "([^"]*)")re")))
      << generated;
  const std::string revision = define[1].str();
  EXPECT_EQ(r.out, "orthomech " + project[1].str() +
                       (revision.empty() ? "" : " (git " + revision + ")") + "\n");
  if (!revision.empty()) {
    ASSERT_TRUE(std::regex_match(revision, std::regex("[0-9a-f]{10}"))) << revision;
    // A commit of this repository.
    const std::string exists = "git -C '" + std::string(ORTHOMECH_SOURCE_DIR) + "' cat-file -e " +
                               revision + "^{commit} 2>/dev/null";
    EXPECT_EQ(std::system(exists.c_str()), 0) << revision;
  }
}

TEST(Cli, HelpExitsZero) {
  const CliResult r = run_cli({"--help"});
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("info"), std::string::npos) << "the help lists the subcommands:\n" << r.out;
}

TEST(Cli, NoSubcommandIsBadInput) {
  const CliResult r = run_cli({});
  EXPECT_EQ(r.status, 2) << r.out << r.err;
}

TEST(Cli, UnknownOptionIsBadInput) {
  EXPECT_EQ(run_cli({"--no-such-option"}).status, 2);
  EXPECT_EQ(run_cli({"info", test::bundled_file("crank-rocker"), "--no-such-option"}).status, 2);
}

TEST(Cli, UnknownSubcommandIsBadInput) { EXPECT_EQ(run_cli({"no-such-command"}).status, 2); }

}  // namespace
}  // namespace orthomech
