#pragma once
#include <vector>
// Position solvers on f(q) = 0 (docs/design.md §5), Eigen only. Results are data, not exceptions.
#include <string>

#include "orthomech/model/model.hpp"
#include "orthomech/numerics/solve_result.hpp"
#include "orthomech/projection/workspace.hpp"

namespace orthomech {

struct PositionOptions {
  double tolerance = 1e-12;  // max |f_k| (m, rad); positions of mechanisms of 1 mm–10 m
  int max_iterations = 50;
  // project_positions: hold this joint's coordinate at `locked_value` (rad or m), as
  // `assemble --lock` does: the other bodies move to close the joints. −1: nothing held.
  int locked_joint = -1;
  double locked_value = 0.0;
  // Further joints held at their values (several drivers, analysis/multi_drive.hpp); a spatial
  // joint angle is held modulo 2π.
  struct Lock {
    int joint = -1;
    double value = 0.0;
  };
  std::vector<Lock> locks;
};

// Gauss–Newton in the mass metric (the paper's natural metric): Δq = −A E_R (E_Rᵀ A E_R)⁻¹ f_R
// on the independent rows R (rank-revealing), i.e. the smallest correction in the kinetic-energy
// norm. Moves every body; works with redundant constraints. For one-off projections. With
// options.locked_joint (and each of options.locks), the joint's coordinate s(q) = locked_value is
// one more row (its gradient d appended to E_R); if those rows depend on the constraints' (the
// joints cannot move there, a dead point of them), the result is `singular`. Off the manifold,
// where the redundant rows of an overconstrained mechanism regain rank, the lock rows are kept
// first and the constraint rows independent of them are ranked (docs/theory.md).
SolveResult project_positions(const Model& model, VecX& q, const PositionOptions& options = {});

}  // namespace orthomech
