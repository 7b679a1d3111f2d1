// `--set PATH=VALUE` on the command line (docs/cli.md "Changing the file from the command line"):
// a run with --set equals the run on a copy of the file edited by hand, on every command that
// reads a file; a bad change is exit 2 naming the --set.
#include <gtest/gtest.h>

#include <fstream>
#include <string>
#include <vector>

#include "support/cli_runner.hpp"

namespace orthomech {
namespace {

using test::run_cli;

// The file's text with `from` replaced by `to` written to `path`; all occurrences of the copy's
// path in later outputs are compared as the original's.
void write_edited(const std::string& from, const std::string& to, const std::string& path) {
  std::string text = test::read_text(test::bundled_file("crank-rocker"));
  const auto at = text.find(from);
  ASSERT_NE(at, std::string::npos);
  text.replace(at, from.size(), to);
  std::ofstream(path) << text;
}

std::string replace_all(std::string text, const std::string& from, const std::string& to) {
  for (auto at = text.find(from); at != std::string::npos; at = text.find(from, at + to.size()))
    text.replace(at, from.size(), to);
  return text;
}

TEST(SetCli, EqualsTheRunOnAHandEditedCopy) {
  test::TempDir dir("orthomech_set_");
  const std::string original = test::bundled_file("crank-rocker");
  const std::string copy = (dir.path / "crank-rocker.yaml").string();
  write_edited("A: [30, 0]}", "A: [35, 0]}", copy);
  for (const std::string command : {"cycle", "info", "validate"}) {
    SCOPED_TRACE(command);
    const auto changed =
        run_cli({command, original, "--set", "bodies.crank.points.A=[35, 0]", "--json"});
    const auto edited = run_cli({command, copy, "--json"});
    EXPECT_EQ(changed.status, edited.status) << changed.err;
    ASSERT_FALSE(changed.out.empty()) << changed.err;
    EXPECT_EQ(changed.out, replace_all(edited.out, copy, original));
  }
  // And the change does change the answer (the test can fail): the unchanged run differs.
  EXPECT_NE(run_cli({"cycle", original, "--json"}).out,
            run_cli({"cycle", original, "--set", "bodies.crank.points.A=[35, 0]", "--json"}).out);
}

TEST(SetCli, BadChangesAreExitTwoNamingTheSet) {
  const std::string file = test::bundled_file("crank-rocker");
  const auto mass = run_cli({"info", file, "--set", "bodies.crank.mass=-1"});
  EXPECT_EQ(mass.status, 2);
  EXPECT_NE(mass.err.find("--set bodies.crank.mass=-1"), std::string::npos) << mass.err;
  EXPECT_NE(mass.err.find("body 'crank'"), std::string::npos) << mass.err;
  const auto form = run_cli({"cycle", file, "--set", "mass"});
  EXPECT_EQ(form.status, 2);
  EXPECT_NE(form.err.find("PATH=VALUE"), std::string::npos) << form.err;
  const auto path = run_cli({"info", file, "--set", "loads.gravity.g=[0, 0]"});
  EXPECT_EQ(path.status, 2);
  EXPECT_NE(path.err.find("(names: weight)"), std::string::npos) << path.err;
  test::TempDir dir("orthomech_set_");
  const auto write = run_cli({"assemble", file, "--set", "bodies.crank.mass=1", "--write",
                              (dir.path / "out.yaml").string()});
  EXPECT_EQ(write.status, 2);
  EXPECT_NE(write.err.find("--set cannot be combined with --write"), std::string::npos)
      << write.err;
}

}  // namespace
}  // namespace orthomech
