#include "chart_solver.hpp"

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "orthomech/constraints/joints.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/numerics/small_lu.hpp"

namespace orthomech::detail {

namespace {
// Above this rank the dependent block is factorised as a sparse matrix (dense LU is cheaper
// for the small blocks of ordinary linkages; measured in bench/simulate_bench.cpp).
constexpr int kSparseAbove = 48;
}  // namespace

ChartSolver::ChartSolver(const Model& model, int rank)
    : model_(model),
      n_(model.n),
      nc_(model.nc),
      r_(rank),
      sparse_(rank > kSparseAbove),
      selector_(model.nc, model.n),
      dep_pos_(static_cast<size_t>(model.n), -1),
      ED_(rank, rank),
      piv_(Eigen::VectorXi::Zero(rank)),
      EDs_(rank, rank),
      br_(rank),
      xd_(rank),
      sw_(rank) {
  triplets_.reserve(static_cast<size_t>(8 * rank + 8));
  if (sparse_) structural_pattern();
}

void ChartSolver::structural_pattern() {
  MatX Et(nc_, n_);
  row_columns_.assign(static_cast<size_t>(nc_), {});
  std::vector<std::vector<char>> seen(static_cast<size_t>(nc_),
                                      std::vector<char>(static_cast<size_t>(n_), 0));
  for (const double scale : {0.0137, -0.0291}) {  // two generic positions near the design
    VecX q = model_.design_q();
    VecX du(n_);
    for (int k = 0; k < n_; ++k) du(k) = scale * (1.0 + std::sin(1.7 * k + 0.3));
    integrate_positions(model_, q, du, 1.0);
    compute_constraint_jacobian(model_, q, Et);
    for (int i = 0; i < nc_; ++i)
      for (int j = 0; j < n_; ++j)
        if (Et(i, j) != 0.0) seen[static_cast<size_t>(i)][static_cast<size_t>(j)] = 1;
  }
  for (int i = 0; i < nc_; ++i)
    for (int j = 0; j < n_; ++j)
      if (seen[static_cast<size_t>(i)][static_cast<size_t>(j)])
        row_columns_[static_cast<size_t>(i)].push_back(j);
}

void ChartSolver::set_chart(const Chart& c) {
  chart_ = c;
  analyzed_ = false;
  std::fill(dep_pos_.begin(), dep_pos_.end(), -1);
  for (size_t k = 0; k < chart_.dependent.size(); ++k)
    dep_pos_[static_cast<size_t>(chart_.dependent[k])] = static_cast<int>(k);
  block_entries_.clear();
  if (!sparse_) return;
  for (int i = 0; i < r_; ++i)
    for (const int j : row_columns_[static_cast<size_t>(chart_.rows[static_cast<size_t>(i)])])
      if (const int k = dep_pos_[static_cast<size_t>(j)]; k >= 0)
        block_entries_.push_back({i, k, j});
}

bool ChartSolver::select(const MatX& Et, const VecX& A_diag) {
  Chart c;
  if (selector_.select(Et, A_diag, options_, c) != r_) return false;
  set_chart(c);
  return true;
}

void ChartSolver::select_from_tangent(const MatX& F, const VecX& M_sqrt) {
  if (F.cols() == 0) return;
  const MatX S = (M_sqrt.asDiagonal() * F).transpose();  // n_a × n
  const Eigen::ColPivHouseholderQR<MatX> qr(S);
  const auto& perm = qr.colsPermutation().indices();
  Chart c = chart_;
  std::vector<bool> independent(static_cast<size_t>(n_), false);
  for (Eigen::Index k = 0; k < F.cols(); ++k) independent[static_cast<size_t>(perm(k))] = true;
  c.independent.clear();
  c.dependent.clear();
  for (int k = 0; k < n_; ++k)
    (independent[static_cast<size_t>(k)] ? c.independent : c.dependent).push_back(k);
  set_chart(c);
}

bool ChartSolver::factor(const MatX& Et) {
  if (r_ == 0) return true;
  if (!sparse_) {
    for (int i = 0; i < r_; ++i) {
      const int row = chart_.rows[static_cast<size_t>(i)];
      for (int k = 0; k < r_; ++k) ED_(i, k) = Et(row, chart_.dependent[static_cast<size_t>(k)]);
    }
    // Unblocked in-place LU (numerics/small_lu.hpp; Eigen's blocked path costs more than the
    // factorisation itself at r ≈ 20, measured with bench/simulate_bench.cpp).
    return lu_factor(ED_, piv_) > 1e-14;
  }
  triplets_.clear();
  for (const BlockEntry& e : block_entries_)  // the structural entries, zero or not
    triplets_.emplace_back(e.i, e.k, Et(chart_.rows[static_cast<size_t>(e.i)], e.column));
  EDs_.setFromTriplets(triplets_.begin(), triplets_.end());
  // The ordering (COLAMD) is computed once per pattern: the structural pattern is the same
  // within a chart.
  const auto nnz = EDs_.nonZeros();
  bool same = analyzed_ && nnz == static_cast<Eigen::Index>(pattern_inner_.size());
  if (same) {
    for (Eigen::Index k = 0; k < nnz && same; ++k)
      same = EDs_.innerIndexPtr()[k] == pattern_inner_[static_cast<size_t>(k)];
    for (Eigen::Index k = 0; k <= r_ && same; ++k)
      same = EDs_.outerIndexPtr()[k] == pattern_outer_[static_cast<size_t>(k)];
  }
  if (!same) {
    slu_.analyzePattern(EDs_);
    pattern_inner_.assign(EDs_.innerIndexPtr(), EDs_.innerIndexPtr() + nnz);
    pattern_outer_.assign(EDs_.outerIndexPtr(), EDs_.outerIndexPtr() + r_ + 1);
    analyzed_ = true;
  }
  slu_.factorize(EDs_);
  return slu_.info() == Eigen::Success;
}

void ChartSolver::solve(const VecX& b, VecX& x) {
  x.setZero();
  if (r_ == 0) return;
  for (int i = 0; i < r_; ++i) br_(i) = b(chart_.rows[static_cast<size_t>(i)]);
  if (sparse_) {
    xd_ = slu_.solve(br_);
    br_ = xd_;
  } else {
    lu_solve(ED_, piv_, br_);  // in place
  }
  for (int k = 0; k < r_; ++k) x(chart_.dependent[static_cast<size_t>(k)]) = br_(k);
}

void ChartSolver::solve_transposed(const MatX& Et, const VecX& c, VecX& lambda) {
  lambda.setZero();
  if (r_ == 0) return;
  VecX cd(r_);
  for (int k = 0; k < r_; ++k) cd(k) = c(chart_.dependent[static_cast<size_t>(k)]);
  VecX lr(r_);
  if (!sparse_) {
    lr = cd;
    lu_solve_transposed(ED_, piv_, lr);
  } else {
    const Eigen::SparseMatrix<double> EDt = EDs_.transpose();
    Eigen::SparseLU<Eigen::SparseMatrix<double>, Eigen::COLAMDOrdering<int>> lu(EDt);
    lr = lu.solve(cd);
  }
  (void)Et;
  for (int i = 0; i < r_; ++i) lambda(chart_.rows[static_cast<size_t>(i)]) = lr(i);
}

double ChartSolver::polish_positions(VecX& q, MatX& Et, VecX& f, VecX& dq, int iterations) {
  compute_constraint_residual_and_jacobian(model_, q, f, Et);
  double residual = f.size() ? f.cwiseAbs().maxCoeff() : 0.0;
  if (!factor(Et)) return residual;
  for (int it = 0; it < iterations && residual > 0.0; ++it) {
    solve(f, dq);
    VecX trial = q;  // (set-up of a passage only: not a hot path)
    integrate_positions(model_, trial, dq, -1.0);
    VecX f_trial(f.size());
    MatX Et_trial(Et.rows(), Et.cols());
    compute_constraint_residual_and_jacobian(model_, trial, f_trial, Et_trial);
    const double r_trial = f_trial.cwiseAbs().maxCoeff();
    if (!(r_trial <= 0.5 * residual)) break;
    q = trial;
    f = f_trial;
    Et = Et_trial;
    residual = r_trial;
    if (!factor(Et)) break;
  }
  (void)factor(Et);
  return residual;
}

double ChartSolver::estimate_sigma_min(const VecX& col_scale, VecX& w, VecX* left) {
  if (r_ == 0) return std::numeric_limits<double>::infinity();
  if (w.size() != r_ || !(w.norm() > 0.0) || !w.allFinite()) {
    w.resize(r_);  // a start with no structure (set-up or after a breakdown)
    for (int k = 0; k < r_; ++k) w(k) = 1.0 + 0.37 * std::sin(1.0 + 3.1 * k);
  }
  // B̃ = B S with B = E_RDᵀ: B̃⁻ᵀ = B⁻ᵀ S⁻¹ and B̃⁻¹ = S⁻¹ B⁻¹ (w and z indexed by D).
  double sigma = 0.0;
  constexpr int kIterations = 2;
  for (int it = 0; it < kIterations; ++it) {
    w /= w.norm();
    for (int k = 0; k < r_; ++k)  // y = B⁻ᵀ (S⁻¹ ŵ)
      sw_(k) = w(k) / col_scale(chart_.dependent[static_cast<size_t>(k)]);
    if (sparse_) {
      xd_ = slu_.transpose().solve(sw_);
      sw_ = xd_;
    } else {
      lu_solve_transposed(ED_, piv_, sw_);
    }
    const double ny = sw_.norm();
    if (!(ny > 0.0) || !std::isfinite(ny)) return 0.0;
    sigma = 1.0 / ny;
    if (left && it + 1 == kIterations) *left = sw_ / ny;  // ŷ: B̃ (B̃⁻¹ y) = y
    if (sparse_) {                                        // z = S⁻¹ B⁻¹ y
      xd_ = slu_.solve(sw_);
      sw_ = xd_;
    } else {
      lu_solve(ED_, piv_, sw_);
    }
    for (int k = 0; k < r_; ++k)
      w(k) = sw_(k) / col_scale(chart_.dependent[static_cast<size_t>(k)]);
    if (!w.allFinite()) return 0.0;
  }
  return sigma;
}

SolveResult ChartSolver::correct_positions(VecX& q, MatX& Et, VecX& f, VecX& dq, double tolerance,
                                           double max_gain, bool* near_singular, bool prepared) {
  SolveResult result;
  if (near_singular) *near_singular = false;
  constexpr int kMaxIterations = 8;
  // Newton stalled at the rounding level: an iteration that does not halve the residual. Next
  // to a change point the chart's block is ill-conditioned (σ̂ ~ 1e-4 … 1e-6) and rounding in
  // the solve alone leaves |f| ~ ε |q| / σ̂ — above 1e-12 m on the triple-crank (1.03e-12 …
  // 4.2e-12 measured), where the run used to stop. A stalled residual within kStallFactor of the
  // tolerance is accepted as converged (still far below any step's own error).
  constexpr double kStallFactor = 100.0;
  double previous = std::numeric_limits<double>::infinity();
  for (int it = 0;; ++it) {
    // f and Eᵀ together (their point kinematics shared): Eᵀ is needed either for the Newton step
    // or, once converged, by the caller at the corrected q.
    const bool reuse = prepared && it == 0;  // f, Eᵀ and the factors at q are the caller's
    if (!reuse) compute_constraint_residual_and_jacobian(model_, q, f, Et);
    result.residual = f.size() ? f.cwiseAbs().maxCoeff() : 0.0;
    result.iterations = it;
    if (!std::isfinite(result.residual) || (it >= kMaxIterations && result.residual > tolerance)) {
      result.status = SolveStatus::not_converged;
      char buf[96];
      std::snprintf(buf, sizeof buf,
                    "the position corrector did not converge (residual %.3g, tolerance %.3g)",
                    result.residual, tolerance);
      result.message = buf;
      return result;
    }
    if (!reuse && !factor(Et)) {
      result.status = SolveStatus::singular;
      result.message = "the chart's dependent block is singular";
      return result;
    }
    if (result.residual <= tolerance || (it >= 2 && result.residual > 0.5 * previous &&
                                         result.residual <= kStallFactor * tolerance)) {
      result.status = SolveStatus::converged;
      return result;
    }
    previous = result.residual;
    solve(f, dq);  // E_RDᵀ Δq_D = f_R
    if (it == 0 && max_gain > 0.0 &&
        dq.cwiseAbs().maxCoeff() > max_gain * std::max(result.residual, tolerance)) {
      if (near_singular) *near_singular = true;
      result.status = SolveStatus::converged;
      result.message = "not corrected: next to a change point";
      return result;
    }
    integrate_positions(model_, q, dq, -1.0);  // q_D ← q_D − Δq_D
  }
}

}  // namespace orthomech::detail
