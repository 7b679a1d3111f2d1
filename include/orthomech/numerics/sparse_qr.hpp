#pragma once
// A rank-revealing sparse QR of an m × k matrix S: S P = Q R, P a column permutation whose first
// `rank` columns are the ones kept, Q orthogonal (m × m, in Householder form), R upper trapezoidal
// with R(0:rank, 0:rank) upper triangular. A column whose part orthogonal to the columns kept
// before it has a norm at or below the tolerance is dropped (moved behind the kept ones).
// The rank and redundancy of E for large mechanisms (projection/chart.hpp: sparse_row_rank).
//
// SuiteSparseQR (Debian's libsuitesparse-dev) does it: a COLAMD fill-reducing column order, a
// multifrontal Householder QR with Heath's rank detection [Davis 2011, Algorithm 915, §2], Q kept
// as its Householder vectors. Eigen's SparseQR (left-looking, rows not reordered) gave the same
// answers but its Householder vectors filled in where E drops rank by many: on the N-four-bar at
// a change point (rank short by N) 6.7 / 157 / 2075 ms at N = 100 / 400 / 1000, SuiteSparseQR
// 0.6 / 1.1 / 3.7 ms (docs/performance.md). Its header stays in the implementation.
#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <memory>
#include <vector>

namespace orthomech {

class SparseRankQr {
 public:
  // Factorises S (compressed columns). Throws std::runtime_error if SuiteSparseQR fails (out of
  // memory), std::invalid_argument if S is not compressed.
  SparseRankQr(const Eigen::SparseMatrix<double>& S, double tolerance);
  ~SparseRankQr();
  SparseRankQr(const SparseRankQr&) = delete;
  SparseRankQr& operator=(const SparseRankQr&) = delete;

  [[nodiscard]] int rank() const { return rank_; }
  // P as a list: column k of S P is column column_order()[k] of S; kept columns first.
  [[nodiscard]] const std::vector<int>& column_order() const { return order_; }
  // |R_kk| for k < rank (the kept columns' parts orthogonal to the columns kept before them).
  [[nodiscard]] const Eigen::VectorXd& kept_pivots() const { return pivots_; }
  // Qᵀ X and Q X for a dense X with m rows.
  [[nodiscard]] Eigen::MatrixXd apply_Qt(const Eigen::MatrixXd& X) const;
  [[nodiscard]] Eigen::MatrixXd apply_Q(const Eigen::MatrixXd& X) const;
  // Q's last m − rank columns: an orthonormal basis of the orthogonal complement of the kept
  // columns' span ({x : Sᵀx = 0} when the dropped columns are exactly in that span).
  [[nodiscard]] Eigen::MatrixXd trailing_Q() const;

 private:
  struct Spqr;  // CHOLMOD's common object and the Householder form of Q
  std::unique_ptr<Spqr> spqr_;
  int rank_ = 0;
  std::vector<int> order_;
  Eigen::VectorXd pivots_;
};

}  // namespace orthomech
