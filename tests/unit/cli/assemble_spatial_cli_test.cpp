// The commands on spatial files (issue 12 item 6): simulate writes every body's pose (origin and
// quaternion) and named points in 3D, reactions with force and moment components, and chart
// names of spatial velocity components; crosscheck passes; assemble locks spatial joints and
// writes the assembled poses (--write); the commands not yet available on spatial mechanisms
// refuse them with exit 2.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "orthomech/constraints/joints.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/model/spatial.hpp"
#include "support/cli_runner.hpp"
#include "support/spatial_oracles.hpp"

namespace orthomech {
namespace {

using nlohmann::json;
using test::CliResult;
using test::run_cli;

// RSSR (docs/spatial.md §4.1): the rocker turns about the world x axis through
// B0 = (300, 0, 200) mm, so its point B keeps x = 300 mm and a constant distance from B0 along any
// motion; every quaternion stays unit.
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

// sweep and optimize run on spatial files (tests/unit/study/spatial_study_test.cpp,
// OptimizeCli.SpatialRssrCrankForARockerSwing); balance does not yet.
TEST(SpatialCli, CommandsNotYetSpatialRefuseWithExitTwo) {
  for (const char* cmd : {"balance"}) {
    const std::vector<std::string> args = {cmd, test::bundled_file("rssr"), "--counterweight",
                                           "crank:50"};
    const CliResult r = run_cli(args);
    EXPECT_EQ(r.status, 2) << cmd << ": " << r.err;
    EXPECT_NE(r.err.find("not available for spatial mechanisms yet"), std::string::npos)
        << cmd << ": " << r.err;
  }
}

// assemble on a spatial file with a lock on a spatial joint's coordinate: exit 0, the rocker at
// (M1) (docs/spatial.md §4.1) on the file's branch, in the file's degrees; limits are bounds (the
// crank limited to [0°, 20°] from its drawn 30° ends at 20°); an unreachable lock is exit 3
// naming it; a joint without a coordinate is exit 2.
TEST(SpatialCli, AssembleLocksSpatialJointsAndHonoursLimits) {
  const std::string rssr = test::bundled_file("rssr");
  auto rocker_deg = [](double theta_deg) {  // (M1), the file's branch
    return test::rssr_rocker_angle(theta_deg * M_PI / 180) * 180 / M_PI;
  };
  auto wrap_deg = [](double a) { return std::remainder(a, 360.0); };
  const CliResult lock = run_cli({"assemble", rssr, "--lock", "A0=90deg", "--json"});
  ASSERT_EQ(lock.status, 0) << lock.err;
  const json j = json::parse(lock.out);
  EXPECT_EQ(j["status"], "assembled");
  EXPECT_EQ(j["locks"][0]["joint"], "A0");
  EXPECT_EQ(j["locks"][0]["unit"], "deg");
  EXPECT_NEAR(j["locks"][0]["value"].get<double>(), 90.0, 1e-12);
  EXPECT_NEAR(wrap_deg(j["measures"]["crank_angle"].get<double>() - 90.0), 0.0, 1e-10);
  EXPECT_NEAR(wrap_deg(j["measures"]["rocker_angle"].get<double>() - rocker_deg(90.0)), 0.0,
              1e-7);  // 1e-9 rad in degrees
  const CliResult text = run_cli({"assemble", rssr, "--lock", "A0=90"});
  EXPECT_EQ(text.status, 0) << text.err;
  EXPECT_NE(text.out.find("lock        A0 = 90 deg"), std::string::npos) << text.out;

  const CliResult lim = run_cli({"assemble", rssr, "--set", "joints.A0.limits=[0, 20]", "--json"});
  ASSERT_EQ(lim.status, 0) << lim.err;
  const json l = json::parse(lim.out);
  EXPECT_NEAR(l["measures"]["crank_angle"].get<double>(), 20.0, 1e-8);
  EXPECT_NEAR(wrap_deg(l["measures"]["rocker_angle"].get<double>() - rocker_deg(20.0)), 0.0, 1e-7);
  const CliResult ok =
      run_cli({"assemble", rssr, "--set", "joints.A0.limits=[0, 20]", "--no-limits", "--json"});
  ASSERT_EQ(ok.status, 0) << ok.err;
  EXPECT_NEAR(json::parse(ok.out)["measures"]["crank_angle"].get<double>(), 30.0, 1e-6);

  const CliResult far = run_cli({"assemble", rssr, "--lock", "B0=90"});
  EXPECT_EQ(far.status, 3) << far.err;
  EXPECT_NE(far.err.find("the mechanism cannot close with joint 'B0' locked at 90 deg"),
            std::string::npos)
      << far.err;
  // A measure's value: the rocker's point B at z = 250 mm (file units), on the file's branch.
  const CliResult bz = run_cli({"assemble", rssr, "--lock", "B_z=250", "--json"});
  ASSERT_EQ(bz.status, 0) << bz.err;
  const json b = json::parse(bz.out);
  EXPECT_EQ(b["locks"][0]["measure"], "B_z");
  EXPECT_EQ(b["locks"][0]["unit"], "mm");
  EXPECT_NEAR(b["measures"]["B_z"].get<double>(), 250.0, 1e-9);
  EXPECT_NEAR(wrap_deg(b["measures"]["rocker_angle"].get<double>() -
                       rocker_deg(b["measures"]["crank_angle"].get<double>())),
              0.0, 1e-7);
  const CliResult unknown = run_cli({"assemble", rssr, "--lock", "Q=1"});
  EXPECT_EQ(unknown.status, 2) << unknown.err;
  EXPECT_NE(unknown.err.find("--lock: joint 'Q' is not defined, nor a measure of that name"),
            std::string::npos)
      << unknown.err;
  const CliResult none = run_cli({"assemble", rssr, "--lock", "A=10"});
  EXPECT_EQ(none.status, 2) << none.err;
  EXPECT_NE(none.err.find("--lock: joint 'A' has no coordinate"), std::string::npos) << none.err;
}

// `assemble --write` on a spatial file, checked against the library: the written file, read back
// by the reader, (a) closes its joints at its design pose (the constraint residual evaluated here,
// ≤ 1e-10), (b) holds the assembled poses of --json (origin in m and R to 1e-12), and (c)
// assembles again without moving (every body ≤ 1e-12). The orientations are written as
// quaternions whatever form the file used.
void check_spatial_write(const std::string& in, const std::filesystem::path& out) {
  const CliResult r = run_cli({"assemble", in, "--write", out.string(), "--json"});
  ASSERT_EQ(r.status, 0) << in << ": " << r.err;
  const json j = json::parse(r.out);
  ASSERT_EQ(j["written"], out.string());
  const Model back = load_mechanism(out.string());
  const double length = back.units.length == "mm" ? 1e-3 : 1.0;
  ASSERT_TRUE(back.units.length == "mm" || back.units.length == "m") << back.units.length;
  // (a) an independent check of the closure: the residual function on the re-read model.
  VecX f = VecX::Zero(back.nc);
  compute_constraint_residual(back, back.design_q(), f);
  EXPECT_LE(f.cwiseAbs().maxCoeff(), 1e-10) << in;
  // (b) the written poses are the assembled ones.
  ASSERT_EQ(j["poses"].size(), back.bodies.size());
  for (size_t b = 0; b < back.bodies.size(); ++b) {
    const json& p = j["poses"][b];
    const SpatialBodyData& s = back.bodies[b].spatial;
    EXPECT_EQ(p["name"], back.bodies[b].name);
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(s.design_position(k),
                  p["position"][static_cast<size_t>(k)].get<double>() * length, 1e-12)
          << in << " " << back.bodies[b].name;
    const Quat e(p["orientation"][0].get<double>(), p["orientation"][1].get<double>(),
                 p["orientation"][2].get<double>(), p["orientation"][3].get<double>());
    EXPECT_LE((rotation_matrix(s.design_orientation) - rotation_matrix(e)).cwiseAbs().maxCoeff(),
              1e-12)
        << in << " " << back.bodies[b].name;
  }
  // `q` of --json: each body's centre of mass (length unit) and unit quaternion (unit-free), as
  // the re-read model's design coordinates.
  const VecX q = back.design_q();
  ASSERT_EQ(j["q"].size(), static_cast<size_t>(q.size()));
  for (const Body& body : back.bodies) {
    const auto at = [&](int k) {
      return j["q"][static_cast<size_t>(body.q_offset + k)].get<double>();
    };
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(at(k) * length, q(body.q_offset + k), 1e-12) << in << " " << body.name;
    const Quat e(at(3), at(4), at(5), at(6));
    EXPECT_NEAR(e.norm(), 1.0, 1e-14) << in << " " << body.name;
    EXPECT_LE((rotation_matrix(e) - rotation_matrix(q.segment<4>(body.q_offset + 3)))
                  .cwiseAbs()
                  .maxCoeff(),
              1e-12)
        << in << " " << body.name;
  }
  // (c) assembling the written file again moves nothing.
  const CliResult again = run_cli({"assemble", out.string(), "--json"});
  ASSERT_EQ(again.status, 0) << again.err;
  const json a = json::parse(again.out);
  for (const json& b : a["bodies"]) {
    EXPECT_LE(b["translation"].get<double>() * length, 1e-12) << out << " " << b["name"];
    EXPECT_LE(b["rotation"].get<double>(), 1e-12) << out << " " << b["name"];
  }
}

TEST(SpatialCli, AssembleWritesTheAssembledPoses) {
  const test::TempDir dir("orthomech_spatial_write_");
  // rssr: axis–angle and two-axes orientations; bennett: two axes; bricard: none (the identity).
  for (const char* name : {"rssr", "bennett", "bricard"})
    check_spatial_write(test::bundled_file(name), dir.path / (std::string(name) + ".yaml"));
  const std::string rssr = test::read_text(dir.path / "rssr.yaml");
  EXPECT_EQ(rssr.find("axis: [0, 0, 1], angle"), std::string::npos) << rssr;
  EXPECT_NE(rssr.find("orientation: {quaternion: ["), std::string::npos) << rssr;
  EXPECT_NE(rssr.find("# rssr.yaml"), std::string::npos);  // comments kept

  // Other forms and layouts: Euler angles in a block mapping (replaced by the quaternion form, the
  // comment kept), a quaternion (its numbers edited), bodies moved off the drawn Bricard with no
  // orientation (the key added, in the flow and the block layout), CRLF line ends.
  std::string text = test::read_text(test::bundled_file("rssr"));
  auto replace = [](std::string& t, const std::string& from, const std::string& to) {
    const auto at = t.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    t.replace(at, from.size(), to);
  };
  replace(text, "pose: {position: [0, 0, 0], orientation: {axis: [0, 0, 1], angle: 30}}",
          "pose:\n      position: [0, 0, 0]\n      orientation:\n        euler: [30, 0, 0]\n"
          "        sequence: zyx   # yaw only");
  replace(text, "orientation: {x: [0, -0.92802728, 0.37251223], z: [1, 0, 0]}",
          "orientation: {quaternion: [0.3960706, -0.5857713, 0.3960706, -0.5857713]}");
  const std::filesystem::path forms = dir.path / "forms.yaml";
  std::ofstream(forms) << text;
  check_spatial_write(forms.string(), dir.path / "forms-out.yaml");
  const std::string written = test::read_text(dir.path / "forms-out.yaml");
  EXPECT_EQ(written.find("euler"), std::string::npos) << written;
  EXPECT_NE(written.find("{quaternion: ["), std::string::npos) << written;
  EXPECT_NE(written.find("# yaw only"), std::string::npos) << written;

  std::string bricard = test::read_text(test::bundled_file("bricard"));
  replace(bricard, "pose: {position: [1, 0, 0]}", "pose: {position: [1.01, 0, 0]}");
  replace(bricard, "pose: {position: [1, -1, 0]}", "pose:\n      position: [1, -1, 0.01]  # moved");
  for (size_t at = bricard.find('\n'); at != std::string::npos; at = bricard.find('\n', at + 2))
    bricard.replace(at, 1, "\r\n");
  const std::filesystem::path moved = dir.path / "moved.yaml";
  std::ofstream(moved, std::ios::binary) << bricard;
  check_spatial_write(moved.string(), dir.path / "moved-out.yaml");
  const std::string m = test::read_text(dir.path / "moved-out.yaml");
  EXPECT_NE(m.find("# moved\r\n      orientation: {quaternion: ["), std::string::npos) << m;
  EXPECT_EQ(std::count(m.begin(), m.end(), '\n'),
            std::count(bricard.begin(), bricard.end(), '\n') + 1);  // the one added line
  for (size_t at = m.find('\n'); at != std::string::npos; at = m.find('\n', at + 1))
    EXPECT_TRUE(at > 0 && m[at - 1] == '\r') << "a bare LF at offset " << at;

  // --in-place on a copy; --write with --set stays refused (the file is written as on disk).
  const std::filesystem::path copy = dir.path / "copy.yaml";
  std::filesystem::copy_file(test::bundled_file("rssr"), copy);
  const CliResult in_place = run_cli({"assemble", copy.string(), "--in-place"});
  EXPECT_EQ(in_place.status, 0) << in_place.err;
  EXPECT_EQ(test::read_text(copy), rssr);
  const CliResult set =
      run_cli({"assemble", test::bundled_file("rssr"), "--set", "joints.A0.limits=[0, 20]",
               "--write", (dir.path / "set.yaml").string()});
  EXPECT_EQ(set.status, 2) << set.err;
  EXPECT_NE(set.err.find("--set cannot be combined with --write"), std::string::npos) << set.err;
  EXPECT_EQ(set.err.find("not available for spatial"), std::string::npos) << set.err;
  EXPECT_FALSE(std::filesystem::exists(dir.path / "set.yaml"));
}

}  // namespace
}  // namespace orthomech
