// The metric blocks of a design study (study.hpp, docs/cli.md "sweep": `metrics:`) against
// independent oracles:
//   - deviation: shifting every ground point by (dx, dy) translates the whole mechanism, so every
//     traced point's path deviates from the nominal's by exactly √(dx² + dy²) at every input (max =
//     RMS = |d|); the nominal design deviates by 0 exactly; a variant whose design position has
//     another input is compared at the nominal's inputs (the same mechanism: deviation 0);
//   - validate: whether position P (crank angle θ_P locked) can close is the triangle inequality
//     |b − c| ≤ |A(θ_P) − B0| ≤ b + c, computed here; a target missed by |d| > tolerance fails;
//   - assemble: a loop with a − d > b + c closes at no crank angle (0); the rigid translation is a
//     closed pose, so the mass-metric distance is at most √(Σm)·|d|;
//   - results do not depend on the number of threads.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "orthomech/study/study.hpp"
#include "support/cli_runner.hpp"

namespace orthomech {
namespace {

// Translations are solved to ~1e-12 m; the file is in mm.
constexpr double kDeviationTolerance = 1e-9;  // mm
// A start reached again by continuation along the branch (each position projected to a 1e-12 m
// residual): the paths agree to ~1e-10 mm; one grid step off would be ~0.5 mm.
constexpr double kReachedTolerance = 1e-8;  // mm

std::string crank_rocker_text() { return test::read_text(test::bundled_file("crank-rocker")); }

// The crank-rocker with its ground points as parameters: A0 = (dx, dy), B0 = (70 + dx, dy).
std::string shiftable_crank_rocker() {
  std::string text = crank_rocker_text();
  const std::string units = "units: {length: mm, angle: deg, mass: kg, time: s, force: N}\n";
  const std::string ground = "points: {A0: [0, 0], B0: [70, 0]}";
  const auto u = text.find(units);
  const auto g = text.find(ground);
  EXPECT_NE(u, std::string::npos);
  EXPECT_NE(g, std::string::npos);
  text.replace(g, ground.size(), "points: {A0: [dx, dy], B0: [70 + dx, dy]}");
  text.insert(u + units.size(), "parameters: {dx: 0, dy: 0}\n");
  return text;
}

std::map<std::string, double> by_name(const VariantResult& r) {
  std::map<std::string, double> m;
  for (const auto& [name, value] : r.metrics) m[name] = value;
  return m;
}

double metric(const VariantResult& r, const std::string& name) {
  const auto m = by_name(r);
  const auto it = m.find(name);
  if (it == m.end()) {
    ADD_FAILURE() << "variant " << r.index << " has no metric " << name;
    return std::nan("");
  }
  return it->second;
}

TEST(StudyDeviation, S1_GroundShiftTranslatesEveryPathByExactlyTheShift) {
  const std::string mech = shiftable_crank_rocker();
  Study study = parse_study(R"(study: grid
steps: 72
parameters:
  - {path: dx, values: [0, 0.6]}
  - {path: dy, values: [0, -0.8]}
metrics: {cycle: true, assemble: true, validate: true,
          deviation: [coupler.P, rocker.B, crank.A, coupler.origin]}
)",
                            "s.yaml", mech, "m.yaml");
  attach_nominal_paths(study, mech, "m.yaml");
  ASSERT_TRUE(study.nominal);
  ASSERT_TRUE(study.nominal->available) << study.nominal->message;
  ASSERT_EQ(study.nominal->input.size(), 72u);
  ASSERT_EQ(variant_count(study), 4);
  const double total_mass = 0.03 + 0.08 + 0.06;  // kg, the file's bodies
  for (long k = 0; k < 4; ++k) {
    const std::vector<double> v = variant_values(study, k);
    const VariantResult r = evaluate_variant(mech, "m.yaml", study, k, v);
    ASSERT_EQ(r.status, "completed") << r.message;
    const double d = std::hypot(v[0], v[1]);  // mm
    SCOPED_TRACE("shift " + std::to_string(d) + " mm");
    for (const char* p : {"coupler.P", "rocker.B", "crank.A", "coupler.origin"}) {
      const double max = metric(r, std::string("deviation.") + p + ".max");
      const double rms = metric(r, std::string("deviation.") + p + ".rms");
      if (d == 0.0) {  // the nominal design itself: the same computation, bit for bit
        EXPECT_EQ(max, 0.0) << p;
        EXPECT_EQ(rms, 0.0) << p;
      } else {
        EXPECT_NEAR(max, d, kDeviationTolerance) << p;
        EXPECT_NEAR(rms, d, kDeviationTolerance) << p;
      }
    }
    // Translating the mechanism changes no force: the drive peak is the nominal's.
    EXPECT_NEAR(metric(r, "drive.peak"), 168.80644750920152, 1e-6);
    // assemble: closes; the drawn pose (not shifted) is at most the rigid translation away.
    EXPECT_EQ(metric(r, "assemble.ok"), 1.0);
    const double distance = metric(r, "assemble.distance");  // sqrt(kg)*mm
    if (d == 0.0) {
      EXPECT_EQ(distance, 0.0);
    } else {
      EXPECT_GT(distance, 0.0);
      EXPECT_LE(distance, std::sqrt(total_mass) * d + 1e-9);
    }
    // validate: the targets (tolerance 0.5 mm, on the nominal to 1e-6 mm) are missed by |d|.
    for (const char* p : {"p1", "p2", "p3"}) {
      EXPECT_EQ(metric(r, std::string("validate.") + p + ".assembles"), 1.0) << p;
      EXPECT_EQ(metric(r, std::string("validate.") + p + ".target"), d > 0.5 ? 0.0 : 1.0) << p;
      EXPECT_EQ(metric(r, std::string("validate.") + p + ".transmission"), 1.0) << p;
    }
    EXPECT_EQ(metric(r, "validate.pass"), d > 0.5 ? 0.0 : 1.0);
  }
}

TEST(StudyDeviation, S1_AnotherDesignInputIsComparedAtTheNominalsInputs) {
  // The crank drawn at 61° instead of 60°: the same mechanism, its cycle starting at 61°. Compared
  // at the nominal's inputs (60°, 65°, …) the paths are the nominal's: deviation 0 to the solver's
  // tolerance; compared position by position (61° vs 60°) it would be ≈ 0.5 mm.
  const std::string mech = crank_rocker_text();
  Study study = parse_study(R"(study: grid
steps: 72
parameters:
  - {path: bodies.crank.pose.2, values: [61]}
metrics: {deviation: coupler.P}
)",
                            "s.yaml", mech, "m.yaml");
  attach_nominal_paths(study, mech, "m.yaml");
  const VariantResult r = evaluate_variant(mech, "m.yaml", study, 0, variant_values(study, 0));
  ASSERT_EQ(r.status, "completed") << r.message;
  EXPECT_LT(metric(r, "deviation.coupler.P.max"), kReachedTolerance);
  EXPECT_LT(metric(r, "deviation.coupler.P.rms"), kReachedTolerance);
  EXPECT_EQ(by_name(r).count("drive.peak"), 0u);  // no cycle block asked for
}

TEST(StudyDeviation, WithoutAttachedNominalPathsTheVariantComputesThemItself) {
  const std::string mech = shiftable_crank_rocker();
  Study study = parse_study(
      "study: grid\nsteps: 36\nparameters:\n  - {path: dx, values: [0.3]}\n"
      "metrics: {deviation: [coupler.P]}\n",
      "s.yaml", mech, "m.yaml");
  const VariantResult alone = evaluate_variant(mech, "m.yaml", study, 0, {0.3});
  attach_nominal_paths(study, mech, "m.yaml");
  const VariantResult attached = evaluate_variant(mech, "m.yaml", study, 0, {0.3});
  EXPECT_EQ(metric(alone, "deviation.coupler.P.max"), metric(attached, "deviation.coupler.P.max"));
  EXPECT_NEAR(metric(attached, "deviation.coupler.P.max"), 0.3, kDeviationTolerance);
}

// Whether the loop closes with the crank at θ: |b − c| ≤ |A(θ) − B0| ≤ b + c (a = crank length,
// ground A0 = 0, B0 = (70, 0), coupler b = 80, rocker c = 60).
bool closes_at(double a, double theta_deg) {
  const double t = theta_deg * std::numbers::pi / 180.0;
  const double r = std::hypot(a * std::cos(t) - 70.0, a * std::sin(t));
  return r <= 80.0 + 60.0 && r >= 80.0 - 60.0;
}

TEST(StudyChecks, AssemblyAndValidateFollowTheTriangleInequality) {
  const std::string mech = crank_rocker_text();
  const Study study = parse_study(R"(study: grid
steps: 36
parameters:
  - {name: crank, path: bodies.crank.points.A.0, values: [30, 100, 250]}
metrics: {cycle: true, validate: true, assemble: true}
)",
                                  "s.yaml", mech, "m.yaml");
  const std::map<std::string, double> inputs = {{"p1", 60.0}, {"p2", 150.0}, {"p3", 270.0}};
  // The oracle's own expectations (so that the test cannot pass by everything being 1 or 0).
  ASSERT_TRUE(closes_at(100, 60) && !closes_at(100, 150) && closes_at(100, 270));
  for (long k = 0; k < 3; ++k) {
    const std::vector<double> v = variant_values(study, k);
    const double a = v[0];
    SCOPED_TRACE("crank " + std::to_string(a));
    const VariantResult r = evaluate_variant(mech, "m.yaml", study, k, v);
    // Free crank: the loop closes at some angle iff a − d ≤ b + c (a > d here or a ≤ d).
    const bool closes_somewhere = std::abs(a - 70.0) <= 140.0;
    EXPECT_EQ(metric(r, "assemble.ok"), closes_somewhere ? 1.0 : 0.0);
    EXPECT_EQ(std::isnan(metric(r, "assemble.distance")), !closes_somewhere);
    bool all = true;
    for (const auto& [p, theta] : inputs) {
      const bool c = closes_at(a, theta);
      all = all && c;
      EXPECT_EQ(metric(r, "validate." + p + ".assembles"), c ? 1.0 : 0.0) << p;
      // Not checked where it does not assemble: empty (NaN), not a pass.
      EXPECT_EQ(std::isnan(metric(r, "validate." + p + ".target")), !c) << p;
    }
    if (!all) {
      EXPECT_EQ(metric(r, "validate.pass"), 0.0);
    }
    // The crank turns fully iff Grashof with the crank shortest: only a = 30. Otherwise the row
    // carries the cycle's status, never an exception.
    if (a == 30.0) {
      EXPECT_EQ(r.status, "completed");
      EXPECT_EQ(metric(r, "validate.pass"), 1.0);
      EXPECT_EQ(metric(r, "assemble.distance"), 0.0);  // the file's pose is closed
    } else {
      EXPECT_NE(r.status, "completed") << r.message;
      EXPECT_FALSE(r.message.empty());
    }
  }
}

TEST(StudyChecks, ResultsDoNotDependOnTheNumberOfThreads) {
  const std::string mech = shiftable_crank_rocker();
  Study study = parse_study(R"(study: monte-carlo
samples: 8
seed: 5
steps: 36
parameters:
  - {path: dx, normal: {mean: 0, sigma: 0.2}}
  - {name: crank, path: bodies.crank.points.A.0, uniform: {tolerance: 60}}
metrics: {cycle: true, validate: true, assemble: true, deviation: [coupler.P]}
)",
                            "s.yaml", mech, "m.yaml");
  attach_nominal_paths(study, mech, "m.yaml");
  std::vector<long> all(8);
  for (long k = 0; k < 8; ++k) all[static_cast<size_t>(k)] = k;
  const auto run = [&](int jobs) {
    std::map<long, VariantResult> out;
    run_variants(mech, "m.yaml", study, all, jobs,
                 [&](const VariantResult& r) { out[r.index] = r; });
    return out;
  };
  const auto one = run(1), two = run(2);
  ASSERT_EQ(one.size(), 8u);
  ASSERT_EQ(two.size(), 8u);
  std::set<std::string> statuses;
  for (const auto& [k, r] : one) {
    const VariantResult& s = two.at(k);
    statuses.insert(r.status);
    EXPECT_EQ(r.status, s.status);
    EXPECT_EQ(r.message, s.message);
    ASSERT_EQ(r.metrics.size(), s.metrics.size());
    for (size_t m = 0; m < r.metrics.size(); ++m) {
      EXPECT_EQ(r.metrics[m].first, s.metrics[m].first);
      const double x = r.metrics[m].second, y = s.metrics[m].second;
      EXPECT_TRUE((std::isnan(x) && std::isnan(y)) || x == y) << r.metrics[m].first;
    }
  }
  // The draws reach both failing and completed variants (crank 30 ± 60 mm).
  EXPECT_GE(statuses.size(), 2u);
}

TEST(StudyFile, MetricBlocksAreCheckedWithTheirLine) {
  const std::string mech = crank_rocker_text();
  const auto error = [&](const std::string& metrics) {
    try {
      (void)parse_study(
          "study: grid\nparameters:\n  - {path: bodies.crank.mass, values: [1]}\n" + metrics,
          "s.yaml", mech, "m.yaml");
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error("metrics: {valdate: true}\n").find("s.yaml:4:"), std::string::npos);
  EXPECT_NE(error("metrics: {valdate: true}\n").find("unknown key 'valdate'"), std::string::npos);
  EXPECT_NE(error("metrics: {validate: maybe}\n").find("must be true or false"), std::string::npos);
  const std::string point = error("metrics: {deviation: [coupler.Q]}\n");
  EXPECT_NE(point.find("s.yaml:4:"), std::string::npos) << point;
  EXPECT_NE(point.find("body 'coupler' has no point 'Q'"), std::string::npos) << point;
  EXPECT_NE(error("metrics: {deviation: [ground.A0]}\n").find("not body.point of a moving body"),
            std::string::npos);
  EXPECT_NE(error("metrics: {cycle: false}\n").find("no metric block is on"), std::string::npos);
  // Absent: the cycle alone.
  const Study s =
      parse_study("study: grid\nparameters:\n  - {path: bodies.crank.mass, values: [1]}\n",
                  "s.yaml", mech, "m.yaml");
  EXPECT_TRUE(s.metrics.cycle);
  EXPECT_FALSE(s.metrics.validate || s.metrics.assemble);
  EXPECT_TRUE(s.metrics.deviation.empty());
}

// The shaking and friction columns are `cycle --json`'s numbers for the same sweep (the wiper
// drive: pin friction in every joint, the shaking force and moment about the origin): the
// peaks' "shaking force", "shaking moment", "drive without friction", "A0 friction moment",
// "friction power" and friction's efficiency and dissipated energy.
TEST(StudyShakingAndFriction, ColumnsAreTheCyclesNumbers) {
  const std::string file = test::bundled_file("wiper-drive");
  const std::string mech = test::read_text(file);
  const Study study = parse_study(
      "study: grid\nparameters:\n  - {path: bodies.crank.mass, "
      "values: [0.2]}\n",
      "s.yaml", mech, file);
  // The crank's own mass (0.2 kg in the file): the variant is the file.
  const VariantResult r = evaluate_variant(mech, file, study, 0, variant_values(study, 0));
  ASSERT_EQ(r.status, "completed") << r.message;
  const auto cli = test::run_cli({"cycle", file, "--json"});
  ASSERT_EQ(cli.status, 0) << cli.err;
  const nlohmann::json j = nlohmann::json::parse(cli.out);
  const std::pair<const char*, const char*> pairs[] = {
      {"shaking force", "shaking_force"},
      {"shaking moment", "shaking_moment"},
      {"drive without friction", "drive_without_friction"},
      {"A0 friction moment", "A0.friction_moment"},
      {"friction power", "friction_power"}};
  for (const auto& [peak, column] : pairs) {
    const double p = j["peaks"][peak]["peak"], rms = j["peaks"][peak]["rms"];
    EXPECT_NEAR(metric(r, std::string(column) + ".peak"), p, 1e-9 * std::abs(p)) << column;
    EXPECT_NEAR(metric(r, std::string(column) + ".rms"), rms, 1e-9 * std::abs(rms)) << column;
  }
  const double eta = j["friction"]["efficiency"], lost = j["friction"]["dissipated"];
  EXPECT_NEAR(metric(r, "friction.efficiency"), eta, 1e-12);
  EXPECT_NEAR(metric(r, "friction.dissipated"), lost, 1e-9 * lost);
  EXPECT_GT(eta, 0.5);
  EXPECT_LT(eta, 1.0);
  // Without friction in the file: no friction columns; the shaking ones still.
  const Study plain =
      parse_study("study: grid\nparameters:\n  - {path: bodies.crank.mass, values: [0.03]}\n",
                  "s.yaml", crank_rocker_text(), "m.yaml");
  const VariantResult q = evaluate_variant(crank_rocker_text(), "m.yaml", plain, 0, {0.03});
  const auto m = by_name(q);
  EXPECT_EQ(m.count("friction.efficiency"), 0u);
  EXPECT_EQ(m.count("shaking_force.peak"), 1u);
  // A variant without a value per parameter is a failed variant, not a crash.
  const VariantResult bad = evaluate_variant(crank_rocker_text(), "m.yaml", plain, 0, {});
  EXPECT_EQ(bad.status, "failed");
  EXPECT_NE(bad.message.find("a value per parameter"), std::string::npos) << bad.message;
}

}  // namespace
}  // namespace orthomech
