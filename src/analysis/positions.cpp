#include "orthomech/analysis/positions.hpp"

#include <Eigen/Cholesky>
#include <cmath>
#include <numbers>

#include "orthomech/constraints/joints.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/model/measures.hpp"
#include "orthomech/projection/dual.hpp"
#include "orthomech/projection/primal.hpp"

namespace orthomech {

const char* to_string(SolveStatus s) {
  switch (s) {
    case SolveStatus::converged:
      return "converged";
    case SolveStatus::not_converged:
      return "not converged";
    case SolveStatus::singular:
      return "singular";
  }
  return "?";
}

SolveResult project_positions(const Model& model, VecX& q, const PositionOptions& options) {
  SolveResult result;
  VecX f(model.nc);
  MatX Et(model.nc, model.n);
  MatX A;  // A = M⁻¹, eq. (6): formed at the first step (a design position that holds needs none)
  VecX A_diag;
  ChartSelector selector(model.nc, model.n);
  Chart chart;
  ChartOptions chart_options;
  VecX du(model.n);
  std::vector<PositionOptions::Lock> locks = options.locks;
  if (options.locked_joint >= 0)
    locks.insert(locks.begin(), PositionOptions::Lock{options.locked_joint, options.locked_value});
  const bool locked = !locks.empty();
  const int nl = static_cast<int>(locks.size());
  MatX d(nl, model.n);  // gradients of the held joint coordinates
  VecX lock_residual(nl);
  VecX row(model.n);
  double previous = std::numeric_limits<double>::infinity();
  int stalled = 0;
  // Off the manifold the redundant rows of an overconstrained mechanism (Bennett's) regain rank:
  // the constraint rows ranked alone may then span every direction, the lock rows included, and
  // the step is singular although the lock can move the mechanism. Then (and from there on) the
  // lock rows are kept first and only the constraint rows independent of them are ranked (a
  // stacked rank-revealing selection): at most n − nl of them, as on the manifold.
  bool lock_first = false;
  MatX Et_free;
  for (int it = 0;; ++it) {
    compute_constraint_residual(model, q, f);
    const double f_residual = f.size() ? f.cwiseAbs().maxCoeff() : 0.0;
    result.residual = f_residual;
    for (int i = 0; i < nl; ++i) {
      const PositionOptions::Lock& l = locks[static_cast<size_t>(i)];
      double gap = compute_scalar(model, JointCoordinate{l.joint}, q, nullptr, row).value - l.value;
      if (joint_coordinate_wraps(model.joints[static_cast<size_t>(l.joint)]))
        gap = std::remainder(gap, 2.0 * std::numbers::pi);
      lock_residual(i) = gap;
      d.row(i) = row.transpose();
      result.residual = std::max(result.residual, std::abs(gap));
    }
    result.iterations = it;
    if (!std::isfinite(result.residual)) {
      result.status = SolveStatus::not_converged;
      result.message = "residual is not finite";
      return result;
    }
    if (result.residual <= options.tolerance) {
      result.status = SolveStatus::converged;
      return result;
    }
    // Gauss–Newton stalls at the least-squares gap when the mechanism cannot close.
    stalled = result.residual > 0.5 * previous ? stalled + 1 : 0;
    if (it >= options.max_iterations || stalled >= 5) {
      result.status = SolveStatus::not_converged;
      result.message = "no convergence: remaining residual " + std::to_string(result.residual);
      return result;
    }
    previous = result.residual;
    if (A.size() == 0) {
      A.resize(model.n, model.n);
      compute_inverse_mass_matrix(model, q, A);
      A_diag = A.diagonal();
    }
    compute_constraint_jacobian(model, q, Et);
    if (lock_first) {  // the constraint rows' parts A-orthogonal to the lock rows
      const MatX AD = A * d.transpose();
      const Eigen::LDLT<MatX> dad(d * AD);
      Et_free = Et - (Et * AD) * dad.solve(d);
    }
    const int r = selector.select(lock_first ? Et_free : Et, A_diag, chart_options, chart);
    if (r == 0) {
      result.status = SolveStatus::singular;
      result.message = "constraint Jacobian is zero";
      return result;
    }
    const int rows = r + nl;
    MatX Er(rows, model.n);
    VecX fr(rows);
    for (int i = 0; i < r; ++i) {
      Er.row(i) = Et.row(chart.rows[static_cast<size_t>(i)]);
      fr(i) = f(chart.rows[static_cast<size_t>(i)]);
    }
    if (locked) {  // the held joints' rows
      Er.bottomRows(nl) = d;
      fr.tail(nl) = lock_residual;
    }
    const MatX AEr = A * Er.transpose();
    const MatX Gr = Er * AEr;  // eq. (42) on the independent rows
    const Eigen::LDLT<MatX> ldlt(Gr);
    if (locked) {  // the held row must be independent of the constraints' rows
      const VecX D = ldlt.vectorD().cwiseAbs();
      if (!(D.minCoeff() > 1e-12 * D.maxCoeff())) {
        if (!lock_first && f_residual > options.tolerance) {  // off the manifold: rank anew
          lock_first = true;
          previous = std::numeric_limits<double>::infinity();
          stalled = 0;
          continue;
        }
        result.status = SolveStatus::singular;
        result.message = "the held joint cannot move the mechanism here";
        return result;
      }
    }
    du = -AEr * ldlt.solve(fr);
    integrate_positions(model, q, du, 1.0);
  }
}

}  // namespace orthomech
