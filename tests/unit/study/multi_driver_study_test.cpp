// Design studies swept by several drivers (Study::drivers, docs/cli.md "sweep": `drivers:`), on
// mechanisms/five-bar.yaml driven by both cranks (left 60 rpm, right 30 rpm) over 2 s at 201
// positions, the right crank's length r2 a parameter. Oracles:
//   - the closed form of the file's header: C is the upper intersection of |C − A| = 300 and
//     |C − E| = 300 with A = 100 (cos θ1, sin θ1), E = (300, 0) + r2 (cos θ2, sin θ2), θ1 = 90° +
//     360° t, θ2 = 90° + 180° t — evaluated here at the study's times t_k = k · 0.01 s, so the
//     sampled extremes of C_x and C_y and their times are exact (each position solved to ~1e-12);
//   - the drivers' laws: θ1 sweeps 720°, θ2 360°;
//   - `cycle --drivers left,right --set …` on the command line: the drives' extremes from its
//     positions;
//   - the reader's refusals: an unknown driver, a deviation, at().
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>
#include <vector>

#include "orthomech/study/study.hpp"
#include "support/cli_runner.hpp"

namespace orthomech {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

struct Point {
  double x, y;
};

Point coupler_point(double t, double r2) {
  const double t1 = (90 + 360 * t) * kDeg, t2 = (90 + 180 * t) * kDeg;
  const Point A{100 * std::cos(t1), 100 * std::sin(t1)};
  const Point E{300 + r2 * std::cos(t2), r2 * std::sin(t2)};
  const double dx = E.x - A.x, dy = E.y - A.y, L = std::hypot(dx, dy);
  const double h = std::sqrt(300.0 * 300.0 - L * L / 4);
  return {0.5 * (A.x + E.x) - h * dy / L, 0.5 * (A.y + E.y) + h * dx / L};
}

const char* kStudy = R"(study: grid
drivers: [left, right]
t_end: 2
steps: 201
parameters:
  - {name: r2, path: bodies.crank2.points.E.0, values: [90, 110]}
best: {metric: drive.left.peak, order: min, count: 2}
)";

TEST(MultiDriverStudy, CouplerPointExtremesAreTheClosedFormsAtTheStudysTimes) {
  const std::string file = test::bundled_file("five-bar");
  const std::string mechanism = test::read_text(file);
  const Study study = parse_study(kStudy, "s.yaml", mechanism, file);
  ASSERT_EQ(study.drivers.size(), 2u);
  EXPECT_DOUBLE_EQ(study.t_end, 2.0);
  for (long k = 0; k < variant_count(study); ++k) {
    const std::vector<double> values = variant_values(study, k);
    const VariantResult r = evaluate_variant(mechanism, file, study, k, values);
    ASSERT_EQ(r.status, "completed") << r.message;
    EXPECT_EQ(r.positions, 201);
    std::map<std::string, double> m;
    for (const auto& [name, value] : r.metrics) m[name] = value;
    double x_lo = 1e9, x_hi = -1e9, y_lo = 1e9, y_hi = -1e9, y_hi_at = 0;
    for (int i = 0; i <= 200; ++i) {
      const double t = 0.01 * i;
      const Point c = coupler_point(t, values[0]);
      x_lo = std::min(x_lo, c.x);
      x_hi = std::max(x_hi, c.x);
      y_lo = std::min(y_lo, c.y);
      if (c.y > y_hi) y_hi = c.y, y_hi_at = t;
    }
    EXPECT_NEAR(m.at("C_x.min"), x_lo, 1e-8) << "r2 " << values[0];
    EXPECT_NEAR(m.at("C_x.max"), x_hi, 1e-8) << "r2 " << values[0];
    EXPECT_NEAR(m.at("C_y.min"), y_lo, 1e-8) << "r2 " << values[0];
    EXPECT_NEAR(m.at("C_y.max"), y_hi, 1e-8) << "r2 " << values[0];
    EXPECT_NEAR(m.at("C_y.max_at"), y_hi_at, 1e-12) << "r2 " << values[0];
    EXPECT_NEAR(m.at("C_y.range"), y_hi - y_lo, 1e-8);
    EXPECT_TRUE(std::isnan(m.at("C_y.time_ratio")));
    EXPECT_NEAR(m.at("theta1.range"), 720.0, 1e-9);
    EXPECT_NEAR(m.at("theta2.range"), 360.0, 1e-9);

    // The drives' extremes from `cycle --drivers` on the same variant.
    const auto cli =
        test::run_cli({"cycle", file, "--drivers", "left,right", "--t-end", "2", "--steps", "201",
                       "--set", "bodies.crank2.points.E.0=" + value_text(values[0]), "--json"});
    ASSERT_EQ(cli.status, 0) << cli.err;
    const nlohmann::json j = nlohmann::json::parse(cli.out);
    for (const char* d : {"left", "right"}) {
      double lo = 1e300, hi = -1e300;
      for (const auto& p : j["points"]) {
        lo = std::min(lo, p["drives"][d].get<double>());
        hi = std::max(hi, p["drives"][d].get<double>());
      }
      const std::string name = std::string("drive.") + d;
      EXPECT_NEAR(m.at(name + ".max"), hi, 1e-9 * std::abs(hi)) << d;
      EXPECT_NEAR(m.at(name + ".min"), lo, 1e-9 * std::abs(lo)) << d;
      EXPECT_NEAR(m.at(name + ".peak"), std::max(std::abs(lo), std::abs(hi)), 1e-9 * std::abs(hi));
    }
    EXPECT_GT(m.at("A0.|F|.peak"), 0.0);
  }
}

TEST(MultiDriverStudy, TheReaderRefusesWhatNeedsOneDriver) {
  const std::string file = test::bundled_file("five-bar");
  const std::string mechanism = test::read_text(file);
  auto message = [&](const std::string& text) {
    try {
      (void)parse_study(text, "s.yaml", mechanism, file);
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  const std::string params = "parameters:\n  - {path: bodies.crank2.points.E.0, values: [90]}\n";
  EXPECT_NE(message("study: grid\ndrivers: [left, middle]\n" + params)
                .find("s.yaml:2:17: error: drivers: the file has no driver 'middle' (it has "
                      "left, right)"),
            std::string::npos)
      << message("study: grid\ndrivers: [left, middle]\n" + params);
  EXPECT_NE(message("study: grid\ndrivers: [left, left]\n" + params).find("listed twice"),
            std::string::npos);
  EXPECT_NE(message("study: grid\nt_end: 2\n" + params).find("belongs to a study with 'drivers'"),
            std::string::npos);
  EXPECT_NE(message("study: grid\ndrivers: [left, right]\nt_end: -1\n" + params)
                .find("t_end must be a positive time"),
            std::string::npos);
  EXPECT_NE(message("study: grid\ndrivers: [left, right]\n" + params +
                    "metrics: {cycle: true, deviation: [link3.C]}\n")
                .find("'deviation' compares paths at the inputs of one driver"),
            std::string::npos);
  EXPECT_NE(
      message("study: grid\ndrivers: [left, right]\n" + params + "expressions:\n  x: at(C_x, 90)\n")
          .find("needs the input of one driver"),
      std::string::npos);
  EXPECT_EQ(message("study: grid\ndrivers: [left, right]\n" + params), "accepted");
}

}  // namespace
}  // namespace orthomech
