#pragma once
// Private: the dependent block of a chart (design §4) factorised for the integrators, dense LU
// for small mechanisms and sparse LU for large ones (Eᵀ of a linkage has ≤ 6 non-zeros per row,
// so the sparse factorisation keeps the cost per step near-linear in the number of bodies).
//
// A chart (rows R, dependent components D, independent components I; projection/chart.hpp)
// gives F = P [I; −(E_RDᵀ)⁻¹ E_RIᵀ]. This class solves E_RDᵀ x_D = b_R (x_I = 0) and the
// transposed system E_RD λ_R = c_D, and corrects positions in the chart.
#include <Eigen/LU>
#include <Eigen/SparseCore>
#include <Eigen/SparseLU>
#include <string>
#include <vector>

#include "orthomech/analysis/positions.hpp"
#include "orthomech/model/model.hpp"
#include "orthomech/projection/chart.hpp"

namespace orthomech::detail {

class ChartSolver {
 public:
  ChartSolver(const Model& model, int rank);
  // Chooses a chart at Eᵀ (rank-revealing QR; projection/chart.hpp). Returns false when the
  // rank found differs from the branch's rank.
  bool select(const MatX& Et, const VecX& A_diag);
  // Keeps the rows R and chooses the independent components I from a basis F of the admissible
  // velocities: the n_a components where F, scaled to the mass metric (rows × √M_kk), is best
  // conditioned (QR with column pivoting of (S F)ᵀ). For n_a = 1 this is the component that
  // moves most, so every entry of the new F is ≤ 1 in the mass metric. Near a change point this
  // keeps the branch by continuity of the tangent: F is the current branch tangent.
  void select_from_tangent(const MatX& F, const VecX& M_sqrt);
  // Factorises E_RDᵀ at Eᵀ. Returns false when it is singular.
  bool factor(const MatX& Et);
  // x (size n): x_D = (E_RDᵀ)⁻¹ b_R, x_I = 0 (b of size nc). Allocation-free (dense path).
  void solve(const VecX& b, VecX& x);
  // λ (size nc): λ_R = (E_RD)⁻¹ c_D, other rows 0 (c of size n). The unique λ of E λ = c when
  // E has full column rank and c ∈ range(E).
  void solve_transposed(const MatX& Et, const VecX& c, VecX& lambda);
  // Newton in the chart on f(q) = 0: the independent coordinates stay fixed. With max_gain > 0,
  // a first Newton step larger than max_gain · |f| (the dependent block is nearly singular: a
  // change point is close, and Newton could jump to another branch) is not taken: q is left
  // as it was, *near_singular is set and the result says converged.
  // On a converged return Et = Eᵀ(q) at the returned q and the dependent block is factorised
  // there (F is one compute away: no second evaluation at the same q). With prepared = true
  // the caller has already computed f = f(q), Et = Eᵀ(q) and factorised it at the given q:
  // the first iteration uses them.
  SolveResult correct_positions(VecX& q, MatX& Et, VecX& f, VecX& dq, double tolerance,
                                double max_gain = 0.0, bool* near_singular = nullptr,
                                bool prepared = false);
  // Newton in the chart beyond a tolerance: iterates from a corrected q while max |f| falls by
  // at least half per iteration (at most `iterations`), down to rounding. Next to a change point
  // F off f(q) = 0 is the tangent of the level set f = c, which bends away from the branch by
  // ~c/σ² at a distance σ: the passage evaluates its equations at positions polished to
  // rounding. Leaves f, Eᵀ at the returned q, factorised in the chart. Returns max |f|.
  double polish_positions(VecX& q, MatX& Et, VecX& f, VecX& dq, int iterations);
  // Estimate of the smallest singular value of the factorised block scaled to the mass metric,
  // σ_min(E_RDᵀ S_D) with S = diag(col_scale) (col_scale = 1/√M_kk): two steps of inverse
  // iteration on (B̃ᵀB̃)⁻¹, B̃ = E_RDᵀ S_D, warm-started from w (size rank, kept by the caller
  // between calls). Returns 1/‖B̃⁻ᵀ ŵ‖ for the unit iterate ŵ, an upper bound of σ_min that
  // converges to it. Near a change point σ_min → 0 linearly in the distance to it (E loses
  // rank there, so does every chart block). Allocation-free on the dense path.
  // With `left` given, it receives the unit left singular vector estimate ŷ (size rank, indexed
  // by the chart's rows) paired with the returned w (right, indexed by D, not normalised):
  // B̃ w = c ŷ with c > 0, so that dσ_min/dt ≈ ŷᵀ (dB̃/dt) ŵ (first-order perturbation of a simple
  // singular value [Stewart & Sun 1990, §IV.2]; used by simulate's change-point monitor).
  [[nodiscard]] double estimate_sigma_min(const VecX& col_scale, VecX& w, VecX* left = nullptr);
  [[nodiscard]] const Chart& chart() const { return chart_; }
  void set_chart(const Chart& c);
  [[nodiscard]] int rank() const { return r_; }
  [[nodiscard]] int na() const { return n_ - r_; }

 private:
  void structural_pattern();  // fills row_columns_ (sparse path)

  const Model& model_;
  int n_, nc_, r_;
  bool sparse_;
  Chart chart_;
  ChartSelector selector_;
  ChartOptions options_;
  std::vector<int> dep_pos_;  // n: position of a component in chart.dependent, or −1
  MatX ED_;                   // r × r (dense path): E_RDᵀ, then its LU factors (small_lu.hpp)
  Eigen::VectorXi piv_;       // r: row interchanges of the dense LU
  Eigen::SparseMatrix<double> EDs_;
  Eigen::SparseLU<Eigen::SparseMatrix<double>, Eigen::COLAMDOrdering<int>> slu_;
  std::vector<Eigen::Triplet<double>> triplets_;
  // Structural pattern of Eᵀ (sparse path): the columns each row can have non-zero, from Eᵀ at
  // two generic positions (an entry that vanishes at one position, sin 0, does not at the
  // other). block_entries_: (row of the block, column of the block, column of Eᵀ) of the
  // dependent block's structural entries in the current chart (set_chart), so that factor
  // reads O(non-zeros) entries instead of scanning r × n, and the block's pattern, hence its
  // ordering, stays the same within a chart.
  std::vector<std::vector<int>> row_columns_;
  struct BlockEntry {
    int i, k, column;
  };
  std::vector<BlockEntry> block_entries_;
  bool analyzed_ = false;  // slu_ has the ordering of pattern_*
  std::vector<int> pattern_inner_, pattern_outer_;
  VecX br_, xd_;  // r
  VecX sw_;       // r: work vector of estimate_sigma_min
};

}  // namespace orthomech::detail
