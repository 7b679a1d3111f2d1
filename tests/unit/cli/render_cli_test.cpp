// `orthomech render` (cli/render.cpp; docs/cli.md "render"): its command-line errors, each with
// its exit code and message and no picture written. The pictures themselves are checked against
// the crank-rocker's closed form in io/render_test.cpp (through this command) and
// cli/render_spatial_cli_test.cpp.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "support/cli_runner.hpp"

namespace orthomech {
namespace {

namespace fs = std::filesystem;
using test::CliResult;
using test::run_cli;

std::string bundled(const std::string& name) { return test::bundled_file(name); }

struct TempDir : test::TempDir {
  TempDir() : test::TempDir("orthomech_render_cli_") {}
};

TEST(RenderCli, UnknownImageTypeIsBadInput) {
  TempDir dir;
  const std::string out = (dir.path / "x.jpg").string();
  const CliResult r = run_cli({"render", bundled("crank-rocker"), "--out", out});
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("unknown image type"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(".svg, .png or .pdf"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
}

TEST(RenderCli, UnknownDesignPositionIsBadInput) {
  TempDir dir;
  const std::string out = (dir.path / "x.png").string();
  const CliResult r =
      run_cli({"render", bundled("crank-rocker"), "--position", "p9", "--out", out});
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("design position 'p9' is not defined (the file has p1, p2, p3)"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(out));
}

// The double rocker's input reaches ±77.608916° only (its comment block): at 120° it cannot close.
TEST(RenderCli, InputThatCannotAssembleIsANumericalFailure) {
  TempDir dir;
  const std::string out = (dir.path / "x.svg").string();
  const CliResult r =
      run_cli({"render", bundled("double-rocker"), "--input", "120deg", "--out", out});
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(r.err.find("cannot assemble joint 'A0' at 120 deg"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
}

TEST(RenderCli, PositionAndInputAreExclusiveAndOutIsRequired) {
  TempDir dir;
  const std::string out = (dir.path / "x.png").string();
  EXPECT_EQ(run_cli({"render", bundled("crank-rocker"), "--position", "p1", "--input", "10",
                     "--out", out})
                .status,
            2);
  EXPECT_EQ(run_cli({"render", bundled("crank-rocker")}).status, 2);
  const CliResult bad_unit =
      run_cli({"render", bundled("crank-rocker"), "--input", "10mm", "--out", out});
  EXPECT_EQ(bad_unit.status, 2) << bad_unit.err;
  EXPECT_FALSE(fs::exists(out));
}

}  // namespace
}  // namespace orthomech
