// `orthomech cycle` (docs/cli.md): exit codes, the JSON document (peaks against the positions it
// lists, dead points against their closed form), the CSV (header units, one row per position,
// empty cells of the components that diverge next to a change point, RMS recomputed from it), the
// gnuplot script and plots, and command-line errors.
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
#include <vector>

#include "support/cli_runner.hpp"

namespace orthomech {
namespace {

namespace fs = std::filesystem;
using test::CliResult;
using test::run_cli;

std::string bundled(const std::string& name) { return test::bundled_file(name); }

// A fresh output directory (test::TempDir), removed at the end of the test.
struct TempDir : test::TempDir {
  TempDir() : test::TempDir("orthomech_cycle_", false) {}
};

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::string cell;
  std::istringstream in(line);
  while (std::getline(in, cell, ',')) out.push_back(cell);
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

std::vector<std::vector<std::string>> read_csv(const fs::path& file) {
  std::ifstream in(file);
  std::vector<std::vector<std::string>> rows;
  for (std::string line; std::getline(in, line);) rows.push_back(split(line));
  return rows;
}

TEST(CycleCli, CrankRockerJsonPeaksMatchThePositions) {
  const CliResult r =
      run_cli({"cycle", bundled("crank-rocker"), "--json", "--positions", "--units", "si"});
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["status"], "completed");
  EXPECT_EQ(j["positions"], 360);
  EXPECT_EQ(j["driver"]["joint"], "A0");
  EXPECT_NEAR(j["driver"]["speed"].get<double>(), 300.0 * 2.0 * std::numbers::pi / 60.0, 1e-12);
  const auto& pts = j["points"];
  ASSERT_EQ(pts.size(), 360u);
  // Peak and RMS of the drive and of |A0| from the listed positions.
  double peak = 0.0, sum2 = 0.0, at = 0.0, peak_a0 = 0.0;
  for (const auto& p : pts) {
    const double d = p["drive"].get<double>();
    sum2 += d * d;
    if (std::abs(d) > peak) peak = std::abs(d), at = p["input"].get<double>();
    peak_a0 = std::max(peak_a0, std::hypot(p["reactions"]["A0.Fx"].get<double>(),
                                           p["reactions"]["A0.Fy"].get<double>()));
  }
  const auto& peaks = j["peaks"];
  EXPECT_DOUBLE_EQ(peaks["drive"]["peak"].get<double>(), peak);
  EXPECT_DOUBLE_EQ(peaks["drive"]["input"].get<double>(), at);
  EXPECT_NEAR(peaks["drive"]["rms"].get<double>(), std::sqrt(sum2 / 360.0), 1e-14);
  EXPECT_EQ(peaks["drive"]["unit"], "N*m");
  EXPECT_DOUBLE_EQ(peaks["A0.|F|"]["peak"].get<double>(), peak_a0);
  for (const char* joint : {"A0", "A", "B", "B0"}) {
    const std::string key = std::string(joint) + ".|F|";
    ASSERT_TRUE(peaks.contains(key)) << key;
    EXPECT_TRUE(peaks[key]["determinate"].get<bool>());
    EXPECT_GT(peaks[key]["peak"].get<double>(), 0.0);
  }
  EXPECT_TRUE(j["dead_points"].empty());
}

TEST(CycleCli, TableIsTheDefault) {
  const CliResult r = run_cli({"cycle", bundled("crank-rocker"), "--steps", "36"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("driver          joint 'A0' (revolute), constant speed 300 rpm"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("36 positions"), std::string::npos);
  EXPECT_NE(r.out.find("A0.|F|"), std::string::npos);
  EXPECT_EQ(r.err, "");  // not a terminal: no progress
}

TEST(CycleCli, DoubleRockerStopsAtTheDeadPointWithExitOne) {
  const CliResult r = run_cli({"cycle", bundled("double-rocker"), "--speed", "10rpm", "--json",
                               "--positions", "--units", "si"});
  ASSERT_EQ(r.status, 1) << r.err;
  EXPECT_NE(r.err.find("dead point of driver joint 'A0'"), std::string::npos) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["status"], "stopped_at_dead_point");
  ASSERT_EQ(j["dead_points"].size(), 1u);
  const double a = 60, b = 40, c = 65, g = 100;
  const double theta = std::acos((a * a + g * g - (b + c) * (b + c)) / (2 * a * g));
  EXPECT_NEAR(j["dead_points"][0]["input"].get<double>(), theta, 1e-6);
  // Never a NaN or an infinity (they would be null in JSON).
  for (const auto& p : j["points"]) {
    ASSERT_TRUE(p["drive"].is_number());
    for (const auto& [name, v] : p["reactions"].items()) ASSERT_TRUE(v.is_number()) << name;
  }
  for (const auto& [name, v] : j["peaks"].items()) ASSERT_TRUE(v["peak"].is_number()) << name;
}

// Nothing is lost when the sweep stops: the CSV holds every position before the dead point.
TEST(CycleCli, DeadPointStopStillWritesTheFiles) {
  TempDir dir;
  ::setenv("ORTHOMECH_GNUPLOT", "none", 1);
  const CliResult r = run_cli({"cycle", bundled("double-rocker"), "--speed", "10rpm", "--json",
                               "--out", dir.path.string()});
  ::unsetenv("ORTHOMECH_GNUPLOT");
  ASSERT_EQ(r.status, 1) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  const auto rows = read_csv(dir.path / "cycle.csv");
  EXPECT_EQ(rows.size(), 1u + j["positions"].get<size_t>());
  EXPECT_GT(rows.size(), 50u);
}

TEST(CycleCli, UnwritableOutputIsACommandLineError) {
  const CliResult r =
      run_cli({"cycle", bundled("crank-rocker"), "--steps", "8", "--out", "/proc/orthomech"});
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("/proc/orthomech"), std::string::npos) << r.err;
  EXPECT_EQ(r.out, "");
}

TEST(CycleCli, ReverseAtDeadPointCloses) {
  const CliResult r = run_cli(
      {"cycle", bundled("double-rocker"), "--speed", "10rpm", "--reverse-at-dead-point", "--json"});
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["reversals"], 2);
  EXPECT_EQ(j["dead_points"].size(), 2u);
}

TEST(CycleCli, TripleCrankSaysWhichComponentsAreIndeterminate) {
  TempDir dir;
  const CliResult r = run_cli({"cycle", bundled("triple-crank"), "--steps", "90", "--json", "--out",
                               dir.path.string(), "--units", "si"});
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_TRUE(j["peaks"]["drive"]["determinate"].get<bool>());
  EXPECT_FALSE(j["peaks"]["O1.|F|"]["determinate"].get<bool>());
  for (const auto& c : j["components"]) {
    const std::string name = c["name"];
    if (name == "A1.Fy_local" || name == "A2.Fy_local" || name == "A3.Fy_local") {
      EXPECT_TRUE(c["determinate"].get<bool>()) << name;
    }
    if (name == "A1.Fx_local") {
      EXPECT_FALSE(c["determinate"].get<bool>()) << name;
    }
  }
  EXPECT_EQ(j["singular_positions"].size(), 2u);
  // Both change points are bridged on the branch (issue 10 item 3): the axial crank forces
  // diverge there (the self-stress that appears at the change point), the transverse ones do not.
  ASSERT_EQ(j["bridges"].size(), 2u);
  for (const auto& b : j["bridges"]) {
    const auto& div = b["diverging"];
    EXPECT_NE(std::find(div.begin(), div.end(), "A1.Fx_local"), div.end());
    EXPECT_EQ(std::find(div.begin(), div.end(), "A2.Fy_local"), div.end());
  }
  // CSV: every position has its drive; at the bridged positions the cells of the diverging
  // components are empty and the others are filled.
  const auto rows = read_csv(dir.path / "cycle.csv");
  ASSERT_EQ(rows.size(), 91u);
  size_t drive_col = 0, axial_col = 0, transverse_col = 0;
  for (size_t c = 0; c < rows[0].size(); ++c) {
    if (rows[0][c] == "drive [N*m]") drive_col = c;
    if (rows[0][c] == "A1.Fx_local [N]") axial_col = c;
    if (rows[0][c] == "A2.Fy_local [N]") transverse_col = c;
  }
  ASSERT_GT(drive_col, 0u);
  ASSERT_GT(axial_col, 0u);
  ASSERT_GT(transverse_col, 0u);
  int empty = 0;
  for (size_t k = 1; k < rows.size(); ++k) {
    ASSERT_EQ(rows[k].size(), rows[0].size()) << k;
    EXPECT_FALSE(rows[k][drive_col].empty()) << k;
    EXPECT_FALSE(rows[k][transverse_col].empty()) << k;
    if (rows[k][axial_col].empty()) ++empty;
  }
  EXPECT_GE(empty, 2);  // at least the two grid positions on the change points (90 steps: 4°)
}

// --out: CSV with units in the header, one row per position, RMS of the drive from the CSV equal
// to the JSON's; the gnuplot script is always written; plots when gnuplot is there.
TEST(CycleCli, CsvAndPlots) {
  TempDir dir;
  const CliResult r = run_cli(
      {"cycle", bundled("slider-crank"), "--json", "--out", dir.path.string(), "--units", "si"});
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  const auto rows = read_csv(dir.path / "cycle.csv");
  ASSERT_EQ(rows.size(), 1u + j["positions"].get<size_t>());
  const auto& head = rows[0];
  EXPECT_EQ(head[0], "input [rad]");
  EXPECT_EQ(head[1], "time [s]");
  EXPECT_EQ(head.back(), "limits");
  size_t drive_col = 0, slide_n = 0;
  for (size_t c = 0; c < head.size(); ++c) {
    if (head[c] == "drive [N*m]") drive_col = c;
    if (head[c] == "slide.N [N]") slide_n = c;
    if (c + 1 < head.size()) {
      EXPECT_NE(head[c].find(" ["), std::string::npos) << "no unit: " << head[c];
    }
  }
  ASSERT_GT(drive_col, 0u);
  ASSERT_GT(slide_n, 0u);
  double sum2 = 0.0;
  for (size_t k = 1; k < rows.size(); ++k) sum2 += std::pow(std::stod(rows[k][drive_col]), 2);
  EXPECT_NEAR(std::sqrt(sum2 / static_cast<double>(rows.size() - 1)),
              j["peaks"]["drive"]["rms"].get<double>(),
              1e-8 * j["peaks"]["drive"]["rms"].get<double>());
  EXPECT_TRUE(fs::exists(dir.path / "cycle.gp"));
  if (std::system("command -v gnuplot >/dev/null 2>&1") == 0) {
    for (const char* f : {"drive.svg", "drive.png", "reactions.svg", "reactions.png"})
      EXPECT_GT(fs::file_size(dir.path / f), 1000u) << f;
  }
}

TEST(CycleCli, WithoutGnuplotWritesTheScriptAndSaysSo) {
  TempDir dir;
  ::setenv("ORTHOMECH_GNUPLOT", "/nonexistent/gnuplot", 1);
  const CliResult r =
      run_cli({"cycle", bundled("crank-rocker"), "--steps", "36", "--out", dir.path.string()});
  ::unsetenv("ORTHOMECH_GNUPLOT");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("gnuplot not found"), std::string::npos) << r.err;
  EXPECT_TRUE(fs::exists(dir.path / "cycle.csv"));
  EXPECT_TRUE(fs::exists(dir.path / "cycle.gp"));
  EXPECT_FALSE(fs::exists(dir.path / "drive.svg"));
}

// The start position is a dead point of the driver: said, exit 1, no crash, empty CSV body.
TEST(CycleCli, StartAtADeadPoint) {
  TempDir dir;
  ::setenv("ORTHOMECH_GNUPLOT", "none", 1);
  const std::string file =
      std::string(ORTHOMECH_SOURCE_DIR) + "/tests/data/cycle/rocker-starts-at-dead-point.yaml";
  const CliResult t = run_cli({"cycle", file});
  const CliResult j = run_cli({"cycle", file, "--json", "--out", dir.path.string()});
  ::unsetenv("ORTHOMECH_GNUPLOT");
  EXPECT_EQ(t.status, 1) << t.err;
  EXPECT_NE(t.out.find("no position computed"), std::string::npos) << t.out;
  EXPECT_NE(t.err.find("the start position is a dead point of driver joint 'B0'"),
            std::string::npos)
      << t.err;
  ASSERT_EQ(j.status, 1) << j.err;
  const auto doc = nlohmann::json::parse(j.out);
  EXPECT_EQ(doc["positions"], 0);
  EXPECT_EQ(doc["dead_points"].size(), 1u);
  EXPECT_EQ(read_csv(dir.path / "cycle.csv").size(), 1u);  // the header
}

// Requests that do not fit the driver are command-line errors (exit 2), naming the option.
TEST(CycleCli, RequestsThatDoNotFitTheDriverAreExitTwo) {
  const CliResult a =
      run_cli({"cycle", bundled("slider-crank"), "--driver", "slide", "--speed", "1m/s"});
  EXPECT_EQ(a.status, 2);
  EXPECT_NE(a.err.find("--to"), std::string::npos) << a.err;
  const CliResult b = run_cli({"cycle", bundled("double-rocker"), "--from", "30deg"});
  EXPECT_EQ(b.status, 2);
  EXPECT_NE(b.err.find("constant-speed"), std::string::npos) << b.err;
  const CliResult c = run_cli({"cycle", bundled("double-rocker"), "--reverse-at-dead-point"});
  EXPECT_EQ(c.status, 2);
  const CliResult d = run_cli({"cycle", bundled("crank-rocker"), "--to", "60deg"});
  EXPECT_EQ(d.status, 2);
  EXPECT_NE(d.err.find("empty"), std::string::npos) << d.err;
  for (const CliResult* r : {&a, &b, &c, &d}) EXPECT_EQ(r->out, "");
}

// An output directory whose name needs quoting in a shell; plots still made when gnuplot is
// there.
TEST(CycleCli, OutputDirectoryWithAQuote) {
  TempDir dir;
  const fs::path out = dir.path / "it's here";
  const CliResult r =
      run_cli({"cycle", bundled("crank-rocker"), "--steps", "36", "--out", out.string()});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(fs::exists(out / "cycle.csv"));
  if (std::system("command -v gnuplot >/dev/null 2>&1") == 0) {
    EXPECT_TRUE(fs::exists(out / "drive.svg")) << r.err;
  }
}

// Body velocities in the CSV against the closed form: the crank's centre of mass (mid-crank,
// 15 mm from A0) moves at ω × 15 mm, perpendicular to the crank.
TEST(CycleCli, BodyVelocitiesInTheCsv) {
  TempDir dir;
  ::setenv("ORTHOMECH_GNUPLOT", "none", 1);
  const CliResult r = run_cli({"cycle", bundled("crank-rocker"), "--steps", "12", "--out",
                               dir.path.string(), "--units", "si"});
  ::unsetenv("ORTHOMECH_GNUPLOT");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto rows = read_csv(dir.path / "cycle.csv");
  size_t vx = 0, vy = 0, om = 0, ax = 0;
  for (size_t c = 0; c < rows[0].size(); ++c) {
    if (rows[0][c] == "crank.vx [m/s]") vx = c;
    if (rows[0][c] == "crank.vy [m/s]") vy = c;
    if (rows[0][c] == "crank.omega [rad/s]") om = c;
    if (rows[0][c] == "crank.ax [m/s^2]") ax = c;
  }
  ASSERT_TRUE(vx && vy && om && ax);
  const double w = 300.0 * 2.0 * std::numbers::pi / 60.0;
  for (size_t k = 1; k < rows.size(); ++k) {
    const double th = std::stod(rows[k][0]);
    EXPECT_NEAR(std::stod(rows[k][om]), w, 1e-9);
    EXPECT_NEAR(std::stod(rows[k][vx]), -w * 0.015 * std::sin(th), 1e-9);
    EXPECT_NEAR(std::stod(rows[k][vy]), w * 0.015 * std::cos(th), 1e-9);
    EXPECT_NEAR(std::stod(rows[k][ax]), -w * w * 0.015 * std::cos(th), 1e-7);
  }
}

TEST(CycleCli, DriverAndRangeFromTheCommandLine) {
  // A range of the crank at another speed than the file's.
  const CliResult r =
      run_cli({"cycle", bundled("slider-crank"), "--from", "30deg", "--to", "120deg", "--steps",
               "10", "--speed", "600rpm", "--json", "--positions", "--units", "si"});
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["points"].size(), 10u);
  EXPECT_NEAR(j["points"][0]["input"].get<double>(), std::numbers::pi / 6, 1e-12);
  EXPECT_NEAR(j["points"][9]["input"].get<double>(), 2 * std::numbers::pi / 3, 1e-12);
  EXPECT_NEAR(j["driver"]["speed"].get<double>(), 20 * std::numbers::pi, 1e-12);
}

TEST(CycleCli, BadOptionsAreCommandLineErrors) {
  const CliResult a = run_cli({"cycle", bundled("crank-rocker"), "--driver", "Z"});
  EXPECT_EQ(a.status, 2);
  EXPECT_NE(a.err.find("joint 'Z' is not defined"), std::string::npos) << a.err;
  EXPECT_NE(a.err.find("joints: A0, A, B, B0"), std::string::npos) << a.err;
  EXPECT_EQ(a.out, "");
  const CliResult b = run_cli({"cycle", bundled("crank-rocker"), "--speed", "300rpmm"});
  EXPECT_EQ(b.status, 2);
  EXPECT_NE(b.err.find("unknown speed unit 'rpmm'"), std::string::npos) << b.err;
  const CliResult c = run_cli({"cycle", bundled("crank-rocker"), "--driver", "B"});
  EXPECT_EQ(c.status, 2);
  EXPECT_NE(c.err.find("give --speed"), std::string::npos) << c.err;
  const CliResult d = run_cli({"cycle", bundled("crank-rocker"), "--steps", "1"});
  EXPECT_EQ(d.status, 2);
}

// Pin friction from the file (--set here): the JSON `friction` object, the drive without friction
// equal to the plain file's drive, the extra lines of the table; in a redundant mechanism the
// friction of a pin whose force is indeterminate is flagged, and simulate says it ignores it.
// The knuckle press's ram height at a cylinder length (mechanisms/knuckle-press.yaml): the knee
// K = (x, 600 − √(300² − x²)) with |C − K| = length (C = (700, 330)) by bisection, and the ram
// 600 − 2√(300² − x²) below the straight toggle.
double press_ram_y(double length) {
  auto knee_y = [](double x) { return 600.0 - std::sqrt(300.0 * 300.0 - x * x); };
  double lo = 0.0, hi = 299.0;  // |C − K| falls as x grows
  for (int it = 0; it < 200; ++it) {
    const double x = 0.5 * (lo + hi);
    (std::hypot(x - 700.0, knee_y(x) - 330.0) > length ? lo : hi) = x;
  }
  const double x = 0.5 * (lo + hi);
  return 600.0 - 2.0 * std::sqrt(300.0 * 300.0 - x * x);
}

TEST(CycleCli, WiperDriveTakesTheBladeDragsWorkAndItsPinsDissipate) {
  // Issue 49's wiper: the blade's drag (1.5 N*m against the rocker's rotation) takes twice the
  // drag times the rocker's swing per turn, the swing from the law of cosines at the dead centres
  // (A0B = 250 ± 40 mm, B0B = 60, A0B0 = 240): the frictionless drive's net work W0; with friction
  // in every pin the drive's work W is W0 plus what the pins dissipate, and eta = W0/W.
  const CliResult r = run_cli({"cycle", bundled("wiper-drive"), "--json", "-q"});
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  auto beta = [](double L) {
    return std::acos((240.0 * 240.0 + 60.0 * 60.0 - L * L) / (2.0 * 240.0 * 60.0));
  };
  const double swing = beta(290.0) - beta(210.0);  // rad
  const double W0 = 2.0 * 1500.0 * swing;          // N*mm
  const auto& f = j["friction"];
  EXPECT_EQ(f["unit"], "N*mm");
  EXPECT_NEAR(f["drive_work_frictionless"].get<double>(), W0, 1e-4 * W0);
  const double W = f["drive_work"].get<double>(), D = f["dissipated"].get<double>();
  EXPECT_NEAR(W - f["drive_work_frictionless"].get<double>(), D, 1e-6 * D);
  EXPECT_NEAR(f["efficiency"].get<double>(), f["drive_work_frictionless"].get<double>() / W, 1e-12);
  // (A plain bound, not an oracle: the pins take less than a fifth of the drive's work.)
  EXPECT_GT(f["efficiency"].get<double>(), 0.8);
  EXPECT_LT(f["efficiency"].get<double>(), 1.0);
  for (const auto& pin : f["joints"]) EXPECT_TRUE(pin["determinate"].get<bool>()) << pin;
  EXPECT_TRUE(f["lower_bound"].is_null());
  const auto& rocker = j["strokes"][0];
  ASSERT_EQ(rocker["name"], "rocker_angle");
  const double deg = 180.0 / std::numbers::pi;
  EXPECT_NEAR(rocker["min"]["value"].get<double>(), 180.0 - beta(290.0) * deg, 1e-4);
  EXPECT_NEAR(rocker["max"]["value"].get<double>(), 180.0 - beta(210.0) * deg, 1e-4);
  EXPECT_GT(j["peaks"]["shaking force"]["peak"].get<double>(), 0.0) << j["peaks"];
}

TEST(CycleCli, KnucklePressFormingWorkIsTheForceTimesItsStroke) {
  // The forming force (20 kN, factor 1 below a ram height of 6 mm, 0 above 6.5 mm, linear between)
  // acts on the down-stroke only: over a cycle the loads take F (6 − y_min + 0.25 mm), y_min the
  // ram's height at the cylinder's longest (680 mm): the frictionless drive's net work.
  const CliResult r =
      run_cli({"cycle", bundled("knuckle-press"), "--steps", "3600", "--json", "-q"});
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  const double y_min = press_ram_y(680.0), y_max = press_ram_y(540.0);
  const double W0 = 20000.0 * (6.0 - y_min + 0.25);  // N*mm
  const auto& f = j["friction"];
  EXPECT_NEAR(f["drive_work_frictionless"].get<double>(), W0, 1e-4 * W0);
  // (A plain bound, not an oracle: the pins take less than a fifth of the drive's work.)
  EXPECT_GT(f["efficiency"].get<double>(), 0.8);
  EXPECT_LT(f["efficiency"].get<double>(), 1.0);
  bool found = false;
  for (const auto& s : j["strokes"]) {
    if (s["name"] != "ram_y") continue;
    found = true;
    EXPECT_NEAR(s["min"]["value"].get<double>(), y_min, 1e-6);
    EXPECT_NEAR(s["max"]["value"].get<double>(), y_max, 1e-6);
  }
  EXPECT_TRUE(found);
}

TEST(CycleCli, PinFrictionIsReportedAndFlaggedWhereNotDetermined) {
  std::vector<std::string> args = {"cycle", bundled("crank-rocker"), "--steps", "72"};
  for (const char* j : {"A0", "A", "B", "B0"}) {
    args.push_back("--set");
    args.push_back(std::string("joints.") + j + ".friction={coefficient: 0.15, radius: 4}");
  }
  std::vector<std::string> json_args = args;
  json_args.insert(json_args.end(), {"--json", "-q"});
  const CliResult r = run_cli(json_args);
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["friction"]["joints"].size(), 4u);
  EXPECT_EQ(j["friction"]["joints"][0]["joint"], "A0");
  EXPECT_EQ(j["friction"]["joints"][0]["radius"], 4.0);
  EXPECT_TRUE(j["friction"]["converged"].get<bool>());
  EXPECT_GT(j["friction"]["dissipated"].get<double>(), 0.0);
  const CliResult plain = run_cli({"cycle", bundled("crank-rocker"), "--steps", "72", "--json"});
  ASSERT_EQ(plain.status, 0) << plain.err;
  const double rms0 = nlohmann::json::parse(plain.out)["peaks"]["drive"]["rms"].get<double>();
  EXPECT_NEAR(j["peaks"]["drive without friction"]["rms"].get<double>(), rms0, 1e-9 * rms0);
  // Over the turn (0.2 s at 300 rpm) the drive's work is what the pins dissipate.
  EXPECT_NEAR(j["power"]["mean"].get<double>() * 0.2, j["friction"]["dissipated"].get<double>(),
              1e-5 * j["friction"]["dissipated"].get<double>());
  EXPECT_GT(j["peaks"]["A0 friction moment"]["peak"].get<double>(), 0.0);
  const CliResult text = run_cli(args);
  ASSERT_EQ(text.status, 0) << text.err;
  EXPECT_NE(text.out.find("friction  dissipated"), std::string::npos) << text.out;

  const CliResult redundant =
      run_cli({"cycle", bundled("triple-crank"), "--set",
               "joints.O2.friction={coefficient: 0.1, radius: 2}", "--json", "-q"});
  ASSERT_EQ(redundant.status, 0) << redundant.err;
  const auto rj = nlohmann::json::parse(redundant.out)["friction"];
  const auto f = rj["joints"];
  ASSERT_EQ(f.size(), 1u);
  EXPECT_FALSE(f[0]["determinate"].get<bool>());
  // With it, the least friction over the admissible splits: at most the minimum-norm split's.
  EXPECT_TRUE(j["friction"]["lower_bound"].is_null()) << "the crank-rocker has one split";
  ASSERT_TRUE(rj["lower_bound"].is_object()) << rj.dump();
  EXPECT_EQ(rj["lower_bound"]["unsolved"], 0);
  EXPECT_GT(rj["lower_bound"]["positions"].get<int>(), 300);
  EXPECT_GT(rj["lower_bound"]["dissipated"].get<double>(), 0.0);
  EXPECT_LT(rj["lower_bound"]["dissipated"].get<double>(), rj["dissipated"].get<double>());
  const CliResult sim = run_cli({"simulate", bundled("crank-rocker"), "--t-end", "0.01", "--set",
                                 "joints.A0.friction={coefficient: 0.1, radius: 2}"});
  EXPECT_EQ(sim.status, 0) << sim.err;
  EXPECT_EQ(sim.err.find("does not apply joint friction"), std::string::npos) << sim.err;
  const CliResult cross = run_cli({"crosscheck", bundled("crank-rocker"), "--t-end", "0.01",
                                   "--set", "joints.A0.friction={coefficient: 0.1, radius: 2}"});
  EXPECT_NE(cross.err.find("does not apply joint friction"), std::string::npos) << cross.err;
}

}  // namespace
}  // namespace orthomech
