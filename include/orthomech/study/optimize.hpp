#pragma once
// Design optimisation (issue 51 item 2; docs/cli.md "optimize"): a `study: optimize` file's
// bounded design variables (any `--set` path or parameter), one objective and inequality and
// equality constraints, each an expression of the variant's metric columns
// (study/measure_metrics.hpp), searched by NLopt — COBYLA (local, derivative-free; the default)
// or ISRES (global, seeded). Each evaluation is a variant of the study (evaluate_variant): a
// variant that is not valid, does not assemble, stops at a dead point or has no value of a
// metric the goal uses is infeasible — never the end of the run.
//
// The search runs in the unit box (x_j = (v_j − lower_j) / (upper_j − lower_j)); a constraint
// g(v) ≥ b becomes (b − g) / s ≤ 0 with s = max(|b|, 1), g ≤ b becomes (g − b) / s ≤ 0 and
// |g − b| ≤ t the two of them with b ± t; an infeasible variant gets every constraint value 1
// and the worst objective seen so far. The result is the best feasible evaluation: constraints
// met within kOptimizeFeasibility × s.
#include <functional>
#include <string>
#include <vector>

#include "orthomech/study/study.hpp"

namespace orthomech {

inline constexpr double kOptimizeFeasibility = 1e-6;

// One evaluation as the search saw it.
struct OptimizeStep {
  long evaluation = 0;     // 0-based, in the order the optimiser asked
  bool feasible = false;   // completed, every goal column a number, every constraint met
  double objective = 0.0;  // the objective column (NaN: none)
  double violation = 0.0;  // the largest scaled constraint value above 0 (0: met; 1: infeasible)
  long best = -1;          // the best feasible evaluation so far (−1: none yet)
  double best_objective = 0.0;
  bool replayed = false;  // taken from `stored` (run_optimize), not computed again
};

struct OptimizeResult {
  bool found = false;   // a feasible evaluation was found
  VariantResult best;   // … the best one (its values are the optimal design variables)
  std::string outcome;  // how the search ended: converged, evaluation limit, stopped, …
  std::string message;
  long evaluations = 0;
  std::vector<OptimizeStep> steps;
};

// Runs the search, calling `done` with each evaluated variant and its step as it finishes (the
// caller stores it: a database row, progress), and `stop` before each evaluation that is
// computed (true: end the search there, outcome "stopped"). Never throws for a bad variant.
//
// Resuming (`optimize --resume`): `stored` are the evaluations of an earlier run of the same
// study, in order. The search is deterministic (COBYLA has no randomness, ISRES draws from its
// seed) and a stored evaluation gives it the same numbers as computing it again (the database
// holds the doubles exactly), so it asks for the same points: evaluation k < stored.size() is
// taken from stored[k] (its step `replayed`), the search going on from there exactly as one
// uninterrupted run. Throws std::invalid_argument when the search asks for other values than a
// stored evaluation's (the stored evaluations are not this search's).
//
// Multistart (`algorithm: multistart`): `starts` COBYLA searches, search s from the start (s = 0)
// or from a point of the unit box drawn from its own stream (Boost.Random mt19937_64 seeded from
// the study's seed and s), each with the budget `evaluations`, on `jobs` OpenMP threads (0: every
// core). Search s numbers its evaluations from s × evaluations, so the evaluations, the steps
// (in evaluation order, the best so far over every search before it in that order) and the result
// (the best feasible objective, the lowest evaluation on a tie) are the same for any number of
// threads; `done` and `stop` are called one at a time. `stored` then holds each search's stored
// evaluations at their numbers (in evaluation order).
[[nodiscard]] OptimizeResult run_optimize(
    const std::string& mechanism, const std::string& origin, const Study& study,
    const std::function<void(const VariantResult&, const OptimizeStep&)>& done,
    const std::function<bool()>& stop = {}, const std::vector<VariantResult>& stored = {},
    int jobs = 0);

// The mechanism file of a variant (the study's text with the variant's values written in place
// at their paths, every other byte kept) with its design poses closed: the bodies at the start
// of the variant's cycle (the driver at its drawn input, the joints assembled), so that the file
// reads back without "does not close as drawn". When that start cannot be computed, or a pose
// cannot be edited in place, the poses are left as drawn and `note` says why. Throws InputError
// when a value cannot be written in place (io/mechanism_file.hpp with_file_values).
[[nodiscard]] std::string variant_file(const std::string& mechanism, const std::string& origin,
                                       const Study& study, const VariantResult& variant,
                                       std::string* note = nullptr);

}  // namespace orthomech
