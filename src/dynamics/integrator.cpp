// Boost.Odeint adapter (the only translation unit that includes odeint).
#include "integrator.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <boost/numeric/odeint.hpp>
#include <boost/numeric/odeint/external/eigen/eigen.hpp>  // mandatory for Eigen states
#include <cmath>
#include <exception>
#include <limits>

namespace orthomech::detail {

namespace odeint = boost::numeric::odeint;

namespace {

constexpr double kBulirschStoerMargin = 0.1;  // NOTE(BS tolerance) below

// Output times t0 + k·dt_out, k = 0, 1, …, up to t_end (with a relative slack of 1e-12 so that
// t_end itself is an output time when it is a multiple of dt_out).
struct OutputClock {
  double t0, dt, t_end;
  long k = 0;
  [[nodiscard]] double next() const { return t0 + static_cast<double>(k) * dt; }
  [[nodiscard]] double slack() const { return 1e-12 * std::max(1.0, std::abs(t_end)); }
  [[nodiscard]] bool pending() const { return next() <= t_end + slack(); }
};

// A step below 64 spacings of doubles at t cannot advance t (every stepper stops there).
bool step_underflow(double dt, double t) {
  return dt < 64.0 * std::numeric_limits<double>::epsilon() * std::max(1.0, std::abs(t));
}

std::string underflow_message(double t, double dt) {
  return "step size underflow at t = " + std::to_string(t) + " s (step " + std::to_string(dt) +
         " s)";
}

double first_step(const OdeOptions& o) {
  const double span = o.t_end - o.t0;
  double dt = o.dt_init > 0.0 ? o.dt_init : 1e-6 * span;
  // Not at the rounding level of t (step_underflow): 1e-6 of a short run's span is (t_end = 1e-9
  // stopped at its first step with "step size underflow at t = 0").
  const double t_scale = std::max({1.0, std::abs(o.t0), std::abs(o.t_end)});
  dt = std::max(dt, 1024.0 * std::numeric_limits<double>::epsilon() * t_scale);
  if (o.max_dt > 0.0) dt = std::min(dt, o.max_dt);
  return std::min(dt, span);
}

double clamp_step(double dt, double t, const OdeOptions& o) {
  if (o.max_dt > 0.0) dt = std::min(dt, o.max_dt);
  return std::min(dt, o.t_end - t);
}

// ---- Steppers with dense output (dopri5, Bulirsch–Stoer) ------------------------------------
// Outputs strictly inside a step come from the stepper's interpolant; an output at a step's end
// is the corrected state. The stepper restarts after every acceptance (the state may have been
// corrected), with the step size it proposed, clamped to t_end.
template <class Dense>
OdeStats run_dense(const OdeProblem& p, VecX& x, const OdeOptions& o, Dense dense) {
  OdeStats stats;
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
    (void)t_old;
    ++stats.steps;
    // A step size down at the rounding level of t (e.g. at a change point, where the right-hand
    // side is not smooth) cannot advance: stop with a message instead of stepping for ever.
    if (step_underflow(dense.current_time_step(), t_new)) {
      stats.message = underflow_message(t_new, dense.current_time_step());
      x = dense.current_state();
      stats.t = t_new;
      return stats;
    }
    // Outputs strictly inside the step: the stepper's dense output.
    while (clock.pending() && clock.next() < t_new - clock.slack()) {
      dense.calc_state(clock.next(), xo);
      p.output(clock.next(), xo);
      ++clock.k;
    }
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
    // The state was corrected: restart the stepper there (its derivative is recomputed), with
    // its proposed step within the problem's limit.
    const double limit = p.step_limit ? p.step_limit() : dense.current_time_step();
    dense.initialize(x, t, clamp_step(std::min(dense.current_time_step(), limit), t, o));
  }
  stats.completed = true;
  stats.t = t;
  return stats;
}

// ---- Controlled steppers without a dense output of their order (rkf78, rosenbrock4) ---------
// Every step is shortened, if need be, to end on the next output time (or t_end): outputs are
// step ends, at the integrator's full accuracy (issue 10, item 5). A step that the output time
// shortened does not shrink the next one: the controller's proposal from before is kept when it
// was larger. `try_step(x, t, dt)` is odeint's controlled-stepper contract: on success it
// advances x and t and proposes the next dt; on failure it leaves x and t and shrinks dt.
template <class TryStep>
OdeStats run_controlled(const OdeProblem& p, VecX& x, const OdeOptions& o, TryStep&& try_step) {
  OdeStats stats;
  OutputClock clock{o.t0, o.dt_out, o.t_end};
  double t = o.t0;
  double dt = first_step(o);
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
    // 1. The step: the controller's proposal, shortened (or stretched by at most 1 %, so as not
    //    to leave a sliver) to end on the next output time or t_end.
    const double target = clock.pending() ? std::min(clock.next(), o.t_end) : o.t_end;
    const double proposed = clamp_step(dt, t, o);
    double h = proposed;
    const bool lands = target - t <= 1.01 * h;
    if (lands) h = target - t;
    double t_try = t;
    if (!try_step(x, t_try, h)) {
      ++stats.rejected;
      if (++failures > 500 || step_underflow(h, t)) {
        stats.message = underflow_message(t, h);
        stats.t = t;
        return stats;
      }
      dt = h;
      continue;
    }
    failures = 0;
    ++stats.steps;
    // 2. The step ended on the target exactly (not t + h in floating point); the next step
    //    starts from the larger of the new proposal and the one the landing cut short.
    t = lands ? target : t_try;
    dt = lands ? std::max(h, proposed) : h;
    if (!p.accept(t, x)) {
      stats.t = t;
      return stats;
    }
    if (p.step_limit) dt = std::min(dt, p.step_limit());
    if (clock.pending() && clock.next() <= t + clock.slack()) {
      p.output(clock.next(), x);
      ++clock.k;
    }
  }
  stats.completed = true;
  stats.t = t;
  return stats;
}

OdeStats run_rkf78(const OdeProblem& p, VecX& x, const OdeOptions& o) {
  auto controlled = odeint::make_controlled(o.atol, o.rtol, odeint::runge_kutta_fehlberg78<VecX>());
  auto system = [&p](const VecX& y, VecX& dy, double t) { p.rhs(y, dy, t); };
  return run_controlled(p, x, o, [&](VecX& y, double& t, double& dt) {
    return controlled.try_step(system, y, t, dt) == odeint::success;
  });
}

// ---- Rosenbrock 4(3): RODAS4 ---------------------------------------------------------------
// The L-stable, stiffly accurate Rosenbrock method RODAS of order 4 with an embedded order-3
// error estimate, in the transformed form without products J·g in the stages
// [Hairer & Wanner 1996, Solving ODEs II, §IV.7 and their code rodas.f]. The
// coefficients (but d4, below) and the stage algorithm are those of Boost.Odeint's rosenbrock4
// (default_rosenbrock_coefficients); it is written here on Eigen because odeint's stiff steppers
// keep their state in uBLAS vectors, and Boost 1.74's uBLAS storage does not compile as C++20
// (it calls std::allocator::construct, removed in C++20).
//   W = I/(γ h) − J,  W g_i = f(t + c_i h, x + Σ_j a_ij g_j) + h d_i f_t + Σ_j c_ij g_j / h,
//   x_new = x + Σ_j a_5j g_j + g_5 + g_6 (stiffly accurate); error estimate g_6.
// f_t (the d_i terms) is differenced unless the problem says it is autonomous (simulate: every
// model but a general system, whose forces may depend on t); the order is tested on a
// non-autonomous problem.
struct Rodas4 {
  static constexpr double gamma = 0.25;
  // NOTE(RODAS d4): Boost 1.74's default_rosenbrock_coefficients has d4 = +0.0362; rodas.f has
  // D4 = −0.0362…, and only that sign gives order 4 on a non-autonomous problem (order 1 with
  // +0.0362: tests/unit/dynamics/integrator_rosenbrock_test.cpp,
  // Rosenbrock4.OrderFour_NonAutonomous).
  static constexpr double d1 = 0.25, d2 = -0.1043, d3 = 0.1035, d4 = -0.3620000000000023e-01;
  static constexpr double c2 = 0.386, c3 = 0.21, c4 = 0.63;
  static constexpr double c21 = -0.5668800000000000e+01, a21 = 0.1544000000000000e+01;
  static constexpr double c31 = -0.2430093356833875e+01, c32 = -0.2063599157091915e+00;
  static constexpr double a31 = 0.9466785280815826e+00, a32 = 0.2557011698983284e+00;
  static constexpr double c41 = -0.1073529058151375e+00, c42 = -0.9594562251023355e+01,
                          c43 = -0.2047028614809616e+02;
  static constexpr double a41 = 0.3314825187068521e+01, a42 = 0.2896124015972201e+01,
                          a43 = 0.9986419139977817e+00;
  static constexpr double c51 = 0.7496443313967647e+01, c52 = -0.1024680431464352e+02,
                          c53 = -0.3399990352819905e+02, c54 = 0.1170890893206160e+02;
  static constexpr double a51 = 0.1221224509226641e+01, a52 = 0.6019134481288629e+01,
                          a53 = 0.1253708332932087e+02, a54 = -0.6878860361058950e+00;
  static constexpr double c61 = 0.8083246795921522e+01, c62 = -0.7981132988064893e+01,
                          c63 = -0.3152159432874371e+02, c64 = 0.1631930543123136e+02,
                          c65 = -0.6058818238834054e+01;
};

class Rosenbrock4 {
 public:
  Rosenbrock4(const OdeProblem& p, Eigen::Index n, double atol, double rtol, OdeStats& counts)
      : p_(p),
        atol_(atol),
        rtol_(rtol),
        counts_(counts),
        J_(n, n),
        W_(n, n),
        lu_(n),
        f0_(n),
        ft_(n),
        fs_(n),
        xs_(n),
        xnew_(n),
        err_(n),
        b_(n),
        g1_(n),
        g2_(n),
        g3_(n),
        g4_(n),
        g5_(n) {}

  // odeint's controlled-stepper contract (see run_controlled). Step-size control of
  // [Hairer & Wanner 1996, §IV.8 (8.21)] (predictive, Gustafsson), as odeint's
  // rosenbrock4_controller: fac = clamp(err^¼ / 0.9, 1/6, 5), h_new = h / fac.
  bool try_step(VecX& x, double& t, double& dt) {
    step(x, t, dt);
    const double err = error_norm(x);
    constexpr double safe = 0.9, fac_max = 5.0, fac_min = 1.0 / 6.0;
    double fac = std::clamp(std::pow(err, 0.25) / safe, fac_min, fac_max);
    double dt_new = dt / fac;
    if (!(err <= 1.0)) {  // rejected (also a NaN error)
      dt = dt_new;
      last_rejected_ = true;
      return false;
    }
    if (!first_step_) {
      const double fac_pred = std::clamp(
          (dt_old_ / dt) * std::pow(err * err / err_old_, 0.25) / safe, fac_min, fac_max);
      fac = std::max(fac, fac_pred);
      dt_new = dt / fac;
    }
    first_step_ = false;
    dt_old_ = dt;
    err_old_ = std::max(0.01, err);
    if (last_rejected_) dt_new = std::min(dt_new, dt);
    last_rejected_ = false;
    t += dt;
    x = xnew_;
    dt = dt_new;
    return true;
  }

 private:
  // One step of size h from (t, x) into xnew_, error estimate into err_.
  void step(const VecX& x, double t, double h) {
    using C = Rodas4;
    p_.rhs(x, f0_, t);
    fd_.compute(p_, x, t, J_, ft_);
    ++counts_.jacobians;
    factor_W(1.0 / (C::gamma * h));
    // Each right-hand side is formed in b_ first: solving an expression would allocate.
    b_ = f0_ + h * C::d1 * ft_;
    solve_W(g1_);
    xs_ = x + C::a21 * g1_;
    p_.rhs(xs_, fs_, t + C::c2 * h);
    b_ = fs_ + h * C::d2 * ft_ + C::c21 / h * g1_;
    solve_W(g2_);
    xs_ = x + C::a31 * g1_ + C::a32 * g2_;
    p_.rhs(xs_, fs_, t + C::c3 * h);
    b_ = fs_ + h * C::d3 * ft_ + (C::c31 / h) * g1_ + (C::c32 / h) * g2_;
    solve_W(g3_);
    xs_ = x + C::a41 * g1_ + C::a42 * g2_ + C::a43 * g3_;
    p_.rhs(xs_, fs_, t + C::c4 * h);
    b_ = fs_ + h * C::d4 * ft_ + (C::c41 / h) * g1_ + (C::c42 / h) * g2_ + (C::c43 / h) * g3_;
    solve_W(g4_);
    xs_ = x + C::a51 * g1_ + C::a52 * g2_ + C::a53 * g3_ + C::a54 * g4_;
    p_.rhs(xs_, fs_, t + h);
    b_ = fs_ + (C::c51 / h) * g1_ + (C::c52 / h) * g2_ + (C::c53 / h) * g3_ + (C::c54 / h) * g4_;
    solve_W(g5_);
    xs_ += g5_;
    p_.rhs(xs_, fs_, t + h);
    b_ = fs_ + (C::c61 / h) * g1_ + (C::c62 / h) * g2_ + (C::c63 / h) * g3_ + (C::c64 / h) * g4_ +
         (C::c65 / h) * g5_;
    solve_W(err_);
    xnew_ = xs_ + err_;
  }
  // W = α I − J, α = 1/(γ h). With few non-zero columns C of J (problem.jacobian_columns,
  // m = |C| < n/2), J = U Sᵀ with U = J_C (n × m) and S the columns of I at C, and by the
  // Sherman–Morrison–Woodbury identity W⁻¹ = (I + U K⁻¹ Sᵀ)/α with K = α I_m − Sᵀ U (m × m):
  // O(n m) per solve instead of an n × n LU per step (n = 125, m = 2 on the N = 40 four-bar).
  void factor_W(double alpha) {
    alpha_ = alpha;
    const auto& cols = fd_.columns;
    const auto m = static_cast<Eigen::Index>(cols.size());
    low_rank_ = p_.jacobian_columns && 2 * m < J_.rows();
    if (!low_rank_) {
      W_ = -J_;
      W_.diagonal().array() += alpha;
      lu_.compute(W_);
      return;
    }
    U_.resize(J_.rows(), m);
    K_.resize(m, m);
    for (Eigen::Index k = 0; k < m; ++k) U_.col(k) = J_.col(cols[static_cast<size_t>(k)]);
    for (Eigen::Index i = 0; i < m; ++i)
      for (Eigen::Index k = 0; k < m; ++k)
        K_(i, k) = (i == k ? alpha : 0.0) - U_(cols[static_cast<size_t>(i)], k);
    klu_.compute(K_);
  }
  // g = W⁻¹ b_ (b_ holds the stage's right-hand side).
  void solve_W(VecX& g) {
    if (!low_rank_) {
      g = lu_.solve(b_);
      return;
    }
    const auto& cols = fd_.columns;
    bc_.resize(static_cast<Eigen::Index>(cols.size()));
    for (Eigen::Index i = 0; i < bc_.size(); ++i) bc_(i) = b_(cols[static_cast<size_t>(i)]);
    yc_ = klu_.solve(bc_);
    g = b_;
    g.noalias() += U_ * yc_;
    g /= alpha_;
  }

  // Largest |err_i| / (atol + rtol·max(|x_i|, |x_new,i|)): the max norm of odeint's Runge–Kutta
  // controllers, so that a tolerance means the same for every integrator. (odeint's
  // rosenbrock4_controller takes the RMS over the components; with simulate's ~125 coordinates of
  // the N = 40 four-bar, of which a few move independently, that let B0 end 4.9e-5 off at rtol
  // 1e-8, the max norm 8e-6 — issue 10.)
  double error_norm(const VecX& x) const {
    double worst = 0.0;
    for (Eigen::Index i = 0; i < x.size(); ++i) {
      const double sk = atol_ + rtol_ * std::max(std::abs(x(i)), std::abs(xnew_(i)));
      worst = std::max(worst, std::abs(err_(i)) / sk);
    }
    return worst;
  }

  const OdeProblem& p_;
  double atol_, rtol_;
  OdeStats& counts_;
  FiniteDifferenceJacobian fd_;
  MatX J_, W_;
  Eigen::PartialPivLU<MatX> lu_;
  bool low_rank_ = false;  // W solved by the Woodbury identity (factor_W)
  double alpha_ = 0.0;
  MatX U_, K_;
  Eigen::PartialPivLU<MatX> klu_;
  VecX bc_, yc_;
  VecX f0_, ft_, fs_, xs_, xnew_, err_, b_, g1_, g2_, g3_, g4_, g5_;
  bool first_step_ = true, last_rejected_ = false;
  double dt_old_ = 0.0, err_old_ = 1.0;
};

OdeStats run_rosenbrock4(const OdeProblem& p, VecX& x, const OdeOptions& o, OdeStats& counts) {
  Rosenbrock4 stepper(p, x.size(), o.atol, o.rtol, counts);
  return run_controlled(p, x, o,
                        [&](VecX& y, double& t, double& dt) { return stepper.try_step(y, t, dt); });
}

}  // namespace

void FiniteDifferenceJacobian::compute(const OdeProblem& problem, const VecX& x, double t, MatX& J,
                                       VecX& dfdt) {
  const Eigen::Index n = x.size();
  const double cbrt_eps = std::cbrt(std::numeric_limits<double>::epsilon());
  J.resize(n, n);
  dfdt.resize(n);
  xp = x;
  // ∂f/∂x_j into `out` by the fourth-order central stencil (integrator.hpp).
  const auto difference_column = [&](Eigen::Index j, auto&& out) {
    const double h = cbrt_eps * std::max(1.0, std::abs(x(j)));
    xp(j) = x(j) + h;
    problem.rhs(xp, fp, t);
    xp(j) = x(j) - h;
    problem.rhs(xp, fm, t);
    out = (8.0 / (12.0 * h)) * (fp - fm);
    xp(j) = x(j) + 2.0 * h;
    problem.rhs(xp, fp, t);
    xp(j) = x(j) - 2.0 * h;
    problem.rhs(xp, fm, t);
    xp(j) = x(j);
    out -= (1.0 / (12.0 * h)) * (fp - fm);
  };
  if (problem.jacobian_columns) {
    // Zero outside the differenced columns. Clearing all of J at each call (n = 243 on the
    // primal N = 40 four-bar: 472 KB) took 18 % of a rosenbrock4 run; the J this object filled
    // last is zero but for that call's columns, which are cleared instead.
    if (J.data() == cleared_ && n == cleared_size_) {
      for (const Eigen::Index j : columns) J.col(j).setZero();
    } else {
      J.setZero();
    }
    problem.jacobian_columns(columns);
    for (const Eigen::Index j : columns) difference_column(j, J.col(j));
    cleared_ = J.data();
    cleared_size_ = n;
  } else {
    for (Eigen::Index j = 0; j < n; ++j) difference_column(j, J.col(j));
    cleared_ = nullptr;
  }
  if (problem.autonomous) {
    dfdt.setZero();
    return;
  }
  const double ht = cbrt_eps * std::max(1.0, std::abs(t));  // ∂f/∂t by the same stencil
  problem.rhs(x, fp, t + ht);
  problem.rhs(x, fm, t - ht);
  dfdt = (8.0 / (12.0 * ht)) * (fp - fm);
  problem.rhs(x, fp, t + 2.0 * ht);
  problem.rhs(x, fm, t - 2.0 * ht);
  dfdt -= (1.0 / (12.0 * ht)) * (fp - fm);
}

OdeStats integrate_ode(const OdeProblem& problem, VecX& x, const OdeOptions& options) {
  OdeStats counts;
  try {
    OdeStats stats;
    switch (options.stepper) {
      case OdeStepper::dopri5:
        stats = run_dense(problem, x, options,
                          odeint::make_dense_output(options.atol, options.rtol,
                                                    odeint::runge_kutta_dopri5<VecX>()));
        break;
      case OdeStepper::rkf78:
        stats = run_rkf78(problem, x, options);
        break;
      case OdeStepper::bulirsch_stoer:
        // NOTE(BS tolerance): odeint's Bulirsch–Stoer is given atol/10 and rtol/10. simulate
        // corrects the state after every step, so the stepper restarts at every step, and a
        // restarted step is accepted at the first extrapolation level whose error estimate
        // passes, down to the coarsest (2 and 6 midpoint substeps), whose estimate is not yet
        // asymptotic: on the N = 40 bar at rtol 1e-8 single such steps lost 2e-7 of the energy
        // and B0 ended 4e-5 off at 20 s (dopri5 8e-6); with the margin 2.6e-6 (docs/theory.md).
        // The margin stops at 1e-15 relative (rounding): a requested rtol ≤ 1e-15 is kept.
        stats = run_dense(
            problem, x, options,
            odeint::bulirsch_stoer_dense_out<VecX>(
                kBulirschStoerMargin * options.atol,
                std::max(kBulirschStoerMargin * options.rtol, std::min(options.rtol, 1e-15)), 1.0,
                1.0, options.max_dt));
        break;
      case OdeStepper::rosenbrock4:
        stats = run_rosenbrock4(problem, x, options, counts);
        break;
    }
    stats.jacobians = counts.jacobians;
    return stats;
  } catch (const odeint::odeint_error& e) {  // step-size control gave up
    OdeStats stats;
    stats.message = std::string("step size control failed: ") + e.what();
    stats.jacobians = counts.jacobians;
    return stats;
  }
}

}  // namespace orthomech::detail
