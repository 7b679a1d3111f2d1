#pragma once
// Private adapter around Boost.Odeint (house style: public headers carry no odeint types; odeint
// costs ~4 s of compile time per translation unit, so it lives in integrator.cpp only).
//
// The integrators of simulate step manually so that the state can be corrected after every
// accepted step (position correction, chart switch): after `accept` changes x the stepper is
// re-initialised (its first-same-as-last derivative is recomputed).
#include <functional>
#include <string>

#include "orthomech/model/model.hpp"

namespace orthomech::detail {

enum class OdeStepper { dopri5, rkf78 };

struct OdeProblem {
  // dx/dt at (x, t).
  std::function<void(const VecX& x, VecX& dxdt, double t)> rhs;
  // Called after every accepted step with the new state; may modify x (projection, chart
  // switch). Returns false to stop the integration (its message is the caller's business).
  std::function<bool(double t, VecX& x)> accept;
  // Called at every output time t0 + k·dt_out ≤ t_end with the (interpolated) state. The state
  // at an output time that coincides with the end of a step is the corrected one.
  std::function<void(double t, const VecX& x)> output;
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
};

// Integrates from (t0, x) to t_end; x holds the final (corrected) state. Never throws for
// numerical trouble (odeint's step-size exceptions become a message).
OdeStats integrate_ode(const OdeProblem& problem, VecX& x, const OdeOptions& options);

}  // namespace orthomech::detail
