// `orthomech validate` on spatial files (issue 13 item 2): every bundled spatial file runs (exit
// 0, JSON parses); the planar-only checks read "not applicable" in text and JSON; joint limits
// that keep a spatial position from closing name the joint; spatial targets met and missed; the
// transmission index of the spatial loops.
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
  // With a transmission loop (3 entries: the planar checks) or without (a 4th: the index). The
  // RSSR's index at its design position is 0.3976 (validate_spatial_test.cpp): a bound of 0.3
  // lets every file pass.
  for (const auto& [name, loops] : {std::pair<const char*, bool>{"rssr", true},
                                    {"bennett", false},
                                    {"bricard", false},
                                    {"hooke-joint", false},
                                    {"spatial-slider-crank", true},
                                    {"heavy-top", false},
                                    {"crank-rocker-3d", true}}) {
    const CliResult r = run_cli(
        {"validate", test::bundled_file(name), "--json", "--min-transmission-index", "0.3"});
    ASSERT_EQ(r.status, 0) << name << ": " << r.err << r.out;
    const json j = json::parse(r.out);
    EXPECT_TRUE(j["pass"].get<bool>()) << name;
    ASSERT_EQ(j["not_applicable"].size(), loops ? 3u : 4u) << name;
    EXPECT_NE(j["not_applicable"][0].get<std::string>().find("Grashof"), std::string::npos);
    EXPECT_EQ(j["min_loop_transmission_index"].is_object(), loops) << name;
    EXPECT_DOUBLE_EQ(j["transmission_index_bound"].get<double>(), 0.3) << name;
    for (const json& p : j["positions"]) {
      EXPECT_EQ(p["four_bars"], "not applicable") << name;
      EXPECT_EQ(p["slider_cranks"], "not applicable") << name;
      EXPECT_EQ(p["transmission_loops"].is_array(), loops) << name;
      EXPECT_TRUE(p["assembles"].get<bool>()) << name;
      EXPECT_GT(p["sigma_min"].get<double>(), 0.0) << name;
    }
  }
  // The files' design positions (their comment blocks): DOF 1 at each, 3 redundant equations in
  // the Bennett linkage and Hooke's joint (docs/spatial.md §4.2, §4.5), none in the slider-crank.
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
// validate_spatial_test.cpp); the text table says n/a for the transmission angle.
// Its Sutherland–Roth transmission index there, 0.3976 (the closed form:
// validate_spatial_test.cpp), is below the default bound sin 30° = 0.5: exit 1 naming the loop; 0
// with a bound of 0.3.
TEST(SpatialValidateCli, RssrReportInTextAndJson) {
  const std::string rssr = test::bundled_file("rssr");
  const CliResult by_default = run_cli({"validate", rssr});
  EXPECT_EQ(by_default.status, 1) << by_default.err;
  EXPECT_NE(by_default.out.find("FAIL p30: transmission index 0.3976 in loop A0-A-B-B0 (RSUR, "
                                "Sutherland & Roth; needs at least 0.5)"),
            std::string::npos)
      << by_default.out;
  const CliResult r = run_cli({"validate", rssr, "--json", "--min-transmission-index", "0.3"});
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
  ASSERT_EQ(p["transmission_loops"].size(), 1u);
  EXPECT_EQ(p["transmission_loops"][0]["joints"], "A0-A-B-B0");
  EXPECT_EQ(p["transmission_loops"][0]["type"], "RSUR");
  EXPECT_NEAR(p["transmission_loops"][0]["index"].get<double>(), 0.39757105919581, 1e-9);
  EXPECT_TRUE(p["transmission_loops"][0]["ok"].get<bool>());
  EXPECT_EQ(j["min_loop_transmission_index"]["position"], "p30");
  const CliResult text = run_cli({"validate", rssr, "--min-transmission-index", "0.3"});
  ASSERT_EQ(text.status, 0) << text.err;
  EXPECT_NE(text.out.find("transmission index of the spatial loops (Sutherland & Roth 1973; "
                          "needs at least 0.3)\n  p30        A0-A-B-B0 (RSUR)  0.3976\n"
                          "  minimum 0.3976 at p30"),
            std::string::npos)
      << text.out;
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
  // The mechanism has a transmission loop, the position no index (it does not assemble).
  EXPECT_TRUE(doc["positions"][0]["transmission_loops"].is_array());
  EXPECT_TRUE(doc["positions"][0]["transmission_loops"].empty());
  EXPECT_TRUE(doc["min_loop_transmission_index"].is_null());
}

// The RSSR with a spherical joint at B (an S–S coupler): an idle spin about AB
// (docs/spatial.md §4.1), DOF 2 with one idle, so the crank alone fixes the position (exit 0),
// and the report says so.
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
  const CliResult r = run_cli({"validate", file, "--min-transmission-index", "0.3"});
  ASSERT_EQ(r.status, 0) << r.err << r.out;
  EXPECT_NE(r.out.find("idle degrees of freedom at p30 (held at zero rate): body 'coupler' (1 "
                       "direction)"),
            std::string::npos)
      << r.out;
  const CliResult j = run_cli({"validate", file, "--json", "--min-transmission-index", "0.3"});
  ASSERT_EQ(j.status, 0) << j.err;
  const json doc = json::parse(j.out);
  const json& p = doc["positions"][0];
  EXPECT_EQ(p["transmission_loops"][0]["type"], "RSSR");  // a binary S–S coupler
  EXPECT_EQ(p["dof"], 2);
  ASSERT_EQ(p["idle"].size(), 1u);
  EXPECT_EQ(p["idle"][0]["body"], "coupler");
  EXPECT_EQ(p["idle"][0]["count"], 1);
  EXPECT_GT(p["transmission_index"].get<double>(), 1e-6);  // the spin held: not a dead point
}

// Targets in a spatial file: one met, one missed by 5 mm (the design pose's B moved along z) and
// one with a direction 90° off: exit 1 naming both; the JSON errors in mm and deg.
TEST(SpatialValidateCli, SpatialTargetsMetAndMissed) {
  std::ifstream in(test::bundled_file("rssr"));
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string key = "  - name: p30\n    inputs: {A0: 30}\n";
  const size_t at = text.find(key);
  ASSERT_NE(at, std::string::npos);
  // B at θ = 30° (the file's header: (300, −185.6055, 274.5025) mm, to 1e-4 mm).
  text.replace(at, key.size(),
               "  - {name: met, inputs: {A0: 30}, target: {point: rocker.B, at: [300, -185.6055, "
               "274.5025], tolerance: 0.001}}\n"
               "  - {name: high, inputs: {A0: 30}, target: {point: rocker.B, at: [300, -185.6055, "
               "279.5025], tolerance: 1}}\n"
               "  - {name: tilted, inputs: {A0: 30}, target: {point: rocker.B, at: [300, "
               "-185.6055, 274.5025], direction: {body: [0, 0, 1], world: [0, 1, 0]}}}\n");
  const test::TempDir dir("orthomech_spatial_validate_");
  const std::string file = (dir.path / "rssr-target.yaml").string();
  std::ofstream(file) << text;
  const CliResult r = run_cli({"validate", file, "--min-transmission-index", "0.3"});
  EXPECT_EQ(r.status, 1) << r.err << r.out;
  EXPECT_NE(r.out.find("FAIL high: target missed by 5 mm (tolerance 1 mm)"), std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("FAIL tilted: target direction missed by 90 deg"), std::string::npos)
      << r.out;
  EXPECT_EQ(r.out.find("FAIL met"), std::string::npos) << r.out;
  const CliResult j = run_cli({"validate", file, "--json", "--min-transmission-index", "0.3"});
  ASSERT_EQ(j.status, 1) << j.err;
  const json doc = json::parse(j.out);
  ASSERT_EQ(doc["positions"].size(), 3u);
  const json& met = doc["positions"][0];
  EXPECT_TRUE(met["target_met"].get<bool>());
  EXPECT_LT(met["target_error"].get<double>(), 1e-3);  // mm: the header's 4 decimals
  EXPECT_TRUE(met["target_angle_error"].is_null());
  EXPECT_NEAR(doc["positions"][1]["target_error"].get<double>(), 5.0, 1e-3);
  EXPECT_FALSE(doc["positions"][1]["target_met"].get<bool>());
  // The rocker's z axis is world x (its revolute axis): 90° from world y.
  EXPECT_NEAR(doc["positions"][2]["target_angle_error"].get<double>(), 90.0, 1e-9);
}

}  // namespace
}  // namespace orthomech
