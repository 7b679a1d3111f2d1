// The private NLopt adapter (src/solvers/nlopt_minimize.cpp): every failure mode comes back as a
// status, and an exception thrown by the objective never crosses the solver (it is stored and
// reported). Oracles: closed-form minimisers of small problems.
#include "../../../src/solvers/nlopt_minimize.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>

namespace orthomech::solvers {
namespace {

using Eigen::VectorXd;

TEST(NloptAdapter, Converged_ClosedForm) {
  const auto f = [](const VectorXd& x) { return std::pow(x(0) - 0.3, 2) + 1.0; };
  const NloptOutcome r = minimize_bounded(f, VectorXd::Constant(1, 0.9), VectorXd::Constant(1, 0.0),
                                          VectorXd::Constant(1, 1.0));
  EXPECT_EQ(r.kind, NloptOutcomeKind::converged) << r.message;
  EXPECT_NEAR(r.x(0), 0.3, 1e-6);
  EXPECT_NEAR(r.value, 1.0, 1e-12);
}

TEST(NloptAdapter, Bounded2D_ClosedForm) {
  // Minimum of (x − 2)² + (y + 1)² on [0, 1]²: the corner (1, 0).
  const auto f = [](const VectorXd& x) { return std::pow(x(0) - 2, 2) + std::pow(x(1) + 1, 2); };
  const NloptOutcome r =
      minimize_bounded(f, VectorXd::Constant(2, 0.5), VectorXd::Zero(2), VectorXd::Ones(2));
  EXPECT_EQ(r.kind, NloptOutcomeKind::converged) << r.message;
  EXPECT_NEAR(r.x(0), 1.0, 1e-8);
  EXPECT_NEAR(r.x(1), 0.0, 1e-8);
}

TEST(NloptAdapter, ThrowingObjective_StoredNotPropagated) {
  int calls = 0;
  const auto f = [&calls](const VectorXd& x) {
    if (++calls > 3) throw std::logic_error("boom in the objective");
    return x(0) * x(0);
  };
  NloptOutcome r;
  EXPECT_NO_THROW(r = minimize_bounded(f, VectorXd::Constant(1, 0.5), VectorXd::Constant(1, -1.0),
                                       VectorXd::Constant(1, 1.0)));
  EXPECT_EQ(r.kind, NloptOutcomeKind::callback_error);
  ASSERT_TRUE(r.error);
  EXPECT_NE(r.message.find("boom in the objective"), std::string::npos);
}

TEST(NloptAdapter, NaN_InvalidBounds_EvaluationLimit_AreStatuses) {
  const auto nan = [](const VectorXd&) { return std::numeric_limits<double>::quiet_NaN(); };
  EXPECT_EQ(minimize_bounded(nan, VectorXd::Constant(1, 0.5), VectorXd::Constant(1, 0.0),
                             VectorXd::Constant(1, 1.0))
                .kind,
            NloptOutcomeKind::callback_error);
  const auto sq = [](const VectorXd& x) { return x.squaredNorm(); };
  EXPECT_EQ(minimize_bounded(sq, VectorXd::Constant(1, 0.5), VectorXd::Constant(1, 1.0),
                             VectorXd::Constant(1, 0.0))
                .kind,
            NloptOutcomeKind::invalid);
  NloptSettings s;
  s.max_evaluations = 3;
  s.xtol_abs = 0.0;
  const auto wavy = [](const VectorXd& x) { return std::sin(20 * x(0)) + x(0) * x(0); };
  EXPECT_EQ(minimize_bounded(wavy, VectorXd::Constant(1, 0.5), VectorXd::Constant(1, -1.0),
                             VectorXd::Constant(1, 1.0), s)
                .kind,
            NloptOutcomeKind::max_evaluations);
}

}  // namespace
}  // namespace orthomech::solvers
