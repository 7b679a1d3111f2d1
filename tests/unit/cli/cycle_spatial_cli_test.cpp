// `orthomech cycle` on spatial files (issue 13 item 1): the table, JSON and CSV (the pictures:
// render_spatial_cli_test.cpp).
// The numbers themselves are checked against closed forms in analysis/cycle_spatial_test.cpp;
// here the CLI's outputs agree with each other and with the library's determinacy.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "support/cli_runner.hpp"

namespace orthomech {
namespace {

using nlohmann::json;
using test::CliResult;
using test::run_cli;

TEST(SpatialCycleCli, RssrPrintsTheDriveAndEveryJointsForceAndMoment) {
  const CliResult r = run_cli({"cycle", test::bundled_file("rssr")});
  ASSERT_EQ(r.status, 0) << r.err;
  for (const char* row :
       {"drive", "A0.|F|", "A0.|M|", "A.|F|", "B.|F|", "B.|M|", "B0.|F|", "B0.|M|"})
    EXPECT_NE(r.out.find(std::string("\n") + row + " "), std::string::npos) << row << "\n" << r.out;
  EXPECT_EQ(r.out.find("indeterminate"), std::string::npos) << "RSSR has no redundancy";
}

TEST(SpatialCycleCli, CrankRocker3dNamesTheOutOfPlaneComponentsIndeterminate) {
  const CliResult r = run_cli({"cycle", test::bundled_file("crank-rocker-3d"), "--json"});
  ASSERT_EQ(r.status, 0) << r.err;
  const json j = json::parse(r.out);
  std::map<std::string, bool> det;
  for (const json& c : j["components"]) det[c["name"].get<std::string>()] = c["determinate"];
  for (const char* jt : {"A0", "A", "B", "B0"}) {
    const std::string p = std::string(jt) + ".";
    EXPECT_TRUE(det.at(p + "Fx")) << jt;
    EXPECT_TRUE(det.at(p + "Fy")) << jt;
    EXPECT_FALSE(det.at(p + "Fz")) << jt;
    EXPECT_FALSE(det.at(p + "Mx")) << jt;
    EXPECT_FALSE(det.at(p + "My")) << jt;
  }
}

TEST(SpatialCycleCli, JsonPositionsAndCsvCarryTheSpatialPosesAndVelocities) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / "orthomech_spatial_cycle_cli";
  std::filesystem::remove_all(dir);
  const CliResult r = run_cli({"cycle", test::bundled_file("rssr"), "--steps", "12", "--json",
                               "--positions", "--units", "si", "--out", dir.string()});
  ASSERT_EQ(r.status, 0) << r.err;
  const json j = json::parse(r.out);
  ASSERT_EQ(j["points"].size(), 12u);
  const json& p = j["points"][3];
  ASSERT_EQ(p["poses"]["coupler"].size(), 7u);  // x, y, z, e0 … e3
  double norm = 0.0;
  for (int k = 3; k < 7; ++k) norm += std::pow(p["poses"]["coupler"][k].get<double>(), 2);
  EXPECT_NEAR(norm, 1.0, 1e-12);
  ASSERT_EQ(p["named_points"]["rocker.B"].size(), 3u);
  EXPECT_NEAR(p["named_points"]["rocker.B"][2].get<double>(), p["measures"]["B_z"].get<double>(),
              1e-12);
  ASSERT_EQ(p["bodies"]["crank"]["velocity"].size(), 6u);
  // The crank turns about z at 60 rpm: its body-frame ω is (0, 0, 2π) rad/s.
  EXPECT_NEAR(p["bodies"]["crank"]["velocity"][5].get<double>(), 2 * M_PI, 1e-12);
  std::ifstream csv(dir / "cycle.csv");
  std::string header;
  std::getline(csv, header);
  for (const char* col : {"coupler.e3 [1]", "rocker.B.z [m]", "crank.wz [rad/s]",
                          "coupler.alpha_y [rad/s^2]", "B0.Mx [N*m]", "A.Fh [N]", "B0.|M| [N*m]"})
    EXPECT_NE(header.find(col), std::string::npos) << col << "\n" << header;
  int rows = 0;
  for (std::string line; std::getline(csv, line);) ++rows;
  EXPECT_EQ(rows, 12);
}

// Several drivers: `cycle --drivers` sweeps the Stewart platform's six legs over one period; the
// JSON's leg lengths are the harmonic laws (the closed-form IK is checked in
// analysis/multi_drive_test.cpp); a wrong driver name is exit 2.
TEST(SpatialCycleCli, SeveralDriversSweepTheStewartPlatform) {
  const std::string file = test::bundled_file("stewart-platform");
  const CliResult r =
      run_cli({"cycle", file, "--drivers", "L1,L2,L3,L4,L5,L6", "--steps", "9", "--json"});
  ASSERT_EQ(r.status, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j["status"], "completed");
  EXPECT_EQ(j["dof"], 6);
  ASSERT_EQ(j["points"].size(), 9u);
  const json& p = j["points"][2];  // t = 0.5 s: sin(2π·0.5·0.5) = 1
  EXPECT_NEAR(p["time"].get<double>(), 0.5, 1e-12);
  EXPECT_NEAR(p["inputs"]["L3"].get<double>() - j["points"][0]["inputs"]["L3"].get<double>(), 0.05,
              1e-12);
  EXPECT_TRUE(p["drives"].contains("L6"));
  EXPECT_TRUE(p["reactions"].contains("S1.Fz"));
  const CliResult bad = run_cli({"cycle", file, "--drivers", "L1,L9"});
  EXPECT_EQ(bad.status, 2) << bad.err;
  EXPECT_NE(bad.err.find("'L9' is not a driver"), std::string::npos) << bad.err;
}

}  // namespace
}  // namespace orthomech
