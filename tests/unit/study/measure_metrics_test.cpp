// Study metrics of every measure and stroke, and expressions of them (study/measure_metrics.hpp,
// issue 51 item 1), against closed forms written here. A crank turns a gear at twice its speed
// (gear ratio 2, both pivoted on the ground; 60 rpm, 360 positions θ_k = k°, file in mm and deg):
//   - the crank's point T at 40 mm: y = 40 sin θ, one maximum per turn: min −40 at θ = 270°, max
//     40 at θ = 90°, stroke 80, RMS over the full turn 40/√2, time ratio π/π = 1;
//   - its rate ẏ = 40 ω cos θ (ω = 2π rad/s): extremes ±40ω at θ = 0° and 180° (samples), RMS
//     40ω/√2 — a rate is not a stroke: no time ratio;
//   - the gear's point P at 30 mm, a tracer (no measure): x = 100 + 30 cos 2θ, two maxima per turn
//     — stroke 60, no time ratio (NaN).
// Expressions: columns by name and f(NAME) against the same values computed here; refused names;
// at(NAME, X) against the closed forms.
#include "orthomech/study/measure_metrics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>
#include <stdexcept>
#include <string>

#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/study/study.hpp"
#include "support/cli_runner.hpp"
#include "support/fixtures.hpp"

namespace orthomech {
namespace {

constexpr double kPi = std::numbers::pi;

std::string gear_pair() {
  return test::read_text(std::string(ORTHOMECH_SOURCE_DIR) + "/tests/data/cycle/gear-pair.yaml");
}

std::map<std::string, double> columns_of(const MetricColumns& c) {
  std::map<std::string, double> m;
  for (const auto& [name, value] : c) m[name] = value;
  return m;
}

TEST(MeasureMetrics, StrokesRatesAndTracersAgainstClosedForms) {
  const Model model = parse_mechanism(gear_pair(), "gear-pair.yaml", {});
  const CycleResult c = test::full_cycle(model, 360);
  ASSERT_EQ(c.status, CycleStatus::completed);
  CycleMetricsOptions options;
  options.driver_joint = model.find_joint("O");
  MetricColumns out;
  measure_metrics(model, c, compute_cycle_metrics(model, c, options), options.driver_joint, out);
  auto m = columns_of(out);
  ASSERT_EQ(m.size(), out.size());  // each column once
  EXPECT_NEAR(m.at("tip_y.min"), -40.0, 1e-9);
  EXPECT_NEAR(m.at("tip_y.max"), 40.0, 1e-9);
  EXPECT_NEAR(m.at("tip_y.range"), 80.0, 1e-9);
  EXPECT_NEAR(m.at("tip_y.min_at"), 270.0, 1e-6);
  EXPECT_NEAR(m.at("tip_y.max_at"), 90.0, 1e-6);
  EXPECT_NEAR(m.at("tip_y.rms"), 40.0 / std::sqrt(2.0), 1e-9);
  EXPECT_NEAR(m.at("tip_y.time_ratio"), 1.0, 1e-6);
  const double w = 2.0 * kPi;  // rad/s
  EXPECT_NEAR(m.at("tip_vy.max"), 40.0 * w, 1e-7);
  EXPECT_NEAR(m.at("tip_vy.min"), -40.0 * w, 1e-7);
  EXPECT_NEAR(m.at("tip_vy.max_at"), 0.0, 1e-9);
  EXPECT_NEAR(m.at("tip_vy.min_at"), 180.0, 1e-9);
  EXPECT_NEAR(m.at("tip_vy.rms"), 40.0 * w / std::sqrt(2.0), 1e-7);
  EXPECT_TRUE(std::isnan(m.at("tip_vy.time_ratio")));
  EXPECT_NEAR(m.at("gear.P.x.min"), 70.0, 1e-9);
  EXPECT_NEAR(m.at("gear.P.x.max"), 130.0, 1e-9);
  EXPECT_NEAR(m.at("gear.P.x.range"), 60.0, 1e-9);
  EXPECT_TRUE(std::isnan(m.at("gear.P.x.time_ratio")));
  EXPECT_EQ(m.count("gear.P.x.rms"), 0u);  // a tracer's RMS: give it a measure
  EXPECT_EQ(m.count("crank_angle.min"), 0u);
}

// The crank-rocker's measure `transmission` would give transmission.min, the loops' own column:
// its columns are measure.transmission.*, and range(transmission) finds them. The coupler's
// angle between the bodies swings between the loop's transmission extremes (the bundled
// file's facts: 28.955° … 90° … 151.045° is the loop's μ; here only that the range is the
// max − min of its own columns).
TEST(MeasureMetrics, ASeriesNamedLikeAColumnIsPrefixed) {
  const Model model = test::load_bundled("crank-rocker");
  const CycleResult c = test::full_cycle(model, 90);
  CycleMetricsOptions options;
  options.driver_joint = model.find_joint("A0");
  MetricColumns out{{"transmission.min", 30.0}};
  measure_metrics(model, c, compute_cycle_metrics(model, c, options), options.driver_joint, out);
  const auto m = columns_of(out);
  EXPECT_EQ(m.count("transmission.max"), 0u);
  ASSERT_EQ(m.count("measure.transmission.max"), 1u);
  EXPECT_DOUBLE_EQ(m.at("transmission.min"), 30.0);
  EXPECT_DOUBLE_EQ(evaluate_metric_expression("range(transmission)", out),
                   m.at("measure.transmission.max") - m.at("measure.transmission.min"));
  EXPECT_EQ(m.count("rocker_angle.max"), 1u);  // the others keep their names
}

TEST(MeasureMetrics, ExpressionsOfColumns) {
  const MetricColumns c{{"drive.peak", 3.0},
                        {"A.|F|.peak", 5.0},
                        {"rocker_angle.range", 89.0},
                        {"rocker_angle.max_at", 120.0},
                        {"gap.min", std::nan("")}};
  EXPECT_DOUBLE_EQ(evaluate_metric_expression("range(rocker_angle) - 75", c), 14.0);
  EXPECT_DOUBLE_EQ(evaluate_metric_expression("rocker_angle.range - 75", c), 14.0);
  EXPECT_DOUBLE_EQ(evaluate_metric_expression("2*drive.peak + A.|F|.peak", c), 11.0);
  EXPECT_DOUBLE_EQ(evaluate_metric_expression("sqrt(drive.peak^2 + 16)", c), 5.0);
  EXPECT_DOUBLE_EQ(evaluate_metric_expression("min(drive.peak, 1.5e0)", c), 1.5);  // muparser's
  EXPECT_DOUBLE_EQ(evaluate_metric_expression("max_at( rocker_angle ) / 2", c), 60.0);
  EXPECT_TRUE(std::isnan(evaluate_metric_expression("min(gap) + 1", c)));
  EXPECT_THROW((void)evaluate_metric_expression("drive.peek", c), std::invalid_argument);
  EXPECT_THROW((void)evaluate_metric_expression("rms(rocker_angle)", c), std::invalid_argument);
  EXPECT_THROW((void)evaluate_metric_expression("swing + 1", c), std::invalid_argument);
  EXPECT_THROW((void)evaluate_metric_expression("drive.peak +", c), std::invalid_argument);
  try {
    (void)evaluate_metric_expression("drive.peek * 2", c);
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("unknown metric 'drive.peek'"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("drive.peak, A.|F|.peak"), std::string::npos);
  }
}

// A study's expressions are columns of every variant, after the blocks' (each may use the ones
// before it), and a grid ranks by one. The crank length L of the gear pair is a parameter: the
// tip's stroke is 2L (closed form), so `swing: range(tip_y)` is 2L and `error: swing - 75` is
// 2L − 75.
TEST(MeasureMetrics, StudyExpressionsAreColumns) {
  std::string mech = gear_pair();
  mech.replace(mech.find("T: [40, 0]"), 10, "T: [L, 0]");
  mech.insert(mech.find("ground:"), "parameters: {L: 40}\n");
  const Study study = parse_study(R"(study: grid
steps: 72
parameters:
  - {path: L, values: [30, 37.5, 45]}
expressions:
  swing: range(tip_y)
  error: abs(swing - 75)
best: {metric: error, order: min, count: 1}
)",
                                  "s.yaml", mech, "m.yaml");
  for (long k = 0; k < 3; ++k) {
    const std::vector<double> values = variant_values(study, k);
    const VariantResult r = evaluate_variant(mech, "m.yaml", study, k, values);
    ASSERT_EQ(r.status, "completed") << r.message;
    const auto m = columns_of(r.metrics);
    EXPECT_NEAR(m.at("swing"), 2.0 * values[0], 1e-9);
    EXPECT_NEAR(m.at("error"), std::abs(2.0 * values[0] - 75.0), 1e-9);
    EXPECT_EQ(r.metrics[r.metrics.size() - 2].first, "swing");
    EXPECT_EQ(r.metrics.back().first, "error");
  }
}

TEST(MeasureMetrics, StudyExpressionsRefusedAtTheirLine) {
  const std::string mech = gear_pair();
  auto message = [&](const std::string& text) {
    try {
      (void)parse_study(text, "s.yaml", mech, "m.yaml");
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  const std::string head =
      "study: grid\nparameters:\n  - {path: bodies.crank.mass, values: [1, 2]}\n";
  EXPECT_NE(message(head + "expressions:\n  swing: range(tip_z)\n").find("s.yaml:5:10"),
            std::string::npos)
      << message(head + "expressions:\n  swing: range(tip_z)\n");
  EXPECT_NE(message(head + "expressions:\n  swing: range(tip_z)\n").find("tip_z"),
            std::string::npos);
  EXPECT_NE(message(head + "expressions:\n  drive.peak: 1\n").find("metric column"),
            std::string::npos);
  EXPECT_NE(message(head + "expressions:\n  status: 1\n").find("column of the study"),
            std::string::npos);
  EXPECT_NE(message(head + "expressions:\n  2x: 1\n").find("a letter first"), std::string::npos);
  EXPECT_NE(message(head + "expressions: [a]\n").find("mapping"), std::string::npos);
  EXPECT_EQ(message(head + "expressions:\n  s: range(tip_y)\n  t: s / 2\n"), "accepted");
}

// at(NAME, X): the measure at an input. The gear pair's tip y = L sin θ and its rate
// ẏ = L ω cos θ (ω = 2π rad/s), at 72 positions 5° apart (h = 0.0873 rad): between samples the
// cubic through the four positions around θ errs by at most |f⁗|/4! · 1.5h · 0.5h · 0.5h · 1.5h
// = 0.0234 L h⁴ (the middle of an interval): 5.4e-5 mm for L = 40, and for the rate, whose
// fourth derivative in θ is at most L ω, 3.4e-4 mm/s; a revolute input counts up to whole turns;
// at a sample the measure itself.
TEST(MeasureMetrics, AtIsTheMeasureAtAnInput) {
  const std::string mech = gear_pair();
  const Study study = parse_study(R"(study: grid
steps: 72
parameters:
  - {path: bodies.crank.mass, values: [1]}
expressions:
  y_mid: at(tip_y, 32.5)
  y_turn: at(tip_y, 392.5) - at(tip_y , -327.5)
  y_sample: at(tip_y, 30)
  vy: at(tip_vy, 102.5)
  rise: at(tip_y, 90) - at(tip_y, 32.5)
)",
                                  "s.yaml", mech, "m.yaml");
  ASSERT_EQ(study.metrics.at.size(), 6u);  // each (measure, input) once
  EXPECT_EQ(study.metrics.at[0].column, "tip_y@32.5");
  const VariantResult r = evaluate_variant(mech, "m.yaml", study, 0, variant_values(study, 0));
  ASSERT_EQ(r.status, "completed") << r.message;
  const auto m = columns_of(r.metrics);
  const double deg = kPi / 180, L = 40, w = 2 * kPi, h = 5 * deg;
  const double bound = 0.0234375 * std::pow(h, 4);  // per unit of |f⁗|
  EXPECT_NEAR(m.at("y_mid"), L * std::sin(32.5 * deg), bound * L);
  EXPECT_NEAR(m.at("tip_y@32.5"), m.at("y_mid"), 0.0);
  EXPECT_NEAR(m.at("y_turn"), 0.0, 1e-12);  // 392.5° and −327.5° are 32.5° a turn away
  EXPECT_NEAR(m.at("y_sample"), L * 0.5, 1e-9);
  EXPECT_NEAR(m.at("vy"), L * w * std::cos(102.5 * deg), bound * L * w);
  EXPECT_NEAR(m.at("rise"), L - L * std::sin(32.5 * deg), bound * L + 1e-9);
  // Refused at the line: not a measure, not a number.
  auto message = [&](const std::string& e) {
    try {
      (void)parse_study(
          "study: grid\nparameters:\n  - {path: bodies.crank.mass, values: [1]}\nexpressions:\n"
          "  x: " +
              e + "\n",
          "s.yaml", mech, "m.yaml");
    } catch (const std::exception& error) {
      return std::string(error.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(message("at(tip_z, 30)").find("'tip_z' is not a measure"), std::string::npos)
      << message("at(tip_z, 30)");
  EXPECT_NE(message("at(tip_y, thirty)").find("input as a number"), std::string::npos)
      << message("at(tip_y, thirty)");
}

// Numbers with a unit are the file's units of their kind (the gear pair is in mm and deg): 0.08 m
// is 80 mm, π/6 rad is 30°; at(…, X) takes a unit for X too. Without the file's units (the
// library call alone) a unit is an error, and a plain number stays as written.
TEST(MeasureMetrics, NumbersWithUnitsAreInTheFilesUnits) {
  const std::string mech = gear_pair();
  const Study study = parse_study(R"(study: grid
steps: 72
parameters:
  - {path: bodies.crank.mass, values: [1]}
expressions:
  stroke_error: range(tip_y) - 0.08m
  spaced: 8 cm + 2mm
  angle: 0.5235987755982988rad + 60deg
  y30: at(tip_y, 0.5235987755982988 rad)
  force: 2kN
)",
                                  "s.yaml", mech, "m.yaml");
  const VariantResult r = evaluate_variant(mech, "m.yaml", study, 0, variant_values(study, 0));
  ASSERT_EQ(r.status, "completed") << r.message;
  const auto m = columns_of(r.metrics);
  EXPECT_NEAR(m.at("stroke_error"), 0.0, 1e-9);  // the stroke 2 · 40 mm
  EXPECT_NEAR(m.at("spaced"), 82.0, 1e-12);
  EXPECT_NEAR(m.at("angle"), 90.0, 1e-12);
  EXPECT_NEAR(m.at("y30"), 20.0, 1e-9);      // 30° is a sample: 40 sin 30°
  EXPECT_NEAR(m.at("force"), 2000.0, 1e-9);  // the file's force unit is N
  EXPECT_THROW((void)evaluate_metric_expression("75deg", {}), std::invalid_argument);
  EXPECT_EQ(evaluate_metric_expression("1e3 + 2", {}), 1002.0);
}

}  // namespace
}  // namespace orthomech
