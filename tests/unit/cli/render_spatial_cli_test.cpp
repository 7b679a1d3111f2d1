// The pictures of `cycle` and `render` on spatial files (issue 13 item 1): --trace, --animate and
// --report work on a spatial mechanism (they exited 2 before), the trace has its z in the CSV,
// the JSON and the summary, and --view names a view or is a usage error naming the option.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "support/cli_runner.hpp"

namespace orthomech {
namespace {

using nlohmann::json;
using test::CliResult;
using test::run_cli;

std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(SpatialPicturesCli, CycleTraceAnimateAndReportOnTheRssr) {
  const test::TempDir dir("orthomech_spatial_pictures_");
  const std::string svg = (dir.path / "rssr.svg").string();
  const std::string html = (dir.path / "rssr.html").string();
  const CliResult r =
      run_cli({"cycle", test::bundled_file("rssr"), "--steps", "12", "--trace", "rocker.B",
               "--animate", svg, "--report", html, "--out", (dir.path / "out").string()});
  ASSERT_EQ(r.status, 0) << r.err;
  // The summary's trace line has the z range: B moves on x = 300 mm, z in [0, 400] mm.
  EXPECT_NE(r.out.find("trace  rocker.B: x 300 ... 300, y "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(", z "), std::string::npos) << r.out;
  // One frame per position in the animation and in the report.
  const std::string animation = slurp(svg);
  EXPECT_NE(animation.find("id=\"frame-11\""), std::string::npos);
  EXPECT_EQ(animation.find("id=\"frame-12\""), std::string::npos);
  const std::string page = slurp(html);
  EXPECT_NE(page.find("frame-11"), std::string::npos);
  // The CSV has the trace's x, y and z.
  std::ifstream csv(dir.path / "out" / "cycle.csv");
  std::string header;
  std::getline(csv, header);
  for (const char* col :
       {"trace rocker.B.x [mm]", "trace rocker.B.y [mm]", "trace rocker.B.z [mm]"})
    EXPECT_NE(header.find(col), std::string::npos) << col << "\n" << header;
}

TEST(SpatialPicturesCli, CycleJsonTraceHasZ) {
  const CliResult r = run_cli(
      {"cycle", test::bundled_file("rssr"), "--steps", "8", "--trace", "coupler.B", "--json"});
  ASSERT_EQ(r.status, 0) << r.err;
  const json j = json::parse(r.out);
  ASSERT_EQ(j["traces"].size(), 1u);
  const json& t = j["traces"][0];
  ASSERT_EQ(t["z"].size(), 8u);
  // coupler.B is the rocker's B: on the circle of radius 200 mm about (y, z) = (0, 200) mm.
  for (size_t k = 0; k < 8; ++k) {
    EXPECT_NEAR(t["x"][k].get<double>(), 300.0, 1e-6);
    const double y = t["y"][k], z = t["z"][k];
    EXPECT_NEAR(std::hypot(y, z - 200.0), 200.0, 1e-6) << k;
  }
}

TEST(SpatialPicturesCli, RenderDrawsASpatialFileInEveryNamedView) {
  const test::TempDir dir("orthomech_spatial_pictures_");
  for (const std::string view : {"iso", "front", "top", "side", "30,20"}) {
    const std::string out = (dir.path / ("view " + view + ".svg")).string();
    const CliResult r = run_cli({"render", test::bundled_file("rssr"), "--view", view, "--labels",
                                 "--trace", "coupler.B", "--out", out});
    EXPECT_EQ(r.status, 0) << view << ": " << r.err;
    EXPECT_TRUE(std::filesystem::exists(out)) << view;
  }
  const std::string anim = (dir.path / "anim.svg").string();
  const CliResult a = run_cli({"render", test::bundled_file("rssr"), "--animate", "--out", anim});
  EXPECT_EQ(a.status, 0) << a.err;
  EXPECT_NE(slurp(anim).find("id=\"frame-359\""), std::string::npos);
}

// --input and --position lock spatial joints (assemble's locks): an SVG at the input, exit 0
// (RenderRssr.InputAndPositionDrawTheClosedFormPoseThere checks the pixels); an input the
// mechanism cannot reach is exit 3 naming the joint and the value.
TEST(SpatialPicturesCli, RenderInputOnASpatialFileDrawsThere) {
  const test::TempDir dir("orthomech_spatial_pictures_");
  const std::string out = (dir.path / "x.svg").string();
  const CliResult r =
      run_cli({"render", test::bundled_file("rssr"), "--input", "90", "--out", out});
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_NE(slurp(out).find("<svg"), std::string::npos);
  const std::string design = (dir.path / "design.svg").string();
  ASSERT_EQ(run_cli({"render", test::bundled_file("rssr"), "--out", design}).status, 0);
  EXPECT_NE(slurp(out), slurp(design));  // drawn at 90°, not at the drawing's 30°
  const CliResult p =
      run_cli({"render", test::bundled_file("rssr"), "--position", "p30", "--out", out});
  EXPECT_EQ(p.status, 0) << p.err;
  // Driven by its rocker instead, the RSSR cannot reach 90° (the rocker swings over
  // 129.6°…237.4°): exit 3 with assemble's reason.
  const CliResult far = run_cli({"render", test::bundled_file("rssr"), "--set",
                                 "drivers.motor.joint=B0", "--input", "90", "--out", out});
  EXPECT_EQ(far.status, 3) << far.err;
  EXPECT_NE(far.err.find("cannot assemble joint 'B0' at 90 deg"), std::string::npos) << far.err;
}

TEST(SpatialPicturesCli, AnUnknownViewIsAUsageErrorNamingTheOption) {
  const test::TempDir dir("orthomech_spatial_pictures_");
  const std::string out = (dir.path / "x.png").string();
  for (const auto& args : std::vector<std::vector<std::string>>{
           {"render", test::bundled_file("rssr"), "--view", "oblique", "--out", out},
           {"cycle", test::bundled_file("rssr"), "--view", "oblique", "--animate",
            (dir.path / "x.svg").string()},
           {"render", test::bundled_file("crank-rocker"), "--view", "iso", "--out", out}}) {
    const CliResult r = run_cli(args);
    EXPECT_EQ(r.status, 2) << args[0] << " " << args[3] << ": " << r.err;
    EXPECT_NE(r.err.find("--view"), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(out));
  }
}

}  // namespace
}  // namespace orthomech
