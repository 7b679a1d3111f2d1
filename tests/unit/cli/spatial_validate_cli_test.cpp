// `orthomech validate` on spatial files (issue 13 item 2): every bundled spatial file runs (exit
// 0, JSON parses); the planar-only checks read "not applicable" in text and JSON; joint limits
// that keep a spatial position from closing name the joint; a target in 3D is exit 2.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <numbers>

#include "support/cli_runner.hpp"

namespace orthomech {
namespace {

using nlohmann::json;
using test::CliResult;
using test::run_cli;

TEST(SpatialValidateCli, EverySpatialFileRunsWithPlanarChecksNotApplicable) {
  for (const char* name : {"rssr", "bennett", "bricard", "hooke-joint", "spatial-slider-crank",
                           "heavy-top", "crank-rocker-3d"}) {
    const CliResult r = run_cli({"validate", test::bundled_file(name), "--json"});
    ASSERT_EQ(r.status, 0) << name << ": " << r.err << r.out;
    const json j = json::parse(r.out);
    EXPECT_TRUE(j["pass"].get<bool>()) << name;
    ASSERT_EQ(j["not_applicable"].size(), 3u) << name;
    EXPECT_NE(j["not_applicable"][0].get<std::string>().find("Grashof"), std::string::npos);
    for (const json& p : j["positions"]) {
      EXPECT_EQ(p["four_bars"], "not applicable") << name;
      EXPECT_EQ(p["slider_cranks"], "not applicable") << name;
      EXPECT_TRUE(p["assembles"].get<bool>()) << name;
      EXPECT_GT(p["sigma_min"].get<double>(), 0.0) << name;
    }
  }
  // The files' design positions (their comment blocks): DOF 1 at each, 3 redundant equations in
  // the Bennett linkage and Hooke's joint (spatial.md §4.2, §4.5), none in the slider-crank.
  for (const auto& [name, redundant] : {std::pair<const char*, size_t>{"bennett", 3},
                                        {"hooke-joint", 3},
                                        {"spatial-slider-crank", 0}}) {
    const CliResult r = run_cli({"validate", test::bundled_file(name), "--json"});
    ASSERT_EQ(r.status, 0) << name << ": " << r.err;
    const json j = json::parse(r.out);
    ASSERT_EQ(j["positions"].size(), 3u) << name;
    EXPECT_EQ(j["circuits"], 1) << name;
    for (const json& p : j["positions"]) {
      EXPECT_EQ(p["dof"], 1) << name;
      EXPECT_EQ(p["redundant"].size(), redundant) << name;
      EXPECT_EQ(p["circuit"], 1) << name;
    }
  }
  // A planar file: the list is empty and the loops are arrays.
  const CliResult planar = run_cli({"validate", test::bundled_file("crank-rocker"), "--json"});
  ASSERT_EQ(planar.status, 0) << planar.err;
  const json pj = json::parse(planar.out);
  EXPECT_TRUE(pj["not_applicable"].empty());
  EXPECT_TRUE(pj["positions"][0]["four_bars"].is_array());
}

// The RSSR's one position (crank 30°): DOF 1, rank 17, rocker angle on (M1)'s branch (checked in
// spatial_validate_test.cpp); the text table says n/a for the transmission angle.
TEST(SpatialValidateCli, RssrReportInTextAndJson) {
  const std::string rssr = test::bundled_file("rssr");
  const CliResult r = run_cli({"validate", rssr, "--json"});
  ASSERT_EQ(r.status, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j["input"], "A0");
  EXPECT_EQ(j["generic_rank"], 17);
  EXPECT_EQ(j["loop_basis"], 1);  // 4 joints, 3 bodies and the ground
  EXPECT_EQ(j["circuits"], 1);
  const json& p = j["positions"][0];
  EXPECT_EQ(p["dof"], 1);
  EXPECT_EQ(p["rank"], 17);
  EXPECT_TRUE(p["redundant"].empty());
  EXPECT_TRUE(p["idle"].empty());
  EXPECT_GT(p["transmission_index"].get<double>(), 0.0);
  EXPECT_GE(p["modes"].get<int>(), 2);
  EXPECT_EQ(p["circuit"], 1);
  const CliResult text = run_cli({"validate", rssr});
  ASSERT_EQ(text.status, 0) << text.err;
  EXPECT_NE(text.out.find("n/a"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("not applicable (spatial mechanism)"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("every position passes every check"), std::string::npos) << text.out;
}

// The RSSR's rocker stands at 158.13° at the crank's 30°: limits [0, 90]° on its joint keep the
// position from closing (exit 1, the joint named with the angle it would need).
TEST(SpatialValidateCli, SpatialJointLimitsNameTheJoint) {
  const CliResult r =
      run_cli({"validate", test::bundled_file("rssr"), "--set", "joints.B0.limits=[0, 90]"});
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_NE(r.out.find("joint 'B0' would need 158.1"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("outside its limits [0 deg, 90 deg]"), std::string::npos) << r.out;
  const CliResult j = run_cli(
      {"validate", test::bundled_file("rssr"), "--set", "joints.B0.limits=[0, 90]", "--json"});
  ASSERT_EQ(j.status, 1) << j.err;
  const json doc = json::parse(j.out);
  const json& b = doc["positions"][0]["limit_blocks"][0];
  EXPECT_EQ(b["joint"], "B0");
  EXPECT_EQ(b["unit"], "deg");
  EXPECT_NEAR(b["needed"].get<double>(), 158.12936317866155, 1e-6);
}

// The RSSR with a spherical joint at B (an S–S coupler): an idle spin about AB (spatial.md §4.1),
// DOF 2 with one idle, so the crank alone fixes the position (exit 0), and the report says so.
TEST(SpatialValidateCli, IdleSpinIsReported) {
  std::ifstream in(test::bundled_file("rssr"));
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string u =
      "{name: B, type: universal, connects: [coupler.B, rocker.B], axes: [[0, 0, 1], [0, 0, 1]]}";
  const size_t at = text.find(u);
  ASSERT_NE(at, std::string::npos);
  text.replace(at, u.size(), "{name: B, type: spherical, connects: [coupler.B, rocker.B]}");
  const test::TempDir dir("orthomech_spatial_validate_");
  const std::string file = (dir.path / "rssr-ss.yaml").string();
  std::ofstream(file) << text;
  const CliResult r = run_cli({"validate", file});
  ASSERT_EQ(r.status, 0) << r.err << r.out;
  EXPECT_NE(r.out.find("idle degrees of freedom at p30 (held at zero rate): body 'coupler' (1 "
                       "direction)"),
            std::string::npos)
      << r.out;
  const CliResult j = run_cli({"validate", file, "--json"});
  ASSERT_EQ(j.status, 0) << j.err;
  const json doc = json::parse(j.out);
  const json& p = doc["positions"][0];
  EXPECT_EQ(p["dof"], 2);
  ASSERT_EQ(p["idle"].size(), 1u);
  EXPECT_EQ(p["idle"][0]["body"], "coupler");
  EXPECT_EQ(p["idle"][0]["count"], 1);
  EXPECT_GT(p["transmission_index"].get<double>(), 1e-6);  // the spin held: not a dead point
}

// A target in a spatial file is refused by the reader: exit 2 with the file position.
TEST(SpatialValidateCli, TargetInSpatialFileIsExitTwo) {
  std::ifstream in(test::bundled_file("rssr"));
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string key = "    inputs: {A0: 30}\n";
  const size_t at = text.find(key);
  ASSERT_NE(at, std::string::npos);
  text.insert(at + key.size(), "    target: {point: rocker.B, at: [300, -185.6, 274.5]}\n");
  const test::TempDir dir("orthomech_spatial_validate_");
  const std::string file = (dir.path / "rssr-target.yaml").string();
  std::ofstream(file) << text;
  const CliResult r = run_cli({"validate", file});
  EXPECT_EQ(r.status, 2) << r.out;
  EXPECT_NE(r.err.find("a target is not yet supported in a spatial mechanism"), std::string::npos)
      << r.err;
}

}  // namespace
}  // namespace orthomech
