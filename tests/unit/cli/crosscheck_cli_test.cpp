// `orthomech crosscheck` (cli/crosscheck.cpp; docs/cli.md): exit 0 when the dual and primal forms
// agree, 1 when they do not (an impossible tolerance), the JSON keys, and the primal form skipped
// with its reason on a mechanism with a redundant equation (the check itself:
// dynamics/crosscheck_test.cpp).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "support/cli_runner.hpp"
#include "support/fixtures.hpp"

namespace orthomech {
namespace {

// The check can fail: with an impossible tolerance the rounding differences fail it.
TEST(CrosscheckCli, ExitStatusAndJson) {
  const auto ok = test::run_cli({"crosscheck", test::source_path("mechanisms/crank-rocker.yaml"),
                                 "--samples", "3", "--json"});
  ASSERT_EQ(ok.status, 0) << ok.err;
  const auto j = nlohmann::json::parse(ok.out);
  EXPECT_TRUE(j["pass"].get<bool>());
  EXPECT_EQ(j["samples"].get<int>(), 3);

  const auto bad = test::run_cli({"crosscheck", test::source_path("mechanisms/crank-rocker.yaml"),
                                  "--samples", "3", "--tolerance", "1e-30", "--json"});
  EXPECT_EQ(bad.status, 1);
  EXPECT_FALSE(nlohmann::json::parse(bad.out)["pass"].get<bool>());

  const auto red = test::run_cli(
      {"crosscheck", test::source_path("mechanisms/triple-crank.yaml"), "--samples", "3"});
  EXPECT_EQ(red.status, 0) << red.err;
  EXPECT_NE(red.out.find("primal      skipped"), std::string::npos) << red.out;
}

}  // namespace
}  // namespace orthomech
