#include "orthomech/projection/chart.hpp"

#include <algorithm>

namespace orthomech {

ChartSelector::ChartSelector(int nc, int n)
    : scaled_E_(n, nc),
      scaled_Et_rows_(nc, n),
      qr_rows_(n, nc),
      qr_cols_(nc, n),
      row_pivots_(nc),
      row_order_(static_cast<size_t>(nc)) {}

int ChartSelector::select(const MatX& Et, const VecX& A_diag, const ChartOptions& options,
                          Chart& chart) {
  const Eigen::Index nc = Et.rows(), n = Et.cols();
  if (nc == 0) {  // no constraints: every velocity component is independent
    chart.rows.clear();
    chart.dependent.clear();
    chart.independent.resize(static_cast<size_t>(n));
    for (Eigen::Index k = 0; k < n; ++k)
      chart.independent[static_cast<size_t>(k)] = static_cast<int>(k);
    chart.row_scale.resize(0);
    return 0;
  }
  // 1. Rows: QR with column pivoting of E = (Eᵀ)ᵀ in the metric A (each constraint row scaled
  //    by 1/‖row‖_A so that units and joint sizes do not bias the choice).
  VecX& scale = chart.row_scale;
  scaled_E_ = Et.transpose();
  for (Eigen::Index k = 0; k < n; ++k) scaled_E_.row(k) *= std::sqrt(A_diag(k));
  for (Eigen::Index c = 0; c < nc; ++c) {
    const double norm = scaled_E_.col(c).norm();
    if (norm > 0.0) scaled_E_.col(c) /= norm;
  }
  qr_rows_.compute(scaled_E_);
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

}  // namespace orthomech
