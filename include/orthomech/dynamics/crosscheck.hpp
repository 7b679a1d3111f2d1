#pragma once
// The built-in cross-check of the two formulations (design §4, §8; issue 5): at states along a
// motion, the dual (F-based) and the primal (E-based) forms must give the same projections,
// accelerations and reactions, and the paper's identities must hold. With a rank-deficient E
// (redundant constraints) G is singular and the primal form is undefined: only the dual checks
// run, and the result says why the primal ones were skipped.
#include <string>
#include <vector>

#include "orthomech/model/model.hpp"

namespace orthomech {

struct CrosscheckOptions {
  int samples = 10;         // states along the motion
  double t_end = 0.2;       // s: length of the motion the states are taken from
  unsigned seed = 1;        // initial velocity guess: seeded uniform in [−1, 1] (SI)
  double tolerance = 1e-8;  // largest relative difference that passes
};

struct CrosscheckItem {
  std::string name;  // e.g. "alpha dual vs primal (eq. (44) vs (70))"
  std::string kind;  // "dual-vs-primal" or "identity"
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
  std::vector<CrosscheckItem> items;
};

// Simulates the motion (dual form) from the design position with the seeded initial velocity,
// then compares the forms at `samples` states of it. Never throws for numerical trouble.
[[nodiscard]] CrosscheckResult run_crosscheck(const Model& model,
                                              const CrosscheckOptions& options = {});

}  // namespace orthomech
