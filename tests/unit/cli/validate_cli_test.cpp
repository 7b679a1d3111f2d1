// `orthomech validate` (cli/validate.cpp; docs/cli.md): exit codes (0 pass, 1 defects), JSON keys.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "support/cli_runner.hpp"
#include "support/fixtures.hpp"

namespace orthomech {
namespace {

using test::run_cli;

TEST(ValidateCli, BundledCrankRocker_Exit0_JsonPass) {
  const auto r = run_cli({"validate", test::source_path("mechanisms/crank-rocker.yaml"), "--json"});
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_TRUE(j["pass"].get<bool>());
  EXPECT_EQ(j["positions"].size(), 3u);
  EXPECT_EQ(j["positions"][0]["four_bars"][0]["grashof"], "crank-rocker");
  EXPECT_EQ(j["positions"][0]["modes"], 2);
  const auto table = run_cli({"validate", test::source_path("mechanisms/crank-rocker.yaml")});
  EXPECT_EQ(table.status, 0);
  EXPECT_NE(table.out.find("every position passes every check"), std::string::npos);
}

TEST(ValidateCli, Defects_Exit1) {
  for (const char* f : {"crank-rocker-circuit-defect", "double-rocker-branch-defect",
                        "crank-rocker-order-defect"}) {
    const std::string file = test::source_path(std::string("tests/data/validate/") + f + ".yaml");
    const auto r = run_cli({"validate", file, "--json"});
    EXPECT_EQ(r.status, 1) << f << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_FALSE(j["pass"].get<bool>());
    EXPECT_FALSE(j["defects"].empty());
    const auto t = run_cli({"validate", file});
    EXPECT_EQ(t.status, 1);
    EXPECT_NE(t.out.find("defect"), std::string::npos) << t.out;
  }
}

}  // namespace
}  // namespace orthomech
