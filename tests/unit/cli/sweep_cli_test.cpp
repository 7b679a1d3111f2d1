// `orthomech sweep` (docs/cli.md "sweep"): a variant's metrics equal a standalone `cycle --set`
// run; 1 and 2 threads give identical files; a study killed mid-way and resumed gives the file of
// an uninterrupted one; σ = 0 gives the nominal design; bad study files are exit 2 at their line.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "support/cli_runner.hpp"

namespace orthomech {
namespace {

namespace fs = std::filesystem;
using test::run_cli;

struct Dir : test::TempDir {
  Dir() : test::TempDir("orthomech_sweep_") {}
  std::string file(const std::string& name) const { return (path / name).string(); }
  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(path / name) << text;
    return file(name);
  }
};

std::vector<std::vector<std::string>> csv(const std::string& text) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> cells;
    std::string cell;
    std::istringstream l(line);
    while (std::getline(l, cell, ',')) cells.push_back(cell);
    if (!line.empty() && line.back() == ',') cells.emplace_back();
    rows.push_back(cells);
  }
  return rows;
}

std::string column(const std::vector<std::vector<std::string>>& rows, size_t row,
                   const std::string& name) {
  for (size_t c = 0; c < rows[0].size(); ++c)
    if (rows[0][c] == name) return rows.at(row).at(c);
  ADD_FAILURE() << "no column " << name;
  return "";
}

const std::string kMonteCarlo = R"(study: monte-carlo
samples: SAMPLES
seed: 11
parameters:
  - {name: crank, path: bodies.crank.points.A.0, normal: {sigma: SIGMA}}
  - {name: ground, path: ground.points.B0.0, uniform: {tolerance: TOLERANCE}}
)";

std::string monte_carlo(int samples, const std::string& sigma, const std::string& tolerance) {
  std::string s = kMonteCarlo;
  s.replace(s.find("SAMPLES"), 7, std::to_string(samples));
  s.replace(s.find("SIGMA"), 5, sigma);
  s.replace(s.find("TOLERANCE"), 9, tolerance);
  return s;
}

TEST(SweepCli, AVariantsMetricsEqualACycleSetRun) {
  Dir dir;
  const std::string mech = test::bundled_file("crank-rocker");
  const std::string study = dir.write("grid.yaml", R"(study: grid
parameters:
  - {name: crank, path: bodies.crank.points.A.0, values: [30, 32.5]}
  - {path: drivers.motor.speed, values: [300, 600]}
)");
  const auto r =
      run_cli({"sweep", mech, "--study", study, "--out", dir.file("out"), "--jobs", "1"});
  ASSERT_EQ(r.status, 0) << r.err;
  const auto rows = csv(test::read_text(dir.path / "out" / "variants.csv"));
  ASSERT_EQ(rows.size(), 5u);
  // Variant 3: crank 32.5, speed 600 (deg/s in the file's units: the file's bare numbers).
  EXPECT_EQ(column(rows, 4, "crank"), "32.5");
  EXPECT_EQ(column(rows, 4, "drivers.motor.speed"), "600");
  const auto c = run_cli({"cycle", mech, "--set", "bodies.crank.points.A.0=32.5", "--set",
                          "drivers.motor.speed=600", "--json"});
  ASSERT_EQ(c.status, 0) << c.err;
  const auto j = nlohmann::json::parse(c.out);
  const auto metric = [&](const std::string& name) { return std::stod(column(rows, 4, name)); };
  EXPECT_EQ(metric("drive.max"), j["peaks"]["drive"]["max"]["value"].get<double>());
  EXPECT_EQ(metric("drive.min"), j["peaks"]["drive"]["min"]["value"].get<double>());
  EXPECT_EQ(metric("drive.peak"), j["peaks"]["drive"]["peak"].get<double>());
  EXPECT_EQ(metric("drive.rms"), j["peaks"]["drive"]["rms"].get<double>());
  EXPECT_EQ(metric("B.|F|.peak"), j["peaks"]["B.|F|"]["peak"].get<double>());
  EXPECT_EQ(metric("power.mean"), j["power"]["mean"].get<double>());
  EXPECT_EQ(metric("transmission.min"), j["loops"][0]["worst"]["value"].get<double>());
  EXPECT_EQ(metric("dead_points"), 0.0);
  // The variants differ (the comparison can fail): variant 0 is the nominal design.
  EXPECT_NE(column(rows, 1, "drive.peak"), column(rows, 4, "drive.peak"));
}

TEST(SweepCli, OneAndTwoThreadsGiveIdenticalFiles) {
  Dir dir;
  const std::string mech = test::bundled_file("crank-rocker");
  const std::string study = dir.write("mc.yaml", monte_carlo(12, "0.05", "0.1"));
  const auto one = run_cli({"sweep", mech, "--study", study, "--out", dir.file("one"), "-j", "1"});
  const auto two = run_cli({"sweep", mech, "--study", study, "--out", dir.file("two"), "-j", "2"});
  ASSERT_EQ(one.status, 0) << one.err;
  ASSERT_EQ(two.status, 0) << two.err;
  std::string out = one.out;  // the same but for the output directory's name
  for (auto at = out.find("/one/"); at != std::string::npos; at = out.find("/one/", at))
    out.replace(at, 5, "/two/");
  EXPECT_EQ(out, two.out);
  const std::string a = test::read_text(dir.path / "one" / "variants.csv");
  EXPECT_EQ(a, test::read_text(dir.path / "two" / "variants.csv"));
  EXPECT_EQ(test::read_text(dir.path / "one" / "summary.json"),
            test::read_text(dir.path / "two" / "summary.json"));
  EXPECT_EQ(csv(a).size(), 13u);
}

// mpirun -n 2 and -n 3 (rank 0 stores, the others evaluate what they are handed) write the files
// of one process. Open MPI comes from scripts/setup; a missing mpirun is a failure, not a skip.
TEST(SweepCli, MpirunGivesTheFilesOfOneProcess) {
  ASSERT_EQ(std::system("command -v mpirun > /dev/null 2>&1"), 0)
      << "mpirun is not installed: scripts/setup installs Open MPI (openmpi-bin, libopenmpi-dev)";
  Dir dir;
  const std::string mech = test::bundled_file("crank-rocker");
  const std::string study = dir.write("mc.yaml", monte_carlo(20, "0.05", "0.1"));
  const auto one = run_cli({"sweep", mech, "--study", study, "--out", dir.file("one"), "-j", "1"});
  ASSERT_EQ(one.status, 0) << one.err;
  for (const char* ranks : {"2", "3"}) {
    SCOPED_TRACE(ranks);
    const std::string out = dir.file(std::string("mpi") + ranks);
    const std::string command =
        "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 "
        "OMPI_MCA_rmaps_base_oversubscribe=1 "
        "mpirun -n " +
        std::string(ranks) + " '" + std::string(ORTHOMECH_CLI) + "' sweep '" + mech +
        "' --study '" + study + "' --out '" + out + "' -v > '" + out + ".log' 2>&1";
    const int status = std::system(command.c_str());
    const std::string log = test::read_text(out + ".log");
    ASSERT_EQ(status, 0) << log;
    EXPECT_NE(log.find(std::string(ranks) + " MPI ranks"), std::string::npos) << log;
    EXPECT_EQ(test::read_text(fs::path(out) / "variants.csv"),
              test::read_text(dir.path / "one" / "variants.csv"));
    EXPECT_EQ(test::read_text(fs::path(out) / "summary.json"),
              test::read_text(dir.path / "one" / "summary.json"));
  }
}

// The metric blocks under mpirun: each rank computes the nominal paths once; the files are
// those of one process.
TEST(SweepCli, MpirunGivesTheFilesOfOneProcessWithEveryMetricBlock) {
  ASSERT_EQ(std::system("command -v mpirun > /dev/null 2>&1"), 0)
      << "mpirun is not installed: scripts/setup installs Open MPI (openmpi-bin, libopenmpi-dev)";
  Dir dir;
  const std::string mech = test::bundled_file("crank-rocker");
  const std::string study = dir.write("all.yaml", R"(study: monte-carlo
samples: 8
seed: 4
steps: 36
parameters:
  - {name: crank, path: bodies.crank.points.A.0, normal: {sigma: 0.3}}
  - {name: ground, path: ground.points.B0.0, uniform: {tolerance: 0.5}}
metrics: {cycle: true, validate: true, assemble: true, deviation: [coupler.P, rocker.B]}
)");
  const auto one = run_cli({"sweep", mech, "--study", study, "--out", dir.file("one"), "-j", "1"});
  ASSERT_EQ(one.status, 0) << one.err;
  const std::string out = dir.file("mpi");
  const std::string command =
      "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 "
      "OMPI_MCA_rmaps_base_oversubscribe=1 mpirun -n 2 '" +
      std::string(ORTHOMECH_CLI) + "' sweep '" + mech + "' --study '" + study + "' --out '" + out +
      "' > '" + out + ".log' 2>&1";
  ASSERT_EQ(std::system(command.c_str()), 0) << test::read_text(out + ".log");
  const std::string csv_one = test::read_text(dir.path / "one" / "variants.csv");
  EXPECT_EQ(test::read_text(fs::path(out) / "variants.csv"), csv_one);
  EXPECT_EQ(test::read_text(fs::path(out) / "summary.json"),
            test::read_text(dir.path / "one" / "summary.json"));
  EXPECT_NE(csv_one.find("deviation.rocker.B.rms"), std::string::npos);
  EXPECT_NE(csv_one.find("validate.p3.target"), std::string::npos);
}

TEST(SweepCli, AKilledStudyResumedGivesTheUninterruptedFile) {
  Dir dir;
  const std::string mech = test::bundled_file("crank-rocker");
  const std::string study = dir.write("mc.yaml", monte_carlo(400, "0.05", "0.1"));
  const auto full = run_cli({"sweep", mech, "--study", study, "--out", dir.file("full")});
  ASSERT_EQ(full.status, 0) << full.err;
  // Kill a run part-way (SIGKILL: nothing flushed on the way out), at growing delays until the
  // kill lands mid-study; then resume it.
  bool partial = false;
  for (const char* delay : {"0.4", "0.8", "1.6", "3.2"}) {
    fs::remove_all(dir.path / "killed");
    const std::string command =
        "timeout -s KILL " + std::string(delay) + " '" + std::string(ORTHOMECH_CLI) + "' sweep '" +
        mech + "' --study '" + study + "' --out '" + dir.file("killed") + "' -j 1 > /dev/null 2>&1";
    (void)std::system(command.c_str());
    const auto resumed =
        run_cli({"sweep", mech, "--study", study, "--out", dir.file("killed"), "--resume", "-v"});
    ASSERT_EQ(resumed.status, 0) << resumed.err;
    EXPECT_EQ(test::read_text(dir.path / "killed" / "variants.csv"),
              test::read_text(dir.path / "full" / "variants.csv"));
    // "400 variants, K stored, 400 - K to compute": the kill landed mid-way when 0 < K < 400.
    const auto at = resumed.err.find("400 variants, ");
    ASSERT_NE(at, std::string::npos) << resumed.err;
    const long stored = std::stol(resumed.err.substr(at + 14));
    if (stored > 0 && stored < 400) {
      partial = true;
      break;
    }
  }
  EXPECT_TRUE(partial) << "no kill landed mid-study";
}

TEST(SweepCli, ZeroSpreadGivesTheNominalDesign) {
  Dir dir;
  const std::string mech = test::bundled_file("crank-rocker");
  const std::string study = dir.write("mc.yaml", monte_carlo(3, "0", "0"));
  const auto r =
      run_cli({"sweep", mech, "--study", study, "--out", dir.file("out"), "--json", "-j", "1"});
  ASSERT_EQ(r.status, 0) << r.err;
  const auto rows = csv(test::read_text(dir.path / "out" / "variants.csv"));
  const auto c = nlohmann::json::parse(run_cli({"cycle", mech, "--json"}).out);
  for (size_t row = 1; row <= 3; ++row) {
    EXPECT_EQ(column(rows, row, "crank"), "30");
    EXPECT_EQ(std::stod(column(rows, row, "drive.peak")),
              c["peaks"]["drive"]["peak"].get<double>());
    EXPECT_EQ(std::stod(column(rows, row, "A.|F|.peak")),
              c["peaks"]["A.|F|"]["peak"].get<double>());
  }
  const auto summary = nlohmann::json::parse(r.out);
  EXPECT_EQ(summary["nominal"]["drive.peak"].get<double>(),
            c["peaks"]["drive"]["peak"].get<double>());
}

// The metric blocks (`metrics:`): the validate and assemble columns of a variant equal standalone
// `validate --set` and `assemble --set` runs of the same values; a loop that cannot close
// (a − d = 250 − 70 > b + c = 80 + 60: no crank angle closes it) is a row with its status,
// assemble.ok 0 and validate.pass 0, never the end of the study; the nominal design's deviation
// is 0; -j 1 and -j 2 give the same files.
TEST(SweepCli, CheckColumnsEqualStandaloneValidateAndAssembleRuns) {
  Dir dir;
  const std::string mech = test::bundled_file("crank-rocker");
  const std::string study = dir.write("checks.yaml", R"(study: grid
steps: 36
parameters:
  - {name: crank, path: bodies.crank.points.A.0, values: [30, 31, 250]}
metrics: {cycle: true, validate: true, assemble: true, deviation: [coupler.P]}
)");
  const auto one =
      run_cli({"sweep", mech, "--study", study, "--out", dir.file("one"), "-j", "1", "--json"});
  ASSERT_EQ(one.status, 0) << one.err;
  const auto two =
      run_cli({"sweep", mech, "--study", study, "--out", dir.file("two"), "-j", "2", "--json"});
  ASSERT_EQ(two.status, 0) << two.err;
  const std::string text = test::read_text(dir.path / "one" / "variants.csv");
  EXPECT_EQ(text, test::read_text(dir.path / "two" / "variants.csv"));
  EXPECT_EQ(one.out, two.out);
  const auto rows = csv(text);
  ASSERT_EQ(rows.size(), 4u);
  const auto summary = nlohmann::json::parse(one.out);
  EXPECT_EQ(summary["nominal"]["deviation.coupler.P.max"].get<double>(), 0.0);
  EXPECT_EQ(summary["nominal"]["validate.pass"].get<double>(), 1.0);
  EXPECT_EQ(summary["nominal"]["assemble.ok"].get<double>(), 1.0);

  // Row 3, crank 250: a row with its status; nothing of the cycle, the checks fail.
  EXPECT_EQ(column(rows, 3, "crank"), "250");
  EXPECT_EQ(column(rows, 3, "status"), "failed");
  EXPECT_NE(column(rows, 3, "message").find("does not assemble"), std::string::npos);
  EXPECT_EQ(column(rows, 3, "drive.peak"), "");
  EXPECT_EQ(column(rows, 3, "deviation.coupler.P.max"), "");
  EXPECT_EQ(column(rows, 3, "assemble.ok"), "0");
  EXPECT_EQ(column(rows, 3, "assemble.distance"), "");
  EXPECT_EQ(column(rows, 3, "validate.pass"), "0");
  EXPECT_EQ(column(rows, 3, "validate.p1.assembles"), "0");

  // Rows 2 and 3 against the standalone commands.
  for (const size_t row : {size_t{2}, size_t{3}}) {
    const std::string set = "bodies.crank.points.A.0=" + column(rows, row, "crank");
    SCOPED_TRACE(set);
    const auto v = run_cli({"validate", mech, "--set", set, "--json"});
    ASSERT_TRUE(v.status == 0 || v.status == 1) << v.err;
    const auto vj = nlohmann::json::parse(v.out);
    EXPECT_EQ(column(rows, row, "validate.pass"), vj["pass"].get<bool>() ? "1" : "0");
    for (const auto& p : vj["positions"]) {
      const std::string name = p["name"];
      EXPECT_EQ(column(rows, row, "validate." + name + ".assembles"),
                p["assembles"].get<bool>() ? "1" : "0");
      if (p["assembles"].get<bool>()) {
        EXPECT_EQ(column(rows, row, "validate." + name + ".target"),
                  p["target_met"].get<bool>() ? "1" : "0");
        bool transmission = true;
        for (const auto& f : p["four_bars"]) transmission = transmission && f["ok"].get<bool>();
        EXPECT_EQ(column(rows, row, "validate." + name + ".transmission"),
                  transmission ? "1" : "0");
      }
    }
    const auto a = run_cli({"assemble", mech, "--set", set, "--json"});
    const auto aj = nlohmann::json::parse(a.out);
    const bool ok = a.status == 0;
    EXPECT_EQ(column(rows, row, "assemble.ok"), ok ? "1" : "0");
    if (ok) {
      EXPECT_EQ(std::stod(column(rows, row, "assemble.distance")), aj["distance"].get<double>());
    }
  }
  // Crank 31: moved from the file's closed pose, the targets missed (a check that can fail).
  EXPECT_EQ(column(rows, 2, "validate.pass"), "0");
  EXPECT_GT(std::stod(column(rows, 2, "assemble.distance")), 0.0);
  EXPECT_GT(std::stod(column(rows, 2, "deviation.coupler.P.max")), 0.1);
}

// The summary of a Monte Carlo study counts the checks (assemble.*, validate.*) of every variant
// that has them — a variant that cannot close is part of the yield — and the cycle's metrics of
// the completed variants only. Oracle: the loop closes at some crank angle iff a − d ≤ b + c
// (a − 70 ≤ 140), read off each row's crank length.
TEST(SweepCli, MonteCarloSummaryCountsTheChecksOfEveryVariant) {
  Dir dir;
  const std::string mech = test::bundled_file("crank-rocker");
  const std::string study = dir.write("mc.yaml", R"(study: monte-carlo
samples: 16
seed: 3
steps: 36
parameters:
  - {name: crank, path: bodies.crank.points.A.0, uniform: {mean: 200, tolerance: 60}}
metrics: {cycle: true, assemble: true}
)");
  const auto r =
      run_cli({"sweep", mech, "--study", study, "--out", dir.file("out"), "--json", "-j", "2"});
  ASSERT_EQ(r.status, 0) << r.err;
  const auto rows = csv(test::read_text(dir.path / "out" / "variants.csv"));
  ASSERT_EQ(rows.size(), 17u);
  long closes = 0, completed = 0;
  for (size_t row = 1; row < rows.size(); ++row) {
    const double a = std::stod(column(rows, row, "crank"));
    const bool c = a - 70.0 <= 140.0;
    closes += c ? 1 : 0;
    completed += column(rows, row, "status") == "completed" ? 1 : 0;
    EXPECT_EQ(column(rows, row, "assemble.ok"), c ? "1" : "0") << "crank " << a;
  }
  ASSERT_GT(closes, 0);   // the draws reach both sides of a − d = b + c
  ASSERT_LT(closes, 16);  // (the test could not tell the two counts apart otherwise)
  const auto summary = nlohmann::json::parse(r.out);
  for (const auto& m : summary["metrics"]) {
    if (m["metric"] == "assemble.ok") {
      EXPECT_EQ(m["n"].get<long>(), 16);
      EXPECT_DOUBLE_EQ(m["mean"].get<double>(), double(closes) / 16.0);
    }
    if (m["metric"] == "drive.peak") {
      EXPECT_EQ(m["n"].get<long>(), completed);
    }
  }
  EXPECT_LT(completed, 16);  // a non-Grashof crank does not turn: its cycle is not completed
}

// Issue 51 item 4: a Monte Carlo study resumed with more samples computes only the new variants,
// and its files equal one run with the larger sample count (variant k's draws depend only on the
// seed and k). Fewer samples, or another seed, is another study (exit 2).
TEST(SweepCli, AMonteCarloStudyExtendedEqualsOneRunWithMoreSamples) {
  Dir dir;
  const std::string mech = test::bundled_file("crank-rocker");
  const std::string small = dir.write("small.yaml", monte_carlo(6, "0.05", "0.1"));
  const std::string large = dir.write("large.yaml", monte_carlo(10, "0.05", "0.1"));
  ASSERT_EQ(run_cli({"sweep", mech, "--study", small, "--out", dir.file("a")}).status, 0);
  const std::string first = test::read_text(dir.path / "a" / "variants.csv");
  const auto extended =
      run_cli({"sweep", mech, "--study", large, "--out", dir.file("a"), "--resume", "-v"});
  ASSERT_EQ(extended.status, 0) << extended.err;
  EXPECT_NE(extended.err.find("10 variants, 6 stored, 4 to compute"), std::string::npos)
      << extended.err;
  ASSERT_EQ(run_cli({"sweep", mech, "--study", large, "--out", dir.file("b")}).status, 0);
  const std::string whole = test::read_text(dir.path / "b" / "variants.csv");
  EXPECT_EQ(test::read_text(dir.path / "a" / "variants.csv"), whole);
  EXPECT_EQ(whole.substr(0, first.size()), first);  // the first six rows as they were
  EXPECT_EQ(csv(whole).size(), 11u);
  const auto fewer = run_cli({"sweep", mech, "--study", small, "--out", dir.file("a"), "--resume"});
  EXPECT_EQ(fewer.status, 2);
  EXPECT_NE(fewer.err.find("samples differ"), std::string::npos) << fewer.err;
  std::string reseeded = monte_carlo(12, "0.05", "0.1");
  reseeded.replace(reseeded.find("seed: 11"), 8, "seed: 12");
  const auto other = run_cli({"sweep", mech, "--study", dir.write("seed.yaml", reseeded), "--out",
                              dir.file("a"), "--resume"});
  EXPECT_EQ(other.status, 2);
  EXPECT_NE(other.err.find("holds another study"), std::string::npos) << other.err;
}

// Two Monte Carlo studies of the same file (seeds 11 and 12) combined: one study of their 6 + 4
// variants (the first's rows as they were, the second's renumbered 6 …), its quantiles those of
// the 10 values (numpy's linear interpolation, computed here from the CSV); not a study to
// --resume; a study of another mechanism file is refused.
TEST(SweepCli, CombinedStudiesAreOneStudyOfAllTheirVariants) {
  Dir dir;
  const std::string mech = test::bundled_file("crank-rocker");
  const std::string a = dir.write("a.yaml", monte_carlo(6, "0.05", "0.1"));
  std::string reseeded = monte_carlo(4, "0.05", "0.1");
  reseeded.replace(reseeded.find("seed: 11"), 8, "seed: 12");
  const std::string b = dir.write("b.yaml", reseeded);
  ASSERT_EQ(run_cli({"sweep", mech, "--study", a, "--out", dir.file("a")}).status, 0);
  ASSERT_EQ(run_cli({"sweep", mech, "--study", b, "--out", dir.file("b")}).status, 0);
  const auto r = run_cli({"sweep", mech, "--study", a, "--out", dir.file("ab"), "--combine",
                          dir.file("a") + "," + dir.file("b"), "--json"});
  ASSERT_EQ(r.status, 0) << r.err;
  const auto rows_a = csv(test::read_text(dir.path / "a" / "variants.csv"));
  const auto rows_b = csv(test::read_text(dir.path / "b" / "variants.csv"));
  const auto rows = csv(test::read_text(dir.path / "ab" / "variants.csv"));
  ASSERT_EQ(rows.size(), 11u);
  EXPECT_EQ(rows[0], rows_a[0]);  // the header
  for (size_t k = 1; k <= 6; ++k) EXPECT_EQ(rows[k], rows_a[k]);
  for (size_t k = 1; k <= 4; ++k) {
    std::vector<std::string> renumbered = rows_b[k];
    renumbered[0] = std::to_string(5 + k);
    EXPECT_EQ(rows[6 + k], renumbered);
  }
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["variants"].get<long>(), 10);
  ASSERT_EQ(j["combined"].size(), 2u);
  EXPECT_EQ(j["combined"][1]["variants"].get<long>(), 4);
  // The median and q95 of drive.peak over the 10 values.
  const size_t col = std::find(rows[0].begin(), rows[0].end(), "drive.peak") - rows[0].begin();
  std::vector<double> v;
  for (size_t k = 1; k < rows.size(); ++k) v.push_back(std::stod(rows[k][col]));
  std::sort(v.begin(), v.end());
  const auto quantile = [&](double p) {
    const double h = p * static_cast<double>(v.size() - 1);
    const auto i = static_cast<size_t>(std::floor(h));
    return i + 1 < v.size() ? v[i] + (h - static_cast<double>(i)) * (v[i + 1] - v[i]) : v[i];
  };
  bool found = false;
  for (const auto& m : j["metrics"])
    if (m["metric"] == "drive.peak") {
      found = true;
      EXPECT_NEAR(m["q50"].get<double>(), quantile(0.5), 1e-12 * quantile(0.5));
      EXPECT_NEAR(m["q95"].get<double>(), quantile(0.95), 1e-12 * quantile(0.95));
      EXPECT_EQ(m["n"].get<long>(), 10);
    }
  EXPECT_TRUE(found);
  // Not a study to resume; another mechanism's study is refused.
  const auto resume = run_cli({"sweep", mech, "--study", a, "--out", dir.file("ab"), "--resume"});
  EXPECT_EQ(resume.status, 2) << resume.err;
  std::string other_text = test::read_text(mech);
  other_text.replace(other_text.find("speed: 300 rpm"), 14, "speed: 200 rpm");
  const std::string other = dir.write("other.yaml", other_text);
  ASSERT_EQ(run_cli({"sweep", other, "--study", a, "--out", dir.file("c")}).status, 0);
  const auto mixed = run_cli({"sweep", mech, "--study", a, "--out", dir.file("ac"), "--combine",
                              dir.file("a") + "," + dir.file("c")});
  EXPECT_EQ(mixed.status, 2);
  EXPECT_NE(mixed.err.find("a study of another mechanism file"), std::string::npos) << mixed.err;
  const auto missing = run_cli(
      {"sweep", mech, "--study", a, "--out", dir.file("ad"), "--combine", dir.file("nowhere")});
  EXPECT_EQ(missing.status, 2);
  EXPECT_NE(missing.err.find("no study here"), std::string::npos) << missing.err;
}

TEST(SweepCli, BadStudiesAndOutputsAreExitTwo) {
  Dir dir;
  const std::string mech = test::bundled_file("crank-rocker");
  const auto run = [&](const std::string& text) {
    return run_cli({"sweep", mech, "--study", dir.write("s.yaml", text), "--out", dir.file("o")});
  };
  const auto key = run("study: grid\nparameters:\n  - {path: bodies.crank.mass, valus: [1]}\n");
  EXPECT_EQ(key.status, 2);
  EXPECT_NE(key.err.find("s.yaml:3:"), std::string::npos) << key.err;
  EXPECT_NE(key.err.find("unknown key 'valus'"), std::string::npos) << key.err;
  const auto path = run("study: grid\nparameters:\n  - {path: bodies.crnk.mass, values: [1]}\n");
  EXPECT_EQ(path.status, 2);
  EXPECT_NE(path.err.find("no item named 'crnk'"), std::string::npos) << path.err;
  const auto law =
      run("study: grid\nparameters:\n  - {path: bodies.crank.mass, normal: {sigma: 1}}\n");
  EXPECT_EQ(law.status, 2);
  EXPECT_NE(law.err.find("a grid study takes values or range"), std::string::npos) << law.err;
  // An existing study is continued only with --resume, and only the same study.
  const std::string good =
      "study: grid\nparameters:\n  - {path: bodies.crank.mass, values: [0.03]}\n";
  ASSERT_EQ(run(good).status, 0);
  const auto again = run(good);
  EXPECT_EQ(again.status, 2);
  EXPECT_NE(again.err.find("--resume"), std::string::npos) << again.err;
  const auto other = run_cli({"sweep", mech, "--study",
                              dir.write("s.yaml",
                                        "study: grid\nparameters:\n  - {path: "
                                        "bodies.crank.mass, values: [0.04]}\n"),
                              "--out", dir.file("o"), "--resume"});
  EXPECT_EQ(other.status, 2);
  EXPECT_NE(other.err.find("holds another study"), std::string::npos) << other.err;
}

}  // namespace
}  // namespace orthomech
