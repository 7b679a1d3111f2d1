// The commands on spatial files (issue 12 item 6): simulate writes every body's pose (origin and
// quaternion) and named points in 3D, reactions with force and moment components, and chart
// names of spatial velocity components; crosscheck passes; the commands not yet available on
// spatial mechanisms refuse them with exit 2.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "support/cli_runner.hpp"

namespace orthomech {
namespace {

using nlohmann::json;
using test::CliResult;
using test::run_cli;

// RSSR (spatial.md §4.1): the rocker turns about the world x axis through B0 = (300, 0, 200) mm,
// so its point B keeps x = 300 mm and a constant distance from B0 along any motion; every
// quaternion stays unit.
TEST(SpatialCli, SimulateWritesPosesAndPointsIn3d) {
  const CliResult r = run_cli({"simulate", test::bundled_file("rssr"), "--t-end", "0.5", "--rtol",
                               "1e-11", "--positions", "--json", "-v"});
  ASSERT_EQ(r.status, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j["status"], "completed");
  const json& p = j["samples"]["positions"];
  const auto& bx = p["rocker.B.x"];
  const auto& by = p["rocker.B.y"];
  const auto& bz = p["rocker.B.z"];
  ASSERT_GT(bx.size(), 10u);
  double lo = 1e300, hi = -1e300;
  for (size_t k = 0; k < bx.size(); ++k) {
    EXPECT_NEAR(bx[k].get<double>(), 300.0, 1e-9);
    const double d = std::hypot(by[k].get<double>(), bz[k].get<double>() - 200.0);
    lo = std::min(lo, d);
    hi = std::max(hi, d);
  }
  EXPECT_LT(hi - lo, 1e-7);      // outputs between steps: the integrator's dense output
  EXPECT_NEAR(lo, 200.0, 1e-5);  // the file's 8-digit axes
  for (const char* body : {"crank", "coupler", "rocker"}) {
    const std::string b(body);
    for (size_t k = 0; k < bx.size(); ++k) {
      double n2 = 0.0;
      for (const char* c : {".e0", ".e1", ".e2", ".e3"}) {
        const double e = p[b + c][k].get<double>();
        n2 += e * e;
      }
      EXPECT_NEAR(n2, 1.0, 1e-12) << body;
    }
  }
  // Reactions: force and moment, world and joint frame.
  for (const char* c : {"A0.Fx", "A0.Fz", "A0.Mx", "A0.Mh", "B.Ff", "B.Mg"})
    EXPECT_TRUE(j["samples"]["reactions"].contains(c)) << c;
  // Chart switches name spatial velocity components (vx … wz), never planar ones.
  for (const auto& sw : j["chart_switches"]) {
    const std::string to = sw["to"];
    EXPECT_EQ(to.find(".phi"), std::string::npos) << to;
    EXPECT_EQ(to.find(".ay"), std::string::npos) << to;
  }
}

TEST(SpatialCli, CrosscheckPassesOnTheSpatialFiles) {
  for (const char* f : {"rssr", "bricard", "hooke-joint", "heavy-top", "crank-rocker-3d"}) {
    const CliResult r = run_cli({"crosscheck", test::bundled_file(f), "--json"});
    EXPECT_EQ(r.status, 0) << f << ": " << r.err;
    EXPECT_TRUE(json::parse(r.out)["pass"].get<bool>()) << f;
  }
}

// A rod held by spherical joints at both ends can only spin about the line through them: DOF 1,
// one redundant row, and `info` says the DOF is idle.
TEST(SpatialCli, InfoReportsAnIdleDegreeOfFreedom) {
  const test::TempDir dir("orthomech_idle_");
  const std::string file = (dir.path / "rod.yaml").string();
  {
    std::ofstream out(file);
    out << "orthomech: 1\ndimension: 3\nname: rod\n"
           "units: {length: m, angle: deg, mass: kg, time: s, force: N}\n"
           "ground:\n  points: {A: [0, 0, 0], B: [0.4, 0.3, 0.5]}\n"
           "bodies:\n  - name: rod\n    mass: 1\n    inertia: [0.01, 0.01, 0.001]\n"
           "    pose: {position: [0, 0, 0]}\n    points: {A: [0, 0, 0], B: [0.4, 0.3, 0.5]}\n"
           "joints:\n  - {name: A, type: spherical, connects: [ground.A, rod.A]}\n"
           "  - {name: B, type: spherical, connects: [ground.B, rod.B]}\n";
  }
  const CliResult r = run_cli({"info", file, "--json"});
  ASSERT_EQ(r.status, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j["dof"], 1);
  EXPECT_EQ(j["redundant"].size(), 1u);
  ASSERT_EQ(j["idle"].size(), 1u);
  EXPECT_EQ(j["idle"][0]["body"], "rod");
  EXPECT_EQ(j["idle"][0]["count"], 1);
  const CliResult text = run_cli({"info", file});
  EXPECT_NE(text.out.find("idle          body 'rod' can move alone (1 direction"),
            std::string::npos)
      << text.out;
}

TEST(SpatialCli, CommandsNotYetSpatialRefuseWithExitTwo) {
  for (const char* cmd : {"sweep"}) {  // render draws spatial files now (spatial_pictures_cli)
    std::vector<std::string> args = {cmd, test::bundled_file("rssr")};
    if (std::string(cmd) == "sweep")
      args.insert(args.end(), {"--study", "/tmp/never.yaml", "--out", "/tmp/never-sweep"});
    const CliResult r = run_cli(args);
    EXPECT_EQ(r.status, 2) << cmd << ": " << r.err;
    EXPECT_NE(r.err.find("not available for spatial mechanisms yet"), std::string::npos)
        << cmd << ": " << r.err;
  }
}

// assemble on a spatial file: locks and limits are not available yet: exit 2 naming the joint
// (not an internal error), and --no-limits assembles.
TEST(SpatialCli, AssembleRefusesSpatialLocksAndLimitsWithExitTwo) {
  const std::string rssr = test::bundled_file("rssr");
  const CliResult lim = run_cli({"assemble", rssr, "--set", "joints.A0.limits=[0, 90]"});
  EXPECT_EQ(lim.status, 2) << lim.err;
  EXPECT_NE(lim.err.find("joint 'A0': limits on spatial joints are not available"),
            std::string::npos)
      << lim.err;
  const CliResult ok =
      run_cli({"assemble", rssr, "--set", "joints.A0.limits=[0, 90]", "--no-limits", "--json"});
  EXPECT_EQ(ok.status, 0) << ok.err;
  const CliResult lock = run_cli({"assemble", rssr, "--lock", "A0=40"});
  EXPECT_EQ(lock.status, 2) << lock.err;
  EXPECT_NE(lock.err.find("locks on spatial joints are not available yet"), std::string::npos)
      << lock.err;
  const test::TempDir dir("orthomech_spatial_write_");
  const CliResult write = run_cli({"assemble", rssr, "--write", (dir.path / "out.yaml").string()});
  EXPECT_EQ(write.status, 2) << write.err;
  EXPECT_NE(write.err.find("not available for spatial mechanisms yet"), std::string::npos)
      << write.err;
  EXPECT_FALSE(std::filesystem::exists(dir.path / "out.yaml"));
}

}  // namespace
}  // namespace orthomech
