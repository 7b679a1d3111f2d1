// The private Ipopt adapter (src/solvers/ipopt_nlp.cpp): every failure mode comes back as a
// status, and an exception thrown by a callback never crosses the solver (it is stored and
// reported). Oracles: closed-form minimisers of small problems.
#include "../../../src/solvers/ipopt_nlp.hpp"

#include <gtest/gtest.h>

#include <vector>

#include <cmath>
#include <limits>
#include <stdexcept>

namespace orthomech::solvers {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

// min (x0 − 1)² + (x1 − 2)² subject to x0 + x1 = 1: closed form x = (0, 1).
DenseNlp plane_problem() {
  DenseNlp p;
  p.n = 2;
  p.m = 1;
  p.x0 = VectorXd::Zero(2);
  p.g_lower = VectorXd::Constant(1, 1.0);
  p.g_upper = VectorXd::Constant(1, 1.0);
  p.objective = [](const VectorXd& x) { return std::pow(x(0) - 1, 2) + std::pow(x(1) - 2, 2); };
  p.gradient = [](const VectorXd& x, VectorXd& g) {
    g(0) = 2 * (x(0) - 1);
    g(1) = 2 * (x(1) - 2);
  };
  p.constraints = [](const VectorXd& x, VectorXd& g) { g(0) = x(0) + x(1); };
  p.jacobian = [](const VectorXd&, MatrixXd& J) { J << 1, 1; };
  p.hessian = [](const VectorXd&, double s, const VectorXd&, MatrixXd& H) {
    H = 2 * s * MatrixXd::Identity(2, 2);
  };
  return p;
}

TEST(IpoptAdapter, Solved_ClosedForm) {
  const IpoptOutcome r = solve_with_ipopt(plane_problem(), {});
  EXPECT_EQ(r.kind, IpoptOutcomeKind::solved) << r.message;
  EXPECT_NEAR(r.x(0), 0.0, 1e-9);
  EXPECT_NEAR(r.x(1), 1.0, 1e-9);
}

TEST(IpoptAdapter, Infeasible_IsAStatus) {
  DenseNlp p = plane_problem();
  p.constraints = [](const VectorXd& x, VectorXd& g) { g(0) = x(0) * x(0) + x(1) * x(1); };
  p.jacobian = [](const VectorXd& x, MatrixXd& J) { J << 2 * x(0), 2 * x(1); };
  p.hessian = [](const VectorXd&, double s, const VectorXd& l, MatrixXd& H) {
    H = (2 * s + 2 * l(0)) * MatrixXd::Identity(2, 2);
  };
  p.x0 = VectorXd::Constant(2, 0.5);
  p.g_lower(0) = p.g_upper(0) = -1.0;  // x0² + x1² = −1 has no solution
  const IpoptOutcome r = solve_with_ipopt(p, {});
  EXPECT_EQ(r.kind, IpoptOutcomeKind::infeasible) << r.status;
}

TEST(IpoptAdapter, IterationLimit_IsAStatus) {
  DenseNlp p = plane_problem();
  p.objective = [](const VectorXd& x) {  // Rosenbrock, unconstrained
    return 100 * std::pow(x(1) - x(0) * x(0), 2) + std::pow(1 - x(0), 2);
  };
  p.gradient = [](const VectorXd& x, VectorXd& g) {
    g(0) = -400 * x(0) * (x(1) - x(0) * x(0)) - 2 * (1 - x(0));
    g(1) = 200 * (x(1) - x(0) * x(0));
  };
  p.hessian = {};  // quasi-Newton
  p.m = 0;
  p.g_lower.resize(0);
  p.g_upper.resize(0);
  p.x0 << -1.2, 1.0;
  IpoptSettings s;
  s.max_iter = 2;
  const IpoptOutcome r = solve_with_ipopt(p, s);
  EXPECT_EQ(r.kind, IpoptOutcomeKind::not_converged) << r.status;
  EXPECT_EQ(r.status, "Maximum_Iterations_Exceeded");
}

// IpoptSettings::keep_going: asked after every iteration with its number; false stops the solve
// there with outcome `stopped` (not `not_converged`), the iterate of that iteration kept.
TEST(IpoptAdapter, KeepGoingFalse_StopsAtThatIteration) {
  DenseNlp p = plane_problem();
  p.objective = [](const VectorXd& x) {  // Rosenbrock, unconstrained: many iterations
    return 100 * std::pow(x(1) - x(0) * x(0), 2) + std::pow(1 - x(0), 2);
  };
  p.gradient = [](const VectorXd& x, VectorXd& g) {
    g(0) = -400 * x(0) * (x(1) - x(0) * x(0)) - 2 * (1 - x(0));
    g(1) = 200 * (x(1) - x(0) * x(0));
  };
  p.hessian = {};
  p.m = 0;
  p.g_lower.resize(0);
  p.g_upper.resize(0);
  p.x0 << -1.2, 1.0;
  std::vector<int> asked;
  IpoptSettings s;
  s.keep_going = [&](int iteration) {
    asked.push_back(iteration);
    return iteration < 3;
  };
  const IpoptOutcome r = solve_with_ipopt(p, s);
  EXPECT_EQ(r.kind, IpoptOutcomeKind::stopped) << r.status;
  EXPECT_EQ(r.status, "User_Requested_Stop");
  EXPECT_EQ(asked, (std::vector<int>{0, 1, 2, 3}));
  EXPECT_EQ(r.x.size(), 2);
  s.keep_going = [](int) { return true; };  // never stops: Ipopt's own end
  EXPECT_EQ(solve_with_ipopt(p, s).kind, IpoptOutcomeKind::solved);
}

TEST(IpoptAdapter, NaNFromCallback_IsAStatus) {
  DenseNlp p = plane_problem();
  p.objective = [](const VectorXd&) { return std::numeric_limits<double>::quiet_NaN(); };
  const IpoptOutcome r = solve_with_ipopt(p, {});
  EXPECT_NE(r.kind, IpoptOutcomeKind::solved);
  EXPECT_FALSE(r.error);
}

TEST(IpoptAdapter, ThrowingCallback_StoredNotPropagated) {
  DenseNlp p = plane_problem();
  int calls = 0;
  p.jacobian = [&calls](const VectorXd&, MatrixXd& J) {
    if (++calls > 1) throw std::runtime_error("boom in the Jacobian");
    J << 1, 1;
  };
  IpoptOutcome r;
  EXPECT_NO_THROW(r = solve_with_ipopt(p, {}));
  EXPECT_EQ(r.kind, IpoptOutcomeKind::callback_error);
  ASSERT_TRUE(r.error);
  EXPECT_NE(r.message.find("boom in the Jacobian"), std::string::npos) << r.message;
  EXPECT_THROW(std::rethrow_exception(r.error), std::runtime_error);
}

TEST(IpoptAdapter, TooFewDegreesOfFreedom_IsAStatus) {
  DenseNlp p = plane_problem();  // two independent equalities and one more on two variables
  p.m = 3;
  p.g_lower = VectorXd::Constant(3, 1.0);
  p.g_upper = p.g_lower;
  p.constraints = [](const VectorXd& x, VectorXd& g) { g << x(0) + x(1), x(0), x(1); };
  p.jacobian = [](const VectorXd&, MatrixXd& J) { J << 1, 1, 1, 0, 0, 1; };
  const IpoptOutcome r = solve_with_ipopt(p, {});
  EXPECT_EQ(r.kind, IpoptOutcomeKind::too_few_dof) << r.status;
}

}  // namespace
}  // namespace orthomech::solvers
