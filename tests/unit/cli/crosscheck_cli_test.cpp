// `orthomech crosscheck` (cli/crosscheck.cpp; docs/cli.md): exit 0 when the dual and primal forms
// agree, 1 when they do not (an impossible tolerance), the JSON keys, --method, and the primal form
// skipped with its reason on a mechanism with a redundant equation (the check itself:
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

// --method: the JSON says which comparison ran; `probes` forms no n × n matrix, so it also runs
// where `dense` is refused; an unknown method is a usage error (exit 2) naming the choices.
TEST(CrosscheckCli, MethodOption) {
  const std::string file = test::source_path("mechanisms/crank-rocker.yaml");
  for (const char* m : {"dense", "probes"}) {
    const auto r = test::run_cli({"crosscheck", file, "--samples", "3", "--method", m, "--json"});
    ASSERT_EQ(r.status, 0) << m << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["method"].get<std::string>(), m);
    EXPECT_TRUE(j["pass"].get<bool>());
    EXPECT_TRUE(j["primal_checked"].get<bool>());
  }
  const auto automatic = test::run_cli({"crosscheck", file, "--samples", "3", "--json"});
  EXPECT_EQ(nlohmann::json::parse(automatic.out)["method"].get<std::string>(), "dense");
  const auto bad = test::run_cli({"crosscheck", file, "--method", "sparse"});
  EXPECT_EQ(bad.status, 2);
  EXPECT_NE(bad.err.find("probes"), std::string::npos) << bad.err;
}

}  // namespace
}  // namespace orthomech
