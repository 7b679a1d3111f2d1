#pragma once
// Charts for the dual form (docs/design.md §4). A global basis F of admissible velocities does not
// exist in general (paper §5, last paragraph), so F is built by coordinate partitioning in charts:
//   - `rows`: r = rank(Eᵀ) independent constraint rows (the others are redundant),
//   - `dependent`: r velocity components D whose block E_RDᵀ is best conditioned,
//   - `independent`: the n_a = n − r others, I; the chart's coordinates are v = u_I.
// Then F = P [I; −(E_RDᵀ)⁻¹ E_RIᵀ] (eq. (68) needs only Eᵀ F = 0 and rank F = n_a).
// Both choices come from rank-revealing QR with column pivoting on Eᵀ scaled to the mass metric
// (columns by 1/√M_kk, rows to unit length), so they do not depend on units.
#include <Eigen/QR>
#include <Eigen/SparseCore>
#include <algorithm>
#include <vector>

#include "orthomech/model/model.hpp"

namespace orthomech {

struct ChartOptions {
  // A constraint row is redundant when its pivot |R_kk| ≤ rank_tolerance · |R_11| in the scaled,
  // column-pivoted QR of E (docs/theory.md, "Rank and redundancy").
  double rank_tolerance = 1e-8;
  // Switch charts when the current chart's quality (min |U_kk| / max |U_kk| of the LU of the
  // scaled dependent block) falls below switch_below and the best chart is better by the factor
  // hysteresis.
  double switch_below = 0.05;
  double hysteresis = 2.0;
};

// The one chart-switching rule, with hysteresis on a chart's quality (larger is better; the
// owner says what it measures: ChartEngine::update the LU's pivot ratio, simulate 1/spread of F).
// A switch is due when the quality is below the retry threshold, at first `threshold`. A
// candidate is taken only when better than the kept chart by `factor`. After a refusal (no
// candidate is that much better, or the candidate has another rank: a change point is near,
// where every chart is poor) the retry policy says when to look again:
//   - every_time: at the next evaluation below the threshold. The kept chart's quality is then
//     within `factor` of the best chart's wherever a switch is due: the cycle reads it as the
//     distance to a change point (ChangePointBridger).
//   - after_further_fall: only once the quality has fallen by `factor` more; the threshold comes
//     back as the quality recovers. For an owner whose attempt costs a new basis F (simulate).
class ChartSwitchRule {
 public:
  enum class Retry { every_time, after_further_fall };
  ChartSwitchRule(double threshold, double factor, Retry retry)
      : threshold_(threshold), factor_(factor), retry_(retry), retry_below_(threshold) {}
  // True: look for a better chart now. False: keep the chart (the threshold follows a recovery).
  bool due(double quality) {
    if (quality < retry_below_) return true;
    if (quality > factor_ * retry_below_) retry_below_ = std::min(threshold_, quality / factor_);
    return false;
  }
  [[nodiscard]] bool better(double candidate, double kept) const {
    return candidate > factor_ * kept;
  }
  void switched() { retry_below_ = threshold_; }
  void refused(double quality) {
    if (retry_ == Retry::after_further_fall) retry_below_ = quality / factor_;
  }
  [[nodiscard]] double retry_below() const { return retry_below_; }

 private:
  double threshold_, factor_;
  Retry retry_;
  double retry_below_;
};

struct Chart {
  std::vector<int> rows;         // r independent constraint rows
  std::vector<int> dependent;    // r dependent velocity components
  std::vector<int> independent;  // n_a independent velocity components
  Eigen::VectorXd row_scale;     // r: scaling of the rows at selection (fixed within the chart)
  [[nodiscard]] int rank() const { return static_cast<int>(rows.size()); }
};

// Scaled rank-revealing factorisation of Eᵀ, preallocated (docs/design.md §4).
class ChartSelector {
 public:
  ChartSelector(int nc, int n);
  // Chooses rows and the dependent/independent split at the current Eᵀ and the diagonal of A.
  // Returns the rank. Allocation-free for a given (nc, n) after construction, except for the
  // index vectors of `chart` (resized only if the rank changed).
  int select(const MatX& Et, const VecX& A_diag, const ChartOptions& options, Chart& chart);
  // The same by a sparse QR (sparse_row_rank) for large mechanisms, where the two dense QRs cost
  // O(n³) (N = 400 four-bar, n = 2403: 90 % of a 12.8 s run): rows = those the sparse QR keeps;
  // dependent components = all but the n_a where an orthonormal basis of the admissible
  // velocities in the mass metric is best conditioned (QR with column pivoting of its
  // transpose, as ChartEngine::select_from_tangent).
  // Allocates (a start or a fallback, not a hot path); row_pivots()/row_order() are not updated.
  // With `required_rank` ≥ 0, a rank other than it is returned at once, `chart` unchanged (the
  // caller takes only a chart of its rank: next to a change point the tangent basis would have
  // n − rank ≈ N columns and cost O(N² n) for nothing).
  int select_sparse(const Eigen::SparseMatrix<double>& Et, const VecX& A_diag,
                    const ChartOptions& options, Chart& chart, int required_rank = -1);
  // |R_kk| / |R_11| of the last dense row selection (size nc, in pivot order), for reports.
  [[nodiscard]] const VecX& row_pivots() const { return row_pivots_; }
  [[nodiscard]] const std::vector<int>& row_order() const { return row_order_; }

 private:
  MatX scaled_E_;        // n × nc: (Eᵀ)ᵀ with rows scaled by √A_kk and columns normalised
  MatX scaled_Et_rows_;  // r × n
  Eigen::ColPivHouseholderQR<MatX> qr_rows_;
  Eigen::ColPivHouseholderQR<MatX> qr_cols_;
  VecX row_pivots_;
  std::vector<int> row_order_;
};

// Rank and redundant rows of Eᵀ (n_c × n) by a sparse QR of S = diag(√A) E with unit columns
// (docs/theory.md, "Rank and redundancy"; compute_mobility's sparse path and select_sparse).
struct SparseRowRank {
  int rank = 0;
  std::vector<int> redundant_rows;  // the rows the QR dropped, in the order dropped
  double smallest_pivot = 0.0;      // smallest kept |R_kk| (the columns have unit length)
  double largest_dropped = 0.0;     // largest part of a dropped row outside the kept ones' span
  // With request.tangent: n × (n − rank), an orthonormal basis of {x : Sᵀx = 0}, i.e. of the
  // admissible velocities u = diag(√A) x in the mass metric (x = √M u for a diagonal M).
  MatX tangent;
};
// What sparse_row_rank computes beyond the rank and the redundant rows: largest_dropped (one
// product with Qᵀ per dropped row), and the tangent basis (one product with Q per column) only
// where the rank is tangent_rank (any rank when negative).
struct SparseRowRankRequest {
  bool largest_dropped = true;
  bool tangent = false;
  int tangent_rank = -1;
};
[[nodiscard]] SparseRowRank sparse_row_rank(const Eigen::SparseMatrix<double>& Et,
                                            const VecX& A_diag, double tolerance,
                                            const SparseRowRankRequest& request);

}  // namespace orthomech
