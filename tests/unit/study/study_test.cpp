// Study statistics (study.hpp): quantiles against numpy's default rule computed here by hand, the
// least-squares sensitivities against the normal equations solved independently (Cramer's rule)
// and an exactly linear metric, and the variants' values (grid order, reproducible draws).
#include "orthomech/study/study.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "support/cli_runner.hpp"

namespace orthomech {
namespace {

TEST(StudyStatistics, QuantilesFollowLinearInterpolationOfOrderStatistics) {
  // Five values: h = q (n - 1); q05 → h = 0.2: 1 + 0.2 (2 - 1); q50 → the middle; q95 → h = 3.8.
  const std::vector<double> metric = {5.0, 1.0, 4.0, 2.0, 3.0};
  const std::vector<std::vector<double>> values(5, std::vector<double>{0.0});
  const MetricStatistics s = metric_statistics("m", values, metric);
  EXPECT_EQ(s.n, 5);
  EXPECT_DOUBLE_EQ(s.q05, 1.2);
  EXPECT_DOUBLE_EQ(s.q50, 3.0);
  EXPECT_DOUBLE_EQ(s.q95, 4.8);
  EXPECT_DOUBLE_EQ(s.mean, 3.0);
  EXPECT_DOUBLE_EQ(s.stddev, std::sqrt(2.5));
  EXPECT_FALSE(s.sensitivity[0].has_value());  // the parameter does not vary
}

TEST(StudyStatistics, SensitivitiesEqualTheNormalEquationsSolution) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, 0.1), x(0.0, 1.0);
  std::vector<std::vector<double>> values;
  std::vector<double> metric;
  for (int k = 0; k < 50; ++k) {
    const double a = x(rng), b = x(rng);
    values.push_back({a, b});
    metric.push_back(2.0 + 3.0 * a - 1.0 * b + noise(rng));
  }
  metric[7] = std::nan("");  // a variant without a value is left out
  // The normal equations of y = c0 + c1 a + c2 b on centred columns, solved by Cramer's rule.
  double ma = 0, mb = 0, my = 0;
  int n = 0;
  for (size_t k = 0; k < metric.size(); ++k)
    if (!std::isnan(metric[k])) {
      ma += values[k][0];
      mb += values[k][1];
      my += metric[k];
      ++n;
    }
  ma /= n;
  mb /= n;
  my /= n;
  double saa = 0, sbb = 0, sab = 0, say = 0, sby = 0;
  for (size_t k = 0; k < metric.size(); ++k) {
    if (std::isnan(metric[k])) continue;
    const double a = values[k][0] - ma, b = values[k][1] - mb, y = metric[k] - my;
    saa += a * a;
    sbb += b * b;
    sab += a * b;
    say += a * y;
    sby += b * y;
  }
  const double det = saa * sbb - sab * sab;
  const double c1 = (say * sbb - sab * sby) / det, c2 = (saa * sby - sab * say) / det;
  double rss = 0;
  for (size_t k = 0; k < metric.size(); ++k) {
    if (std::isnan(metric[k])) continue;
    const double r = metric[k] - my - c1 * (values[k][0] - ma) - c2 * (values[k][1] - mb);
    rss += r * r;
  }
  const double s2 = rss / (n - 3);
  const double se1 = std::sqrt(s2 * sbb / det), se2 = std::sqrt(s2 * saa / det);

  const MetricStatistics s = metric_statistics("m", values, metric);
  EXPECT_EQ(s.n, 49);
  ASSERT_TRUE(s.sensitivity[0] && s.sensitivity[1]);
  EXPECT_NEAR(s.sensitivity[0]->coefficient, c1, 1e-12);
  EXPECT_NEAR(s.sensitivity[1]->coefficient, c2, 1e-12);
  EXPECT_NEAR(s.sensitivity[0]->std_error, se1, 1e-12);
  EXPECT_NEAR(s.sensitivity[1]->std_error, se2, 1e-12);
  // 95 % interval: Student's t with 46 degrees of freedom, t = 2.012896 (tables).
  EXPECT_NEAR(s.sensitivity[0]->high - c1, 2.012896 * se1, 1e-6 * se1);
  EXPECT_NEAR(c1 - s.sensitivity[0]->low, 2.012896 * se1, 1e-6 * se1);
  // The true slopes lie in their intervals (noise 0.1, 49 points).
  EXPECT_LT(s.sensitivity[0]->low, 3.0);
  EXPECT_GT(s.sensitivity[0]->high, 3.0);
}

TEST(StudyVariants, GridIsTheProductWithTheLastParameterFastest) {
  Study s;
  s.kind = StudyKind::grid;
  s.parameters.resize(2);
  s.parameters[0].values = {1, 2};
  s.parameters[1].values = {10, 20, 30};
  EXPECT_EQ(variant_count(s), 6);
  EXPECT_EQ(variant_values(s, 0), (std::vector<double>{1, 10}));
  EXPECT_EQ(variant_values(s, 2), (std::vector<double>{1, 30}));
  EXPECT_EQ(variant_values(s, 4), (std::vector<double>{2, 20}));
}

TEST(StudyVariants, MonteCarloDrawsDependOnSeedAndIndexOnly) {
  Study s;
  s.kind = StudyKind::monte_carlo;
  s.samples = 1000;
  s.seed = 5;
  s.parameters.resize(2);
  s.parameters[0].law = StudyParameter::Law::normal;
  s.parameters[0].mean = 30.0;
  s.parameters[0].sigma = 0.05;
  s.parameters[1].law = StudyParameter::Law::uniform;
  s.parameters[1].mean = 70.0;
  s.parameters[1].tolerance = 0.1;
  EXPECT_EQ(variant_values(s, 17), variant_values(s, 17));
  EXPECT_NE(variant_values(s, 17), variant_values(s, 18));
  // The sample moments of 1000 draws: mean within 4 standard errors, sigma within 10 %; the
  // uniform draws inside mean ± tolerance, with standard deviation tolerance / sqrt(3).
  double sum = 0, sum2 = 0, usum2 = 0;
  for (long i = 0; i < 1000; ++i) {
    const auto v = variant_values(s, i);
    sum += v[0];
    sum2 += (v[0] - 30.0) * (v[0] - 30.0);
    EXPECT_LE(std::abs(v[1] - 70.0), 0.1);
    usum2 += (v[1] - 70.0) * (v[1] - 70.0);
  }
  EXPECT_NEAR(sum / 1000, 30.0, 4 * 0.05 / std::sqrt(1000.0));
  EXPECT_NEAR(std::sqrt(sum2 / 1000), 0.05, 0.005);
  EXPECT_NEAR(std::sqrt(usum2 / 1000), 0.1 / std::sqrt(3.0), 0.006);
  // sigma 0: the mean itself.
  s.parameters[0].sigma = 0.0;
  EXPECT_EQ(variant_values(s, 3)[0], 30.0);
  // The FileChange text reads back to the same double.
  for (double v : {0.1, 1.0 / 3.0, -2.5e-7, 30.012345678901234})
    EXPECT_EQ(std::stod(value_text(v)), v);
}

// A variant's cycle (the report's click-through) is the variant's: its drive spans the drive.max
// and drive.min of evaluate_variant (the cycle summary's extremes of the same sweep) and its
// rocker_angle the measure's M.max (a stroke: parabola-refined, so at most the refined extreme
// and within 0.1° of it at 72 positions 5° apart); an invalid variant has no positions.
TEST(StudyVariants, VariantCycleIsTheVariantsSweep) {
  const std::string file = test::bundled_file("crank-rocker");
  const std::string mechanism = test::read_text(file);
  const Study study = parse_study(R"(study: grid
steps: 72
parameters:
  - {name: crank, path: bodies.crank.points.A.0, values: [26, 32]}
  - {name: mass, path: bodies.crank.mass, values: [0.03]}
)",
                                  "s.yaml", mechanism, file);
  for (long k = 0; k < 2; ++k) {
    const VariantResult r = evaluate_variant(mechanism, file, study, k, variant_values(study, k));
    const VariantCycle c = variant_cycle(mechanism, file, study, k, variant_values(study, k));
    ASSERT_EQ(c.status, "completed") << c.message;
    EXPECT_EQ(static_cast<long>(c.input.size()), r.positions);
    EXPECT_EQ(c.input_label, "input A0 [deg]");
    ASSERT_EQ(c.series.front().name, "drive");
    const auto metric = [&](const std::string& name) {
      for (const auto& [n, v] : r.metrics)
        if (n == name) return v;
      return std::nan("");
    };
    const auto& drive = c.series.front().values;
    EXPECT_DOUBLE_EQ(*std::max_element(drive.begin(), drive.end()), metric("drive.max"));
    EXPECT_DOUBLE_EQ(*std::min_element(drive.begin(), drive.end()), metric("drive.min"));
    for (const VariantCycle::Series& s : c.series)
      if (s.name == "rocker_angle") {
        const double top = *std::max_element(s.values.begin(), s.values.end());
        EXPECT_LE(top, metric("rocker_angle.max") + 1e-12);
        EXPECT_GT(top, metric("rocker_angle.max") - 0.1);
      }
  }
  const VariantCycle bad = variant_cycle(mechanism, file, study, 2, {30, -1});  // mass −1 kg
  EXPECT_EQ(bad.status, "invalid");
  EXPECT_TRUE(bad.input.empty());
}

}  // namespace
}  // namespace orthomech
