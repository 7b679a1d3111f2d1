#pragma once
// The one Gauss–Newton position corrector of the commands that bring a position onto the
// constraint manifold from off it: the initial projection of `simulate`, `cycle` and the
// multi-driver sweep (project_positions), `assemble`'s projections with locks
// (project_with_locks, follow_locks) and its polish after Ipopt, and `validate`'s
// tangent-constrained Newton of its circuit tracing. (The per-step corrector of continuation and
// integration, where a chart is factorised anyway, is ChartEngine::correct_positions.)
//
// It solves c(q) = 0, c = [f_rows(q); g(q)]: chosen rows of f (eq. (20)) and extra rows g given by
// the caller (locks, a tangent row, …), by minimum-norm steps in velocity space,
//   Δu = −W Cᵀ (C W Cᵀ)⁺ c,   q ← q ⊕ Δu   (docs/spatial.md §6.3: nq ≠ n for spatial bodies),
// with C = [E_rowsᵀ; ∂g/∂u] and W the mass metric A = M⁻¹ (eq. (6), at the start q) or the
// identity (then Δu = −C⁺ c by a complete orthogonal decomposition of C, without squaring its
// condition). The pseudo-inverse takes redundant rows (an overconstrained mechanism) as they
// come; or the rows of f are chosen independent at each step (choose_f_rows, a rank-revealing
// selection) and C W Cᵀ is factorised by LDLᵀ. Not a hot path: it allocates.
#include <functional>
#include <string>
#include <vector>

#include "orthomech/model/model.hpp"

namespace orthomech {

// Rows beyond f: residuals g (size count) and their gradients in velocity space (count × n) at q.
struct ExtraRows {
  int count = 0;
  std::function<void(const VecX& q, Eigen::Ref<VecX> g, Eigen::Ref<MatX> G)> evaluate;
};

struct GaussNewtonOptions {
  enum class Metric { mass, euclidean };
  // What a step must do to be taken:
  //   backtrack — the step is halved (at most 8 times) until the residual falls; fails if none does
  //   monotone  — a step that does not lower the residual ends the iteration (q stays before it)
  //   free      — every step is taken (Newton on a square system, e.g. with a tangent row)
  enum class Descent { backtrack, monotone, free };

  // Converged when the residual ≤ tolerance; with extra_tolerance ≥ 0, when max |f| ≤ tolerance
  // and max |g| ≤ extra_tolerance instead (a tangent row measured on its own scale).
  double tolerance = 1e-12;
  double extra_tolerance = -1.0;
  int max_iterations = 50;
  // After max_iterations without convergence: converged anyway when max |f| ≤ accept (< 0: no).
  double accept = -1.0;
  Metric metric = Metric::mass;
  Descent descent = Descent::backtrack;
  // The rows of f in the step (empty: all); the residual reads every row of f.
  std::vector<int> f_rows;
  // Or chosen at each step from Eᵀ, the extra rows' gradients G and A = M⁻¹ (rows left empty:
  // stop, Stop::no_rows). The step then solves C W Cᵀ by LDLᵀ; with dependent_below > 0 a pivot
  // ≤ dependent_below × the largest stops it (Stop::dependent_rows: e.g. a lock row that the
  // constraints' rows span, a dead point of the held joint).
  std::function<void(const MatX& Et, const MatX& G, const MatX& A, std::vector<int>& rows)>
      choose_f_rows;
  double dependent_below = 0.0;
  // > 0: stop (Stop::stalled) after this many successive iterations that did not halve the
  // residual (Gauss–Newton stalls at the least-squares gap when the mechanism cannot close).
  int stall_limit = 0;
  // The residual that decides descent and convergence; empty: max(max |f|, max |g|).
  std::function<double(const VecX& q)> residual;
};

struct GaussNewtonResult {
  enum class Stop {
    converged,
    iterations,      // max_iterations steps taken
    stalled,         // see stall_limit
    no_descent,      // a step (and its halvings) did not lower the residual
    not_finite,      // the residual or the step is not finite
    no_rows,         // choose_f_rows chose none
    dependent_rows,  // see dependent_below
  };
  Stop stop = Stop::iterations;
  bool converged = false;
  int steps = 0;          // steps taken
  double residual = 0.0;  // at the returned q (+∞ when not finite)
};

// Corrects q in place; on failure q is the last position reached (backtrack: the last one with
// a lower residual).
GaussNewtonResult gauss_newton_positions(const Model& model, VecX& q, const ExtraRows& extra,
                                         const GaussNewtonOptions& options);

}  // namespace orthomech
