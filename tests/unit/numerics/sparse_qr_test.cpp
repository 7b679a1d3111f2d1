// The rank-revealing sparse QR (SuiteSparseQR; include/orthomech/numerics/sparse_qr.hpp) against
// dense oracles on the same matrix: the rank from a singular value decomposition, the kept
// columns' Gram determinant (|det R₁₁|² = det(S_Kᵀ S_K)), the dropped columns' distance from the
// kept ones' span by a dense least-squares solve, and the orthogonal projector onto the
// complement of that span (I − S_K (S_Kᵀ S_K)⁻¹ S_Kᵀ) against trailing_Q.
#include "orthomech/numerics/sparse_qr.hpp"

#include <gtest/gtest.h>

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace orthomech {
namespace {

using Sparse = Eigen::SparseMatrix<double>;
using Eigen::MatrixXd;

// m × k: `per_column` random entries a column in [−1, 1]; the last `deficient` columns are
// combinations of two earlier ones (so the rank is k − deficient almost surely).
Sparse random_deficient(int m, int k, int per_column, int deficient, unsigned seed) {
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> value(-1.0, 1.0);
  std::uniform_int_distribution<int> row(0, m - 1);
  MatrixXd D = MatrixXd::Zero(m, k);
  for (int j = 0; j < k - deficient; ++j)
    for (int e = 0; e < per_column; ++e) D(row(gen), j) += value(gen);
  std::uniform_int_distribution<int> col(0, k - deficient - 1);
  for (int j = k - deficient; j < k; ++j) D.col(j) = value(gen) * D.col(col(gen)) + D.col(col(gen));
  Sparse S = D.sparseView();
  S.makeCompressed();
  return S;
}

int svd_rank(const MatrixXd& D, double tolerance) {
  const Eigen::JacobiSVD<MatrixXd> svd(D);
  const Eigen::VectorXd s = svd.singularValues();
  return static_cast<int>((s.array() > tolerance).count());
}

MatrixXd columns(const MatrixXd& D, const std::vector<int>& order, int from, int to) {
  MatrixXd out(D.rows(), to - from);
  for (int c = from; c < to; ++c) out.col(c - from) = D.col(order[static_cast<size_t>(c)]);
  return out;
}

void expect_factorisation_right(const Sparse& S, double tolerance) {
  const MatrixXd D(S);
  const SparseRankQr qr(S, tolerance);
  const int m = static_cast<int>(S.rows());
  const int k = static_cast<int>(S.cols());
  const int r = qr.rank();
  // The rank, and P a permutation.
  EXPECT_EQ(r, svd_rank(D, 1e-9));
  std::vector<int> sorted = qr.column_order();
  std::sort(sorted.begin(), sorted.end());
  for (int j = 0; j < k; ++j) ASSERT_EQ(sorted[static_cast<size_t>(j)], j);
  // The kept columns: independent, with ∏|R_kk| = √det(S_Kᵀ S_K).
  const MatrixXd K = columns(D, qr.column_order(), 0, r);
  const MatrixXd gram = K.transpose() * K;
  ASSERT_EQ(qr.kept_pivots().size(), r);
  EXPECT_GT(qr.kept_pivots().minCoeff(), tolerance);
  const double log_det = 0.5 * std::log(gram.determinant());
  EXPECT_NEAR(qr.kept_pivots().array().log().sum(), log_det, 1e-9 * (1.0 + std::abs(log_det)));
  // The dropped columns lie in the kept ones' span (least squares by a dense QR).
  const MatrixXd dropped = columns(D, qr.column_order(), r, k);
  if (dropped.cols() > 0) {
    const MatrixXd fit = K.colPivHouseholderQr().solve(dropped);
    EXPECT_LT((K * fit - dropped).norm(), 1e-10);
    // ... and Qᵀ s has nothing below row r, within rounding.
    EXPECT_LT(qr.apply_Qt(dropped).bottomRows(m - r).norm(), 1e-10);
  }
  // trailing_Q: orthonormal, and its projector is the dense one onto the complement.
  const MatrixXd T = qr.trailing_Q();
  ASSERT_EQ(T.rows(), m);
  ASSERT_EQ(T.cols(), m - r);
  EXPECT_LT((T.transpose() * T - MatrixXd::Identity(m - r, m - r)).norm(), 1e-12);
  const MatrixXd complement = MatrixXd::Identity(m, m) - K * gram.ldlt().solve(K.transpose());
  EXPECT_LT((T * T.transpose() - complement).norm(), 1e-10);
  // Q is orthogonal: Qᵀ(Q X) = X.
  const MatrixXd X = MatrixXd::Random(m, 3);
  EXPECT_LT((qr.apply_Qt(qr.apply_Q(X)) - X).norm(), 1e-12);
}

TEST(SparseRankQr, FullRankTallMatrixAgreesWithDenseOracles) {
  expect_factorisation_right(random_deficient(60, 30, 3, 0, 1u), 1e-8);
}

TEST(SparseRankQr, RankDeficientMatrixKeepsIndependentColumns) {
  for (unsigned seed = 2; seed < 6; ++seed)
    expect_factorisation_right(random_deficient(80, 50, 3, 7, seed), 1e-8);
}

TEST(SparseRankQr, EmptyRowsBelongToTheComplement) {
  // Rows 0 and 5 are empty: each is a unit vector of the complement.
  std::vector<Eigen::Triplet<double>> e{{1, 0, 1.0}, {2, 0, 1.0}, {2, 1, 2.0}, {3, 1, -1.0},
                                        {4, 2, 1.0}, {1, 3, 2.0}, {2, 3, 2.0}};  // col 3 = 2 col 0
  Sparse S(6, 4);
  S.setFromTriplets(e.begin(), e.end());
  S.makeCompressed();
  expect_factorisation_right(S, 1e-8);
  const SparseRankQr qr(S, 1e-8);
  EXPECT_EQ(qr.rank(), 3);
  const MatrixXd T = qr.trailing_Q();
  EXPECT_NEAR(T.row(0).norm(), 1.0, 1e-14);
  EXPECT_NEAR(T.row(5).norm(), 1.0, 1e-14);
}

TEST(SparseRankQr, TheToleranceDecidesWhatIsDropped) {
  // Column 2 = column 0 + 1e-3 e₃: dropped at tolerance 1e-2, kept at 1e-4 with |R| = 1e-3.
  std::vector<Eigen::Triplet<double>> e{{0, 0, 1.0}, {1, 1, 1.0}, {0, 2, 1.0}, {2, 2, 1e-3}};
  Sparse S(3, 3);
  S.setFromTriplets(e.begin(), e.end());
  S.makeCompressed();
  const SparseRankQr loose(S, 1e-2);
  EXPECT_EQ(loose.rank(), 2);
  // Whichever of columns 0 and 2 comes first, the other's distance from it is 1e-3 (to 1e-9).
  const int dropped = loose.column_order()[2];
  EXPECT_TRUE(dropped == 0 || dropped == 2);
  const MatrixXd column = MatrixXd(S).col(dropped);
  EXPECT_NEAR(loose.apply_Qt(column).bottomRows(1).norm(), 1e-3, 1e-9);
  const SparseRankQr tight(S, 1e-4);
  EXPECT_EQ(tight.rank(), 3);
  EXPECT_NEAR(tight.kept_pivots().minCoeff(), 1e-3, 1e-9);
}

TEST(SparseRankQr, RejectsAnUncompressedMatrix) {
  Sparse S(3, 3);
  S.insert(0, 0) = 1.0;  // not compressed after insert
  EXPECT_THROW(SparseRankQr(S, 1e-8), std::invalid_argument);
}

}  // namespace
}  // namespace orthomech
