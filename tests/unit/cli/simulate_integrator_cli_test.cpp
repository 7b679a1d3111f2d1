// `orthomech simulate --integrator NAME` (docs/cli.md): every documented name runs and is echoed
// in the JSON with the step counters; an unknown name is a bad command line.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <string>

#include "support/cli_runner.hpp"
#include "support/fixtures.hpp"

namespace orthomech {
namespace {

using test::run_cli;

TEST(SimulateIntegratorCli, EveryIntegratorRunsThePendulum) {
  // Published A01 sample at t = 1 s (mechanisms/pendulum.yaml): (0.986292, -0.165011), 6 digits.
  for (const std::string name : {"dopri5", "rkf78", "bulirsch-stoer", "rosenbrock4"}) {
    const auto r =
        run_cli({"simulate", test::source_path("mechanisms/pendulum.yaml"), "--t-end", "1",
                 "--rtol", "1e-9", "--atol", "1e-9", "--integrator", name, "--json"});
    ASSERT_EQ(r.status, 0) << name << ": " << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["integrator"], name);
    EXPECT_EQ(j["status"], "completed");
    EXPECT_NEAR(j["final"]["measures"]["P1_x"].get<double>(), 0.986292, 1e-6) << name;
    EXPECT_NEAR(j["final"]["measures"]["P1_y"].get<double>(), -0.165011, 1e-6) << name;
    EXPECT_GE(j["rejected_steps"].get<long>(), 0);
    EXPECT_EQ(j["jacobians"].get<long>() > 0, name == "rosenbrock4") << name;
  }
}

TEST(SimulateIntegratorCli, UnknownIntegratorIsBadInput) {
  const auto r = run_cli({"simulate", test::source_path("mechanisms/pendulum.yaml"), "--t-end", "1",
                          "--integrator", "euler"});
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("euler"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace orthomech
