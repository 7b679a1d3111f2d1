// Boost.Odeint adapter (the only translation unit that includes odeint).
#include "integrator.hpp"

#include <algorithm>
#include <boost/numeric/odeint.hpp>
#include <boost/numeric/odeint/external/eigen/eigen.hpp>  // mandatory for Eigen states
#include <cmath>
#include <exception>
#include <limits>

namespace orthomech::detail {

namespace odeint = boost::numeric::odeint;

namespace {

// Output times t0 + k·dt_out, k = 0, 1, …, up to t_end (with a relative slack of 1e-12 so that
// t_end itself is an output time when it is a multiple of dt_out).
struct OutputClock {
  double t0, dt, t_end;
  long k = 0;
  [[nodiscard]] double next() const { return t0 + static_cast<double>(k) * dt; }
  [[nodiscard]] double slack() const { return 1e-12 * std::max(1.0, std::abs(t_end)); }
  [[nodiscard]] bool pending() const { return next() <= t_end + slack(); }
};

// Cubic Hermite interpolation between (t0, x0, f0) and (t1, x1, f1) (used for the outputs of
// the Fehlberg stepper, which has no dense output of its own).
void hermite(double t0, const VecX& x0, const VecX& f0, double t1, const VecX& x1, const VecX& f1,
             double t, VecX& x) {
  const double h = t1 - t0, s = (t - t0) / h;
  const double h00 = (1 + 2 * s) * (1 - s) * (1 - s), h10 = s * (1 - s) * (1 - s);
  const double h01 = s * s * (3 - 2 * s), h11 = s * s * (s - 1);
  x = h00 * x0 + h10 * h * f0 + h01 * x1 + h11 * h * f1;
}

// A step below 64 spacings of doubles at t cannot advance t (both steppers stop there).
bool step_underflow(double dt, double t) {
  return dt < 64.0 * std::numeric_limits<double>::epsilon() * std::max(1.0, std::abs(t));
}

double first_step(const OdeOptions& o) {
  const double span = o.t_end - o.t0;
  double dt = o.dt_init > 0.0 ? o.dt_init : 1e-6 * span;
  if (o.max_dt > 0.0) dt = std::min(dt, o.max_dt);
  return std::min(dt, span);
}

double clamp_step(double dt, double t, const OdeOptions& o) {
  if (o.max_dt > 0.0) dt = std::min(dt, o.max_dt);
  return std::min(dt, o.t_end - t);
}

OdeStats run_dopri5(const OdeProblem& p, VecX& x, const OdeOptions& o) {
  OdeStats stats;
  using Stepper = odeint::runge_kutta_dopri5<VecX>;
  auto dense = odeint::make_dense_output(o.atol, o.rtol, Stepper());
  auto system = [&p](const VecX& y, VecX& dy, double t) { p.rhs(y, dy, t); };
  OutputClock clock{o.t0, o.dt_out, o.t_end};
  double t = o.t0;
  VecX xo(x.size());
  if (clock.pending()) {
    p.output(t, x);
    ++clock.k;
  }
  dense.initialize(x, t, first_step(o));
  const double end_slack = 1e-14 * std::max(1.0, std::abs(o.t_end));
  while (t < o.t_end - end_slack) {
    if (stats.steps >= o.max_steps) {
      stats.message = "maximum number of steps reached";
      stats.t = t;
      return stats;
    }
    const auto [t_old, t_new] = dense.do_step(system);
    ++stats.steps;
    // A step size down at the rounding level of t (e.g. at a change point, where the right-hand
    // side is not smooth) cannot advance: stop with a message instead of stepping for ever.
    if (step_underflow(dense.current_time_step(), t_new)) {
      stats.message = "step size underflow at t = " + std::to_string(t_new) + " s (step " +
                      std::to_string(dense.current_time_step()) + " s)";
      x = dense.current_state();
      stats.t = t_new;
      return stats;
    }
    // Outputs strictly inside the step: dense output of Dormand–Prince (order 4).
    while (clock.pending() && clock.next() < t_new - clock.slack()) {
      dense.calc_state(clock.next(), xo);
      p.output(clock.next(), xo);
      ++clock.k;
    }
    (void)t_old;
    x = dense.current_state();
    t = t_new;
    if (!p.accept(t, x)) {
      stats.t = t;
      return stats;
    }
    if (clock.pending() && clock.next() <= t + clock.slack()) {  // output at the step's end
      p.output(clock.next(), x);
      ++clock.k;
    }
    // The state was corrected: restart the stepper there (the FSAL derivative is recomputed).
    dense.initialize(x, t, clamp_step(dense.current_time_step(), t, o));
  }
  stats.completed = true;
  stats.t = t;
  return stats;
}

OdeStats run_rkf78(const OdeProblem& p, VecX& x, const OdeOptions& o) {
  OdeStats stats;
  using Stepper = odeint::runge_kutta_fehlberg78<VecX>;
  auto controlled = odeint::make_controlled(o.atol, o.rtol, Stepper());
  auto system = [&p](const VecX& y, VecX& dy, double t) { p.rhs(y, dy, t); };
  OutputClock clock{o.t0, o.dt_out, o.t_end};
  double t = o.t0;
  double dt = first_step(o);
  VecX x_old(x.size()), f_old(x.size()), f_new(x.size()), xo(x.size());
  if (clock.pending()) {
    p.output(t, x);
    ++clock.k;
  }
  const double end_slack = 1e-14 * std::max(1.0, std::abs(o.t_end));
  int failures = 0;
  while (t < o.t_end - end_slack) {
    if (stats.steps >= o.max_steps) {
      stats.message = "maximum number of steps reached";
      stats.t = t;
      return stats;
    }
    x_old = x;
    const double t_old = t;
    dt = clamp_step(dt, t, o);
    if (controlled.try_step(system, x, t, dt) == odeint::fail) {
      if (++failures > 500 || step_underflow(dt, t)) {
        stats.message = "step size underflow at t = " + std::to_string(t);
        stats.t = t;
        return stats;
      }
      continue;
    }
    failures = 0;
    ++stats.steps;
    // Outputs strictly inside the step: cubic Hermite from the end points (before correction).
    if (clock.pending() && clock.next() < t - clock.slack()) {
      p.rhs(x_old, f_old, t_old);
      p.rhs(x, f_new, t);
      while (clock.pending() && clock.next() < t - clock.slack()) {
        hermite(t_old, x_old, f_old, t, x, f_new, clock.next(), xo);
        p.output(clock.next(), xo);
        ++clock.k;
      }
    }
    if (!p.accept(t, x)) {
      stats.t = t;
      return stats;
    }
    if (clock.pending() && clock.next() <= t + clock.slack()) {
      p.output(clock.next(), x);
      ++clock.k;
    }
  }
  stats.completed = true;
  stats.t = t;
  return stats;
}

}  // namespace

OdeStats integrate_ode(const OdeProblem& problem, VecX& x, const OdeOptions& options) {
  try {
    return options.stepper == OdeStepper::dopri5 ? run_dopri5(problem, x, options)
                                                 : run_rkf78(problem, x, options);
  } catch (const odeint::odeint_error& e) {  // step-size control gave up
    OdeStats stats;
    stats.message = std::string("step size control failed: ") + e.what();
    return stats;
  }
}

}  // namespace orthomech::detail
