// `orthomech balance` (cli/balance.cpp): the JSON document, the balanced file it writes and
// `cycle`'s own shaking force of that file (a separate run of the other command as the check),
// and the refusals (exit 2 naming the option or the element).
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "support/cli_runner.hpp"

namespace orthomech {
namespace {

using test::bundled_file;
using test::run_cli;

// Berkof and Lowen's counterweights of the crank-rocker at 40 mm (tests/unit/analysis/
// balancing_test.cpp): 41.25 g on the crank and 105 g on the rocker, both at [−40, 0] mm; the
// written file's cycle has no shaking force (its peak below 1e-6 of the mechanism's before).
TEST(BalanceCli, ForceBalancesTheCrankRockerAndWritesAFileCycleConfirms) {
  const test::TempDir dir("balance_cli_");
  const std::string out = (dir.path / "balanced.yaml").string();
  const auto r = run_cli({"balance", bundled_file("crank-rocker"), "--counterweight", "crank:40",
                          "--counterweight", "rocker:40", "--write", out, "--json", "-q"});
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["status"], "balanced");
  ASSERT_EQ(j["counterweights"].size(), 2u);
  EXPECT_EQ(j["counterweights"][0]["body"], "crank");
  EXPECT_NEAR(j["counterweights"][0]["mass"].get<double>(), 0.04125, 1e-7);
  EXPECT_NEAR(j["counterweights"][1]["mass"].get<double>(), 0.105, 1e-7);
  EXPECT_NEAR(j["counterweights"][1]["position"][0].get<double>(), -40.0, 1e-4);
  const double before = j["before"]["shaking_force_rms"].get<double>();
  EXPECT_GT(before, 1.0);
  EXPECT_LT(j["after"]["shaking_force_rms"].get<double>(), 1e-6 * before);
  EXPECT_EQ(j["written"], out);
  const auto cy = run_cli({"cycle", out, "--json", "-q"});
  ASSERT_EQ(cy.status, 0) << cy.err;
  const auto peaks = nlohmann::json::parse(cy.out)["peaks"];
  EXPECT_LT(peaks["shaking force"]["peak"].get<double>(), 1e-6 * before);
  const auto plain = run_cli({"cycle", bundled_file("crank-rocker"), "--json", "-q"});
  ASSERT_EQ(plain.status, 0) << plain.err;
  EXPECT_NEAR(nlohmann::json::parse(plain.out)["peaks"]["shaking force"]["rms"].get<double>(),
              before, 1e-9 * before);
}

TEST(BalanceCli, RefusesBadSitesSpatialFilesAndOverwritingItsInput) {
  const std::string file = bundled_file("crank-rocker");
  const auto unknown = run_cli({"balance", file, "--counterweight", "flywheel:40"});
  EXPECT_EQ(unknown.status, 2);
  EXPECT_NE(unknown.err.find("'flywheel'"), std::string::npos) << unknown.err;
  const auto no_radius = run_cli({"balance", file, "--counterweight", "crank"});
  EXPECT_EQ(no_radius.status, 2);
  EXPECT_NE(no_radius.err.find("BODY:RADIUS"), std::string::npos) << no_radius.err;
  const auto twice =
      run_cli({"balance", file, "--counterweight", "crank:40", "--counterweight", "crank:20"});
  EXPECT_EQ(twice.status, 2);
  EXPECT_NE(twice.err.find("two counterweight sites"), std::string::npos) << twice.err;
  const auto spatial =
      run_cli({"balance", bundled_file("crank-rocker-3d"), "--counterweight", "crank:40"});
  EXPECT_EQ(spatial.status, 2);
  const auto over = run_cli({"balance", file, "--counterweight", "crank:40", "--write", file});
  EXPECT_EQ(over.status, 2);
  EXPECT_NE(over.err.find("overwrite"), std::string::npos) << over.err;
  const auto about = run_cli({"cycle", file, "--shaking-about", "1,2,3", "-q"});
  EXPECT_EQ(about.status, 2);
  EXPECT_NE(about.err.find("--shaking-about"), std::string::npos) << about.err;
}

// Bounded like every long run: --time-limit stops its sweep (1e5 positions of the crank-rocker,
// about 0.4 s in the Release build) with exit 5 and nothing written.
TEST(BalanceCli, TimeLimitStopsItsSweepAndWritesNothing) {
  const test::TempDir dir("balance_cli_");
  const std::string out = (dir.path / "balanced.yaml").string();
  const auto r = run_cli({"balance", bundled_file("crank-rocker"), "--counterweight", "crank:40",
                          "--steps", "100000", "--time-limit", "0.02", "--write", out, "-q"});
  EXPECT_EQ(r.status, 5) << r.err;
  EXPECT_NE(r.err.find("--time-limit"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(out));
}

}  // namespace
}  // namespace orthomech
