// `orthomech optimize` (docs/cli.md "optimize", issue 51's Done-when): the wiper drive sized for a
// 75° swing with the least peak drive torque and a worst transmission angle of at least 40°
// (examples/wiper-optimize.yaml). Oracles: the optimum's swing against the law of cosines for
// its crank a, coupler b and rocker c (ground d = 240 mm: the limit positions have A0B = b ± a,
// and ψ(l) = π − acos((d² + c² − l²) / (2dc))), and its worst transmission angle against
// cos μ = (b² + c² − (d ∓ a)²) / (2bc); `cycle` on the written optimum.yaml shows
// the same swing and transmission angle; an impossible constraint is exit 3 without an optimum
// file; `sweep` refuses an optimize study and `optimize` a grid. A spatial file: the RSSR's crank
// sized for a rocker swing, checked against the swing's closed form.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "support/cli_runner.hpp"
#include "support/spatial_oracles.hpp"

namespace orthomech {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using test::run_cli;

std::string example(const std::string& name) {
  return (fs::path(test::bundled_file("wiper-drive")).parent_path().parent_path() / "examples" /
          name)
      .string();
}

constexpr double d = 240;

double worst_transmission_deg(double a, double b, double c) {
  double worst = 90.0;
  for (const double l : {d - a, d + a}) {
    const double mu = std::acos((b * b + c * c - l * l) / (2 * b * c)) * 180.0 / std::numbers::pi;
    worst = std::min(worst, std::min(mu, 180.0 - mu));
  }
  return worst;
}

double swing_deg(double a, double b, double c) {
  const auto psi = [&](double l) {
    return std::numbers::pi - std::acos((d * d + c * c - l * l) / (2 * d * c));
  };
  return std::abs(psi(b + a) - psi(b - a)) * 180.0 / std::numbers::pi;
}

TEST(OptimizeCli, WiperDriveFor75DegreesOfSwing) {
  const test::TempDir dir("orthomech_optimize_");
  const std::string out = (dir.path / "wiper").string();
  const auto r = run_cli({"optimize", test::bundled_file("wiper-drive"), "--study",
                          example("wiper-optimize.yaml"), "--out", out, "--json"});
  ASSERT_EQ(r.status, 0) << r.err;
  const json j = json::parse(r.out);
  ASSERT_TRUE(j["found"].get<bool>());
  const json& opt = j["optimum"];
  const double a = opt["variables"]["crank"], b = opt["variables"]["coupler"],
               c = opt["variables"]["rocker"];
  const double swing = opt["metrics"]["swing"];
  EXPECT_NEAR(swing, 75.0, 0.05 + 1e-6);
  // 180 positions 2° apart: the parabola-refined extremes of the swing are within 2e-3° of the
  // closed form (measured −1.3e-5°); the worst transmission angle is at θ = 0° or 180°, both
  // samples of the grid (it starts at 90°), so it is the closed form to rounding
  // (measured 3.6e-11°).
  EXPECT_NEAR(swing, swing_deg(a, b, c), 2e-3) << "a = " << a << ", b = " << b << ", c = " << c;
  const double mu = opt["metrics"]["transmission.min"];
  EXPECT_GE(mu, 40.0 - 40e-6);
  EXPECT_NEAR(mu, worst_transmission_deg(a, b, c), 1e-3);
  // The nominal drive (a = 40, b = 250, c = 60: a swing of 89°, μ 29.5°) is not feasible; the
  // optimum's torque is the objective.
  const double peak = opt["metrics"]["drive.peak"];
  EXPECT_DOUBLE_EQ(opt["objective"].get<double>(), peak);
  EXPECT_TRUE(fs::exists(fs::path(out) / "evaluations.csv"));
  EXPECT_TRUE(fs::exists(fs::path(out) / "study.sqlite"));
  EXPECT_EQ(json::parse(test::read_text(fs::path(out) / "summary.json")), j);

  // `cycle` on the optimal file shows the swing and the transmission angle.
  const auto cyc =
      run_cli({"cycle", (fs::path(out) / "optimum.yaml").string(), "--steps", "180", "--json"});
  ASSERT_EQ(cyc.status, 0) << cyc.err;
  EXPECT_EQ(cyc.err.find("does not close as drawn"), std::string::npos) << cyc.err;
  const json cj = json::parse(cyc.out);
  bool found = false;
  for (const auto& s : cj["strokes"])
    if (s["name"] == "rocker_angle") {
      found = true;
      EXPECT_NEAR(s["range"].get<double>(), swing, 1e-9);
    }
  EXPECT_TRUE(found);
  // The best of every evaluation in the CSV is the optimum (rows: header + evaluations).
  std::ifstream csv(fs::path(out) / "evaluations.csv");
  long lines = 0;
  for (std::string line; std::getline(csv, line);) ++lines;
  EXPECT_EQ(lines, j["evaluations"].get<long>() + 1);

  // The convergence plot: a point per evaluation with an objective (those off the axis counted in
  // its caption), each the objective column of evaluations.csv; none feasible below the optimum;
  // the best-so-far line ends at the optimum's objective.
  const std::string plot = test::read_text(fs::path(out) / "convergence.svg");
  const std::regex point(
      R"re(class="evaluation" data-evaluation="(\d+)" data-objective="([^"]+)" data-feasible="(\w+)")re");
  std::vector<double> objective_column;
  {
    std::ifstream rows(fs::path(out) / "evaluations.csv");
    std::string header;
    std::getline(rows, header);
    size_t at = 0;
    std::stringstream h(header);
    for (std::string name; std::getline(h, name, ',') && name != "objective";) ++at;
    for (std::string row; std::getline(rows, row);) {
      std::stringstream cells(row);
      std::string cell;
      for (size_t k = 0; k <= at; ++k) std::getline(cells, cell, ',');
      objective_column.push_back(cell.empty() ? std::nan("") : std::stod(cell));
    }
  }
  long drawn = 0;
  for (std::sregex_iterator it(plot.begin(), plot.end(), point), end; it != end; ++it) {
    const auto k = static_cast<size_t>(std::stol((*it)[1]));
    ASSERT_LT(k, objective_column.size());
    EXPECT_EQ(std::stod((*it)[2]), objective_column[k]) << "evaluation " << k;
    if ((*it)[3] == "yes") {
      EXPECT_GE(std::stod((*it)[2]), peak) << "evaluation " << k;
    }
    ++drawn;
  }
  std::smatch off;
  long beyond = 0;
  if (std::regex_search(plot, off, std::regex("; (\\d+) off the axis"))) beyond = std::stol(off[1]);
  EXPECT_EQ(drawn + beyond, std::count_if(objective_column.begin(), objective_column.end(),
                                          [](double v) { return std::isfinite(v); }));
  std::smatch line;
  ASSERT_TRUE(
      std::regex_search(plot, line, std::regex(R"re(class="best" data-final="([^"]+)")re")));
  EXPECT_EQ(std::stod(line[1]), peak);

  // The directory holds a study now: a second run there is refused.
  const auto again = run_cli({"optimize", test::bundled_file("wiper-drive"), "--study",
                              example("wiper-optimize.yaml"), "--out", out});
  EXPECT_EQ(again.status, 2) << again.err;
}

// The crank-rocker's crank length between 20 and 40 mm, the least peak drive torque; `extra`
// appended (constraints, a budget).
std::string crank_study(const std::string& extra) {
  return "study: optimize\nsteps: 60\nparameters:\n"
         "  - {name: crank, path: bodies.crank.points.A.0, bounds: [20, 40]}\n"
         "objective: {minimize: drive.peak}\n" +
         extra;
}

// A time limit stops the search after the evaluation that passes it: exit 5, the summary marked
// incomplete, the best design so far written (the crank-rocker's start is feasible).
TEST(OptimizeCli, ATimeLimitKeepsTheBestSoFar) {
  const test::TempDir dir("orthomech_optimize_");
  const std::string study = (dir.path / "o.yaml").string();
  std::ofstream(study) << crank_study("");
  const auto r = run_cli({"optimize", test::bundled_file("crank-rocker"), "--study", study, "--out",
                          (dir.path / "a").string(), "--time-limit", "1e-9", "--json"});
  EXPECT_EQ(r.status, 5) << r.err;
  const json j = json::parse(r.out);
  EXPECT_FALSE(j["complete"].get<bool>());
  EXPECT_EQ(j["stop"], "time_limit");
  EXPECT_EQ(j["outcome"], "stopped");
  EXPECT_EQ(j["evaluations"].get<long>(), 1);
  EXPECT_TRUE(fs::exists(dir.path / "a" / "optimum.yaml"));
}

// A search stopped by its time limit and resumed ends as one uninterrupted run: the same
// summary (but `complete`), the same evaluations.csv and optimum.yaml; the stored evaluations are
// replayed, not computed (the second run logs how many). A larger budget continues it as well.
TEST(OptimizeCli, AStoppedSearchResumedEqualsOneRun) {
  const test::TempDir dir("orthomech_optimize_");
  const std::string study = (dir.path / "o.yaml").string();
  std::ofstream(study) << crank_study("constraints:\n  - {metric: range(rocker_angle), min: 50}\n");
  const std::string once = (dir.path / "once").string(), split = (dir.path / "split").string();
  const auto a = run_cli(
      {"optimize", test::bundled_file("crank-rocker"), "--study", study, "--out", once, "--json"});
  ASSERT_EQ(a.status, 0) << a.err;
  const auto b1 = run_cli({"optimize", test::bundled_file("crank-rocker"), "--study", study,
                           "--out", split, "--time-limit", "1e-9", "--json"});
  ASSERT_EQ(b1.status, 5) << b1.err;
  const auto again = run_cli(
      {"optimize", test::bundled_file("crank-rocker"), "--study", study, "--out", split, "--json"});
  EXPECT_EQ(again.status, 2) << "an existing study without --resume: " << again.err;
  const auto b2 = run_cli({"optimize", test::bundled_file("crank-rocker"), "--study", study,
                           "--out", split, "--resume", "--json", "--verbose"});
  ASSERT_EQ(b2.status, 0) << b2.err;
  EXPECT_NE(b2.err.find("1 evaluations stored, replayed"), std::string::npos) << b2.err;
  json ja = json::parse(a.out), jb = json::parse(b2.out);
  EXPECT_TRUE(jb["complete"].get<bool>());
  ja["optimum"].erase("file");
  jb["optimum"].erase("file");
  EXPECT_EQ(ja, jb);
  EXPECT_EQ(test::read_text(fs::path(once) / "evaluations.csv"),
            test::read_text(fs::path(split) / "evaluations.csv"));
  EXPECT_EQ(test::read_text(fs::path(once) / "optimum.yaml"),
            test::read_text(fs::path(split) / "optimum.yaml"));
  // A search ended by its budget (5 evaluations) resumed with a larger one (60): as one run
  // with 60.
  const std::string small = (dir.path / "small").string();
  std::ofstream(study) << crank_study(
      "constraints:\n  - {metric: range(rocker_angle), min: 50}\nevaluations: 5\n");
  const auto c1 = run_cli(
      {"optimize", test::bundled_file("crank-rocker"), "--study", study, "--out", small, "--json"});
  ASSERT_EQ(c1.status, 0) << c1.err;
  EXPECT_EQ(json::parse(c1.out)["evaluations"].get<long>(), 5);
  std::ofstream(study) << crank_study(
      "constraints:\n  - {metric: range(rocker_angle), min: 50}\nevaluations: 60\n");
  const auto c2 = run_cli({"optimize", test::bundled_file("crank-rocker"), "--study", study,
                           "--out", small, "--resume", "--json"});
  ASSERT_EQ(c2.status, 0) << c2.err;
  json jc = json::parse(c2.out);
  jc["optimum"].erase("file");
  EXPECT_EQ(jc, ja) << c2.out;  // the search converges within 60 (and within 200, run a)
  // Another study in the directory: refused.
  std::ofstream(study) << crank_study("constraints:\n  - {metric: range(rocker_angle), min: 55}\n");
  const auto other = run_cli({"optimize", test::bundled_file("crank-rocker"), "--study", study,
                              "--out", split, "--resume"});
  EXPECT_EQ(other.status, 2) << other.err;
}

// A multistart on one thread and on two writes the same files (the searches' evaluations are
// numbered from s × evaluations whatever thread ran them).
TEST(OptimizeCli, AMultistartWritesTheSameFilesOnAnyNumberOfThreads) {
  const test::TempDir dir("orthomech_optimize_");
  const std::string study = (dir.path / "o.yaml").string();
  std::ofstream(study) << crank_study(
      "constraints:\n  - {metric: range(rocker_angle), min: 50}\nalgorithm: multistart\n"
      "starts: 3\nevaluations: 20\n");
  std::string files[2][2];
  for (const int jobs : {1, 2}) {
    const std::string out = (dir.path / "j").string() + std::to_string(jobs);
    const auto r = run_cli({"optimize", test::bundled_file("crank-rocker"), "--study", study,
                            "--out", out, "-j", std::to_string(jobs), "--json"});
    ASSERT_EQ(r.status, 0) << r.err;
    const json j = json::parse(r.out);
    EXPECT_EQ(j["algorithm"], "multistart");
    EXPECT_TRUE(j["found"].get<bool>());
    files[jobs - 1][0] = test::read_text(fs::path(out) / "evaluations.csv");
    files[jobs - 1][1] = test::read_text(fs::path(out) / "optimum.yaml");
  }
  EXPECT_EQ(files[0][0], files[1][0]);
  EXPECT_EQ(files[0][1], files[1][1]);
}

TEST(OptimizeCli, NoFeasibleDesignIsExit3AndWrongStudiesExit2) {
  const test::TempDir dir("orthomech_optimize_");
  const std::string study = (dir.path / "o.yaml").string();
  std::ofstream(study) << crank_study(
      "constraints:\n  - {metric: range(rocker_angle), min: 170}\nevaluations: 12\n");
  const auto r = run_cli({"optimize", test::bundled_file("crank-rocker"), "--study", study, "--out",
                          (dir.path / "a").string(), "--json"});
  EXPECT_EQ(r.status, 3) << r.err;
  const json j = json::parse(r.out);
  EXPECT_FALSE(j["found"].get<bool>());
  EXPECT_EQ(j["feasible_evaluations"].get<long>(), 0);
  EXPECT_FALSE(fs::exists(dir.path / "a" / "optimum.yaml"));
  EXPECT_TRUE(fs::exists(dir.path / "a" / "evaluations.csv"));

  const auto sweep = run_cli({"sweep", test::bundled_file("crank-rocker"), "--study", study,
                              "--out", (dir.path / "b").string()});
  EXPECT_EQ(sweep.status, 2);
  EXPECT_NE(sweep.err.find("orthomech optimize"), std::string::npos) << sweep.err;
  const std::string grid = (dir.path / "g.yaml").string();
  std::ofstream(grid) << "study: grid\nparameters:\n  - {path: bodies.crank.mass, values: [1]}\n";
  const auto o = run_cli({"optimize", test::bundled_file("crank-rocker"), "--study", grid, "--out",
                          (dir.path / "c").string()});
  EXPECT_EQ(o.status, 2);
  EXPECT_NE(o.err.find("orthomech sweep"), std::string::npos) << o.err;
}

// A spatial mechanism: the RSSR's crank length r1 for a rocker swing of 110° ± 0.01°. The swing of
// r1 is the closed form (support/spatial_oracles.hpp), increasing over [80, 120] mm: one r1 does
// it, found here by bisection.
TEST(OptimizeCli, SpatialRssrCrankForARockerSwing) {
  const test::TempDir dir("orthomech_optimize_");
  const std::string study = (dir.path / "o.yaml").string();
  std::ofstream(study) << "study: optimize\nparameters:\n"
                          "  - {name: crank, path: bodies.crank.points.A.0, bounds: [80, 120]}\n"
                          "objective: {minimize: drive.peak}\n"
                          "constraints:\n"
                          "  - {metric: range(rocker_angle), equal: 110, tolerance: 0.01}\n";
  const std::string out = (dir.path / "rssr").string();
  const auto r =
      run_cli({"optimize", test::bundled_file("rssr"), "--study", study, "--out", out, "--json"});
  ASSERT_EQ(r.status, 0) << r.err;
  const json j = json::parse(r.out);
  ASSERT_TRUE(j["found"].get<bool>()) << r.out;
  const double r1 = j["optimum"]["variables"]["crank"];
  const double deg = 180.0 / std::numbers::pi;
  // The swing at 360 positions is within 5e-4° of the closed form (tests/unit/study/
  // spatial_study_test.cpp): the constraint holds to its tolerance on the closed form too.
  const double swing = test::rssr_swing(r1 / 1000) * deg;
  EXPECT_NEAR(swing, 110.0, 0.01 + 5e-4) << "r1 = " << r1;
  double lo = 80, hi = 120;
  for (int i = 0; i < 60; ++i)
    (test::rssr_swing(0.5 * (lo + hi) / 1000) * deg < 110.0 ? lo : hi) = 0.5 * (lo + hi);
  const double slope = (test::rssr_swing(0.101) - test::rssr_swing(0.099)) * deg / 2;  // °/mm
  EXPECT_NEAR(r1, 0.5 * (lo + hi), (0.01 + 5e-4) / slope) << "slope " << slope << " °/mm";
  // The written optimum closes as drawn and sweeps the same swing.
  const auto cyc = run_cli({"cycle", (fs::path(out) / "optimum.yaml").string(), "--json"});
  ASSERT_EQ(cyc.status, 0) << cyc.err;
  EXPECT_EQ(cyc.err.find("does not close as drawn"), std::string::npos) << cyc.err;
  const json cj = json::parse(cyc.out);
  bool found = false;
  for (const auto& s : cj["strokes"])
    if (s["name"] == "rocker_angle") {
      found = true;
      EXPECT_NEAR(s["range"].get<double>(), j["optimum"]["metrics"]["rocker_angle.range"], 1e-9);
    }
  EXPECT_TRUE(found);
}

}  // namespace
}  // namespace orthomech
