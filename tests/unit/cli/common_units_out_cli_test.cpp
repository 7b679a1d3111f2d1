// The file's units out of `assemble` and `info` and in the library's messages (issue 11), each
// against a closed form written here:
//   - a particle on a rod drawn too far out projects radially onto the rod's circle: its
//     coordinates, the mass-metric distance √m·Δr and the velocity with its radial part removed;
//   - the crank-rocker with its crank locked at 90°: every coordinate against the closed-form
//     open assembly;
//   - a four-bar too short to close: its gaps (four equal parts of the total) in the file's unit;
//   - the harmonic driver's frequency in 1/(the file's time unit).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "support/cli_runner.hpp"

namespace orthomech {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using test::CliResult;
using test::run_cli;

constexpr double kDeg = std::numbers::pi / 180.0;

struct TempDir : test::TempDir {
  TempDir() : test::TempDir("orthomech_units_out_") {}
};

std::string write(const TempDir& dir, const std::string& name, const std::string& text) {
  const fs::path p = dir.path / name;
  std::ofstream(p) << text;
  return p.string();
}

json run_json(const std::vector<std::string>& args, int expected_status = 0) {
  const CliResult r = run_cli(args);
  EXPECT_EQ(r.status, expected_status) << r.err;
  return r.out.empty() ? json() : json::parse(r.out);
}

// A particle of mass m on a massless rod of length L pinned to the ground at O, drawn at
// distance r0 on the −x axis (a sketch: r0 ≠ L), in the units given.
std::string particle_on_rod(const std::string& units, double m, double L, double r0) {
  return "orthomech: 1\nname: particle-on-rod\nunits: " + units +
         "\nground:\n  points: {O: [0, 0]}\nbodies:\n  - {name: P, type: particle, mass: " +
         std::to_string(m) + ", pose: [" + std::to_string(-r0) +
         ", 0]}\njoints:\n  - {name: rod, type: distance, connects: [ground.O, P.origin], "
         "length: " +
         std::to_string(L) + "}\n";
}

// assemble: the projection in the mass metric of a particle onto the circle |r| = L is radial:
// q = (−L, 0) and the distance √m·|r0 − L|. A velocity guess (vx, vy) loses its radial part vx
// (the rod lies along x): u = (0, vy), kinetic energy removed ½ m vx².
TEST(UnitsOut, AssembleParticleOnARodInTheFileUnits) {
  TempDir dir;
  const double m = 4.0, L = 1000.0, r0 = 1100.0;  // kg, mm
  const std::string mm =
      write(dir, "rod-mm.yaml", particle_on_rod("{length: mm, angle: deg}", m, L, r0));
  const json j = run_json({"assemble", mm, "--json", "--velocity", "P=3,4"});
  EXPECT_EQ(j["status"], "assembled");
  ASSERT_EQ(j["q"].size(), 2u);
  EXPECT_NEAR(j["q"][0].get<double>(), -L, 1e-9);
  EXPECT_NEAR(j["q"][1].get<double>(), 0.0, 1e-9);
  EXPECT_NEAR(j["distance"].get<double>(), std::sqrt(m) * (r0 - L), 1e-9);
  EXPECT_EQ(j["distance_unit"], "sqrt(kg)*mm");
  EXPECT_LE(j["residual_length"].get<double>(), 1e-9);  // mm
  EXPECT_EQ(j["residual_angle"].get<double>(), 0.0);    // no angular row
  EXPECT_NEAR(j["bodies"][0]["translation"].get<double>(), r0 - L, 1e-9);
  const json& u = j["velocities"]["u"];
  EXPECT_NEAR(u[0].get<double>(), 0.0, 1e-12);  // mm/s
  EXPECT_NEAR(u[1].get<double>(), 4.0, 1e-12);
  // ½ m vx² with vx = 3 mm/s: 18 kg*mm²/s² = 18e-6 J = 0.018 N*mm.
  EXPECT_NEAR(j["velocities"]["kinetic_removed"].get<double>(), 0.5 * m * 9.0 * 1e-3, 1e-12);
  EXPECT_EQ(j["units"]["energy"], "N*mm");
  // The same run in SI: metres, √kg·m, m/s.
  const json s = run_json({"assemble", mm, "--json", "--velocity", "P=3,4", "--units", "si"});
  EXPECT_NEAR(s["q"][0].get<double>(), -L * 1e-3, 1e-12);
  EXPECT_NEAR(s["distance"].get<double>(), std::sqrt(m) * (r0 - L) * 1e-3, 1e-12);
  EXPECT_EQ(s["distance_unit"], "sqrt(kg)*m");
  EXPECT_NEAR(s["velocities"]["u"][1].get<double>(), 4e-3, 1e-15);
  // The table says the units.
  const CliResult t = run_cli({"assemble", mm});
  ASSERT_EQ(t.status, 0) << t.err;
  EXPECT_NE(t.out.find("distance    200 sqrt(kg)*mm"), std::string::npos) << t.out;
  EXPECT_NE(t.out.find(" mm, 0 deg"), std::string::npos) << t.out;  // residual: both kinds
}

// info: the projection moved the particle by r0 − L, in the file's unit, and says so.
TEST(UnitsOut, InfoMovedAndResidualInTheFileUnits) {
  TempDir dir;
  const std::string mm =
      write(dir, "rod-mm.yaml", particle_on_rod("{length: mm, angle: deg}", 1.0, 1000.0, 1100.0));
  const json j = run_json({"info", mm, "--json"});
  EXPECT_EQ(j["units"]["length"], "mm");
  EXPECT_NEAR(j["assembly"]["max_translation"].get<double>(), 100.0, 1e-9);
  EXPECT_LE(j["assembly"]["residual_length"].get<double>(), 1e-9);
  EXPECT_EQ(j["assembly"]["residual_angle"].get<double>(), 0.0);
  EXPECT_FALSE(j["assembly"].contains("max_coordinate_change"));  // mixed m and rad: gone
  const json s = run_json({"info", mm, "--json", "--units", "si"});
  EXPECT_NEAR(s["assembly"]["max_translation"].get<double>(), 0.1, 1e-12);
  const CliResult t = run_cli({"info", mm});
  ASSERT_EQ(t.status, 0) << t.err;
  EXPECT_NE(t.out.find("bodies moved up to 100 mm"), std::string::npos) << t.out;
  EXPECT_NE(t.out.find(" mm, 0 deg\n"), std::string::npos) << t.out;  // the residual's units
}

// The crank-rocker (a = 30, b = 80, c = 60 on d = 70 mm) with its crank locked at 90°: A =
// (0, 30); B is where the coupler and rocker circles meet above A B0 on the open assembly
// (the design's). Every coordinate (centres of mass and angles) in mm and deg.
TEST(UnitsOut, AssembleCrankRockerLockedAt90DegreesInTheFileUnits) {
  const double a = 30, b = 80, c = 60, d = 70;
  const double Ax = 0.0, Ay = a;
  const double ex = d - Ax, ey = -Ay, D = std::hypot(ex, ey);  // A → B0
  // B = A + b (cos θ3, sin θ3): the intersection left of the direction A → B0 (counter-clockwise
  // side, B above the ground line).
  const double along = (b * b - c * c + D * D) / (2 * D), across = std::sqrt(b * b - along * along);
  const double Bx = Ax + (along * ex - across * ey) / D, By = Ay + (along * ey + across * ex) / D;
  ASSERT_GT(By, 0.0);
  const double th3 = std::atan2(By - Ay, Bx - Ax), th4 = std::atan2(By, Bx - d);
  const std::vector<double> expected = {0.0,
                                        a / 2,
                                        90.0,
                                        Ax + b / 2 * std::cos(th3),
                                        Ay + b / 2 * std::sin(th3),
                                        th3 / kDeg,
                                        d + c / 2 * std::cos(th4),
                                        c / 2 * std::sin(th4),
                                        th4 / kDeg};
  const std::string file = test::bundled_file("crank-rocker");
  const json j = run_json({"assemble", file, "--lock", "A0=90", "--json"});
  EXPECT_EQ(j["status"], "assembled");
  ASSERT_EQ(j["q"].size(), expected.size());
  for (size_t k = 0; k < expected.size(); ++k)
    EXPECT_NEAR(j["q"][k].get<double>(), expected[k], 1e-9) << "q[" << k << "]";
  EXPECT_LE(j["residual_length"].get<double>(), 1e-9);  // mm
  EXPECT_LE(j["residual_angle"].get<double>(), 1e-9);   // deg (the lock)
  for (const json& jt : j["joints"]) {
    EXPECT_LE(std::abs(jt["rows"]["x"].get<double>()), 1e-9) << jt["name"];
    EXPECT_EQ(jt["residual_angle"].get<double>(), 0.0) << jt["name"];  // revolutes: x, y only
  }
  const json s = run_json({"assemble", file, "--lock", "A0=90", "--json", "--units", "si"});
  for (size_t k = 0; k < expected.size(); ++k)
    EXPECT_NEAR(s["q"][k].get<double>(), expected[k] * (k % 3 == 2 ? kDeg : 1e-3), 1e-12)
        << "q[" << k << "] in SI";
}

// A four-bar with links 1 + 2 + 3 on a 10 ground cannot close: the least-squares pose leaves
// the missing 4 split equally over the four joints (min Σ g_i² subject to Σ g_i = 4). In a mm
// file every gap, the rows and the message are in mm; in an m file in m.
TEST(UnitsOut, CannotCloseGapsInTheFileUnits) {
  TempDir dir;
  auto four_bar = [](const std::string& units, double s) {
    auto n = [&](double v) { return std::to_string(v * s); };
    return "orthomech: 1\nname: short\nunits: " + units +
           "\nground:\n  points: {A0: [0, 0], B0: [" + n(10) +
           ", 0]}\nbodies:\n  - {name: crank, mass: 1, inertia: 0.1, pose: [0, 0, 0.5], " +
           "points: {A0: [0, 0], A: [" + n(1) +
           ", 0]}}\n  - {name: coupler, mass: 1, inertia: 0.1, pose: [" + n(1) +
           ", 0, 0.2], points: {A: [0, 0], B: [" + n(2) +
           ", 0]}}\n  - {name: rocker, mass: 1, inertia: 0.1, pose: [" + n(10) +
           ", 0, 2.5], points: {B0: [0, 0], B: [" + n(3) +
           ", 0]}}\njoints:\n  - {name: A0, type: revolute, connects: [ground.A0, crank.A0]}\n"
           "  - {name: A, type: revolute, connects: [crank.A, coupler.A]}\n"
           "  - {name: B, type: revolute, connects: [coupler.B, rocker.B]}\n"
           "  - {name: B0, type: revolute, connects: [rocker.B0, ground.B0]}\n";
  };
  // The inertias are in kg*(file length)^2; the gaps do not depend on the metric.
  const std::string mm = write(dir, "short-mm.yaml", four_bar("{length: mm, angle: rad}", 1000));
  const std::string m = write(dir, "short-m.yaml", four_bar("{length: m, angle: rad}", 1));
  const CliResult r = run_cli({"assemble", mm, "--json"});
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(r.err.find("joint 'A0' gap 1000 mm"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("total gap 4000 mm"), std::string::npos) << r.err;
  const json j = json::parse(r.out);
  EXPECT_NEAR(j["total_gap"].get<double>(), 4000.0, 1e-3);
  ASSERT_EQ(j["gaps"].size(), 4u);
  for (const json& g : j["gaps"]) {
    EXPECT_NEAR(g["gap"].get<double>(), 1000.0, 1e-3) << g["name"];
    // The rows are the gap's components: √(x² + y²) = gap, in mm.
    EXPECT_NEAR(std::hypot(g["rows"]["x"].get<double>(), g["rows"]["y"].get<double>()), 1000.0,
                1e-3)
        << g["name"];
    EXPECT_NEAR(
        g["residual_length"].get<double>(),
        std::max(std::abs(g["rows"]["x"].get<double>()), std::abs(g["rows"]["y"].get<double>())),
        1e-9);
  }
  const CliResult rm = run_cli({"assemble", m});
  EXPECT_EQ(rm.status, 3);
  EXPECT_NE(rm.err.find("total gap 4 m "), std::string::npos) << rm.err;
  // cycle: the residual left by the failed projection in the file's units, lengths and angles
  // (a four-bar of revolutes has no angular row: 0 rad).
  const std::string driven = write(dir, "short-driven.yaml",
                                   four_bar("{length: mm, angle: rad}", 1000) +
                                       "drivers:\n  - {name: motor, joint: A0, speed: 60 rpm}\n");
  const CliResult c = run_cli({"cycle", driven});
  EXPECT_EQ(c.status, 3);
  EXPECT_NE(c.err.find("does not assemble (residual "), std::string::npos) << c.err;
  EXPECT_NE(c.err.find(" mm, 0 rad)"), std::string::npos) << c.err;
  // info warns with the residual in the same units and still reports (exit 0).
  const CliResult i = run_cli({"info", mm});
  EXPECT_EQ(i.status, 0) << i.err;
  EXPECT_NE(i.err.find("does not assemble ("), std::string::npos) << i.err;
  EXPECT_NE(i.err.find(" mm, 0 rad); mobility"), std::string::npos) << i.err;
}

// A harmonic driver's frequency is in 1/(the file's time unit): "Hz" for seconds. The
// double-rocker rocks at 1 Hz; the same file declared in ms has frequency 0.001 (1/ms).
TEST(UnitsOut, HarmonicFrequencyInTheFileTimeUnit) {
  TempDir dir;
  const std::string file = test::bundled_file("double-rocker");
  const CliResult s = run_cli({"cycle", file, "--steps", "36"});
  ASSERT_EQ(s.status, 0) << s.err;
  EXPECT_NE(s.out.find("about 0 deg, 1 Hz"), std::string::npos) << s.out;
  std::string text = test::read_text(file);
  for (const auto& [from, to] : {std::pair<std::string, std::string>{"time: s", "time: ms"},
                                 {"frequency: 1}", "frequency: 0.001}"}}) {
    const size_t at = text.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    text.replace(at, from.size(), to);
  }
  const std::string ms = write(dir, "double-rocker-ms.yaml", text);
  const CliResult t = run_cli({"cycle", ms, "--steps", "36"});
  ASSERT_EQ(t.status, 0) << t.err;
  EXPECT_NE(t.out.find("about 0 deg, 0.001 1/ms"), std::string::npos) << t.out;
}

}  // namespace
}  // namespace orthomech
