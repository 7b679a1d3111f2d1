#include "orthomech/projection/chart_engine.hpp"

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "orthomech/constraints/joints.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/numerics/small_lu.hpp"

namespace orthomech {

namespace {
// Chart switches kept in switches() (the count goes on beyond it).
constexpr size_t kMaxRecordedSwitches = 1024;
}  // namespace

ChartEngine::ChartEngine(const Model& model, int rank, ChartFactorisation factorisation)
    : model_(&model),
      n_(model.n),
      nc_(model.nc),
      r_(rank),
      sparse_(factorisation == ChartFactorisation::sparse_when_large && rank > kSparseAbove),
      selector_(model.nc, model.n),
      dep_pos_(static_cast<size_t>(model.n), -1),
      metric_(VecX::Ones(model.n)),
      row_s_(VecX::Ones(rank)),
      col_s_(VecX::Ones(model.n)),
      G_(rank, rank),
      piv_(Eigen::VectorXi::Zero(rank)),
      Gs_(rank, rank),
      br_(rank),
      xd_(rank),
      sw_(rank) {
  switches_.reserve(kMaxRecordedSwitches);
  triplets_.reserve(static_cast<size_t>(8 * rank + 8));
  if (sparse_) structural_pattern();
}

void ChartEngine::structural_pattern() {
  MatX Et(nc_, n_);
  row_columns_.assign(static_cast<size_t>(nc_), {});
  std::vector<std::vector<char>> seen(static_cast<size_t>(nc_),
                                      std::vector<char>(static_cast<size_t>(n_), 0));
  for (const double scale : {0.0137, -0.0291}) {  // two generic positions near the design
    VecX q = model_->design_q();
    VecX du(n_);
    for (int k = 0; k < n_; ++k) du(k) = scale * (1.0 + std::sin(1.7 * k + 0.3));
    integrate_positions(*model_, q, du, 1.0);
    compute_constraint_jacobian(*model_, q, Et);
    for (int i = 0; i < nc_; ++i)
      for (int j = 0; j < n_; ++j)
        if (Et(i, j) != 0.0) seen[static_cast<size_t>(i)][static_cast<size_t>(j)] = 1;
  }
  for (int i = 0; i < nc_; ++i)
    for (int j = 0; j < n_; ++j)
      if (seen[static_cast<size_t>(i)][static_cast<size_t>(j)])
        row_columns_[static_cast<size_t>(i)].push_back(j);
}

// ---- Choosing a chart ---------------------------------------------------------------------------

void ChartEngine::set_chart(const Chart& c) {
  chart_ = c;
  index_chart();
}

void ChartEngine::index_chart() {
  ready_ = true;
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

bool ChartEngine::select(const MatX& Et, const VecX& A_diag) {
  if (selector_.select(Et, A_diag, options_, candidate_) != r_) return false;
  set_chart(candidate_);
  return true;
}

void ChartEngine::select_from_tangent(const MatX& F, const VecX& M_sqrt) {
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

// ---- Factorising --------------------------------------------------------------------------------

double ChartEngine::factor(const MatX& Et, const VecX& A_sqrt) {
  metric_ = A_sqrt;
  if (r_ == 0) return quality_ = 1.0;
  row_s_ = chart_.row_scale;
  col_s_ = metric_;
  const VecX& S_R = row_s_;
  const VecX& S_D = col_s_;
  if (!sparse_) {
    for (int k = 0; k < r_; ++k) {
      const int dk = chart_.dependent[static_cast<size_t>(k)];
      for (int i = 0; i < r_; ++i)
        G_(i, k) = S_R(i) * Et(chart_.rows[static_cast<size_t>(i)], dk) * S_D(dk);
    }
    // Unblocked in-place LU (numerics/small_lu.hpp; Eigen's blocked path costs more than the
    // factorisation itself at r ≈ 20, measured with bench/simulate_bench.cpp).
    return quality_ = lu_factor(G_, piv_);
  }
  triplets_.clear();
  for (const BlockEntry& e : block_entries_) {  // the structural entries, zero or not
    const int dk = chart_.dependent[static_cast<size_t>(e.k)];
    triplets_.emplace_back(
        e.i, e.k, S_R(e.i) * Et(chart_.rows[static_cast<size_t>(e.i)], e.column) * S_D(dk));
  }
  Gs_.setFromTriplets(triplets_.begin(), triplets_.end());
  // The ordering (COLAMD) is computed once per pattern: the structural pattern is the same
  // within a chart.
  const auto nnz = Gs_.nonZeros();
  bool same = analyzed_ && nnz == static_cast<Eigen::Index>(pattern_inner_.size());
  if (same) {
    for (Eigen::Index k = 0; k < nnz && same; ++k)
      same = Gs_.innerIndexPtr()[k] == pattern_inner_[static_cast<size_t>(k)];
    for (Eigen::Index k = 0; k <= r_ && same; ++k)
      same = Gs_.outerIndexPtr()[k] == pattern_outer_[static_cast<size_t>(k)];
  }
  if (!same) {
    slu_.analyzePattern(Gs_);
    pattern_inner_.assign(Gs_.innerIndexPtr(), Gs_.innerIndexPtr() + nnz);
    pattern_outer_.assign(Gs_.outerIndexPtr(), Gs_.outerIndexPtr() + r_ + 1);
    analyzed_ = true;
  }
  slu_.factorize(Gs_);
  return quality_ = slu_.info() == Eigen::Success ? 1.0 : 0.0;
}

double ChartEngine::update(const MatX& Et, const VecX& A_diag, const VecX& A_sqrt, double t) {
  if (!ready_) {
    if (selector_.select(Et, A_diag, options_, candidate_) != r_) return quality_ = 0.0;
    set_chart(candidate_);
    return factor(Et, A_sqrt);
  }
  const double kept = factor(Et, A_sqrt);
  if (kept >= options_.switch_below) return kept;
  // The chart degraded: the QR's best chart, if it is better by the hysteresis factor.
  if (selector_.select(Et, A_diag, options_, candidate_) != r_) return kept;  // LU untouched
  std::swap(chart_, candidate_);  // (swaps the index vectors: no allocation)
  index_chart();
  const double best = factor(Et, A_sqrt);
  if (best > options_.hysteresis * kept) {
    ++switch_count_;
    if (switches_.size() < kMaxRecordedSwitches) switches_.push_back({t, kept, best});
    return best;
  }
  std::swap(chart_, candidate_);
  index_chart();
  return factor(Et, A_sqrt);  // the LU of the chart kept
}

int ChartEngine::determinant_sign() const {
  int sign = 1;
  for (int i = 0; i < r_; ++i) {
    if (G_(i, i) < 0.0) sign = -sign;
    if (piv_(i) != i) sign = -sign;
  }
  return sign;
}

// ---- Solving ------------------------------------------------------------------------------------
// G = S_R B S_D with B = E_RDᵀ: B⁻¹ = S_D G⁻¹ S_R and B⁻ᵀ = S_R G⁻ᵀ S_D.

void ChartEngine::solve_in_place(Eigen::Ref<VecX> x) {
  if (sparse_) {
    xd_ = slu_.solve(x);
    x = xd_;
  } else {
    lu_solve(G_, piv_, x);
  }
}

void ChartEngine::solve_transposed_in_place(Eigen::Ref<VecX> x) {
  if (sparse_) {
    xd_ = slu_.transpose().solve(x);
    x = xd_;
  } else {
    lu_solve_transposed(G_, piv_, x);
  }
}

void ChartEngine::solve(const VecX& b, VecX& x) {
  x.setZero();
  if (r_ == 0) return;
  for (int i = 0; i < r_; ++i) br_(i) = row_s_(i) * b(chart_.rows[static_cast<size_t>(i)]);
  solve_in_place(br_);
  for (int k = 0; k < r_; ++k) {
    const int dk = chart_.dependent[static_cast<size_t>(k)];
    x(dk) = col_s_(dk) * br_(k);
  }
}

void ChartEngine::solve_dependent(MatX& rhs, MatX& out) {
  if (r_ == 0) return;
  for (int i = 0; i < r_; ++i) rhs.row(i) *= row_s_(i);
  // Column by column (vector solves are far cheaper than blocked matrix paths for the small
  // blocks of linkages).
  for (Eigen::Index k = 0; k < out.cols(); ++k) solve_in_place(rhs.col(k).head(r_));
  for (int k = 0; k < r_; ++k) {
    const int dk = chart_.dependent[static_cast<size_t>(k)];
    out.row(dk) = col_s_(dk) * rhs.row(k).head(out.cols());
  }
}

void ChartEngine::solve_transposed(const VecX& c, Eigen::Ref<VecX> lambda_r) {
  if (r_ == 0) return;
  for (int k = 0; k < r_; ++k) {
    const int dk = chart_.dependent[static_cast<size_t>(k)];
    br_(k) = col_s_(dk) * c(dk);
  }
  solve_transposed_in_place(br_);
  for (int i = 0; i < r_; ++i) lambda_r(i) = row_s_(i) * br_(i);
}

double ChartEngine::estimate_sigma_min(VecX& w, VecX* left) {
  if (r_ == 0) return std::numeric_limits<double>::infinity();
  if (w.size() != r_ || !(w.norm() > 0.0) || !w.allFinite()) {
    w.resize(r_);  // a start with no structure (set-up or after a breakdown)
    for (int k = 0; k < r_; ++k) w(k) = 1.0 + 0.37 * std::sin(1.0 + 3.1 * k);
  }
  // B̃ = B S (S = diag of the metric) = S_R⁻¹ G S_D⁻¹ S: B̃⁻ᵀ = S_R G⁻ᵀ S_D S⁻¹ and
  // B̃⁻¹ = S⁻¹ S_D G⁻¹ S_R (S_D = S when the block is scaled).
  const auto dep = [&](int k) { return chart_.dependent[static_cast<size_t>(k)]; };
  double sigma = 0.0;
  constexpr int kIterations = 2;
  for (int it = 0; it < kIterations; ++it) {
    w /= w.norm();
    for (int k = 0; k < r_; ++k) sw_(k) = w(k) * col_s_(dep(k)) / metric_(dep(k));
    solve_transposed_in_place(sw_);  // y = S_R G⁻ᵀ S_D S⁻¹ ŵ
    sw_.array() *= row_s_.array();
    const double ny = sw_.norm();
    if (!(ny > 0.0) || !std::isfinite(ny)) return 0.0;
    sigma = 1.0 / ny;
    if (left && it + 1 == kIterations) *left = sw_ / ny;  // ŷ: B̃ (B̃⁻¹ y) = y
    sw_.array() *= row_s_.array();                        // z = S⁻¹ S_D G⁻¹ S_R y
    solve_in_place(sw_);
    for (int k = 0; k < r_; ++k) w(k) = sw_(k) * col_s_(dep(k)) / metric_(dep(k));
    if (!w.allFinite()) return 0.0;
  }
  return sigma;
}

// ---- Correcting positions -----------------------------------------------------------------------

double ChartEngine::polish_positions(VecX& q, MatX& Et, VecX& f, VecX& dq, int iterations) {
  const VecX A_sqrt = metric_;  // (set-up of a passage only: not a hot path)
  compute_constraint_residual_and_jacobian(*model_, q, f, Et);
  double residual = f.size() ? f.cwiseAbs().maxCoeff() : 0.0;
  if (!(factor(Et, A_sqrt) > 0.0)) return residual;
  for (int it = 0; it < iterations && residual > 0.0; ++it) {
    solve(f, dq);
    VecX trial = q;
    integrate_positions(*model_, trial, dq, -1.0);
    VecX f_trial(f.size());
    MatX Et_trial(Et.rows(), Et.cols());
    compute_constraint_residual_and_jacobian(*model_, trial, f_trial, Et_trial);
    const double r_trial = f_trial.cwiseAbs().maxCoeff();
    if (!(r_trial <= 0.5 * residual)) break;
    q = trial;
    f = f_trial;
    Et = Et_trial;
    residual = r_trial;
    if (!(factor(Et, A_sqrt) > 0.0)) break;
  }
  (void)factor(Et, A_sqrt);
  return residual;
}

ChartCorrectionResult ChartEngine::correct_positions(VecX& q, MatX& Et, VecX& f, VecX& dq,
                                                     const ChartCorrection& options) {
  ChartCorrectionResult result;
  // Newton stalled at the rounding level: an iteration that does not halve the residual. Next
  // to a change point the chart's block is ill-conditioned (σ̂ ~ 1e-4 … 1e-6) and rounding in
  // the solve alone leaves |f| ~ ε |q| / σ̂ — above 1e-12 m on the triple-crank (1.03e-12 …
  // 4.2e-12 measured). A stalled residual within kStallFactor of the tolerance is accepted as
  // converged (still far below any step's own error).
  constexpr double kStallFactor = 100.0;
  // A block this ill-conditioned is singular for the corrector.
  constexpr double kSingularQuality = 1e-14;
  const double tolerance = options.tolerance;
  double previous = std::numeric_limits<double>::infinity();
  for (int it = 0;; ++it) {
    // f and Eᵀ together (their point kinematics shared): Eᵀ is needed either for the Newton step
    // or, once converged, by the caller at the corrected q.
    const bool reuse = options.start == ChartCorrection::Start::prepared && it == 0;
    if (!reuse) compute_constraint_residual_and_jacobian(*model_, q, f, Et);
    result.residual = f.size() ? f.cwiseAbs().maxCoeff() : 0.0;
    result.iterations = it;
    if (!std::isfinite(result.residual) ||
        (it >= options.max_iterations && result.residual > tolerance)) {
      result.status = SolveStatus::not_converged;
      char buf[96];
      std::snprintf(buf, sizeof buf,
                    "the position corrector did not converge (residual %.3g, tolerance %.3g)",
                    result.residual, tolerance);
      result.message = buf;
      return result;
    }
    if (!reuse && !(factor(Et, metric_) > kSingularQuality)) {
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
    if (it == 0 && options.max_gain > 0.0 &&
        dq.cwiseAbs().maxCoeff() > options.max_gain * std::max(result.residual, tolerance)) {
      result.near_singular = true;
      result.status = SolveStatus::converged;
      result.message = "not corrected: next to a change point";
      return result;
    }
    integrate_positions(*model_, q, dq, -1.0);  // q_D ← q_D − Δq_D
  }
}

}  // namespace orthomech
