// `orthomech cycle --drivers` (cli/cycle_drivers.cpp; docs/cli.md "cycle"): the five-bar's two
// cranks (100 mm on a 300 mm ground, 300 mm links, both at 90° in the design) driven at 60 and
// 30 rpm. Oracles written here: the inputs are the time laws 90° + 360°/s · t and
// 90° + 180°/s · t, the sweep lasts one turn of the slower crank (2 s), and the coupler point C
// is the apex of the isosceles triangle on A E (mm, the file's units); a driver count other than
// the DOF is exit 2.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <string>

#include "support/cli_runner.hpp"

namespace orthomech {
namespace {

using test::CliResult;
using test::run_cli;

double wrap_deg(double a) { return std::remainder(a, 360.0); }

TEST(CycleDriversCli, FiveBarInputsAndCouplerPointInTheFileUnits) {
  const CliResult r = run_cli({"cycle", test::bundled_file("five-bar"), "--drivers", "left,right",
                               "--steps", "9", "--json"});
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["dof"], 2);
  EXPECT_NEAR(j["t_end"].get<double>(), 2.0, 1e-12);
  ASSERT_EQ(j["points"].size(), 9u);
  EXPECT_EQ(j["drivers"][0]["input_unit"], "deg");
  for (const auto& p : j["points"]) {
    const double t = p["time"].get<double>();
    const double t1 = p["inputs"]["left"].get<double>(), t2 = p["inputs"]["right"].get<double>();
    EXPECT_NEAR(wrap_deg(t1 - (90.0 + 360.0 * t)), 0.0, 1e-9) << t;
    EXPECT_NEAR(wrap_deg(t2 - (90.0 + 180.0 * t)), 0.0, 1e-9) << t;
    const double a1 = t1 * M_PI / 180.0, a2 = t2 * M_PI / 180.0;
    const double ax = 100.0 * std::cos(a1), ay = 100.0 * std::sin(a1);
    const double ex = 300.0 + 100.0 * std::cos(a2), ey = 100.0 * std::sin(a2);
    const double L = std::hypot(ex - ax, ey - ay);
    const double h = std::sqrt(300.0 * 300.0 - 0.25 * L * L);
    const double cx = 0.5 * (ax + ex) - h * (ey - ay) / L;
    const double cy = 0.5 * (ay + ey) + h * (ex - ax) / L;
    EXPECT_NEAR(p["measures"]["C_x"].get<double>(), cx, 1e-8) << t;
    EXPECT_NEAR(p["measures"]["C_y"].get<double>(), cy, 1e-8) << t;
  }
}

TEST(CycleDriversCli, ADriverCountOtherThanTheDofIsExitTwo) {
  const CliResult r =
      run_cli({"cycle", test::bundled_file("five-bar"), "--drivers", "left", "--json"});
  EXPECT_EQ(r.status, 2) << r.out;
  EXPECT_NE(r.err.find("DOF"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace orthomech
