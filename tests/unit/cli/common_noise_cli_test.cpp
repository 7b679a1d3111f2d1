// Rounding noise in what the tool writes (issue 11, item 9): quantities zero by construction
// are written as exactly 0, and nothing is reported for a quantity that is constant up to
// noise. The oracles are the constructions themselves:
//   - the in-line slider-crank: the crank turns at constant speed about its frame's origin (its
//     origin stays at 0, its angular acceleration is 0), the piston slides on the x axis without
//     turning (y, angle, vy, ω, ay, α are 0; the wrist pin stays on y = 0) and the frictionless
//     slide carries no axial force (Fx = 0);
//   - the triple-crank's coupler translates (its angle is constant) and its cranks turn fully:
//     neither has a range or a time ratio;
//   - `assemble --write` of the slider-crank locked at 30°: the closed-form poses, the zeros
//     written as 0;
//   - `simulate`: the residual in the file's units and the chart switches only with -v.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>
#include <string>
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
  TempDir() : test::TempDir("orthomech_noise_") {}
};

std::vector<std::vector<std::string>> read_csv(const fs::path& file) {
  std::ifstream in(file);
  std::vector<std::vector<std::string>> rows;
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> row;
    std::string cell;
    std::istringstream s(line);
    while (std::getline(s, cell, ',')) row.push_back(cell);
    rows.push_back(row);
  }
  return rows;
}

// The columns of the slider-crank that are zero by construction (see the top of the file).
const std::vector<std::string> kZeroColumns = {
    "crank.x [mm]",     "crank.y [mm]",         "crank.O.x [mm]",     "crank.O.y [mm]",
    "piston.y [mm]",    "piston.angle [deg]",   "rod.B.y [mm]",       "piston.B.y [mm]",
    "piston.vy [mm/s]", "piston.omega [deg/s]", "piston.ay [mm/s^2]", "piston.alpha [deg/s^2]",
    "slide.Fx [N]",     "crank.alpha [deg/s^2]"};

TEST(Noise, CycleCsvAndJsonWriteZeroByConstructionAsZero) {
  TempDir dir;
  const CliResult r = run_cli({"cycle", test::bundled_file("slider-crank"), "--out",
                               dir.path.string(), "--json", "--positions"});
  ASSERT_EQ(r.status, 0) << r.err;
  const auto rows = read_csv(dir.path / "cycle.csv");
  ASSERT_GT(rows.size(), 300u);
  for (const std::string& name : kZeroColumns) {
    const auto it = std::find(rows[0].begin(), rows[0].end(), name);
    ASSERT_NE(it, rows[0].end()) << name;
    const size_t c = static_cast<size_t>(it - rows[0].begin());
    for (size_t k = 1; k < rows.size(); ++k) ASSERT_EQ(rows[k][c], "0") << name << " row " << k;
  }
  // A column that is not zero keeps its values (the piston's x velocity).
  const size_t vx = static_cast<size_t>(
      std::find(rows[0].begin(), rows[0].end(), "piston.vx [mm/s]") - rows[0].begin());
  ASSERT_LT(vx, rows[0].size());
  EXPECT_NE(rows[10][vx], "0");
  const json j = json::parse(r.out);
  for (const char* key : {"peak", "rms"}) EXPECT_EQ(j["peaks"]["slide.Fx"][key].get<double>(), 0.0);
  EXPECT_EQ(j["peaks"]["slide.Fx"]["max"]["value"].get<double>(), 0.0);
  EXPECT_EQ(j["peaks"]["slide.Fx"]["min"]["value"].get<double>(), 0.0);
  for (const json& p : j["points"]) {
    EXPECT_EQ(p["poses"]["piston"][1].get<double>(), 0.0);
    EXPECT_EQ(p["poses"]["piston"][2].get<double>(), 0.0);
    EXPECT_EQ(p["poses"]["crank"][0].get<double>(), 0.0);
    EXPECT_EQ(p["bodies"]["piston"]["velocity"][1].get<double>(), 0.0);
    EXPECT_EQ(p["bodies"]["piston"]["acceleration"][2].get<double>(), 0.0);
    EXPECT_EQ(p["bodies"]["crank"]["acceleration"][2].get<double>(), 0.0);
    EXPECT_EQ(p["reactions"]["slide.Fx"].get<double>(), 0.0);
  }
}

TEST(Noise, NoRangeForAConstantOrFullyTurningMeasure) {
  const CliResult r = run_cli({"cycle", test::bundled_file("triple-crank"), "--json"});
  ASSERT_EQ(r.status, 0) << r.err;
  const json j = json::parse(r.out);
  std::vector<std::string> names;
  for (const json& s : j["strokes"]) names.push_back(s["name"].get<std::string>());
  for (const char* absent : {"coupler_angle", "crank2_angle", "crank3_angle"})
    EXPECT_EQ(std::count(names.begin(), names.end(), absent), 0) << absent;
  // The coupler's tip moves on a circle of radius 50 mm: x and y range over ±50 mm.
  for (const json& s : j["strokes"]) {
    if (s["name"] == "coupler_x" || s["name"] == "coupler_y") {
      EXPECT_NEAR(s["range"].get<double>(), 100.0, 1e-3) << s["name"];
    }
  }
  // Only gravity does work on the triple-crank: over a full turn ∮ P dt = ΔV = 0, so the mean
  // drive power is 0 (not its rounding noise, 1e-13 of the peak).
  EXPECT_EQ(j["power"]["mean"].get<double>(), 0.0);
  EXPECT_GT(j["power"]["peak"].get<double>(), 1000.0);  // 0.1349 N*m * 300 rpm in N*mm/s
  const CliResult t = run_cli({"cycle", test::bundled_file("triple-crank")});
  EXPECT_EQ(t.out.find("range  coupler_angle"), std::string::npos) << t.out;
  EXPECT_NE(t.out.find("range  coupler_x"), std::string::npos) << t.out;
}

// The slider-crank (r = 50, l = 200 mm, in line) locked at θ = 30°: crank frame at the pivot,
// angle 30; rod frame at A = r (cos θ, sin θ), angle −asin(r sin θ / l); piston frame at
// x = r cos θ + √(l² − r² sin² θ), y = 0, angle 0.
TEST(Noise, AssembleWriteWritesNoRoundingNoise) {
  TempDir dir;
  const fs::path out = dir.path / "sc30.yaml";
  const CliResult r = run_cli(
      {"assemble", test::bundled_file("slider-crank"), "--lock", "O=30", "--write", out.string()});
  ASSERT_EQ(r.status, 0) << r.err;
  const double rr = 50, l = 200, th = 30 * kDeg;
  const double x = rr * std::cos(th) + std::sqrt(l * l - rr * rr * std::sin(th) * std::sin(th));
  std::vector<std::vector<double>> poses;
  std::vector<std::string> texts;
  std::ifstream in(out);
  for (std::string line; std::getline(in, line);) {
    const size_t at = line.find("pose: [");
    if (at == std::string::npos || line.find('#') < at) continue;
    const std::string inner = line.substr(at + 7, line.find(']', at) - at - 7);
    texts.push_back(inner);
    std::vector<double> v;
    std::istringstream s(inner);
    for (std::string item; std::getline(s, item, ',');) v.push_back(std::stod(item));
    poses.push_back(v);
  }
  ASSERT_EQ(poses.size(), 3u);
  EXPECT_EQ(texts[0], "0, 0, 30");  // the crank: origin at the pivot, exactly 30°
  EXPECT_NEAR(poses[1][0], rr * std::cos(th), 1e-9);
  EXPECT_NEAR(poses[1][1], rr * std::sin(th), 1e-9);
  EXPECT_NEAR(poses[1][2], -std::asin(rr * std::sin(th) / l) / kDeg, 1e-9);
  EXPECT_NEAR(poses[2][0], x, 1e-9);
  const std::string piston_tail = texts[2].substr(texts[2].find(','));
  EXPECT_EQ(piston_tail, ", 0, 0");  // y and angle zero by construction: written as 0
  // At most 15 significant digits anywhere.
  for (const std::string& t : texts) {
    std::istringstream s(t);
    for (std::string item; std::getline(s, item, ',');) {
      const size_t digits = static_cast<size_t>(
          std::count_if(item.begin(), item.end(), [](char c) { return c >= '0' && c <= '9'; }));
      EXPECT_LE(digits, 16u) << item;  // 15 significant, plus a leading 0 of "0.x"
    }
  }
}

TEST(Noise, SimulateResidualInTheFileUnitsChartSwitchesWithVerbose) {
  TempDir dir;
  const std::string file = test::bundled_file("slider-crank");
  const CliResult r = run_cli({"simulate", file, "--t-end", "0.005", "--out", dir.path.string()});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find(" mm (length rows), "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(" deg (angular rows)"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("m or rad"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("chart switches"), std::string::npos) << r.out;
  const CliResult v = run_cli({"simulate", file, "--t-end", "0.005", "-v"});
  EXPECT_NE(v.err.find("chart switches"), std::string::npos) << v.err;
  const auto rows = read_csv(dir.path / "simulate.csv");
  const auto& head = rows[0];
  EXPECT_EQ(head[head.size() - 2], "residual_length [mm]");
  EXPECT_EQ(head.back(), "residual_angle [deg]");
  for (const char* name : {"piston.y [mm]", "piston.angle [deg]", "slide.Fx [N]"}) {
    const size_t c = static_cast<size_t>(std::find(head.begin(), head.end(), name) - head.begin());
    ASSERT_LT(c, head.size()) << name;
    for (size_t k = 1; k < rows.size(); ++k) EXPECT_EQ(rows[k][c], "0") << name << " row " << k;
  }
}

TEST(Noise, AssembleTableColumnsFitTheirNames) {
  TempDir dir;
  // The crank-rocker with a measure whose name is longer than any column width.
  std::string text = test::read_text(test::bundled_file("crank-rocker"));
  const std::string from = "  - {name: crank_angle, type: joint, joint: A0}";
  const size_t at = text.find(from);
  ASSERT_NE(at, std::string::npos);
  text.insert(at, "  - {name: a_rather_long_measure_name_for_the_table, type: joint, joint: B0}\n");
  const fs::path file = dir.path / "long.yaml";
  std::ofstream(file) << text;
  const CliResult r = run_cli({"assemble", file.string()});
  ASSERT_EQ(r.status, 0) << r.err;
  // Every measure line: the value starts in the same column, after the longest name.
  std::istringstream s(r.out.substr(r.out.find("  measure")));
  std::string line;
  std::getline(s, line);
  const size_t value_col = line.find("value");
  ASSERT_NE(value_col, std::string::npos);
  EXPECT_GE(value_col, std::string("  a_rather_long_measure_name_for_the_table  ").size());
  int measures = 0;
  while (std::getline(s, line) && !line.empty()) {
    ++measures;
    EXPECT_EQ(line[value_col - 1], ' ') << line;
    EXPECT_NE(line[value_col], ' ') << line;
  }
  EXPECT_EQ(measures, 9);  // the crank-rocker's 8 position and velocity measures and the new one
}

}  // namespace
}  // namespace orthomech
