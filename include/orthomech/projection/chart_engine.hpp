#pragma once
// The chart engine (docs/design.md §4): the one implementation of charts of the dual form, used by
// every command — `cycle`, `validate` and `crosscheck` through compute_basis (projection/dual.hpp),
// and `simulate` through its own instance. A chart (rows R, dependent components D, independent
// components I; projection/chart.hpp) gives
//   F = P [I; −(E_RDᵀ)⁻¹ E_RIᵀ].
// The engine
//   - chooses a chart: by the scaled rank-revealing QR (select) or from a basis F of the
//     admissible velocities, the tangent (select_from_tangent: near a change point this keeps
//     the branch by continuity of the last regular tangent);
//   - factorises the chart's block scaled to the mass metric, G = S_R E_RDᵀ S_D with
//     S_R = diag(row_scale) and S_D = diag(√A_kk) (dense LU for the small blocks of linkages,
//     sparse LU for large mechanisms when asked: Eᵀ has ≤ 6 non-zeros per row), and measures its
//     quality, min |U_kk| / max |U_kk| of the dense LU;
//   - switches charts with hysteresis when the quality degrades (update);
//   - solves E_RDᵀ x_D = b_R and the transposed system, and estimates σ_min of the block;
//   - corrects positions in the chart: Newton on f(q) = 0 with the independent coordinates fixed
//     (correct_positions), the one per-step position corrector of continuation and integration.
// Allocation-free after set-up on the dense path, except when a chart is switched; on the rated
// sparse path (the cycle of a large model) a chart choice (update, below its quality threshold)
// allocates in the sparse QR.
#include <Eigen/LU>
#include <Eigen/SparseCore>
#include <vector>

#include "orthomech/constraints/sparse_et.hpp"
#include "orthomech/model/model.hpp"
#include "orthomech/numerics/solve_result.hpp"
#include "orthomech/numerics/sparse_lu.hpp"
#include "orthomech/projection/chart.hpp"

namespace orthomech {

struct ChartEvent {
  double t;            // time (or input value) at the switch
  double quality_old;  // quality of the chart that was left
  double quality_new;  // quality of the chart that was entered
};

// How the chart's block is factorised. `dense` measures the quality (and the determinant's
// sign) that the switching policy and the cycle's change-point detection read; `sparse_when_large`
// uses a sparse LU above a rank of kSparseAbove (quality then only says singular or not: the
// owner monitors σ_min instead, as simulate does); `rated_sparse_when_large` uses the sparse LU
// from kRatedSparseFrom velocities on and measures the quality and the determinant's sign there
// as the dense path does (min |U_kk| / max |U_kk| of the sparse LU's own pivots), for owners
// that switch on the quality: the cycle of a large mechanism.
enum class ChartFactorisation { dense, sparse_when_large, rated_sparse_when_large };

// Options of ChartEngine::correct_positions.
struct ChartCorrection {
  double tolerance = 1e-12;  // max |f_k| (m, rad)
  int max_iterations = 8;
  // > 0: a first Newton step larger than max_gain · |f| (the block is nearly singular: a change
  // point is close and Newton could jump to another branch) is not taken; q is left as it was
  // and the result says converged with near_singular set.
  double max_gain = 0.0;
  // The caller has already computed f = f(q), Et = Eᵀ(q) and factorised the block at the given
  // q: the first iteration uses them.
  enum class Start { evaluate, prepared } start = Start::evaluate;
};

struct ChartCorrectionResult : SolveResult {
  bool near_singular = false;  // see ChartCorrection::max_gain
};

class ChartEngine {
 public:
  ChartEngine(const Model& model, int rank,
              ChartFactorisation factorisation = ChartFactorisation::dense);

  // ---- Choosing a chart
  // At Eᵀ by the scaled rank-revealing QR (projection/chart.hpp). False when the rank found
  // differs from the branch's rank (the chart is then unchanged).
  bool select(const MatX& Et, const VecX& A_diag);
  bool select(const SparseEt& Et, const VecX& A_diag);
  // Keeps the rows R and chooses I from a basis F of the admissible velocities: the n_a
  // components where F, scaled to the mass metric (rows × √M_kk), is best conditioned (QR with
  // column pivoting of (S F)ᵀ). For n_a = 1 this is the component that moves most, so every
  // entry of the new F is ≤ 1 in the mass metric.
  void select_from_tangent(const MatX& F, const VecX& M_sqrt);
  void set_chart(const Chart& c);
  // Forces a fresh choice at the next update.
  void reset() { ready_ = false; }

  // ---- Factorising
  // Factorises G = S_R E_RDᵀ S_D at Eᵀ with S_D = diag(A_sqrt) (kept for the solves and the
  // corrector). Returns the quality (1 on the sparse path), 0 when singular.
  double factor(const MatX& Et, const VecX& A_sqrt);
  // The same from Eᵀ on its structural pattern (SparseEt of the same model).
  double factor(const SparseEt& Et, const VecX& A_sqrt);
  // The switching policy (compute_basis): a fresh QR choice when no chart is ready; otherwise
  // ChartSwitchRule (projection/chart.hpp) on the quality with the threshold
  // options().switch_below, the factor options().hysteresis and a retry at every evaluation:
  // the chart is left for the QR's best one when that is better by the factor (recorded in
  // switches(), at t).
  // Leaves the block factorised in the chart kept. Returns the quality, 0 when the chart is
  // singular or its rank is not the branch's. On the rated sparse path the choice is the sparse
  // QR's (ChartSelector::select_sparse: its rows, and the dependent components where the
  // admissible velocities are best conditioned), a sparse factorisation instead of O(n³).
  double update(const MatX& Et, const VecX& A_diag, const VecX& A_sqrt, double t);
  // The same from Eᵀ on its structural pattern (SparseEt of the same model): no n_c × n matrix.
  // Off the rated sparse path a QR choice goes through a dense copy of Eᵀ (a scratch sized once).
  double update(const SparseEt& Et, const VecX& A_diag, const VecX& A_sqrt, double t);

  // ---- Solving (after factor)
  // x (size n): x_D = (E_RDᵀ)⁻¹ b_R, x_I = 0 (b of size nc).
  void solve(const VecX& b, VecX& x);
  // F (n × n_a) = P [I; −(E_RDᵀ)⁻¹ E_RIᵀ] at Eᵀ (factorised there): column k is one solve with
  // −(Eᵀ's column of the independent coordinate k), 1 at that coordinate. Eᵀ F = 0 on the chart's
  // rows, hence on all rows. Scratch: b (nc), x (n). Allocation-free.
  void basis(const SparseEt& Et, VecX& b, VecX& x, MatX& F);
  // rhs (r × m, rows in chart order) ← (E_RDᵀ)⁻¹ rhs, written into the dependent rows of out
  // (n × m; its other rows untouched). rhs is overwritten.
  void solve_dependent(MatX& rhs, MatX& out);
  // λ_R (size r, chart row order) solving E_RD λ_R = c_D, c of size n: the unique λ of E λ = c
  // on the chart's rows when c ∈ range(E).
  void solve_transposed(const VecX& c, Eigen::Ref<VecX> lambda_r);
  // Estimate of the smallest singular value of B̃ = E_RDᵀ S_D: two steps of inverse iteration
  // on (B̃ᵀB̃)⁻¹, warm-started from w (size r, kept by the caller between calls). Returns
  // 1/‖B̃⁻ᵀ ŵ‖ for the unit iterate ŵ, an upper bound of σ_min that converges to it; near a
  // change point σ_min → 0 linearly in the distance to it. With `left` given, it receives the
  // unit left singular vector estimate ŷ (size r, indexed by the chart's rows) paired with the
  // returned w (indexed by D, not normalised): B̃ w = c ŷ, c > 0, so that dσ_min/dt ≈ ŷᵀ (dB̃/dt) ŵ
  // [Stewart & Sun 1990, §IV.2].
  [[nodiscard]] double estimate_sigma_min(VecX& w, VecX* left = nullptr);

  // ---- Correcting positions in the chart
  // Newton on f(q) = 0, Δq_D = (E_RDᵀ)⁻¹ f_R, the independent coordinates fixed. On a converged
  // return Et = Eᵀ(q) at the returned q and the block is factorised there (F is one solve away).
  // Scratch: f (nc), dq (n).
  ChartCorrectionResult correct_positions(VecX& q, MatX& Et, VecX& f, VecX& dq,
                                          const ChartCorrection& options);
  ChartCorrectionResult correct_positions(VecX& q, SparseEt& Et, VecX& f, VecX& dq,
                                          const ChartCorrection& options);
  // Newton beyond a tolerance: from a corrected q while max |f| falls by at least half per
  // iteration (at most `iterations`), down to rounding. Leaves f, Eᵀ at the returned q,
  // factorised in the chart. Returns max |f|. Start::prepared: f, Eᵀ are those at q and the
  // block is factorised there already (as a converged correct_positions leaves them).
  double polish_positions(VecX& q, MatX& Et, VecX& f, VecX& dq, int iterations,
                          ChartCorrection::Start start = ChartCorrection::Start::evaluate);
  double polish_positions(VecX& q, SparseEt& Et, VecX& f, VecX& dq, int iterations,
                          ChartCorrection::Start start = ChartCorrection::Start::evaluate);

  // ---- State
  [[nodiscard]] const Chart& chart() const { return chart_; }
  [[nodiscard]] bool ready() const { return ready_; }
  [[nodiscard]] double quality() const { return quality_; }
  // Sign of det G of the last factorisation (signs of U_kk and of the interchanges; on the sparse
  // path of SparseLu::determinant_sign).
  [[nodiscard]] int determinant_sign() const;
  [[nodiscard]] long switch_count() const { return switch_count_; }
  [[nodiscard]] const std::vector<ChartEvent>& switches() const { return switches_; }
  [[nodiscard]] ChartOptions& options() { return options_; }
  [[nodiscard]] const ChartSelector& selector() const { return selector_; }
  [[nodiscard]] int rank() const { return r_; }
  [[nodiscard]] int na() const { return n_ - r_; }
  [[nodiscard]] bool sparse() const { return sparse_; }

  // Above this rank a `sparse_when_large` engine factorises sparse (dense LU is cheaper for the
  // small blocks of ordinary linkages; measured in bench/simulate_bench.cpp).
  static constexpr int kSparseAbove = 48;
  // select(SparseEt) chooses by the sparse QR (ChartSelector::select_sparse) from n = 600 on
  // (n-four-bar-100: n = 603), where the dense QRs' O(n³) dominates a run's start; below, the
  // dense choice (the charts every test of smaller mechanisms was validated with) is kept.
  static constexpr int kSparseSelectFrom = 600;
  // From this many velocities on a `rated_sparse_when_large` engine factorises sparse (the cycle:
  // n-four-bar-100, n = 603, spent half of each position in the dense LU of its 602 × 602 block,
  // and from N = 60, n = 363, the dense LU's pivot ratio stayed so low around a change point that
  // its bridge failed). 300 until 2026-11-29; at 100 the driven N-four-bar from N = 17 takes the
  // sparse path (N = 40, n = 243: 0.29 → 0.04 s for 360 positions, drive on its closed form to
  // 1.5e-10 of its peak). Every bundled mechanism a `cycle` runs on has n < 100.
  static constexpr int kRatedSparseFrom = 100;

 private:
  bool begin_factor(const VecX& A_sqrt);  // the scalings; false when r = 0
  // update's choice at a dense Eᵀ into candidate_: the dense QRs, or on the rated sparse path the
  // sparse QR on Eᵀ's pattern (ChartSelector::select_sparse). Returns the rank found.
  int select_candidate(const MatX& Et, const VecX& A_diag);
  int select_candidate(const SparseEt& Et, const VecX& A_diag);
  template <typename Jacobian>
  double update_at(const Jacobian& Et, const VecX& A_diag, const VecX& A_sqrt, double t);
  double factor_sparse();  // Gs_ (values written) → slu_
  template <typename Jacobian>
  ChartCorrectionResult correct(VecX& q, Jacobian& Et, VecX& f, VecX& dq,
                                const ChartCorrection& options);
  template <typename Jacobian>
  double polish(VecX& q, Jacobian& Et, VecX& f, VecX& dq, int iterations,
                ChartCorrection::Start start);
  void index_chart();  // dep_pos_, block_entries_ of chart_
  void solve_in_place(Eigen::Ref<VecX> x);
  void solve_transposed_in_place(Eigen::Ref<VecX> x);

  const Model* model_;
  int n_, r_;
  bool sparse_;
  bool rated_;  // sparse_ and the quality measured (rated_sparse_when_large)
  Chart chart_;
  Chart candidate_;  // update's QR choice (kept: no allocation once sized)
  ChartSelector selector_;
  ChartOptions options_;
  bool ready_ = false;
  ChartSwitchRule rule_{ChartOptions{}.switch_below, ChartOptions{}.hysteresis,
                        ChartSwitchRule::Retry::every_time};  // update's rule
  double quality_ = 0.0;
  long switch_count_ = 0;
  std::vector<ChartEvent> switches_;
  std::vector<int> dep_pos_;  // n: position of a component in chart.dependent, or −1
  VecX metric_;               // n: √A_kk given to the last factor (σ_min's metric)
  VecX row_s_;                // r: S_R of the last factorisation
  VecX col_s_;                // n: S_D of the last factorisation
  MatX G_;                    // r × r (dense path): G, then its LU factors (small_lu.hpp)
  Eigen::VectorXi piv_;       // r: row interchanges of the dense LU
  Eigen::SparseMatrix<double> Gs_;
  SparseLu slu_;  // the sparse path's LU (KLU: pivots reused while they stay good)
  std::vector<Eigen::Triplet<double>> triplets_;
  // Structural pattern of Eᵀ (SparseEt: the entries the joints' writers touch, sparse engines
  // only). block_entries_: (row of the block, column of the block, column of Eᵀ, index of
  // the entry in a SparseEt's values, index in Gs_'s values) of the block's structural entries in
  // the current chart, so that factor writes O(non-zeros) values into a pattern fixed within the
  // chart, hence one ordering per chart.
  SparseEt pattern_;
  struct BlockEntry {
    int i, k, column, value, slot;
  };
  std::vector<BlockEntry> block_entries_;
  bool analyzed_ = false;  // slu_ has the ordering of Gs_'s pattern in this chart
  VecX br_;                // r
  MatX dense_Et_;          // select_candidate(SparseEt) off the rated path: Eᵀ copied (n_c × n)
  VecX sw_;                // r: work vector of estimate_sigma_min
};

}  // namespace orthomech
