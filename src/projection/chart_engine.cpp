#include "orthomech/projection/chart_engine.hpp"

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "orthomech/constraints/constraint_system.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/constraints/sparse_et.hpp"
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
      r_(rank),
      sparse_(constraint_system(model).structurally_sparse() && rank > kSparseAbove &&
              (factorisation == ChartFactorisation::sparse_when_large ||
               (factorisation == ChartFactorisation::rated_sparse_when_large &&
                model.n >= kRatedSparseFrom))),
      rated_(sparse_ && factorisation == ChartFactorisation::rated_sparse_when_large),
      selector_(model.nc, model.n),
      dep_pos_(static_cast<size_t>(model.n), -1),
      metric_(VecX::Ones(model.n)),
      row_s_(VecX::Ones(rank)),
      col_s_(VecX::Ones(model.n)),
      G_(sparse_ ? 0 : rank, sparse_ ? 0 : rank),  // the dense path's block only
      piv_(Eigen::VectorXi::Zero(rank)),
      Gs_(rank, rank),
      br_(rank),
      sw_(rank) {
  switches_.reserve(kMaxRecordedSwitches);
  triplets_.reserve(static_cast<size_t>(8 * rank + 8));
  if (sparse_) pattern_ = SparseEt(model);  // the entries the joints' writers touch, whatever q
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
  // The block's structural entries in this chart, and Gs_ on that pattern (values written by
  // factor, the ordering computed once per chart).
  const int* row_start = pattern_.matrix().outerIndexPtr();
  triplets_.clear();
  for (int i = 0; i < r_; ++i) {
    const int row = chart_.rows[static_cast<size_t>(i)];
    const auto cols = pattern_.row_columns(row);
    for (size_t t = 0; t < cols.size(); ++t)
      if (const int k = dep_pos_[static_cast<size_t>(cols[t])]; k >= 0) {
        block_entries_.push_back({i, k, cols[t], row_start[row] + static_cast<int>(t), 0});
        triplets_.emplace_back(i, k, 1.0);
      }
  }
  Gs_.resize(r_, r_);
  Gs_.setFromTriplets(triplets_.begin(), triplets_.end());
  Gs_.makeCompressed();
  for (BlockEntry& e : block_entries_) {  // e.slot: the entry's place in Gs_'s values
    const int* begin = Gs_.innerIndexPtr() + Gs_.outerIndexPtr()[e.k];
    const int* end = Gs_.innerIndexPtr() + Gs_.outerIndexPtr()[e.k + 1];
    e.slot = static_cast<int>(std::lower_bound(begin, end, e.i) - Gs_.innerIndexPtr());
  }
}

bool ChartEngine::select(const MatX& Et, const VecX& A_diag) {
  if (selector_.select(Et, A_diag, options_, candidate_) != r_) return false;
  set_chart(candidate_);
  return true;
}

bool ChartEngine::select(const SparseEt& Et, const VecX& A_diag) {
  // (The start and a singular block's fallback only: not a hot path.)
  if (sparse_ && n_ >= kSparseSelectFrom) {
    const Eigen::SparseMatrix<double> E(Et.matrix());
    if (selector_.select_sparse(E, A_diag, options_, candidate_, r_) != r_) return false;
    set_chart(candidate_);
    return true;
  }
  MatX dense;
  Et.to_dense(dense);
  return select(dense, A_diag);
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

bool ChartEngine::begin_factor(const VecX& A_sqrt) {
  metric_ = A_sqrt;
  if (r_ == 0) return false;
  row_s_ = chart_.row_scale;
  col_s_ = metric_;
  return true;
}

double ChartEngine::factor(const MatX& Et, const VecX& A_sqrt) {
  if (!begin_factor(A_sqrt)) return quality_ = 1.0;
  const VecX& S_R = row_s_;
  const VecX& S_D = col_s_;
  if (!sparse_) {
    const int* rows = chart_.rows.data();
    for (int k = 0; k < r_; ++k) {
      const int dk = chart_.dependent[static_cast<size_t>(k)];
      const auto column = Et.col(dk);  // (the loop reads it at the chart's rows)
      const double s_d = S_D(dk);
      auto g = G_.col(k);
      for (int i = 0; i < r_; ++i) g(i) = S_R(i) * column(rows[i]) * s_d;
    }
    // Unblocked in-place LU (numerics/small_lu.hpp; Eigen's blocked path costs more than the
    // factorisation itself at r ≈ 20, measured with bench/simulate_bench.cpp).
    return quality_ = lu_factor(G_, piv_);
  }
  double* g = Gs_.valuePtr();
  for (const BlockEntry& e : block_entries_)  // the structural entries, zero or not
    g[e.slot] = S_R(e.i) * Et(chart_.rows[static_cast<size_t>(e.i)], e.column) * S_D(e.column);
  return factor_sparse();
}

double ChartEngine::factor(const SparseEt& Et, const VecX& A_sqrt) {
  if (!begin_factor(A_sqrt)) return quality_ = 1.0;
  const VecX& S_R = row_s_;
  const VecX& S_D = col_s_;
  if (!sparse_) {  // the chart's rows of Eᵀ scattered into the dense block
    G_.setZero();
    for (int i = 0; i < r_; ++i) {
      const int row = chart_.rows[static_cast<size_t>(i)];
      const auto cols = Et.row_columns(row);
      const auto vals = Et.row_values(row);
      for (size_t t = 0; t < cols.size(); ++t)
        if (const int k = dep_pos_[static_cast<size_t>(cols[t])]; k >= 0)
          G_(i, k) = S_R(i) * vals[t] * S_D(cols[t]);
    }
    return quality_ = lu_factor(G_, piv_);
  }
  if (Et.nonZeros() != pattern_.nonZeros())
    throw std::logic_error("ChartEngine::factor: Eᵀ is not on the model's pattern");
  const double* v = Et.values();
  double* g = Gs_.valuePtr();
  for (const BlockEntry& e : block_entries_) g[e.slot] = S_R(e.i) * v[e.value] * S_D(e.column);
  return factor_sparse();
}

double ChartEngine::factor_sparse() {
  // The pattern, hence the ordering (KLU's BTF and AMD), is fixed within a chart: analysed once
  // per chart.
  if (!analyzed_) {
    if (!slu_.analyze(Gs_)) return quality_ = 0.0;  // structurally singular
    analyzed_ = true;
  }
  if (!slu_.factorize(Gs_)) return quality_ = 0.0;
  return quality_ = rated_ ? slu_.pivot_ratio() : 1.0;
}

double ChartEngine::update(const MatX& Et, const VecX& A_diag, const VecX& A_sqrt, double t) {
  return update_at(Et, A_diag, A_sqrt, t);
}

double ChartEngine::update(const SparseEt& Et, const VecX& A_diag, const VecX& A_sqrt, double t) {
  return update_at(Et, A_diag, A_sqrt, t);
}

template <typename Jacobian>
double ChartEngine::update_at(const Jacobian& Et, const VecX& A_diag, const VecX& A_sqrt,
                              double t) {
  if (!ready_) {
    rule_ = ChartSwitchRule(options_.switch_below, options_.hysteresis,
                            ChartSwitchRule::Retry::every_time);
    if (select_candidate(Et, A_diag) != r_) return quality_ = 0.0;
    set_chart(candidate_);
    return factor(Et, A_sqrt);
  }
  const double kept = factor(Et, A_sqrt);
  if (!rule_.due(kept)) return kept;
  // The chart degraded: the QR's best chart, if the rule takes it.
  if (select_candidate(Et, A_diag) != r_) {  // another rank: a change point is near
    rule_.refused(kept);
    return kept;  // LU untouched
  }
  std::swap(chart_, candidate_);  // (swaps the index vectors: no allocation)
  index_chart();
  const double best = factor(Et, A_sqrt);
  if (rule_.better(best, kept)) {
    rule_.switched();
    ++switch_count_;
    if (switches_.size() < kMaxRecordedSwitches) switches_.push_back({t, kept, best});
    return best;
  }
  rule_.refused(kept);
  std::swap(chart_, candidate_);
  index_chart();
  return factor(Et, A_sqrt);  // the LU of the chart kept
}

int ChartEngine::select_candidate(const MatX& Et, const VecX& A_diag) {
  if (!rated_) return selector_.select(Et, A_diag, options_, candidate_);
  // The rated sparse path: the sparse QR's choice on Eᵀ's pattern (the dense QRs were 87 % of a
  // 360-position cycle of the N = 200 four-bar).
  for (int i = 0; i < pattern_.rows(); ++i) {
    const auto row = pattern_.row(i);
    for (int t = 0; t < row.count; ++t) row.values[t] = Et(i, row.columns[t]);
  }
  const Eigen::SparseMatrix<double> E(pattern_.matrix());
  return selector_.select_sparse(E, A_diag, options_, candidate_, r_);
}

int ChartEngine::select_candidate(const SparseEt& Et, const VecX& A_diag) {
  if (!rated_) {
    if (dense_Et_.rows() != Et.rows() || dense_Et_.cols() != Et.cols())
      dense_Et_.resize(Et.rows(), Et.cols());  // once
    dense_Et_.setZero();
    Et.copy_values_to(dense_Et_);
    return selector_.select(dense_Et_, A_diag, options_, candidate_);
  }
  if (Et.nonZeros() != pattern_.nonZeros())
    throw std::logic_error("ChartEngine::update: Eᵀ is not on the model's pattern");
  const Eigen::SparseMatrix<double> E(Et.matrix());  // the sparse QR's column-major input
  return selector_.select_sparse(E, A_diag, options_, candidate_, r_);
}

int ChartEngine::determinant_sign() const {
  if (sparse_) return slu_.determinant_sign();
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
    slu_.solve_in_place(x.data());
  } else {
    lu_solve(G_, piv_, x);
  }
}

void ChartEngine::solve_transposed_in_place(Eigen::Ref<VecX> x) {
  if (sparse_) {
    slu_.solve_transposed_in_place(x.data());
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

void ChartEngine::basis(const SparseEt& Et, VecX& b, VecX& x, MatX& F) {
  for (int k = 0; k < n_ - r_; ++k) {
    const int ik = chart_.independent[static_cast<size_t>(k)];
    b.setZero();
    for (const SparseEt::Entry& e : Et.column(ik)) b(e.row) = -Et.values()[e.index];
    solve(b, x);
    x(ik) = 1.0;
    F.col(k) = x;
  }
}

void ChartEngine::solve_dependent(MatX& rhs, MatX& out) {
  // No columns (DOF 0): nothing to solve, and rows of an empty matrix would offset a null pointer.
  if (r_ == 0 || out.cols() == 0) return;
  // Column by column (vector solves are far cheaper than blocked matrix paths for the small
  // blocks of linkages; plain loops: a linkage's F has one column or a few).
  for (Eigen::Index c = 0; c < out.cols(); ++c) {
    auto b = rhs.col(c).head(r_);
    for (int i = 0; i < r_; ++i) b(i) *= row_s_(i);
    solve_in_place(b);
    for (int k = 0; k < r_; ++k) {
      const int dk = chart_.dependent[static_cast<size_t>(k)];
      out(dk, c) = col_s_(dk) * b(k);
    }
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

template <typename Jacobian>
double ChartEngine::polish(VecX& q, Jacobian& Et, VecX& f, VecX& dq, int iterations,
                           ChartCorrection::Start start) {
  const VecX A_sqrt = metric_;  // (stages of a passage only)
  if (start == ChartCorrection::Start::evaluate) {
    compute_constraint_residual_and_jacobian(*model_, q, f, Et);
    if (!(factor(Et, A_sqrt) > 0.0)) return f.size() ? f.cwiseAbs().maxCoeff() : 0.0;
  }
  double residual = f.size() ? f.cwiseAbs().maxCoeff() : 0.0;
  for (int it = 0; it < iterations && residual > 0.0; ++it) {
    solve(f, dq);
    VecX trial = q;
    integrate_positions(*model_, trial, dq, -1.0);
    VecX f_trial(f.size());
    Jacobian Et_trial = Et;
    compute_constraint_residual_and_jacobian(*model_, trial, f_trial, Et_trial);
    const double r_trial = f_trial.cwiseAbs().maxCoeff();
    if (!(r_trial <= 0.5 * residual)) break;
    q = trial;
    f = f_trial;
    Et = Et_trial;
    residual = r_trial;
    if (!(factor(Et, A_sqrt) > 0.0)) break;
  }
  // The block is factorised at the returned q: a rejected trial leaves q, Eᵀ and the factors
  // as they were, an accepted one was factorised above.
  return residual;
}

template <typename Jacobian>
ChartCorrectionResult ChartEngine::correct(VecX& q, Jacobian& Et, VecX& f, VecX& dq,
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

double ChartEngine::polish_positions(VecX& q, MatX& Et, VecX& f, VecX& dq, int iterations,
                                     ChartCorrection::Start start) {
  return polish(q, Et, f, dq, iterations, start);
}
double ChartEngine::polish_positions(VecX& q, SparseEt& Et, VecX& f, VecX& dq, int iterations,
                                     ChartCorrection::Start start) {
  return polish(q, Et, f, dq, iterations, start);
}
ChartCorrectionResult ChartEngine::correct_positions(VecX& q, MatX& Et, VecX& f, VecX& dq,
                                                     const ChartCorrection& options) {
  return correct(q, Et, f, dq, options);
}
ChartCorrectionResult ChartEngine::correct_positions(VecX& q, SparseEt& Et, VecX& f, VecX& dq,
                                                     const ChartCorrection& options) {
  return correct(q, Et, f, dq, options);
}

}  // namespace orthomech
