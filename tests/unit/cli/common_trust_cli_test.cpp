// A designer's trust (issue 11), through the command line, each against an independent oracle:
//   - bare numbers on the command line are in the file's declared units (the same mechanism
//     written in mm/deg and in m/rad, tests/data/units/);
//   - a table over the crank angle wraps with the turn (the press swept from 0° and from 250°
//     gives the same drive RMS); `wrap: false` keys it on the unwrapped angle;
//   - a gravity far from 9.81 m/s² after conversion warns;
//   - outputs in the file's units by default, SI with --units si (the mm/deg file against its
//     SI twin);
//   - signed max/min of the drive and every reaction component against the listed positions;
//   - design metrics against closed forms (transmission and pressure angles, strokes, time
//     ratio, energy fluctuation against the energies T + V);
//   - body poses and named points in the CSV and JSON against the closed-form crank;
//   - joints leaving their limits flagged where the rocker angle says so.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>
#include <string>
#include <tuple>
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

std::string bundled(const std::string& name) { return test::bundled_file(name); }
std::string units_data(const std::string& name) {
  return std::string(ORTHOMECH_SOURCE_DIR) + "/tests/data/units/" + name + ".yaml";
}

// A fresh output directory (test::TempDir), removed at the end of the test.
struct TempDir : test::TempDir {
  TempDir() : test::TempDir("orthomech_trust_") {}
};

// A copy of `file` with `from` replaced by `to` (once), written into dir.
std::string variant(const TempDir& dir, const std::string& file, const std::string& name,
                    const std::string& from, const std::string& to) {
  std::string text = test::read_text(file);
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  const fs::path out = dir.path / name;
  std::ofstream(out) << text;
  return out.string();
}

json run_json(const std::vector<std::string>& args, int expected_status = 0) {
  const CliResult r = run_cli(args);
  EXPECT_EQ(r.status, expected_status) << r.err;
  return r.out.empty() ? json() : json::parse(r.out);
}

std::vector<std::vector<std::string>> read_csv(const fs::path& file) {
  std::ifstream in(file);
  std::vector<std::vector<std::string>> rows;
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> row;
    std::string cell;
    std::istringstream s(line);
    while (std::getline(s, cell, ',')) row.push_back(cell);
    if (!line.empty() && line.back() == ',') row.emplace_back();
    rows.push_back(row);
  }
  return rows;
}
size_t column(const std::vector<std::string>& head, const std::string& name) {
  const auto it = std::find(head.begin(), head.end(), name);
  EXPECT_NE(it, head.end()) << "no column " << name;
  return static_cast<size_t>(it - head.begin());
}

// Relative agreement of results that went through two unit systems: rounding of the
// conversions and of the solver's stopping tests, far below any engineering meaning.
constexpr double kUnitsRel = 1e-9;
void expect_rel(double a, double b, double rel, const std::string& what) {
  EXPECT_NEAR(a, b, rel * std::max({std::abs(a), std::abs(b), 1e-300})) << what;
}

// ---- item 1: no silent misreadings ---------------------------------------------------------

TEST(Trust, BareNumbersOnTheCommandLineAreInTheFileUnits) {
  // `--from 90` in the deg file is 90°, in the rad file 90 rad would be something else: the rad
  // file gets π/2. Both must start at the same position (the crank at 90°).
  const json mm = run_json(
      {"cycle", bundled("crank-rocker"), "--from", "90", "--steps", "36", "--json", "--positions"});
  const json si = run_json({"cycle", units_data("crank-rocker-si"), "--from", "1.5707963267948966",
                            "--steps", "36", "--json", "--positions"});
  ASSERT_FALSE(mm["points"].empty());
  ASSERT_FALSE(si["points"].empty());
  EXPECT_NEAR(mm["points"][0]["input"].get<double>(), 90.0, 1e-9);
  EXPECT_NEAR(si["points"][0]["input"].get<double>(), std::numbers::pi / 2, 1e-12);
  expect_rel(mm["points"][0]["measures"]["rocker_angle"].get<double>() * kDeg,
             si["points"][0]["measures"]["rocker_angle"].get<double>(), kUnitsRel, "rocker");
  // A bare speed is the file's angle unit per time unit: 1800 deg/s = 300 rpm.
  const json fast =
      run_json({"cycle", bundled("crank-rocker"), "--speed", "1800", "--steps", "12", "--json"});
  EXPECT_NEAR(fast["driver"]["speed"].get<double>(), 1800.0, 1e-9);
  EXPECT_EQ(fast["driver"]["speed_unit"], "deg/s");
  // --help says so.
  const CliResult help = run_cli({"cycle", "--help"});
  EXPECT_NE(help.out.find("file's declared units"), std::string::npos) << help.out;
}

TEST(Trust, TableOverTheCrankAngleWrapsWithTheTurn) {
  // The press's process force is a table over crank angles [0°, 360°]. Swept from 0° and from
  // 250°, the same 360 crank angles are visited: the drive RMS must agree (1e-9 relative: the
  // sum of the same squares in another order).
  const json a = run_json({"cycle", units_data("press"), "--json"});
  const json b = run_json({"cycle", units_data("press"), "--from", "250", "--json"});
  const double rms_a = a["peaks"]["drive"]["rms"].get<double>();
  const double rms_b = b["peaks"]["drive"]["rms"].get<double>();
  expect_rel(rms_a, rms_b, 1e-9, "drive RMS from 0 and from 250 deg");
  // The oracle can fail: without wrapping, the sweep from 250° leaves the table after 360° and
  // the force stops acting.
  TempDir dir;
  const std::string no_wrap = variant(dir, units_data("press"), "no-wrap.yaml",
                                      "[220, 0], [360, 0]]}", "[220, 0], [360, 0]], wrap: false}");
  const json c = run_json({"cycle", no_wrap, "--from", "250", "--json"});
  EXPECT_GT(std::abs(c["peaks"]["drive"]["rms"].get<double>() - rms_a), 0.1 * rms_a);
}

TEST(Trust, ALoadActsOnlyWhileAMeasureMovesTheGivenWay) {
  // The process force with `active_while: {measure: ram_x, velocity: negative}` must give, at
  // every position, the drive of the always-acting force where the ram moves toward the crank
  // (ram_v < 0) and the drive without the force elsewhere.
  TempDir dir;
  const std::string file = units_data("press");
  const std::string with_v =
      variant(dir, file, "v.yaml", "  - {name: ram_x, type: joint, joint: slide}",
              "  - {name: ram_x, type: joint, joint: slide}\n"
              "  - {name: ram_v, type: joint, joint: slide, derivative: 1}");
  const std::string down = variant(dir, with_v, "down.yaml", "    table: {measure: crank_angle",
                                   "    active_while: {measure: ram_x, velocity: negative}\n"
                                   "    table: {measure: crank_angle");
  const std::string none = variant(dir, with_v, "none.yaml", "force: [-5000, 0]", "force: [0, 0]");
  const json a = run_json({"cycle", down, "--json", "--positions"});
  const json b = run_json({"cycle", with_v, "--json", "--positions"});
  const json c = run_json({"cycle", none, "--json", "--positions"});
  ASSERT_EQ(a["points"].size(), b["points"].size());
  ASSERT_EQ(a["points"].size(), c["points"].size());
  int acting = 0, differs = 0;
  for (size_t k = 0; k < a["points"].size(); ++k) {
    const double v = a["points"][k]["measures"]["ram_v"].get<double>();
    const json& expected = v < 0.0 ? b["points"][k] : c["points"][k];
    const double d = a["points"][k]["drive"].get<double>();
    EXPECT_NEAR(d, expected["drive"].get<double>(), 1e-9 * (1.0 + std::abs(d))) << k;
    acting += v < 0.0;
    differs += std::abs(b["points"][k]["drive"].get<double>() -
                        c["points"][k]["drive"].get<double>()) > 1.0;
  }
  EXPECT_GT(acting, 100);
  EXPECT_GT(differs, 20);  // the force matters on both sides of the switch
}

TEST(Trust, TableAndConditionKeysAreChecked) {
  TempDir dir;
  const std::string file = units_data("press");
  const std::string bad_sign =
      variant(dir, file, "bad-sign.yaml", "    table: {measure: crank_angle",
              "    active_while: {measure: ram_x, velocity: down}\n"
              "    table: {measure: crank_angle");
  const CliResult a = run_cli({"info", bad_sign});
  EXPECT_EQ(a.status, 2);
  EXPECT_NE(a.err.find("error: load 'process': velocity must be 'positive' or 'negative', got "
                       "'down'"),
            std::string::npos)
      << a.err;
  const std::string long_table =
      variant(dir, file, "long.yaml", "[220, 0], [360, 0]]}", "[220, 0], [400, 0]]}");
  const CliResult b = run_cli({"info", long_table});
  EXPECT_EQ(b.status, 2);
  EXPECT_NE(b.err.find("spans more than one turn"), std::string::npos) << b.err;
  const std::string unwrapped = variant(dir, file, "unwrapped.yaml", "[220, 0], [360, 0]]}",
                                        "[220, 0], [400, 0]], wrap: false}");
  EXPECT_EQ(run_cli({"info", unwrapped}).status, 0);
}

TEST(Trust, GravityFarFromTheEarthsWarns) {
  TempDir dir;
  // 9.81 in a mm file is 0.00981 m/s²: a unit slip, said on stderr (the file still loads).
  const std::string slip =
      variant(dir, bundled("crank-rocker"), "slip.yaml", "g: [0, -9810]", "g: [0, -9.81]");
  const CliResult r = run_cli({"info", slip});
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("warning: load 'weight'"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("far from 9.81 m/s^2"), std::string::npos) << r.err;
  const CliResult ok = run_cli({"info", bundled("crank-rocker")});
  EXPECT_EQ(ok.err.find("far from"), std::string::npos) << ok.err;
}

// ---- item 2: units out ---------------------------------------------------------------------

TEST(Trust, CycleOutputsAreInTheFileUnitsAndInSiOnRequest) {
  const json mm = run_json({"cycle", bundled("crank-rocker"), "--steps", "36", "--json",
                            "--positions", "--speed-fluctuation", "0.05"});
  const json si = run_json({"cycle", units_data("crank-rocker-si"), "--steps", "36", "--json",
                            "--positions", "--speed-fluctuation", "0.05"});
  const json mm_si = run_json({"cycle", bundled("crank-rocker"), "--steps", "36", "--json",
                               "--positions", "--speed-fluctuation", "0.05", "--units", "si"});
  EXPECT_EQ(mm["units"]["length"], "mm");
  EXPECT_EQ(mm["units"]["angle"], "deg");
  EXPECT_EQ(mm["units"]["moment"], "N*mm");
  EXPECT_EQ(si["units"]["length"], "m");
  EXPECT_EQ(mm_si["units"], si["units"]);
  EXPECT_EQ(mm["peaks"]["drive"]["unit"], "N*mm");
  // The mm/deg file's numbers, converted, equal the SI file's; --units si gives them directly.
  const double mmf = 1e-3;
  for (const char* s : {"drive", "A0.|F|", "B.Fx", "B0.Fy_local"}) {
    const double to_si = std::string(s) == "drive" ? mmf : 1.0;  // N*mm → N*m; N stays
    for (const char* k : {"rms", "peak"}) {
      expect_rel(mm["peaks"][s][k].get<double>() * to_si, si["peaks"][s][k].get<double>(),
                 kUnitsRel, std::string(s) + "." + k);
      expect_rel(mm_si["peaks"][s][k].get<double>(), si["peaks"][s][k].get<double>(), kUnitsRel,
                 std::string(s) + "." + k + " (--units si)");
    }
    expect_rel(mm["peaks"][s]["max"]["input"].get<double>() * kDeg,
               si["peaks"][s]["max"]["input"].get<double>(), kUnitsRel, "input of max");
  }
  expect_rel(mm["power"]["peak"].get<double>() * mmf, si["power"]["peak"].get<double>(), kUnitsRel,
             "power");
  expect_rel(mm["energy_fluctuation"]["value"].get<double>() * mmf,
             si["energy_fluctuation"]["value"].get<double>(), kUnitsRel, "energy");
  expect_rel(mm["flywheel"]["inertia"].get<double>() * mmf * mmf,
             si["flywheel"]["inertia"].get<double>(), kUnitsRel, "flywheel kg*mm^2");
  expect_rel(mm["driver"]["speed"].get<double>() * kDeg, si["driver"]["speed"].get<double>(),
             kUnitsRel, "speed");
  const json& p = mm["points"][5];
  const json& q = si["points"][5];
  expect_rel(p["measures"]["P_x"].get<double>() * mmf, q["measures"]["P_x"].get<double>(),
             kUnitsRel, "P_x");
  expect_rel(p["named_points"]["coupler.P"][1].get<double>() * mmf,
             q["named_points"]["coupler.P"][1].get<double>(), kUnitsRel, "coupler.P y");
  expect_rel(p["bodies"]["crank"]["velocity"][2].get<double>() * kDeg,
             q["bodies"]["crank"]["velocity"][2].get<double>(), kUnitsRel, "omega");
  expect_rel(p["bodies"]["coupler"]["acceleration"][0].get<double>() * mmf,
             q["bodies"]["coupler"]["acceleration"][0].get<double>(), kUnitsRel, "ax");
  expect_rel(p["kinetic_energy"].get<double>() * mmf, q["kinetic_energy"].get<double>(), kUnitsRel,
             "kinetic energy");
  // The text output echoes values with their units.
  const CliResult text = run_cli({"cycle", bundled("crank-rocker"), "--steps", "36"});
  EXPECT_NE(text.out.find("drive     N*mm"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("input 60 deg -> 410 deg"), std::string::npos) << text.out;
}

TEST(Trust, CycleCsvHeadersInTheFileUnits) {
  TempDir a, b;
  ::setenv("ORTHOMECH_GNUPLOT", "none", 1);
  const CliResult mm =
      run_cli({"cycle", bundled("crank-rocker"), "--steps", "24", "--out", a.path.string()});
  const CliResult si =
      run_cli({"cycle", units_data("crank-rocker-si"), "--steps", "24", "--out", b.path.string()});
  ::unsetenv("ORTHOMECH_GNUPLOT");
  ASSERT_EQ(mm.status, 0) << mm.err;
  ASSERT_EQ(si.status, 0) << si.err;
  const auto rm = read_csv(a.path / "cycle.csv"), rs = read_csv(b.path / "cycle.csv");
  ASSERT_EQ(rm.size(), rs.size());
  EXPECT_EQ(rm[0][0], "input [deg]");
  EXPECT_EQ(rs[0][0], "input [rad]");
  // Every column: the mm file's header names the mm/deg unit of the SI file's column, and the
  // value is the SI one converted.
  ASSERT_EQ(rm[0].size(), rs[0].size());
  auto factor = [](const std::string& unit) {  // SI per unit of the mm/deg file
    if (unit == "deg" || unit == "deg/s" || unit == "deg/s^2") return kDeg;
    if (unit == "mm" || unit == "mm/s" || unit == "mm/s^2" || unit == "N*mm") return 1e-3;
    return 1.0;
  };
  for (size_t c = 0; c + 1 < rm[0].size(); ++c) {
    const std::string hm = rm[0][c], hs = rs[0][c];
    const std::string um = hm.substr(hm.find('[') + 1, hm.find(']') - hm.find('[') - 1);
    EXPECT_EQ(hm.substr(0, hm.find('[')), hs.substr(0, hs.find('['))) << c;
    for (size_t k = 1; k < rm.size(); ++k) {
      const double vm = std::stod(rm[k][c]) * factor(um), vs = std::stod(rs[k][c]);
      EXPECT_NEAR(vm, vs, kUnitsRel * std::max(1.0, std::abs(vs))) << hm << " row " << k;
    }
  }
}

TEST(Trust, InfoValidateAssembleSimulateCrosscheckOutputsInTheFileUnits) {
  const std::string mm = bundled("crank-rocker"), si = units_data("crank-rocker-si");
  // info: masses and inertias, measures' units.
  {
    const json a = run_json({"info", mm, "--json"}), b = run_json({"info", si, "--json"});
    const json c = run_json({"info", mm, "--json", "--units", "si"});
    EXPECT_EQ(a["units"]["inertia"], "kg*mm^2");
    EXPECT_EQ(c["units"], b["units"]);
    for (size_t k = 0; k < 3; ++k) {
      expect_rel(a["bodies"][k]["inertia"].get<double>() * 1e-6,
                 b["bodies"][k]["inertia"].get<double>(), kUnitsRel, "inertia");
      expect_rel(c["bodies"][k]["inertia"].get<double>(), b["bodies"][k]["inertia"].get<double>(),
                 kUnitsRel, "inertia --units si");
    }
    EXPECT_EQ(a["measures"][4]["unit"], "mm");
    EXPECT_EQ(b["measures"][4]["unit"], "m");
  }
  // validate: distances in mm, angles in deg. The multi-start and continuation run in scaled
  // coordinates: the two files give the same positions to the solvers' tolerances.
  constexpr double kSolverRel = 1e-6;
  {
    const json a = run_json({"validate", mm, "--json"}), b = run_json({"validate", si, "--json"});
    ASSERT_EQ(a["positions"].size(), b["positions"].size());
    for (size_t k = 0; k < a["positions"].size(); ++k) {
      const json &p = a["positions"][k], &q = b["positions"][k];
      EXPECT_EQ(p["pass"], q["pass"]);
      expect_rel(p["four_bars"][0]["transmission_angle"].get<double>() * kDeg,
                 q["four_bars"][0]["transmission_angle"].get<double>(), kSolverRel, "mu");
      EXPECT_NEAR(p["target_error"].get<double>() * 1e-3, q["target_error"].get<double>(), 1e-9);
      EXPECT_EQ(p["singular_distance"].is_null(), q["singular_distance"].is_null());
      expect_rel(p["max_translation"].get<double>() * 1e-3, q["max_translation"].get<double>(),
                 kSolverRel, "moved");
      // The mass-metric distance in sqrt(kg)*mm against sqrt(kg)*m (the same kg).
      EXPECT_EQ(p["distance_unit"], "sqrt(kg)*mm");
      EXPECT_NEAR(p["distance"].get<double>() * 1e-3, q["distance"].get<double>(),
                  kSolverRel * std::max(1.0, q["distance"].get<double>()));
    }
  }
  // assemble: the lock is read in the file's units (bare 90 = 90° in the deg file).
  {
    const json a = run_json({"assemble", mm, "--lock", "A0=90", "--json"});
    const json b = run_json({"assemble", si, "--lock", "A0=1.5707963267948966", "--json"});
    EXPECT_NEAR(a["locks"][0]["value"].get<double>(), 90.0, 1e-9);
    EXPECT_EQ(a["locks"][0]["unit"], "deg");
    for (const char* m : {"P_x", "P_y"})
      expect_rel(a["measures"][m].get<double>() * 1e-3, b["measures"][m].get<double>(), kUnitsRel,
                 m);
    expect_rel(a["measures"]["rocker_angle"].get<double>() * kDeg,
               b["measures"]["rocker_angle"].get<double>(), kUnitsRel, "rocker");
    expect_rel(a["bodies"][1]["translation"].get<double>() * 1e-3,
               b["bodies"][1]["translation"].get<double>(), kSolverRel, "moved");
  }
  // simulate: the same motion; measures, energies and times in the file's units.
  {
    const std::vector<std::string> common = {"--t-end", "0.05",  "--rtol", "1e-10",
                                             "--atol",  "1e-12", "--json"};
    std::vector<std::string> ca = {"simulate", mm}, cb = {"simulate", si};
    ca.insert(ca.end(), common.begin(), common.end());
    cb.insert(cb.end(), common.begin(), common.end());
    const json a = run_json(ca), b = run_json(cb);
    expect_rel(a["final"]["measures"]["P_x"].get<double>() * 1e-3,
               b["final"]["measures"]["P_x"].get<double>(), kSolverRel, "P_x");
    expect_rel(a["final"]["measures"]["rocker_angle"].get<double>() * kDeg,
               b["final"]["measures"]["rocker_angle"].get<double>(), kSolverRel, "rocker");
    expect_rel(a["energy"]["initial"].get<double>() * 1e-3, b["energy"]["initial"].get<double>(),
               kUnitsRel, "energy");
    EXPECT_EQ(a["units"]["energy"], "N*mm");
  }
  // crosscheck: the units object and --units si.
  {
    const json a = run_json({"crosscheck", mm, "--samples", "2", "--json", "--units", "si"});
    EXPECT_EQ(a["units"]["length"], "m");
  }
}

TEST(Trust, SimulatePositionsAndCsvUnits) {
  // A pendulum (particle P1 on a 1 m rod): the named point P1.P... the particle's pose is its
  // position; it must equal the measures P1_x, P1_y at every output time.
  TempDir dir;
  const json j = run_json({"simulate", bundled("pendulum"), "--t-end", "0.5", "--json",
                           "--positions", "--out", dir.path.string()});
  const json& pos = j["samples"]["positions"];
  const json& m = j["samples"]["measures"];
  ASSERT_EQ(pos["P1.x"].size(), m["P1_x"].size());
  for (size_t k = 0; k < m["P1_x"].size(); ++k) {
    EXPECT_NEAR(pos["P1.x"][k].get<double>(), m["P1_x"][k].get<double>(), 1e-12);
    EXPECT_NEAR(pos["P1.y"][k].get<double>(), m["P1_y"][k].get<double>(), 1e-12);
  }
  const auto rows = read_csv(dir.path / "simulate.csv");
  EXPECT_EQ(rows[0][0], "t [s]");
  column(rows[0], "P1.x [m]");
  column(rows[0], "energy [N*m]");
}

TEST(Trust, ValidateAndAssembleNameTheLimitThatKeepsItOpen) {
  // Rocker limits [60°, 130°]: at crank 270° the mechanism closes only with the rocker outside
  // them. The value the tool says the rocker would need is the closed-form rocker angle on the
  // design's assembly mode: with d = B0 − A (A the crank pin), ψ = arg d ± acos((b² − |d|² −
  // c²) / (2 c |d|)); the design is the open assembly (B above the ground line A0 B0, as the
  // file says), so the root with sin ψ > 0 (132.36°, not −85.96° of the crossed mode).
  TempDir dir;
  const std::string limited =
      variant(dir, bundled("crank-rocker"), "limited.yaml",
              "{name: B0, type: revolute, connects: [ground.B0, rocker.B0]}",
              "{name: B0, type: revolute, connects: [ground.B0, rocker.B0], limits: [60, 130]}");
  const double a = 30, b = 80, c = 60, g = 70, th = 270 * kDeg;
  const double dx = g - a * std::cos(th), dy = -a * std::sin(th), D = std::hypot(dx, dy);
  const double base = std::atan2(dy, dx), half = std::acos((b * b - D * D - c * c) / (2 * c * D));
  const double psi = std::sin(base + half) > 0.0 ? base + half : base - half;
  ASSERT_GT(std::sin(psi), 0.0);
  auto on_design_mode = [&](double deg) {
    return std::abs(std::remainder(deg * kDeg - psi, 2 * std::numbers::pi)) < 1e-6;
  };
  const CliResult r = run_cli({"assemble", limited, "--lock", "A0=270", "--json"});
  EXPECT_EQ(r.status, 3);
  const json j = json::parse(r.out);
  ASSERT_EQ(j["limit_blocks"].size(), 1u);
  EXPECT_EQ(j["limit_blocks"][0]["joint"], "B0");
  const double needed = j["limit_blocks"][0]["needed"].get<double>();
  EXPECT_TRUE(on_design_mode(needed)) << needed << " deg, expected " << psi / kDeg;
  EXPECT_TRUE(needed < 60 || needed > 130) << needed;
  EXPECT_NE(r.err.find("joint 'B0' would need"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("outside its limits [60 deg, 130 deg]"), std::string::npos) << r.err;
  // validate: position p3 (crank 270°) fails, naming the limit and the same value.
  const CliResult v = run_cli({"validate", limited, "--json"});
  EXPECT_EQ(v.status, 1);
  const json vj = json::parse(v.out);
  const json& p3 = vj["positions"][2];
  ASSERT_EQ(p3["limit_blocks"].size(), 1u);
  EXPECT_TRUE(on_design_mode(p3["limit_blocks"][0]["needed"].get<double>()))
      << p3["limit_blocks"][0]["needed"];
  EXPECT_NE(p3["failures"][0].get<std::string>().find("joint 'B0' would need"), std::string::npos);
  // The same in the SI twin: the library's message in the file's units (rad), the value on the
  // design's mode too.
  const std::string limited_si = variant(
      dir, units_data("crank-rocker-si"), "limited-si.yaml", "  connects: [ground.B0, rocker.B0]",
      "  connects: [ground.B0, rocker.B0]\n  limits: [1.0471975511965976, "
      "2.2689280275926285]");
  const json vs = run_json({"validate", limited_si, "--json"}, 1);
  const std::string failure = vs["positions"][2]["failures"][0].get<std::string>();
  const std::string lead = "joint 'B0' would need ";
  ASSERT_EQ(failure.rfind(lead, 0), 0u) << failure;
  EXPECT_NEAR(std::stod(failure.substr(lead.size())), psi, 1e-6) << failure;
  EXPECT_NE(failure.find(" rad, outside its limits [1.047198 rad, 2.268928 rad]"),
            std::string::npos)
      << failure;
}

TEST(Trust, ValidateGivesSliderCrankLoopsTheirPressureAngle) {
  // Slider-crank r = 50, l = 200 mm in line: sin α = r sin θ / l. A design position at crank 90°
  // has α = asin(1/4).
  TempDir dir;
  const std::string file =
      variant(dir, bundled("slider-crank"), "p.yaml", "analysis: {driver: motor, steps: 360}",
              "design_positions:\n  - {name: p1, inputs: {O: 90}}\n"
              "analysis: {driver: motor, steps: 360}");
  const json j = run_json({"validate", file, "--json"});
  ASSERT_EQ(j["positions"].size(), 1u);
  ASSERT_EQ(j["positions"][0]["slider_cranks"].size(), 1u);
  EXPECT_NEAR(j["positions"][0]["slider_cranks"][0]["pressure_angle"].get<double>(),
              std::asin(0.25) / kDeg, 1e-9);
}

// ---- item 7: every four-bar loop of a Jansen leg ---------------------------------------------

// Jansen's construction at crank angle t (the oracle, written here from the lengths): the pins
// M, J, K, E, F as circle intersections, as documented in tests/data/loops/gen_jansen.py.
struct JansenPins {
  double Mx, My, Jx, Jy, Kx, Ky, Ex, Ey, Fx, Fy, Zx = -38, Zy = -7.8;
};
JansenPins jansen_pins(double t) {
  auto meet = [](double px, double py, double rp, double qx, double qy, double rq, auto better) {
    const double dx = qx - px, dy = qy - py, D = std::hypot(dx, dy);
    const double x = (rp * rp - rq * rq + D * D) / (2 * D), y = std::sqrt(rp * rp - x * x);
    const double ux = dx / D, uy = dy / D;
    const double ax = px + x * ux - y * uy, ay = py + x * uy + y * ux;
    const double bx = px + x * ux + y * uy, by = py + x * uy - y * ux;
    return better(ax, ay, bx, by) ? std::pair{ax, ay} : std::pair{bx, by};
  };
  auto upper = [](double, double ay, double, double by) { return ay > by; };
  auto lower = [](double, double ay, double, double by) { return ay < by; };
  auto left = [](double ax, double, double bx, double) { return ax < bx; };
  JansenPins p;
  p.Mx = 15 * std::cos(t), p.My = 15 * std::sin(t);
  std::tie(p.Jx, p.Jy) = meet(p.Zx, p.Zy, 41.5, p.Mx, p.My, 50, upper);
  std::tie(p.Kx, p.Ky) = meet(p.Zx, p.Zy, 39.3, p.Mx, p.My, 61.9, lower);
  std::tie(p.Ex, p.Ey) = meet(p.Zx, p.Zy, 40.1, p.Jx, p.Jy, 55.8, left);
  std::tie(p.Fx, p.Fy) = meet(p.Ex, p.Ey, 39.4, p.Kx, p.Ky, 36.7, left);
  return p;
}

TEST(Trust, ValidateFindsEveryFourBarLoopOfAJansenLeg) {
  // Pins O, M, J, Z, K, E, F; four-bar loops O-M-J-Z, O-M-K-Z, M-J-Z-K and the knee Z-E-F-K
  // (no ground link); loop basis 10 − 8 + 1 = 3.
  const std::string file = std::string(ORTHOMECH_SOURCE_DIR) + "/tests/data/loops/jansen.yaml";
  const json j = run_json({"validate", file, "--json"});
  EXPECT_EQ(j["loop_basis"], 3);
  const json& loops = j["positions"][0]["four_bars"];
  ASSERT_EQ(loops.size(), 4u);
  std::vector<std::string> names;
  for (const auto& l : loops) names.push_back(l["joints"]);
  const auto knee = std::find(names.begin(), names.end(), "Zb-Kf-F-E");
  ASSERT_NE(knee, names.end()) << names[0] << " " << names[1] << " " << names[2] << " " << names[3];
  // The knee's transmission angle at the design pose (crank 0°): at F (the coupler–follower pin),
  // between F→K (the foot) and F→E (link f).
  const JansenPins p = jansen_pins(0.0);
  const double ux = p.Kx - p.Fx, uy = p.Ky - p.Fy, vx = p.Ex - p.Fx, vy = p.Ey - p.Fy;
  const double mu = std::atan2(std::abs(ux * vy - uy * vx), ux * vx + uy * vy) / kDeg;
  EXPECT_NEAR(loops[static_cast<size_t>(knee - names.begin())]["transmission_angle"].get<double>(),
              mu, 1e-9);
  // And the ground loop O-Mk-Kk-Zc: at K between K→M and K→Z.
  const auto k2 = std::find(names.begin(), names.end(), "O-Mk-Kk-Zc");
  ASSERT_NE(k2, names.end());
  const double ax = p.Mx - p.Kx, ay = p.My - p.Ky, bx = p.Zx - p.Kx, by = p.Zy - p.Ky;
  EXPECT_NEAR(loops[static_cast<size_t>(k2 - names.begin())]["transmission_angle"].get<double>(),
              std::atan2(std::abs(ax * by - ay * bx), ax * bx + ay * by) / kDeg, 1e-9);
  // cycle reports the same four loops over the turn.
  const json c = run_json({"cycle", file, "--json", "--steps", "36"});
  EXPECT_EQ(c["loops"].size(), 4u);
}

TEST(Trust, WattSixBarSecondLoopTransmissionAngle) {
  // mechanisms/README.md (computed by scripts/gen_mechanisms.py): over a crank revolution the
  // transmission angle at D of the Watt II's second loop runs 51.61°…88.29° (2 decimals; the
  // 1° grid of the sweep is within 0.005° of the extremes there).
  const json j = run_json({"cycle", bundled("watt-six-bar"), "--json"});
  bool found = false;
  for (const auto& l : j["loops"])
    if (l["loop"] == "B0-C-D-D0") {
      found = true;
      EXPECT_NEAR(l["min"]["value"].get<double>(), 51.61, 0.006);
      EXPECT_NEAR(l["max"]["value"].get<double>(), 88.29, 0.006);
    }
  EXPECT_TRUE(found);
}

TEST(Trust, QuietAndVerboseAfterTheCommand) {
  // The gravity slip warns; -q after the command silences it, as before the command.
  TempDir dir;
  const std::string slip =
      variant(dir, bundled("crank-rocker"), "slip.yaml", "g: [0, -9810]", "g: [0, -9.81]");
  EXPECT_NE(run_cli({"info", slip}).err.find("warning"), std::string::npos);
  const CliResult after = run_cli({"info", slip, "-q"});
  EXPECT_EQ(after.status, 0);
  EXPECT_EQ(after.err, "");
  const CliResult before = run_cli({"-q", "info", slip});
  EXPECT_EQ(before.err, "");
  // -v after the command: the chart switches of a cycle are logged (not in the table).
  const CliResult v = run_cli({"cycle", bundled("crank-rocker"), "--steps", "36", "-v"});
  EXPECT_EQ(v.status, 0);
  EXPECT_NE(v.err.find("chart switches"), std::string::npos) << v.err;
  EXPECT_EQ(v.out.find("chart switches"), std::string::npos);
}

// ---- item 8: plots ----------------------------------------------------------------------------

TEST(Trust, GnuplotScriptSeparatesForcesAndMomentsAndMarksDeadPoints) {
  ::setenv("ORTHOMECH_GNUPLOT", "none", 1);
  TempDir a, b, c;
  // Slider-crank: slide.|M| is a moment, on the right axis; the input axis over the sweep from
  // its start (the design crank 45°, 360 steps of 1°); the speed in the title.
  ASSERT_EQ(run_cli({"cycle", bundled("slider-crank"), "--out", a.path.string()}).status, 0);
  const std::string gp = test::read_text(a.path / "cycle.gp");
  EXPECT_NE(gp.find("axes x1y2"), std::string::npos);
  EXPECT_NE(gp.find("set y2label 'moment [N*mm]'"), std::string::npos);
  EXPECT_NE(gp.find("set ylabel 'force [N]'"), std::string::npos);
  EXPECT_NE(gp.find("set xrange [45:404]"), std::string::npos) << gp;
  EXPECT_NE(gp.find("3000 rpm"), std::string::npos);
  // Double-rocker passing both dead points: two dashed marks.
  ASSERT_EQ(run_cli({"cycle", bundled("double-rocker"), "--speed", "10rpm",
                     "--reverse-at-dead-point", "--out", b.path.string()})
                .status,
            0);
  const std::string gb = test::read_text(b.path / "cycle.gp");
  EXPECT_NE(gb.find("set arrow 2 from first"), std::string::npos) << gb;
  EXPECT_EQ(gb.find("set arrow 3 "), std::string::npos);
  // Andrews' squeezer: ten pin-force series; the ninth repeats a colour with another dash.
  ASSERT_EQ(
      run_cli({"cycle", bundled("andrews-squeezer"), "--steps", "12", "--out", c.path.string()})
          .status,
      0);
  const std::string gc = test::read_text(c.path / "cycle.gp");
  EXPECT_NE(gc.find("lc 1 dt 2"), std::string::npos) << gc;
  ::unsetenv("ORTHOMECH_GNUPLOT");
}

// ---- item 3: signed extremes -----------------------------------------------------------------

TEST(Trust, SignedMaxAndMinOfTheDriveAndEveryComponent) {
  const json j = run_json({"cycle", bundled("slider-crank"), "--json", "--positions"});
  // From the listed positions (the oracle): max and min of each series and where.
  for (const std::string name : {"drive", "O.Fx", "A.Fy", "slide.N", "B.Fx_local"}) {
    double mx = -1e300, mn = 1e300, at_max = 0.0, at_min = 0.0;
    for (const auto& p : j["points"]) {
      const double v =
          name == "drive" ? p["drive"].get<double>() : p["reactions"][name].get<double>();
      if (v > mx) mx = v, at_max = p["input"].get<double>();
      if (v < mn) mn = v, at_min = p["input"].get<double>();
    }
    const json& s = j["peaks"][name];
    EXPECT_DOUBLE_EQ(s["max"]["value"].get<double>(), mx) << name;
    EXPECT_DOUBLE_EQ(s["min"]["value"].get<double>(), mn) << name;
    EXPECT_DOUBLE_EQ(s["max"]["input"].get<double>(), at_max) << name;
    EXPECT_DOUBLE_EQ(s["min"]["input"].get<double>(), at_min) << name;
    EXPECT_DOUBLE_EQ(s["peak"].get<double>(), std::max(mx, -mn)) << name;
  }
  // Motoring and braking told apart: the drive changes sign over the turn.
  EXPECT_GT(j["peaks"]["drive"]["max"]["value"].get<double>(), 0.0);
  EXPECT_LT(j["peaks"]["drive"]["min"]["value"].get<double>(), 0.0);
}

// ---- item 4: design metrics ------------------------------------------------------------------

TEST(Trust, CrankRockerTransmissionAngleAgainstTheClosedForm) {
  // Four-bar ground g = 70, crank a = 30, coupler b = 80, rocker c = 60 (mm). The diagonal from
  // the crank pin A to the rocker pivot B0 is BD² = a² + g² − 2ag cos θ, and the triangle
  // A-B-B0 gives cos μ = (b² + c² − BD²) / (2bc): extremes at θ = 0 (BD = g − a) and θ = 180°
  // (BD = g + a), both on the 1° grid of the sweep.
  const double a = 30, b = 80, c = 60, g = 70;
  const double mu_min = std::acos((b * b + c * c - (g - a) * (g - a)) / (2 * b * c)) / kDeg;
  const double mu_max = std::acos((b * b + c * c - (g + a) * (g + a)) / (2 * b * c)) / kDeg;
  const json j = run_json({"cycle", bundled("crank-rocker"), "--json"});
  ASSERT_EQ(j["loops"].size(), 1u);
  const json& l = j["loops"][0];
  EXPECT_EQ(l["angle"], "transmission");
  EXPECT_NEAR(l["min"]["value"].get<double>(), mu_min, 1e-9);
  EXPECT_NEAR(l["max"]["value"].get<double>(), mu_max, 1e-9);
  EXPECT_NEAR(l["worst"]["value"].get<double>(), std::min(mu_min, 180 - mu_max), 1e-9);
  const double at = std::fmod(l["worst"]["input"].get<double>(), 360.0);
  EXPECT_NEAR(std::min(at, 360.0 - at), 0.0, 1e-9);
  // Rocker swing and time ratio (mechanisms/crank-rocker.yaml's facts): the rocker is at its
  // smallest angle in the extended position (crank 29.526265°) and at its largest in the folded
  // one (237.121650°); forward = min → max. The extremes fall between the 1° grid points and are
  // refined by a parabola: error O(h³) of the grid, about 1e-5 of a degree here.
  constexpr double kRefinedAngle = 1e-4;  // deg
  constexpr double kRefinedRatio = 1e-4;
  bool found = false;
  for (const auto& s : j["strokes"])
    if (s["name"] == "rocker_angle") {
      found = true;
      EXPECT_NEAR(s["min"]["value"].get<double>(), 64.623066, kRefinedAngle);
      EXPECT_NEAR(s["max"]["value"].get<double>(), 135.584691, kRefinedAngle);
      EXPECT_NEAR(s["range"].get<double>(), 70.961625, kRefinedAngle);
      const double forward = 237.121650 - 29.526265;
      EXPECT_NEAR(s["time_ratio"]["forward_over_return"].get<double>(), forward / (360 - forward),
                  kRefinedRatio);
    }
  EXPECT_TRUE(found);
}

TEST(Trust, PressPressureAngleStrokeAndTimeRatioAgainstClosedForms) {
  // Offset slider-crank r = 40, l = 160, e = 10 mm: sin α = |r sin θ − e| / l, largest at
  // θ = 270° (on the grid): asin((r + e)/l). The ram's extremes are where crank and rod are
  // collinear: x_max = √((l + r)² − e²) at θ = asin(e/(l + r)), x_min = √((l − r)² − e²) at
  // θ = 180° + asin(e/(l − r)); forward = min → max.
  const double r = 40, l = 160, e = 10;
  const json j = run_json({"cycle", units_data("press"), "--json"});
  ASSERT_EQ(j["loops"].size(), 1u);
  EXPECT_EQ(j["loops"][0]["angle"], "pressure");
  EXPECT_NEAR(j["loops"][0]["max"]["value"].get<double>(), std::asin((r + e) / l) / kDeg, 1e-9);
  EXPECT_NEAR(j["loops"][0]["max"]["input"].get<double>(), 270.0, 1e-9);
  const double x_max = std::sqrt((l + r) * (l + r) - e * e);
  const double x_min = std::sqrt((l - r) * (l - r) - e * e);
  const double th_max = std::asin(e / (l + r)) / kDeg + 360.0;
  const double th_min = 180.0 + std::asin(e / (l - r)) / kDeg;
  const double forward = th_max - th_min;
  ASSERT_EQ(j["strokes"].size(), 1u);
  const json& s = j["strokes"][0];
  EXPECT_EQ(s["name"], "ram_x");
  // The extremes fall between grid points: refined by a parabola, error O(h³) of the 1° grid.
  constexpr double kRefinedLength = 1e-6;  // mm
  constexpr double kRefinedRatio = 1e-5;
  EXPECT_NEAR(s["max"]["value"].get<double>(), x_max, kRefinedLength);
  EXPECT_NEAR(s["min"]["value"].get<double>(), x_min, kRefinedLength);
  EXPECT_NEAR(s["range"].get<double>(), x_max - x_min, 2 * kRefinedLength);
  EXPECT_NEAR(s["time_ratio"]["forward_over_return"].get<double>(), forward / (360 - forward),
              kRefinedRatio);
}

TEST(Trust, EnergyFluctuationAgainstTheEnergies) {
  // Crank-rocker under gravity only (conservative): the drive's work equals the change of
  // T + V, the mean drive power over the turn is 0, and E(t) = ∫ (P − P̄) dt = (T + V)(t) −
  // (T + V)(0). So ΔE = max(T + V) − min(T + V) over the positions. The trapezoid rule over
  // 3600 positions: relative error O(h²) ≈ 1e-6.
  const json j = run_json({"cycle", bundled("crank-rocker"), "--steps", "3600", "--json",
                           "--positions", "--units", "si", "--speed-fluctuation", "0.02"});
  double hi = -1e300, lo = 1e300;
  for (const auto& p : j["points"]) {
    const double E = p["kinetic_energy"].get<double>() + p["potential_energy"].get<double>();
    hi = std::max(hi, E), lo = std::min(lo, E);
  }
  const double dE = j["energy_fluctuation"]["value"].get<double>();
  EXPECT_NEAR(dE, hi - lo, 1e-5 * (hi - lo));
  EXPECT_NEAR(j["power"]["mean"].get<double>(), 0.0, 1e-9 * j["power"]["peak"].get<double>());
  // Flywheel: ΔE = I C_s ω² for ω = 300 rpm.
  const double w = 300.0 * 2.0 * std::numbers::pi / 60.0;
  EXPECT_NEAR(j["flywheel"]["inertia"].get<double>(), dE / (0.02 * w * w), 1e-12);
}

TEST(Trust, TracerPointRangesWithoutAMeasure) {
  // The crank-rocker without its P_x/P_y measures: the coupler point P (used by no joint) gets
  // its x and y ranges all the same, equal to those of the measures in the original file.
  TempDir dir;
  std::string text = test::read_text(bundled("crank-rocker"));
  for (const char* m : {"  - {name: P_x, type: point, point: coupler.P, component: x}\n",
                        "  - {name: P_y, type: point, point: coupler.P, component: y}\n"}) {
    const size_t at = text.find(m);
    ASSERT_NE(at, std::string::npos);
    text.erase(at, std::string(m).size());
  }
  const fs::path file = dir.path / "no-p.yaml";
  std::ofstream(file) << text;
  const json a = run_json({"cycle", file.string(), "--json"});
  const json b = run_json({"cycle", bundled("crank-rocker"), "--json"});
  auto find = [](const json& j, const std::string& name) {
    for (const auto& s : j["strokes"])
      if (s["name"] == name) return s;
    return json();
  };
  for (const auto& [tracer, measure] :
       {std::pair{"coupler.P.x", "P_x"}, std::pair{"coupler.P.y", "P_y"}}) {
    const json s = find(a, tracer), m = find(b, measure);
    ASSERT_FALSE(s.is_null()) << tracer;
    ASSERT_FALSE(m.is_null()) << measure;
    EXPECT_NEAR(s["range"].get<double>(), m["range"].get<double>(), 1e-9) << tracer;
    EXPECT_NEAR(s["max"]["value"].get<double>(), m["max"]["value"].get<double>(), 1e-9);
    EXPECT_TRUE(find(b, tracer).is_null()) << "a measured point is not reported twice";
  }
  EXPECT_TRUE(find(a, "coupler.A.x").is_null()) << "joint points are not tracers";
}

TEST(Trust, NoTimeRatioWhenTheSweepStopsEarly) {
  // The double-rocker driven from its rocker stops at the dead point (exit 1): its ranges are
  // over the part swept, and no time ratio is claimed for a cycle that was not completed.
  const json j = run_json({"cycle", bundled("double-rocker"), "--speed", "10rpm", "--json"}, 1);
  ASSERT_FALSE(j["strokes"].empty());
  for (const auto& s : j["strokes"]) EXPECT_FALSE(s.contains("time_ratio")) << s["name"];
}

// ---- item 5: positions out -------------------------------------------------------------------

TEST(Trust, BodyPosesAndNamedPointsInTheCsvAndJson) {
  TempDir dir;
  ::setenv("ORTHOMECH_GNUPLOT", "none", 1);
  const CliResult r = run_cli({"cycle", bundled("crank-rocker"), "--steps", "36", "--out",
                               dir.path.string(), "--json", "--positions"});
  ::unsetenv("ORTHOMECH_GNUPLOT");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto rows = read_csv(dir.path / "cycle.csv");
  const auto& head = rows[0];
  const size_t in = column(head, "input [deg]"), ang = column(head, "crank.angle [deg]"),
               ax = column(head, "crank.A.x [mm]"), ay = column(head, "crank.A.y [mm]"),
               px = column(head, "coupler.P.x [mm]"), mpx = column(head, "P_x [mm]"),
               rx = column(head, "rocker.x [mm]");
  for (size_t k = 1; k < rows.size(); ++k) {
    const double th = std::stod(rows[k][in]);
    // The crank: its angle is the input, its pin A at 30 mm (cos θ, sin θ).
    EXPECT_NEAR(std::stod(rows[k][ang]), th, 1e-9);
    EXPECT_NEAR(std::stod(rows[k][ax]), 30 * std::cos(th * kDeg), 1e-9);
    EXPECT_NEAR(std::stod(rows[k][ay]), 30 * std::sin(th * kDeg), 1e-9);
    // The named point P against the measure P_x (computed by the measures' own code).
    EXPECT_NEAR(std::stod(rows[k][px]), std::stod(rows[k][mpx]), 1e-9);
    EXPECT_NEAR(std::stod(rows[k][rx]), 70.0, 1e-9);  // the rocker's frame sits on B0
  }
  const json j = json::parse(r.out);
  const json& p = j["points"][3];
  EXPECT_NEAR(p["poses"]["crank"][2].get<double>(), p["input"].get<double>(), 1e-9);
  EXPECT_NEAR(p["named_points"]["coupler.P"][0].get<double>(), p["measures"]["P_x"].get<double>(),
              1e-9);
}

// ---- item 6: limits --------------------------------------------------------------------------

TEST(Trust, CycleSaysWhereAJointLeavesItsLimits) {
  // The rocker swings 64.62°…135.58°; limits [60, 130] are left for rocker angles above 130°.
  TempDir dir;
  const std::string limited =
      variant(dir, bundled("crank-rocker"), "limited.yaml",
              "{name: B0, type: revolute, connects: [ground.B0, rocker.B0]}",
              "{name: B0, type: revolute, connects: [ground.B0, rocker.B0], limits: [60, 130]}");
  ::setenv("ORTHOMECH_GNUPLOT", "none", 1);
  const CliResult r = run_cli({"cycle", limited, "--out", dir.path.string(), "--json"});
  const CliResult text = run_cli({"cycle", limited});
  ::unsetenv("ORTHOMECH_GNUPLOT");
  ASSERT_EQ(r.status, 0) << r.err;
  const json j = json::parse(r.out);
  ASSERT_EQ(j["limits"].size(), 1u);
  EXPECT_EQ(j["limits"][0]["joint"], "B0");
  const auto rows = read_csv(dir.path / "cycle.csv");
  const size_t rocker = column(rows[0], "rocker_angle [deg]"), flag = rows[0].size() - 1;
  ASSERT_EQ(rows[0][flag], "limits");
  int outside = 0;
  double furthest = 0;
  for (size_t k = 1; k < rows.size(); ++k) {
    const double v = std::stod(rows[k][rocker]);
    EXPECT_EQ(rows[k][flag], v > 130.0 ? "B0" : "") << v;
    if (v > 130.0) ++outside, furthest = std::max(furthest, v);
  }
  EXPECT_GT(outside, 0);
  EXPECT_EQ(j["limits"][0]["positions"].get<int>(), outside);
  EXPECT_NEAR(j["limits"][0]["furthest"]["value"].get<double>(), furthest, 1e-6);
  EXPECT_NE(text.out.find("joint 'B0' leaves its limits [60 deg, 130 deg]"), std::string::npos)
      << text.out;
}

// The same on a spatial revolute (the RSSR's rocker limited to [100°, 200°]): the limits and the
// excursion are angles in the file's degrees, as the rocker_angle measure of cycle.csv.
TEST(CommonTrustCli, CycleReportsASpatialJointsLimitExcursionInDegrees) {
  TempDir dir;
  const std::string limited =
      variant(dir, bundled("rssr"), "limited.yaml",
              "{name: B0, type: revolute, connects: [ground.B0, rocker.O], axis: [1, 0, 0]}",
              "{name: B0, type: revolute, connects: [ground.B0, rocker.O], axis: [1, 0, 0], "
              "limits: [100, 200]}");
  ::setenv("ORTHOMECH_GNUPLOT", "none", 1);
  const CliResult r = run_cli({"cycle", limited, "--out", dir.path.string(), "--json"});
  const CliResult text = run_cli({"cycle", limited});
  ::unsetenv("ORTHOMECH_GNUPLOT");
  ASSERT_EQ(r.status, 0) << r.err;
  const json j = json::parse(r.out);
  ASSERT_EQ(j["limits"].size(), 1u);
  EXPECT_EQ(j["limits"][0]["limits"], json::array({100.0, 200.0}));
  const auto rows = read_csv(dir.path / "cycle.csv");
  const size_t rocker = column(rows[0], "rocker_angle [deg]");
  double furthest = 0;
  for (size_t k = 1; k < rows.size(); ++k)
    furthest = std::max(furthest, std::stod(rows[k][rocker]));
  EXPECT_GT(furthest, 200.0);
  EXPECT_NEAR(j["limits"][0]["furthest"]["value"].get<double>(), furthest, 1e-6);
  EXPECT_NE(text.out.find("joint 'B0' leaves its limits [100 deg, 200 deg]"), std::string::npos)
      << text.out;
}

}  // namespace
}  // namespace orthomech
