// The commands on mechanisms/double-wishbone.yaml (docs/spatial.md §4.8): `info` reports its
// mobility (n = 18, n_c = 17, rank 17, DOF 1, no redundant row: the count a reader makes from the
// joint list, revolutes 5 + 5, ball joints 3 + 3, the tie rod 1), `assemble` finds the drawn pose
// closed with camber and toe 0, and `crosscheck` passes.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "support/cli_runner.hpp"

namespace orthomech {
namespace {

using nlohmann::json;
using test::CliResult;
using test::run_cli;

TEST(DoubleWishboneCli, InfoReportsDofOneRankSeventeen) {
  const CliResult r = run_cli({"info", test::bundled_file("double-wishbone"), "--json"});
  ASSERT_EQ(r.status, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j["dimension"], 3);
  EXPECT_EQ(j["dof"], 1);
  EXPECT_EQ(j["rank"], 17);
  EXPECT_EQ(j["grubler"], 1);
  EXPECT_TRUE(j["redundant"].empty());
  ASSERT_EQ(j["joints"].size(), 5u);
}

TEST(DoubleWishboneCli, AssembleAndCrosscheckPass) {
  const std::string file = test::bundled_file("double-wishbone");
  const CliResult a = run_cli({"assemble", file});
  ASSERT_EQ(a.status, 0) << a.err;
  EXPECT_NE(a.out.find("status      unchanged"), std::string::npos) << a.out;
  EXPECT_NE(a.out.find("camber           0 deg"), std::string::npos) << a.out;
  const CliResult c = run_cli({"crosscheck", file, "--json"});
  EXPECT_EQ(c.status, 0) << c.err;
  EXPECT_TRUE(json::parse(c.out)["pass"].get<bool>());
}

}  // namespace
}  // namespace orthomech
