#pragma once
// Private adapter (house style: no NLopt type in a public header): bounded minimisation with
// NLopt's C interface. Every NLopt outcome is returned as data; an exception thrown by the
// objective never crosses NLopt: it is caught in the trampoline, stored, the run is stopped
// with nlopt_force_stop, and the outcome says `callback_error` (the caller may rethrow `error`).
#include <Eigen/Core>
#include <exception>
#include <functional>
#include <string>

namespace orthomech::solvers {

enum class NloptOutcomeKind {
  converged,        // NLOPT_SUCCESS, *_TOL_REACHED, STOPVAL_REACHED
  max_evaluations,  // NLOPT_MAXEVAL_REACHED / MAXTIME_REACHED: best point so far returned
  roundoff,         // NLOPT_ROUNDOFF_LIMITED: best point so far returned
  invalid,          // NLOPT_INVALID_ARGS (bad bounds, start outside, …)
  failed,           // NLOPT_FAILURE, NLOPT_OUT_OF_MEMORY
  callback_error,   // the objective threw (see `error`) or returned NaN
};

struct NloptOutcome {
  NloptOutcomeKind kind = NloptOutcomeKind::failed;
  int code = 0;  // nlopt_result
  std::string message;
  Eigen::VectorXd x;  // best point found (the start if none)
  double value = 0.0;
  int evaluations = 0;
  std::exception_ptr error;
};

struct NloptSettings {
  double xtol_abs = 1e-12;
  double ftol_abs = 0.0;
  int max_evaluations = 500;
};

// Minimises f over the box [lower, upper] from x0 with a derivative-free local method
// (NLOPT_LN_BOBYQA for n ≥ 2, NLOPT_LN_COBYLA for n = 1). Never throws (std::bad_alloc aside).
[[nodiscard]] NloptOutcome minimize_bounded(const std::function<double(const Eigen::VectorXd&)>& f,
                                            const Eigen::VectorXd& x0, const Eigen::VectorXd& lower,
                                            const Eigen::VectorXd& upper,
                                            const NloptSettings& settings = {});

[[nodiscard]] const char* to_string(NloptOutcomeKind k);

}  // namespace orthomech::solvers
