#pragma once
// Private adapter (house style: no NLopt type in a public header): bounded minimisation with
// NLopt's C interface. Every NLopt outcome is returned as data; an exception thrown by the
// objective never crosses NLopt: it is caught in the trampoline, stored, the run is stopped
// with nlopt_force_stop, and the outcome says `callback_error` (the caller may rethrow `error`).
#include <Eigen/Core>
#include <exception>
#include <functional>
#include <string>
#include <vector>

#include "orthomech/process_share.hpp"

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

// Global search by multistart (issue 50): the local method of minimize_bounded from each of the
// starts `extra_starts` (first, in order) and then `starts` quasi-random points of the box
// (quasi_random_starts). Deterministic for a given seed. Stops at the first callback error
// (that outcome is then `best`). Never throws (std::bad_alloc aside).
//
// On several threads (`threads` ≠ 1, OpenMP; 0: every core) the runs are shared out among them,
// each thread with its own objective from the factory (its own scratch), and the outcome is
// assembled in start order as on one thread: the same `best` (the lowest value, the first start
// on a tie), `locals` and `evaluations` for any thread count. The runs after a callback error are
// computed and dropped.
struct MultistartSettings {
  int starts = 64;
  unsigned long long seed = 1;
  NloptSettings local;
  std::vector<Eigen::VectorXd> extra_starts;
  int threads = 1;
  // Processes (MPI ranks) sharing the runs: each runs its own, then every outcome is gathered
  // (code, kind, value, evaluations and x; a message or a callback's exception stays on its
  // process: another process sees a callback_error as "failed on process r").
  ProcessShare share;
};
using Objective = std::function<double(const Eigen::VectorXd&)>;
using ObjectiveFactory = std::function<Objective()>;

struct MultistartOutcome {
  NloptOutcome best;                 // the lowest value over the runs
  std::vector<NloptOutcome> locals;  // one per run, in start order
  int evaluations = 0;               // over all runs
};

[[nodiscard]] MultistartOutcome minimize_multistart(const ObjectiveFactory& make,
                                                    const Eigen::VectorXd& lower,
                                                    const Eigen::VectorXd& upper,
                                                    const MultistartSettings& settings = {});
// One objective shared by every run: on one thread whatever `threads` says.
[[nodiscard]] MultistartOutcome minimize_multistart(const Objective& f,
                                                    const Eigen::VectorXd& lower,
                                                    const Eigen::VectorXd& upper,
                                                    const MultistartSettings& settings = {});

// `count` points of the box [lower, upper] (columns): the Halton sequence (bases the first
// primes, dimension ≤ 40), shifted modulo 1 by a vector drawn from std::mt19937_64(seed)
// (a Cranley–Patterson rotation), mapped affinely onto the box.
[[nodiscard]] Eigen::MatrixXd quasi_random_starts(const Eigen::VectorXd& lower,
                                                  const Eigen::VectorXd& upper, int count,
                                                  unsigned long long seed);

[[nodiscard]] const char* to_string(NloptOutcomeKind k);
// Fills `out` from a finished run: the nlopt_result `code`, NLopt's final point x and `value`
// (kept when finite), the evaluations, and — before the code — an exception the `what`
// ("objective") threw or a NaN it returned (callback_error).
void finish_outcome(int code, double value, const std::vector<double>& x, int evaluations,
                    const std::exception_ptr& error, bool nan, const char* what, NloptOutcome& out);

}  // namespace orthomech::solvers
