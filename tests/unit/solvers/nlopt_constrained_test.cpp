// The constrained NLopt adapter (src/solvers/nlopt_constrained.cpp) against a closed form: the
// nearest point of the half-plane x + y ≤ 1 to (2, 1) is its projection (1, 0) (the constraint
// active, multiplier 1); with x ≤ 0.25 as well, the corner (0.25, 0.75). Errors of the evaluation
// are outcomes, not exceptions; the objective and the constraints are evaluated once per point.
#include "../../../src/solvers/nlopt_constrained.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace orthomech::solvers {
namespace {

ConstrainedValue distance(const Eigen::VectorXd& x, bool corner) {
  ConstrainedValue v;
  v.objective = (x(0) - 2.0) * (x(0) - 2.0) + (x(1) - 1.0) * (x(1) - 1.0);
  v.constraints.push_back(x(0) + x(1) - 1.0);
  if (corner) v.constraints.push_back(x(0) - 0.25);
  return v;
}

TEST(NloptConstrained, CobylaFindsTheProjectionOntoTheHalfPlane) {
  int calls = 0;
  const ConstrainedEvaluation f = [&](const Eigen::VectorXd& x) {
    ++calls;
    return distance(x, false);
  };
  ConstrainedSettings s;
  s.xtol_abs = 1e-10;
  s.max_evaluations = 2000;
  const NloptOutcome o = minimize_constrained(f, 1, Eigen::Vector2d(-3, 4), Eigen::Vector2d(-5, -5),
                                              Eigen::Vector2d(5, 5), s);
  EXPECT_EQ(o.kind, NloptOutcomeKind::converged) << o.message;
  EXPECT_NEAR(o.x(0), 1.0, 1e-6);
  EXPECT_NEAR(o.x(1), 0.0, 1e-6);
  EXPECT_NEAR(o.value, 2.0, 1e-6);
  EXPECT_EQ(calls, o.evaluations);  // objective and constraint share one evaluation per point
}

TEST(NloptConstrained, TwoActiveConstraintsAndTheGlobalMethod) {
  const ConstrainedEvaluation f = [](const Eigen::VectorXd& x) { return distance(x, true); };
  ConstrainedSettings s;
  s.xtol_abs = 1e-10;
  s.max_evaluations = 2000;
  const Eigen::Vector2d lo(-5, -5), hi(5, 5);
  const NloptOutcome o = minimize_constrained(f, 2, Eigen::Vector2d(0, 0), lo, hi, s);
  EXPECT_NEAR(o.x(0), 0.25, 1e-6);
  EXPECT_NEAR(o.x(1), 0.75, 1e-6);
  s.method = ConstrainedMethod::isres;
  s.max_evaluations = 20000;
  s.seed = 7;
  const NloptOutcome g = minimize_constrained(f, 2, Eigen::Vector2d(0, 0), lo, hi, s);
  EXPECT_NEAR(g.x(0), 0.25, 2e-2);
  EXPECT_NEAR(g.x(1), 0.75, 2e-2);
  const NloptOutcome again = minimize_constrained(f, 2, Eigen::Vector2d(0, 0), lo, hi, s);
  EXPECT_EQ(again.x, g.x);  // the same seed, the same run
}

TEST(NloptConstrained, ErrorsOfTheEvaluationAreOutcomes) {
  const ConstrainedEvaluation throws = [](const Eigen::VectorXd&) -> ConstrainedValue {
    throw std::runtime_error("no cycle");
  };
  const Eigen::Vector2d lo(-1, -1), hi(1, 1), x0(0, 0);
  const NloptOutcome t = minimize_constrained(throws, 1, x0, lo, hi);
  EXPECT_EQ(t.kind, NloptOutcomeKind::callback_error);
  EXPECT_NE(t.message.find("no cycle"), std::string::npos);
  const ConstrainedEvaluation nan = [](const Eigen::VectorXd&) {
    return ConstrainedValue{std::nan(""), {0.0}};
  };
  EXPECT_EQ(minimize_constrained(nan, 1, x0, lo, hi).kind, NloptOutcomeKind::callback_error);
  const ConstrainedEvaluation wrong = [](const Eigen::VectorXd&) { return ConstrainedValue{}; };
  EXPECT_EQ(minimize_constrained(wrong, 1, x0, lo, hi).kind, NloptOutcomeKind::callback_error);
}

}  // namespace
}  // namespace orthomech::solvers
