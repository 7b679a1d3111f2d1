// Design optimisation (src/study/optimize.cpp, issue 51 item 2) against the four-bar's closed
// form. The bundled crank-rocker (coupler b = 80, rocker c = 60, ground d = 70 mm) with its crank
// length a as the design variable: the rocker's limit positions are the crank and coupler
// collinear, A0B = b ± a, and in the triangle A0 B0 B the rocker's angle is
// ψ(l) = π − acos((d² + c² − l²) / (2dc)), so its swing is S(a) = ψ(b + a) − ψ(b − a), increasing
// in a. The smallest swing of at least 60° is at S(a*) = 60°, a* solved here by bisection. Above
// a = b + c − d = 70 mm the crank cannot turn (Grashof): those variants stop at a dead point and
// are infeasible, never the end of the search.
#include "orthomech/study/optimize.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "support/cli_runner.hpp"

namespace orthomech {
namespace {

constexpr double b = 80, c = 60, d = 70;
constexpr double kPi = std::numbers::pi;

double swing_deg(double a) {
  const auto psi = [](double l) { return kPi - std::acos((d * d + c * c - l * l) / (2 * d * c)); };
  return std::abs(psi(b + a) - psi(b - a)) * 180.0 / kPi;
}

double crank_for_swing(double target) {
  double lo = 1.0, hi = 69.0;
  for (int k = 0; k < 200; ++k) {
    const double mid = 0.5 * (lo + hi);
    (swing_deg(mid) < target ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

std::string mechanism() { return test::read_text(test::bundled_file("crank-rocker")); }

Study study(const std::string& extra) {
  return parse_study(R"(study: optimize
steps: 360
parameters:
  - {name: crank, path: bodies.crank.points.A.0, bounds: [15, 80], start: 40}
)" + extra,
                     "o.yaml", mechanism(), "crank-rocker.yaml");
}

TEST(Optimize, SmallestSwingOfAtLeast60DegreesIsTheLawOfCosinesCrank) {
  const Study s = study(R"(objective: {minimize: range(rocker_angle)}
constraints:
  - {metric: range(rocker_angle), min: 60}
evaluations: 300
tolerance: 1e-8
)");
  long infeasible = 0, calls = 0;
  const OptimizeResult r = run_optimize(mechanism(), "crank-rocker.yaml", s,
                                        [&](const VariantResult& v, const OptimizeStep& step) {
                                          ++calls;
                                          EXPECT_EQ(v.index, step.evaluation);
                                          if (v.values[0] > 70.5) {
                                            EXPECT_NE(v.status, "completed");
                                            EXPECT_FALSE(step.feasible);
                                          }
                                          infeasible += step.feasible ? 0 : 1;
                                        });
  ASSERT_TRUE(r.found) << r.outcome << ": " << r.message;
  const double a_star = crank_for_swing(60.0);
  // The search's own step limit is 1e-8 of the 65 mm span; what is left is the cycle's swing
  // (parabola-refined extremes at 360 steps, within 1e-4° of S below) over S'(a*) ≈ 2°/mm:
  // about 1e-5 mm, bounded here by 2e-3 mm.
  EXPECT_NEAR(r.best.values[0], a_star, 2e-3) << "a* = " << a_star;
  double swing = 0.0;
  for (const auto& [name, value] : r.best.metrics)
    if (name == "rocker_angle.range") swing = value;
  EXPECT_GE(swing, 60.0 * (1.0 - kOptimizeFeasibility));
  // The cycle's swing is the closed form up to the refinement of its extremes (an O(h³) error of
  // the parabola through three samples 1° apart; measured −2.0e-5° at a*).
  EXPECT_NEAR(swing, swing_deg(r.best.values[0]), 1e-4);
  EXPECT_EQ(calls, r.evaluations);
  EXPECT_EQ(r.steps.back().best, r.best.index);
}

TEST(Optimize, AnEqualityConstraintHoldsToItsTolerance) {
  const double a_star = crank_for_swing(50.0);
  const Study s = study(R"(objective: {maximize: transmission.min}
constraints:
  - {metric: range(rocker_angle), equal: 50, tolerance: 0.05}
evaluations: 300
tolerance: 1e-8
)");
  const OptimizeResult r = run_optimize(mechanism(), "crank-rocker.yaml", s, {});
  ASSERT_TRUE(r.found) << r.outcome << ": " << r.message;
  // |S(a) − 50| ≤ 0.05 holds on a* ± 0.05 / S'(a*) (S' ≈ 2°/mm here): within 0.03 mm.
  EXPECT_NEAR(r.best.values[0], a_star, 0.03);
  EXPECT_NEAR(swing_deg(r.best.values[0]), 50.0, 0.05 + 1e-4);
}

TEST(Optimize, TheGlobalMethodIsSeededAndHonoursTheConstraint) {
  const double a_star = crank_for_swing(50.0);
  const Study s = study(R"(objective: {minimize: range(rocker_angle)}
constraints:
  - {metric: range(rocker_angle), min: 50}
algorithm: isres
seed: 3
evaluations: 300
)");
  const OptimizeResult r = run_optimize(mechanism(), "crank-rocker.yaml", s, {});
  ASSERT_TRUE(r.found) << r.outcome << ": " << r.message;
  EXPECT_GE(swing_deg(r.best.values[0]), 50.0 - 1e-3);  // feasible (the cycle's swing ≈ S(a))
  EXPECT_NEAR(r.best.values[0], a_star, 1.0);           // near the optimum: a stochastic search
  const OptimizeResult again = run_optimize(mechanism(), "crank-rocker.yaml", s, {});
  EXPECT_EQ(again.best.values, r.best.values);  // the same seed, the same search
  EXPECT_EQ(again.evaluations, r.evaluations);
}

TEST(Optimize, StopEndsTheSearchWithTheBestSoFar) {
  const Study s = study("objective: {minimize: drive.peak}\n");
  int asked = 0;
  const OptimizeResult r =
      run_optimize(mechanism(), "crank-rocker.yaml", s, {}, [&] { return ++asked > 3; });
  EXPECT_EQ(r.outcome, "stopped");
  EXPECT_EQ(r.evaluations, 3);
  EXPECT_TRUE(r.found);
}

// Resuming: the search given its first k evaluations (as a stored study would) asks for the same
// points, computes only the others and ends where one uninterrupted run does — for the local
// method and for the seeded global one. Stored evaluations at other values are refused.
TEST(Optimize, AResumedSearchReplaysItsStoredEvaluations) {
  for (const char* algorithm : {"cobyla", "isres"}) {
    const Study s = study(std::string(R"(objective: {minimize: range(rocker_angle)}
constraints:
  - {metric: range(rocker_angle), min: 50}
steps: 60
evaluations: 60
algorithm: )") + algorithm +
                          "\n");
    std::vector<VariantResult> all;
    const OptimizeResult once =
        run_optimize(mechanism(), "crank-rocker.yaml", s,
                     [&](const VariantResult& v, const OptimizeStep&) { all.push_back(v); });
    ASSERT_TRUE(once.found) << algorithm;
    ASSERT_GT(all.size(), 8u) << algorithm;
    const std::vector<VariantResult> stored(all.begin(), all.begin() + 8);
    long computed = 0, replayed = 0;
    const OptimizeResult resumed = run_optimize(
        mechanism(), "crank-rocker.yaml", s,
        [&](const VariantResult& v, const OptimizeStep& step) {
          (step.replayed ? replayed : computed) += 1;
          EXPECT_EQ(step.replayed, v.index < 8) << algorithm << " evaluation " << v.index;
        },
        {}, stored);
    EXPECT_EQ(replayed, 8) << algorithm;
    EXPECT_EQ(computed, static_cast<long>(all.size()) - 8) << algorithm;
    EXPECT_EQ(resumed.evaluations, once.evaluations) << algorithm;
    EXPECT_EQ(resumed.best.index, once.best.index) << algorithm;
    EXPECT_EQ(resumed.best.values, once.best.values) << algorithm;
    EXPECT_EQ(resumed.outcome, once.outcome) << algorithm;
    std::vector<VariantResult> wrong = stored;
    wrong[5].values[0] += 1e-9;
    EXPECT_THROW((void)run_optimize(mechanism(), "crank-rocker.yaml", s, {}, {}, wrong),
                 std::invalid_argument)
        << algorithm;
  }
}

// Multistart: COBYLA from the start and from seeded points, in parallel. The same evaluations,
// steps and optimum on one thread and on three (the searches number their evaluations from
// s × budget; the best so far is taken in that order); the optimum is the law-of-cosines crank
// (the smallest swing of at least 50°) as for one search; resumed from a part of the evaluations
// of every search it ends as one run.
TEST(Optimize, MultistartIsTheSameOnAnyNumberOfThreads) {
  const double a_star = crank_for_swing(50.0);
  const Study s = study(R"(objective: {minimize: range(rocker_angle)}
constraints:
  - {metric: range(rocker_angle), min: 50}
steps: 90
algorithm: multistart
starts: 4
seed: 5
evaluations: 40
)");
  std::vector<VariantResult> all;
  const auto collect = [&](const VariantResult& v, const OptimizeStep&) { all.push_back(v); };
  const OptimizeResult one = run_optimize(mechanism(), "crank-rocker.yaml", s, collect, {}, {}, 1);
  const OptimizeResult three = run_optimize(mechanism(), "crank-rocker.yaml", s, {}, {}, {}, 3);
  ASSERT_TRUE(one.found) << one.outcome << ": " << one.message;
  EXPECT_EQ(one.outcome, "multistart completed") << one.message;
  ASSERT_EQ(one.steps.size(), three.steps.size());
  for (size_t k = 0; k < one.steps.size(); ++k) {
    EXPECT_EQ(one.steps[k].evaluation, three.steps[k].evaluation);
    EXPECT_EQ(one.steps[k].objective, three.steps[k].objective) << k;
    EXPECT_EQ(one.steps[k].best, three.steps[k].best) << k;
  }
  EXPECT_EQ(one.best.index, three.best.index);
  EXPECT_EQ(one.best.values, three.best.values);
  // Four searches, each numbered from s × 40; several of them start elsewhere than the file.
  std::set<long> searches;
  for (const OptimizeStep& step : one.steps) searches.insert(step.evaluation / 40);
  EXPECT_EQ(searches.size(), 4u);
  // The optimum: S(a*) = 50° (90 positions 4° apart: the cycle's swing within 0.05° of S).
  EXPECT_NEAR(swing_deg(one.best.values[0]), 50.0, 0.05);
  EXPECT_NEAR(one.best.values[0], a_star, 0.05);
  // Resumed with the first 5 evaluations of every search stored (in evaluation order).
  std::sort(all.begin(), all.end(),
            [](const VariantResult& x, const VariantResult& y) { return x.index < y.index; });
  std::vector<VariantResult> stored;
  for (const VariantResult& v : all)
    if (v.index % 40 < 5) stored.push_back(v);
  long computed = 0;
  const OptimizeResult resumed = run_optimize(
      mechanism(), "crank-rocker.yaml", s,
      [&](const VariantResult&, const OptimizeStep& step) { computed += step.replayed ? 0 : 1; },
      {}, stored, 2);
  EXPECT_EQ(computed, static_cast<long>(all.size() - stored.size()));
  EXPECT_EQ(resumed.best.index, one.best.index);
  EXPECT_EQ(resumed.best.values, one.best.values);
  EXPECT_EQ(resumed.evaluations, one.evaluations);
}

TEST(Optimize, TheStudyFileIsCheckedAtItsLines) {
  auto message = [](const std::string& text) {
    try {
      (void)parse_study(text, "o.yaml", mechanism(), "crank-rocker.yaml");
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  const std::string head = "study: optimize\nparameters:\n";
  const std::string crank = "  - {path: bodies.crank.points.A.0, bounds: [15, 60]}\n";
  EXPECT_NE(message(head + crank).find("missing field 'objective'"), std::string::npos);
  EXPECT_NE(message(head + crank + "objective: {minimize: drive.peek}\n").find("o.yaml:4:23"),
            std::string::npos)
      << message(head + crank + "objective: {minimize: drive.peek}\n");
  EXPECT_NE(message(head + "  - {path: bodies.crank.points.A.0, values: [1, 2]}\n" +
                    "objective: {minimize: drive.peak}\n")
                .find("bounds: [lower, upper]"),
            std::string::npos);
  EXPECT_NE(message(head + "  - {path: bodies.crank.points.A.0, bounds: [15, 25]}\n" +
                    "objective: {minimize: drive.peak}\n")
                .find("outside the bounds"),
            std::string::npos);  // the file's 30 is the start
  EXPECT_NE(message(head + crank + "objective: {minimize: drive.peak}\nconstraints:\n" +
                    "  - {metric: transmission.min, min: 40, tolerance: 1}\n")
                .find("belongs to an 'equal'"),
            std::string::npos);
  EXPECT_NE(message(head + crank + "objective: {minimize: drive.peak}\nalgorithm: simplex\n")
                .find("'cobyla' (local), 'isres' (global) or 'multistart'"),
            std::string::npos);
  EXPECT_NE(message(head + crank + "objective: {minimize: drive.peak}\nstarts: 4\n")
                .find("'starts' belongs to algorithm: multistart"),
            std::string::npos);
  EXPECT_NE(message(head + crank +
                    "objective: {minimize: drive.peak}\nalgorithm: multistart\nstarts: 0\n")
                .find("starts"),
            std::string::npos);
  EXPECT_NE(message("study: grid\nparameters:\n  - {path: bodies.crank.mass, values: [1]}\n"
                    "objective: {minimize: drive.peak}\n")
                .find("belongs to an optimize study"),
            std::string::npos);
  EXPECT_EQ(message(head + crank + "objective: {minimize: drive.peak}\nconstraints:\n" +
                    "  - {metric: transmission.min, min: 40}\n"),
            "accepted");
}

}  // namespace
}  // namespace orthomech
