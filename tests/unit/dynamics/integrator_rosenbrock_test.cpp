// The stiff integrator's pieces (src/dynamics/integrator.hpp, private): the finite-difference
// Jacobian against analytic derivatives, and RODAS 4(3)'s order of convergence at fixed steps
// against closed-form solutions (a wrong coefficient lowers the order).
#include <gtest/gtest.h>

#include <cmath>

#include "../../../src/dynamics/integrator.hpp"

namespace orthomech::detail {
namespace {

// f(x, t) = (x₁², sin(x₀) x₁ + t², t x₀): ∂f/∂x and ∂f/∂t by hand.
TEST(FiniteDifferenceJacobian, CentralDifferencesMatchAnalyticDerivatives) {
  OdeProblem p;
  p.rhs = [](const VecX& x, VecX& f, double t) {
    f.resize(3);
    f << x(1) * x(1), std::sin(x(0)) * x(1) + t * t, t * x(0);
  };
  VecX x(3);
  x << 0.7, -1.3, 2.0;
  const double t = 0.4;
  MatX J;
  VecX ft;
  FiniteDifferenceJacobian fd;
  fd.compute(p, x, t, J, ft);
  MatX J_exact = MatX::Zero(3, 3);
  J_exact(0, 1) = 2.0 * x(1);
  J_exact(1, 0) = std::cos(x(0)) * x(1);
  J_exact(1, 1) = std::sin(x(0));
  J_exact(2, 0) = t;
  VecX ft_exact(3);
  ft_exact << 0.0, 2.0 * t, x(0);
  // The fourth-order stencil with h = ∛ε·max(1, |x|): truncation h⁴·|f⁽⁵⁾|/30 ~1e-21, rounding
  // ~1.5 ε|f|/h ~1e-10 here.
  constexpr double kFdTol = 1e-9;
  EXPECT_LT((J - J_exact).cwiseAbs().maxCoeff(), kFdTol);
  EXPECT_LT((ft - ft_exact).cwiseAbs().maxCoeff(), kFdTol);
}

// Far from the origin the step h = ∛ε·|x| is large (1.2e-4 at x = 20): a two-point central
// difference of sin(10 x) errs by h²·|f'''|/6 = 1.2e-6 there, the fourth-order stencil by
// h⁴·|f⁽⁵⁾|/30 + 1.5 ε|f|/h ~ 2e-12. Same in t (∂f/∂t of sin(10 t) at t = 20).
TEST(FiniteDifferenceJacobian, FourthOrderWhereTheStepIsLarge) {
  OdeProblem p;
  p.rhs = [](const VecX& x, VecX& f, double t) {
    f.resize(2);
    f << std::sin(10.0 * x(0)), std::sin(10.0 * t) + x(1);
  };
  VecX x(2);
  x << 20.0, 0.3;
  const double t = 20.0;
  MatX J;
  VecX ft;
  FiniteDifferenceJacobian fd;
  fd.compute(p, x, t, J, ft);
  constexpr double kTol = 1e-10;  // 1e4 below the two-point difference's error
  EXPECT_NEAR(J(0, 0), 10.0 * std::cos(10.0 * x(0)), kTol);
  EXPECT_NEAR(J(1, 1), 1.0, kTol);
  EXPECT_NEAR(ft(1), 10.0 * std::cos(10.0 * t), kTol);
  EXPECT_EQ(J(0, 1), 0.0);
  EXPECT_EQ(J(1, 0), 0.0);
}

// With jacobian_columns only the listed columns are differenced; the others are zero. The
// listed ones equal the full difference Jacobian's bit for bit (same steps, same evaluations).
TEST(FiniteDifferenceJacobian, ListedColumnsOnly_OthersZero) {
  OdeProblem p;
  p.rhs = [](const VecX& x, VecX& f, double t) {
    f.resize(3);
    f << x(1) * x(1) + x(2), std::sin(x(0)) * x(1) + t * t, t * x(0) - x(2);
  };
  VecX x(3);
  x << 0.7, -1.3, 2.0;
  MatX J_full, J_cols;
  VecX ft_full, ft_cols;
  FiniteDifferenceJacobian fd;
  fd.compute(p, x, 0.4, J_full, ft_full);
  p.jacobian_columns = [](std::vector<Eigen::Index>& c) { c = {0, 2}; };
  fd.compute(p, x, 0.4, J_cols, ft_cols);
  EXPECT_EQ(J_cols.col(0), J_full.col(0));
  EXPECT_EQ(J_cols.col(2), J_full.col(2));
  EXPECT_EQ(J_cols.col(1), VecX::Zero(3));
  EXPECT_NE(J_full.col(1), VecX::Zero(3));  // the omitted column is not zero in truth
  EXPECT_EQ(ft_cols, ft_full);
  // Other columns into the same J: the previous call's columns are zero again.
  p.jacobian_columns = [](std::vector<Eigen::Index>& c) { c = {1}; };
  fd.compute(p, x, 0.4, J_cols, ft_cols);
  EXPECT_EQ(J_cols.col(1), J_full.col(1));
  EXPECT_EQ(J_cols.col(0), VecX::Zero(3));
  EXPECT_EQ(J_cols.col(2), VecX::Zero(3));
  // An autonomous problem's ∂f/∂t is not differenced: zero.
  p.autonomous = true;
  fd.compute(p, x, 0.4, J_cols, ft_cols);
  EXPECT_EQ(ft_cols, VecX::Zero(3));
}

// Error at t_end of Rosenbrock at a fixed step h: rtol so loose that every step is accepted,
// and the step pinned by dt_init = max_dt = h.
double fixed_step_error(const OdeProblem& p, const VecX& x0, double t_end, double h,
                        const VecX& exact) {
  OdeOptions o;
  o.stepper = OdeStepper::rosenbrock4;
  o.rtol = o.atol = 1e6;
  o.t_end = t_end;
  o.dt_out = t_end;
  o.dt_init = o.max_dt = h;
  VecX x = x0;
  const OdeStats s = integrate_ode(p, x, o);
  EXPECT_TRUE(s.completed) << s.message;
  EXPECT_EQ(s.steps, std::lround(t_end / h));
  return (x - exact).norm();
}

OdeProblem problem(std::function<void(const VecX&, VecX&, double)> f) {
  OdeProblem p;
  p.rhs = std::move(f);
  p.accept = [](double, VecX&) { return true; };
  p.output = [](double, const VecX&) {};
  return p;
}

// Observed order log₂(e(h)/e(h/2)) between 3.5 and 4.5 for a method of order 4 (h = 0.05,
// 0.025, 0.0125: in the asymptotic range, errors 3e-8 … 2e-10, far above rounding).
void expect_order_four(const OdeProblem& p, const VecX& x0, double t_end, const VecX& exact) {
  const double e1 = fixed_step_error(p, x0, t_end, 0.05, exact);
  const double e2 = fixed_step_error(p, x0, t_end, 0.025, exact);
  const double e3 = fixed_step_error(p, x0, t_end, 0.0125, exact);
  EXPECT_NEAR(std::log2(e1 / e2), 4.0, 0.5) << e1 << " " << e2;
  EXPECT_NEAR(std::log2(e2 / e3), 4.0, 0.5) << e2 << " " << e3;
}

TEST(Rosenbrock4, OrderFour_HarmonicOscillator) {
  // x'' = −x: (cos t, −sin t).
  const OdeProblem p = problem([](const VecX& x, VecX& f, double) {
    f.resize(2);
    f << x(1), -x(0);
  });
  VecX x0(2), exact(2);
  x0 << 1.0, 0.0;
  exact << std::cos(2.0), -std::sin(2.0);
  expect_order_four(p, x0, 2.0, exact);
}

// The Woodbury path (jacobian_columns with 2m < n): x'' = −x carried along by three passive
// integrals that f does not depend on, (x₀, x₁, ∫x₀, ∫x₁², ∫x₀x₁): the Jacobian has two non-zero
// columns of five. Order 4 against the closed form, and the same result as the dense LU path to
// rounding (the same method, W⁻¹ by the Sherman–Morrison–Woodbury identity).
TEST(Rosenbrock4, OrderFour_LowRankJacobian_EqualsDensePath) {
  const auto f = [](const VecX& x, VecX& dx, double) {
    dx.resize(5);
    dx << x(1), -x(0), x(0), x(1) * x(1), x(0) * x(1);
  };
  OdeProblem dense = problem(f);
  OdeProblem low_rank = problem(f);
  low_rank.jacobian_columns = [](std::vector<Eigen::Index>& c) { c = {0, 1}; };
  low_rank.autonomous = true;
  VecX x0(5), exact(5);
  x0 << 1.0, 0.0, 0.0, 0.0, 0.0;
  const double T = 2.0;  // x = cos t: ∫cos = sin T, ∫sin² = T/2 − sin 2T/4, ∫−cos sin = −sin² T/2
  exact << std::cos(T), -std::sin(T), std::sin(T), T / 2.0 - std::sin(2.0 * T) / 4.0,
      -std::sin(T) * std::sin(T) / 2.0;
  expect_order_four(low_rank, x0, T, exact);
  for (const double h : {0.05, 0.0125})
    EXPECT_NEAR(fixed_step_error(low_rank, x0, T, h, exact),
                fixed_step_error(dense, x0, T, h, exact), 1e-12);
}

TEST(Rosenbrock4, OrderFour_NonAutonomous) {
  // y' = cos(t) y: y = exp(sin t) — exercises the ∂f/∂t terms (the d_i coefficients).
  const OdeProblem p = problem([](const VecX& x, VecX& f, double t) {
    f.resize(1);
    f(0) = std::cos(t) * x(0);
  });
  VecX x0(1), exact(1);
  x0 << 1.0;
  exact << std::exp(std::sin(2.0));
  expect_order_four(p, x0, 2.0, exact);
}

}  // namespace
}  // namespace orthomech::detail
