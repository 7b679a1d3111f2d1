// The Boost.Odeint adapter (src/dynamics/integrator.hpp, private): it must stop with a message,
// not step for ever, when the step size collapses to the rounding level of t.
#include "../../../src/dynamics/integrator.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace orthomech::detail {
namespace {

// ẋ = 1/(1 − t)²: x = 1/(1 − t) − 1 has a pole at t = 1, so no step can pass it. Dormand–
// Prince only: Fehlberg 7(8)'s error estimate uses four of its 13 stages (k₀, k₁₀, k₁₁, k₁₂,
// weights ±41/840) and accepted a step straddling the pole here (x = 32 at t = 2), so the pole does
// not make its step size collapse; its guard (the same bound) acts on rejected steps.
OdeProblem pole() {
  OdeProblem p;
  p.rhs = [](const VecX&, VecX& dx, double t) {
    dx.resize(1);
    dx(0) = 1.0 / ((1.0 - t) * (1.0 - t));
  };
  p.accept = [](double, VecX&) { return true; };
  p.output = [](double, const VecX&) {};
  return p;
}

TEST(Integrator, Dopri5StopsWithAMessageAtAPole) {
  OdeOptions o;
  o.stepper = OdeStepper::dopri5;
  o.t_end = 2.0;
  o.dt_out = 1.0;
  o.rtol = 1e-10;
  o.atol = 1e-12;
  VecX x = VecX::Zero(1);
  const OdeStats s = integrate_ode(pole(), x, o);
  EXPECT_FALSE(s.completed);
  EXPECT_NE(s.message, "");
  EXPECT_LT(s.t, 1.0);  // it never steps over the pole
  EXPECT_GT(s.t, 1.0 - 1e-6);
  EXPECT_NE(s.message.find("step size underflow"), std::string::npos) << s.message;
  // Until it stopped, the solution was followed: x = 1/(1 − t) − 1 (measured 2.5e-4 relative
  // at x = 4.4e10, where 1 − t is 2e-11).
  const double exact = 1.0 / (1.0 - s.t) - 1.0;
  EXPECT_GT(exact, 1e6);
  EXPECT_NEAR(x(0), exact, 1e-3 * exact);
  EXPECT_LT(s.steps, 100000);
}
// A smooth problem is not stopped: ẋ = x to t = 1 gives e.
TEST(Integrator, SmoothProblemCompletes) {
  OdeProblem p;
  p.rhs = [](const VecX& x, VecX& dx, double) { dx = x; };
  p.accept = [](double, VecX&) { return true; };
  p.output = [](double, const VecX&) {};
  OdeOptions o;
  o.rtol = 1e-12;
  o.atol = 1e-14;
  VecX x = VecX::Ones(1);
  const OdeStats s = integrate_ode(p, x, o);
  EXPECT_TRUE(s.completed) << s.message;
  EXPECT_NEAR(x(0), std::exp(1.0), 1e-10);
}

// A short run (t_end = 1e-9) completes with every stepper: its first step is not at the rounding
// level of t (it was 1e-6 of the span, 1e-15: "step size underflow at t = 0"). ẋ = x: e^(1e-9).
TEST(Integrator, AShortRunCompletesWithEveryStepper) {
  OdeProblem p;
  p.rhs = [](const VecX& x, VecX& dx, double) { dx = x; };
  p.accept = [](double, VecX&) { return true; };
  p.output = [](double, const VecX&) {};
  for (const OdeStepper stepper : {OdeStepper::dopri5, OdeStepper::rkf78,
                                   OdeStepper::bulirsch_stoer, OdeStepper::rosenbrock4}) {
    for (const double t_end : {1e-9, 1e-12}) {
      OdeOptions o;
      o.stepper = stepper;
      o.t_end = t_end;
      o.dt_out = t_end;
      o.rtol = 1e-10;
      o.atol = 1e-12;
      VecX x = VecX::Ones(1);
      const OdeStats s = integrate_ode(p, x, o);
      EXPECT_TRUE(s.completed) << static_cast<int>(stepper) << " t_end " << t_end << ": "
                               << s.message;
      EXPECT_NEAR(x(0), std::exp(t_end), 1e-15) << static_cast<int>(stepper);
    }
  }
}

}  // namespace
}  // namespace orthomech::detail
