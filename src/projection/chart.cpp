#include "orthomech/projection/chart.hpp"

#include <algorithm>
#include <cmath>

#include "orthomech/numerics/sparse_qr.hpp"

namespace orthomech {

namespace {

using SparseMat = Eigen::SparseMatrix<double>;  // column-major

// No constraints: every velocity component is independent.
int unconstrained_chart(Eigen::Index n, Chart& chart) {
  chart.rows.clear();
  chart.dependent.clear();
  chart.independent.resize(static_cast<size_t>(n));
  for (Eigen::Index k = 0; k < n; ++k)
    chart.independent[static_cast<size_t>(k)] = static_cast<int>(k);
  chart.row_scale.resize(0);
  return 0;
}

}  // namespace

// The dense buffers (n × nc each, 4 of them) are sized at the first dense select: a large model
// whose charts are chosen on the sparse path (select_sparse, the chart engine's sparse
// factorisation) never touches them, and a 2400-body spatial chain (n = 14400, n_c = 7200)
// reserved 3.3 GB for them per selector (issue 47).
ChartSelector::ChartSelector(int nc, int /*n: sized at the first select*/)
    : row_pivots_(nc), row_order_(static_cast<size_t>(nc)) {}

int ChartSelector::select(const MatX& Et, const VecX& A_diag, const ChartOptions& options,
                          Chart& chart) {
  const Eigen::Index nc = Et.rows(), n = Et.cols();
  if (nc == 0) return unconstrained_chart(n, chart);
  // 1. Rows: QR with column pivoting of E = (Eᵀ)ᵀ in the metric A (each constraint row scaled
  //    by 1/‖row‖_A so that units and joint sizes do not bias the choice).
  VecX& scale = chart.row_scale;
  scaled_E_ = Et.transpose();
  for (Eigen::Index k = 0; k < n; ++k) scaled_E_.row(k) *= std::sqrt(A_diag(k));
  for (Eigen::Index c = 0; c < nc; ++c) {
    const double norm = scaled_E_.col(c).norm();
    if (norm > 0.0) scaled_E_.col(c) /= norm;
  }
  qr_rows_.compute(scaled_E_);  // allocates at the first call of a size only
  const auto& R = qr_rows_.matrixR();
  const Eigen::Index kmax = std::min(n, nc);
  const double r11 = kmax > 0 ? std::abs(R(0, 0)) : 0.0;
  int rank = 0;
  for (Eigen::Index k = 0; k < nc; ++k) {
    row_order_[static_cast<size_t>(k)] = static_cast<int>(qr_rows_.colsPermutation().indices()(k));
    row_pivots_(k) = (k < kmax && r11 > 0.0) ? std::abs(R(k, k)) / r11 : 0.0;
    if (k < kmax && r11 > 0.0 && row_pivots_(k) > options.rank_tolerance) ++rank;
  }
  chart.rows.assign(row_order_.begin(), row_order_.begin() + rank);
  std::sort(chart.rows.begin(), chart.rows.end());
  scale.resize(rank);
  for (int k = 0; k < rank; ++k) {
    const double norm =
        (Et.row(chart.rows[static_cast<size_t>(k)]).transpose().cwiseProduct(A_diag.cwiseSqrt()))
            .norm();
    scale(k) = norm > 0.0 ? 1.0 / norm : 1.0;
  }
  // 2. Columns: QR with column pivoting of the selected rows of Eᵀ, columns scaled by √A_kk;
  //    the first r pivots are the dependent components (best-conditioned block).
  if (scaled_Et_rows_.rows() != nc || scaled_Et_rows_.cols() != n) scaled_Et_rows_.resize(nc, n);
  auto rows_block = scaled_Et_rows_.topRows(rank);
  for (int k = 0; k < rank; ++k)
    rows_block.row(k) =
        scale(k) *
        Et.row(chart.rows[static_cast<size_t>(k)]).cwiseProduct(A_diag.cwiseSqrt().transpose());
  qr_cols_.compute(rows_block);
  const auto& cols = qr_cols_.colsPermutation().indices();
  chart.dependent.assign(cols.data(), cols.data() + rank);
  chart.independent.assign(cols.data() + rank, cols.data() + n);
  std::sort(chart.dependent.begin(), chart.dependent.end());
  std::sort(chart.independent.begin(), chart.independent.end());
  return rank;
}

int ChartSelector::select_sparse(const SparseMat& Et, const VecX& A_diag,
                                 const ChartOptions& options, Chart& chart, int required_rank) {
  const Eigen::Index n = Et.cols();
  if (Et.rows() == 0) return unconstrained_chart(n, chart);
  // 1. Rows: those the sparse QR keeps (the same scaled matrix as the dense step 1).
  const SparseRowRank s =
      sparse_row_rank(Et, A_diag, options.rank_tolerance,
                      {.largest_dropped = false, .tangent = true, .tangent_rank = required_rank});
  if (required_rank >= 0 && s.rank != required_rank) return s.rank;
  std::vector<char> redundant(static_cast<size_t>(Et.rows()), 0);
  for (const int row : s.redundant_rows) redundant[static_cast<size_t>(row)] = 1;
  chart.rows.clear();
  for (int row = 0; row < Et.rows(); ++row)
    if (!redundant[static_cast<size_t>(row)]) chart.rows.push_back(row);
  const int rank = s.rank;
  VecX norm2 = VecX::Zero(Et.rows());  // ‖row‖² in the metric A
  for (Eigen::Index k = 0; k < Et.outerSize(); ++k)
    for (SparseMat::InnerIterator it(Et, k); it; ++it)
      norm2(it.row()) += it.value() * it.value() * A_diag(k);
  chart.row_scale.resize(rank);
  for (int k = 0; k < rank; ++k) {
    const double norm = std::sqrt(norm2(chart.rows[static_cast<size_t>(k)]));
    chart.row_scale(k) = norm > 0.0 ? 1.0 / norm : 1.0;
  }
  // 2. Columns: the n_a independent components where the orthonormal tangent basis (mass
  //    metric) is best conditioned: the first n_a pivots of the QR of its transpose.
  const Eigen::Index na = n - rank;
  std::vector<int> order(static_cast<size_t>(n));
  if (na > 0) {
    const Eigen::ColPivHouseholderQR<MatX> qr(s.tangent.transpose());
    for (Eigen::Index k = 0; k < n; ++k)
      order[static_cast<size_t>(k)] = qr.colsPermutation().indices()(k);
  } else {
    for (Eigen::Index k = 0; k < n; ++k) order[static_cast<size_t>(k)] = static_cast<int>(k);
  }
  chart.independent.assign(order.begin(), order.begin() + na);
  chart.dependent.assign(order.begin() + na, order.end());
  std::sort(chart.dependent.begin(), chart.dependent.end());
  std::sort(chart.independent.begin(), chart.independent.end());
  return rank;
}

// Rank and redundant rows by a sparse QR of the same scaled matrix as ChartSelector::select's step
// 1 (docs/theory.md, "Rank and redundancy"):
//   (L1) S = diag(√A) E (n × n_c), each column (a constraint row) normalised to unit length;
//   (L2) S P = Q R, rank-revealing sparse QR (numerics/sparse_qr.hpp: SuiteSparseQR, COLAMD
//        order): a column whose part orthogonal to the columns kept before it, |R_kk|, is at or
//        below the tolerance is dropped (moved behind the kept ones) [Davis 2011, Algorithm 915,
//        §2];
//   (L3) r = the number kept; the dropped columns are the redundant rows. Each is within the
//        tolerance of the span of the kept ones, ‖(Qᵀ s_c)_{r…}‖ ≤ tolerance: largest_dropped.
// The columns are unit vectors (|R_11| = 1 in the dense QR), so the same tolerance applies to
// |R_kk| directly. Without column pivoting R's diagonal is not ordered: smallest_pivot is the
// smallest kept |R_kk|.
//   (L4) with request.tangent: Q's columns r … n − 1 span {x : Sᵀx = 0} (an empty row of S, a
//        component no constraint touches, is one of them).
SparseRowRank sparse_row_rank(const SparseMat& Et, const VecX& A_diag, double tolerance,
                              const SparseRowRankRequest& request) {
  SparseRowRank m;
  const int n = static_cast<int>(Et.cols());
  const int nc = static_cast<int>(Et.rows());
  if (nc == 0) {
    if (request.tangent) m.tangent = MatX::Identity(n, n);
    return m;
  }
  SparseMat S = Et.transpose();  // n × n_c
  const VecX sqrt_A = A_diag.cwiseSqrt();
  for (Eigen::Index c = 0; c < S.outerSize(); ++c) {  // (L1)
    double norm2 = 0.0;
    for (SparseMat::InnerIterator it(S, c); it; ++it) {
      it.valueRef() *= sqrt_A(it.row());
      norm2 += it.value() * it.value();
    }
    if (norm2 > 0.0) S.col(c) /= std::sqrt(norm2);
  }
  S.makeCompressed();
  const SparseRankQr qr(S, tolerance);  // (L2)
  m.rank = qr.rank();                   // (L3)
  const std::vector<int>& order = qr.column_order();
  m.smallest_pivot = m.rank > 0 ? std::min(1.0, qr.kept_pivots().minCoeff()) : 0.0;
  m.redundant_rows.assign(order.begin() + m.rank, order.end());
  if (request.largest_dropped) {
    constexpr int kBlock = 64;  // dropped columns per product with Qᵀ (bounds the dense block)
    for (int first = m.rank; first < nc; first += kBlock) {
      const int count = std::min(kBlock, nc - first);
      MatX block = MatX::Zero(n, count);
      for (int c = 0; c < count; ++c)
        for (SparseMat::InnerIterator it(S, order[static_cast<size_t>(first + c)]); it; ++it)
          block(it.row(), c) = it.value();
      const MatX Qt_s = qr.apply_Qt(block);
      for (int c = 0; c < count; ++c)
        m.largest_dropped = std::max(m.largest_dropped, Qt_s.col(c).tail(n - m.rank).norm());
    }
  }
  if (!request.tangent || (request.tangent_rank >= 0 && m.rank != request.tangent_rank)) return m;
  m.tangent = qr.trailing_Q();  // (L4)
  return m;
}

}  // namespace orthomech
