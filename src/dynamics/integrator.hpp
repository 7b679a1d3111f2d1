#pragma once
// Private adapter around Boost.Odeint (house style: public headers carry no odeint types; odeint
// costs ~4 s of compile time per translation unit, so it lives in integrator.cpp only).
//
// The integrators of simulate step manually so that the state can be corrected after every
// accepted step (position correction, chart switch): after `accept` changes x the stepper is
// re-initialised (its first-same-as-last derivative is recomputed).
//
// Output times (issue 10, item 5): every output is at the integrator's own accuracy.
//   - dopri5, bulirsch_stoer: the stepper's dense output between step ends (Dormand–Prince's
//     continuous extension of order 4 [Hairer, Nørsett, Wanner I, §II.6]; the Bulirsch–Stoer
//     extrapolation's Hermite interpolation of order 2k + 1 with its own error check
//     [Hairer, Nørsett, Wanner I, §II.9]).
//   - rkf78, rosenbrock4 (no dense output of their order): the step is shortened to land on the
//     next output time, so every output is a step end (corrected like any other step end).
#include <functional>
#include <string>
#include <vector>

#include "orthomech/model/model.hpp"

namespace orthomech::detail {

enum class OdeStepper {
  dopri5,          // Dormand–Prince 5(4), dense output
  rkf78,           // Runge–Kutta–Fehlberg 7(8), lands on the output times
  bulirsch_stoer,  // Bulirsch–Stoer extrapolation (orders up to 16), dense output
  rosenbrock4,     // Rosenbrock 4(3), L-stable (stiff), Jacobian by central differences
};

struct OdeProblem {
  // dx/dt at (x, t).
  std::function<void(const VecX& x, VecX& dxdt, double t)> rhs;
  // Called after every accepted step with the new state; may modify x (projection, chart
  // switch). Returns false to stop the integration (its message is the caller's business).
  std::function<bool(double t, VecX& x)> accept;
  // Called at every output time t0 + k·dt_out ≤ t_end with the (interpolated) state. The state
  // at an output time that coincides with the end of a step is the corrected one.
  std::function<void(double t, const VecX& x)> output;
  // Optional: after every accepted step, the longest next step the problem allows (+∞ for no
  // limit); e.g. simulate's chart monitor ahead of a chart's singularity.
  std::function<double()> step_limit;
  // Optional (rosenbrock4): the columns of ∂f/∂x that can be non-zero; the Jacobian's other
  // columns are exactly zero and are not differenced. Asked before every Jacobian, so it may
  // change between steps (simulate's projected stages: the chart's independent coordinates and
  // the velocity coordinates; the chart can switch at a step end). Empty function: every column.
  std::function<void(std::vector<Eigen::Index>& columns)> jacobian_columns;
  // f does not depend on t: ∂f/∂t is zero and is not differenced (rosenbrock4).
  bool autonomous = false;
};

struct OdeOptions {
  OdeStepper stepper = OdeStepper::dopri5;
  double rtol = 1e-8, atol = 1e-10;
  double t0 = 0.0, t_end = 1.0;
  double dt_out = 0.01;  // > 0
  double dt_init = 0.0;  // 0: chosen from the time span
  double max_dt = 0.0;   // 0: unlimited
  long max_steps = 100'000'000;
};

struct OdeStats {
  bool completed = false;
  std::string message;  // why it stopped early
  double t = 0.0;       // time reached
  long steps = 0;       // accepted steps
  long rejected = 0;    // rejected step attempts (controlled steppers; 0 for the dense ones)
  long jacobians = 0;   // Jacobians evaluated (rosenbrock4)
};

// Integrates from (t0, x) to t_end; x holds the final (corrected) state. Never throws for
// numerical trouble (odeint's step-size exceptions become a message).
OdeStats integrate_ode(const OdeProblem& problem, VecX& x, const OdeOptions& options);

// Jacobian ∂f/∂x and ∂f/∂t of problem.rhs at (x, t) by the fourth-order central stencil
//   ∂f/∂x_j ≈ [8 (f(x + h e_j) − f(x − h e_j)) − (f(x + 2h e_j) − f(x − 2h e_j))] / (12 h),
// step h_j = ∛ε · max(1, |x_j|): truncation h⁴ |f⁽⁵⁾|/30, rounding ~1.5 ε|f|/h [Fornberg 1988,
// Math. Comp. 51, table 1]. With the two-point central difference (truncation h²|f'''|/6) the
// Jacobian limited rosenbrock4's accuracy: h grows with |x_j| (positions up to 40 m from the
// origin on the N = 40 four-bar: h up to 2.4e-4) and next to a change point the chart's ODE
// bends sharply, and a Rosenbrock method's order assumes the exact Jacobian. Measured on that bar
// at rtol 1e-10 with steps ≤ 1e-3 s: the energy drifted ~4e-5 J/s as a change point neared and
// B0 ended 1.5e-6 off at 20 s; with this stencil the drift is gone and B0 ends 2.7e-8 off
// (2.5e-8 … 7.1e-7 over five variants of the output grid and atol; docs/theory.md, "Change
// points" and "Rosenbrock on the chart's ODE"). Costs 4·(dim x + 1) evaluations of f.
// Buffers are the caller's (no allocation after the first call with a given size). With
// problem.jacobian_columns, only the columns it names are differenced (4 evaluations each); the
// others are set to zero (when J is the matrix the last call filled, of the same size, only that
// call's columns are cleared: the caller must not write J between calls).
struct FiniteDifferenceJacobian {
  VecX xp, fp, fm;
  std::vector<Eigen::Index> columns;
  void compute(const OdeProblem& problem, const VecX& x, double t, MatX& J, VecX& dfdt);

 private:
  // The storage and size of the J that the last call with jacobian_columns left zero outside
  // `columns`.
  const double* cleared_ = nullptr;
  Eigen::Index cleared_size_ = 0;
};

}  // namespace orthomech::detail
