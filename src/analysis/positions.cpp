#include "orthomech/analysis/positions.hpp"

#include <Eigen/Cholesky>
#include <cmath>
#include <numbers>

#include "orthomech/constraints/joints.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/model/measures.hpp"
#include "orthomech/projection/dual.hpp"
#include "orthomech/projection/gauss_newton.hpp"
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
  std::vector<PositionOptions::Lock> locks = options.locks;
  if (options.locked_joint >= 0)
    locks.insert(locks.begin(), PositionOptions::Lock{options.locked_joint, options.locked_value});
  const bool locked = !locks.empty();
  const int nl = static_cast<int>(locks.size());
  // The held joints' rows: s_k(q) − value_k (an angle that wraps, modulo 2π) and ∇s_k.
  VecX row(model.n);
  const ExtraRows lock_rows{
      nl, [&](const VecX& x, Eigen::Ref<VecX> g, Eigen::Ref<MatX> G) {
        for (int i = 0; i < nl; ++i) {
          const PositionOptions::Lock& l = locks[static_cast<size_t>(i)];
          double gap =
              compute_scalar(model, JointCoordinate{l.joint}, x, nullptr, row).value - l.value;
          if (joint_coordinate_wraps(model.joints[static_cast<size_t>(l.joint)]))
            gap = std::remainder(gap, 2.0 * std::numbers::pi);
          g(i) = gap;
          G.row(i) = row.transpose();
        }
      }};
  // The rows of f in each step: the independent ones (rank-revealing, ChartSelector). Off the
  // manifold the redundant rows of an overconstrained mechanism (Bennett's) regain rank: the
  // constraint rows ranked alone may then span every direction, the lock rows included, and the
  // step is singular although the lock can move the mechanism. Then (and from there on) the
  // lock rows are kept first and only the constraint rows independent of them are ranked (a
  // stacked rank-revealing selection): at most n − nl of them, as on the manifold.
  ChartSelector selector(model.nc, model.n);
  Chart chart;
  ChartOptions chart_options;
  bool lock_first = false;
  MatX Et_free;
  GaussNewtonOptions gn;
  gn.tolerance = options.tolerance;
  gn.metric = GaussNewtonOptions::Metric::mass;  // eq. (42) on the independent rows
  gn.descent = GaussNewtonOptions::Descent::free;
  gn.stall_limit = 5;
  gn.dependent_below = locked ? 1e-12 : 0.0;  // a held row must be independent of f's rows
  gn.choose_f_rows = [&](const MatX& Et, const MatX& D, const MatX& A, std::vector<int>& rows) {
    if (lock_first) {  // the constraint rows' parts A-orthogonal to the lock rows
      const MatX AD = A * D.transpose();
      const Eigen::LDLT<MatX> dad(D * AD);
      Et_free = Et - (Et * AD) * dad.solve(D);
    }
    const int r = selector.select(lock_first ? Et_free : Et, A.diagonal(), chart_options, chart);
    rows.assign(chart.rows.begin(), chart.rows.begin() + r);
  };
  SolveResult result;
  GaussNewtonResult g;
  for (;;) {
    gn.max_iterations = options.max_iterations - result.iterations;
    g = gauss_newton_positions(model, q, lock_rows, gn);
    result.iterations += g.steps;
    result.residual = g.residual;
    if (g.stop != GaussNewtonResult::Stop::dependent_rows || lock_first) break;
    VecX f(model.nc);
    compute_constraint_residual(model, q, f);
    if (!(f.size() && f.cwiseAbs().maxCoeff() > options.tolerance)) break;
    lock_first = true;  // off the manifold: rank anew
  }
  switch (g.stop) {
    case GaussNewtonResult::Stop::converged:
      result.status = SolveStatus::converged;
      break;
    case GaussNewtonResult::Stop::not_finite:
      result.status = SolveStatus::not_converged;
      result.message = "residual is not finite";
      break;
    case GaussNewtonResult::Stop::no_rows:
      result.status = SolveStatus::singular;
      result.message = "constraint Jacobian is zero";
      break;
    case GaussNewtonResult::Stop::dependent_rows:
      result.status = SolveStatus::singular;
      result.message = "the held joint cannot move the mechanism here";
      break;
    default:  // iterations, stalled
      result.status = SolveStatus::not_converged;
      result.message = "no convergence: remaining residual " + std::to_string(result.residual);
      break;
  }
  return result;
}

}  // namespace orthomech
