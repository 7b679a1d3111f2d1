#pragma once
// The built-in cross-check of the two formulations (docs/design.md §4, §8; issue 5): at states
// along a motion, the dual (F-based) and the primal (E-based) forms must give the same projections,
// accelerations and reactions, and the paper's identities must hold. With a rank-deficient E
// (redundant constraints) G is singular and the primal form is undefined: only the dual checks
// run, and the result says why the primal ones were skipped.
#include <string>
#include <vector>

#include "orthomech/dynamics/simulate.hpp"
#include "orthomech/model/model.hpp"
#include "orthomech/run_control.hpp"

namespace orthomech {

// How the projections are compared. `dense` forms α, β, ψ, Θ, θ as n × n matrices (O(n³) per
// state, refused above the dense workspace limit); `probes` applies them to a few seeded vectors
// through the sparse stages simulate integrates with (F n × n_a, G = EᵀAE sparse; O(n) per state
// for a mechanism of simple loops) and skips the three checks that need D or Ḟ as operators
// (eqs. (102), (82)/(85), (29)); `automatic` takes `probes` from kCrosscheckProbesFrom velocities.
enum class CrosscheckMethod { automatic, dense, probes };
inline constexpr int kCrosscheckProbesFrom = 300;
[[nodiscard]] const char* to_string(CrosscheckMethod m);
bool parse_crosscheck_method(const std::string& name, CrosscheckMethod& out);

struct CrosscheckOptions {
  int samples = 10;         // states along the motion
  double t_end = 0.2;       // s: length of the motion the states are taken from
  unsigned seed = 1;        // initial velocity guess: seeded uniform in [−1, 1] (SI)
  double tolerance = 1e-8;  // largest relative difference that passes
  CrosscheckMethod method = CrosscheckMethod::automatic;
  long max_steps = kDefaultMaxSteps;  // step budget of the motion (simulate's --max-steps)
  // Wall-clock limit, interrupt and progress over the whole run: the motion is its first half,
  // the comparisons at the states its second.
  RunControl control;
};

struct CrosscheckItem {
  std::string name;  // e.g. "alpha dual vs primal (eq. (44) vs (70))"
  std::string kind;  // "dual-vs-primal" or "identity"
  // The largest difference over the states over the largest size of the compared quantity (or
  // of the terms it sums) over the states: relative to its size along the motion.
  double max_relative = 0.0;
  double at_t = 0.0;  // where the largest difference occurred
  bool pass = true;
};

struct CrosscheckResult {
  bool pass = false;
  std::string message;  // why it failed or what was skipped
  bool primal_checked = false;
  std::string primal_skipped_reason;  // non-empty when the primal checks were skipped
  int samples = 0;
  int rank = 0, nc = 0;
  double tolerance = 0.0;
  CrosscheckMethod method = CrosscheckMethod::dense;  // the one used (never automatic)
  // A bound met (RunControl, the step budget): the checks hold the states compared before it;
  // pass is false and message says which bound.
  StopReason stop = StopReason::none;
  std::vector<CrosscheckItem> items;
};

// Simulates the motion (dual form) from the design position with the seeded initial velocity,
// then compares the forms at `samples` states of it. Never throws for numerical trouble.
[[nodiscard]] CrosscheckResult run_crosscheck(const Model& model,
                                              const CrosscheckOptions& options = {});

}  // namespace orthomech
