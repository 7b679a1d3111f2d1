#pragma once
// A sparse LU of a square matrix whose pattern stays fixed over many factorisations with changing
// values: the chart's block of large mechanisms in `simulate` (projection/chart_engine.hpp), one
// factorisation per right-hand-side evaluation.
//
// SuiteSparse's KLU (Debian's libsuitesparse-dev) does it: a block-triangular (BTF) and AMD
// ordering once per pattern (analyze), a left-looking Gilbert–Peierls LU with partial pivoting
// (fresh factorisation), and a refactorisation with the same pivot sequence, which neither
// searches for pivots nor allocates. A refactorisation whose pivots are no longer good (pivot
// growth above kMaxGrowth, or a zero pivot) is replaced by a fresh factorisation, which bounds
// what reusing the pivots can cost in accuracy (on the N-four-bar's charts the growth stayed
// below 10: N = 40 runs with a limit of 10 and of 1e3 are bit for bit the same). KLU's header
// stays in the implementation (src/numerics/).
#include <Eigen/SparseCore>
#include <memory>
#include <vector>

namespace orthomech {

class SparseLu {
 public:
  SparseLu();
  ~SparseLu();
  SparseLu(const SparseLu&) = delete;
  SparseLu& operator=(const SparseLu&) = delete;

  // The ordering of A's pattern (compressed columns, square). Forgets the factors. False when
  // KLU refuses the pattern (structurally singular).
  bool analyze(const Eigen::SparseMatrix<double>& A);
  // Factorises A, on the pattern given to analyze: by the last fresh factorisation's pivot
  // sequence while its pivot growth stays below kMaxGrowth, afresh otherwise. False when A is
  // singular (a zero pivot after fresh pivoting); the factors are then not usable.
  bool factorize(const Eigen::SparseMatrix<double>& A);
  // x ← A⁻¹ x and x ← A⁻ᵀ x (x of size n), with the factors of the last factorize.
  void solve_in_place(double* x);
  void solve_transposed_in_place(double* x);
  // Of the last successful factorize: min |U_kk| / max |U_kk| (KLU's klu_rcond, the measure the
  // dense LU of numerics/small_lu.hpp returns), and the sign of det A (the signs of U_kk and of
  // the row and column permutations; L has a unit diagonal and no scaling is applied).
  [[nodiscard]] double pivot_ratio();
  [[nodiscard]] int determinant_sign() const;

  // Largest growth max_j max|U_:j| / max|A_:j| accepted from a refactorisation (a fresh partial
  // pivoting of these blocks gives growth of order one).
  static constexpr double kMaxGrowth = 1e3;

  // Counts since construction (tests, benchmarks).
  [[nodiscard]] long fresh_factorisations() const { return fresh_; }
  [[nodiscard]] long refactorisations() const { return refactored_; }

 private:
  bool factor_fresh(const Eigen::SparseMatrix<double>& A);
  struct Klu;  // KLU's Common, Symbolic and Numeric objects
  std::unique_ptr<Klu> klu_;
  long fresh_ = 0, refactored_ = 0;
  mutable std::vector<char> seen_;  // determinant_sign's work space (sized once)
};

}  // namespace orthomech
