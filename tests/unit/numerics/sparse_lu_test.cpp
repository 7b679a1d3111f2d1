// The sparse LU (KLU; include/orthomech/numerics/sparse_lu.hpp) against Eigen's FullPivLU of the
// same matrix made dense (an independent algorithm): plain and transposed solves, on a fixed
// random pattern whose values change between factorisations (the reused pivots), on values that
// make the reused pivots bad (a fresh factorisation must follow), and on a singular matrix.
#include "orthomech/numerics/sparse_lu.hpp"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <algorithm>
#include <random>
#include <vector>

namespace orthomech {
namespace {

// n × n: the diagonal and `per_column` random entries a column, values in [−1, 1] (the diagonal
// in [1, 2]: the matrix is usually regular, and its values are then changed by the tests).
Eigen::SparseMatrix<double> random_sparse(int n, int per_column, std::mt19937& gen) {
  std::uniform_real_distribution<double> value(-1.0, 1.0);
  std::uniform_int_distribution<int> row(0, n - 1);
  std::vector<Eigen::Triplet<double>> entries;
  for (int j = 0; j < n; ++j) {
    entries.emplace_back(j, j, 1.5 + 0.5 * value(gen));
    for (int k = 0; k < per_column; ++k) entries.emplace_back(row(gen), j, value(gen));
  }
  Eigen::SparseMatrix<double> A(n, n);
  A.setFromTriplets(entries.begin(), entries.end());  // (duplicates summed)
  A.makeCompressed();
  return A;
}

// x = A⁻¹ b and y = A⁻ᵀ b by the sparse LU agree with the dense full-pivoting LU.
void expect_solves_agree(SparseLu& lu, const Eigen::SparseMatrix<double>& A, unsigned seed) {
  const Eigen::MatrixXd dense = Eigen::MatrixXd(A);
  const Eigen::FullPivLU<Eigen::MatrixXd> ref(dense);
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> value(-1.0, 1.0);
  Eigen::VectorXd b(A.rows());
  for (Eigen::Index i = 0; i < b.size(); ++i) b(i) = value(gen);
  Eigen::VectorXd x = b;
  lu.solve_in_place(x.data());
  const Eigen::VectorXd x_ref = ref.solve(b);
  EXPECT_LT((x - x_ref).norm(), 1e-10 * (1.0 + x_ref.norm()));
  EXPECT_LT((dense * x - b).norm(), 1e-13 * (1.0 + dense.norm() * x.norm()));
  Eigen::VectorXd y = b;
  lu.solve_transposed_in_place(y.data());
  const Eigen::VectorXd y_ref = ref.transpose().solve(b);
  EXPECT_LT((y - y_ref).norm(), 1e-10 * (1.0 + y_ref.norm()));
}

// One analysis, then new values on the same pattern: the first factorisation pivots, the others
// reuse its pivots (moderate changes keep the growth small), and every solve is right.
TEST(SparseLu, ReusesItsPivotsWhileTheValuesChangeAndSolvesRight) {
  std::mt19937 gen(3);
  Eigen::SparseMatrix<double> A = random_sparse(60, 3, gen);
  const Eigen::SparseMatrix<double> A0 = A;
  SparseLu lu;
  ASSERT_TRUE(lu.analyze(A));
  std::uniform_real_distribution<double> change(0.9, 1.1);
  for (int k = 0; k < 20; ++k) {
    if (k > 0)
      for (Eigen::Index i = 0; i < A.nonZeros(); ++i)
        A.valuePtr()[i] = A0.valuePtr()[i] * change(gen);
    ASSERT_TRUE(lu.factorize(A)) << k;
    expect_solves_agree(lu, A, 100 + static_cast<unsigned>(k));
  }
  EXPECT_EQ(lu.fresh_factorisations(), 1);
  EXPECT_EQ(lu.refactorisations(), 19);
}

// Values for which the first factorisation's pivot (the diagonal) becomes tiny: reusing it would
// grow the factors by ~1e12; the LU pivots afresh, and the solve is as accurate as the dense one.
TEST(SparseLu, PivotsAfreshWhenTheReusedPivotsWouldGrowTheFactors) {
  Eigen::MatrixXd dense(3, 3);
  dense << 4, 1, 0,  //
      1, 4, 1,       //
      0, 1, 4;
  Eigen::SparseMatrix<double> A = dense.sparseView(0.0, 0.0);
  A.makeCompressed();
  SparseLu lu;
  ASSERT_TRUE(lu.analyze(A));
  ASSERT_TRUE(lu.factorize(A));
  expect_solves_agree(lu, A, 1);
  dense(0, 0) = 1e-12;  // the diagonal pivot of column 0 all but vanishes
  Eigen::SparseMatrix<double> B = dense.sparseView(0.0, 0.0);
  B.makeCompressed();
  ASSERT_EQ(B.nonZeros(), A.nonZeros());
  ASSERT_TRUE(lu.factorize(B));
  EXPECT_EQ(lu.refactorisations(), 1);
  EXPECT_EQ(lu.fresh_factorisations(), 2);  // the refactorisation was refused
  expect_solves_agree(lu, B, 2);
}

// A singular matrix (two equal columns) is reported, after the pivots were reused and afresh.
TEST(SparseLu, ReportsASingularMatrix) {
  Eigen::MatrixXd dense(3, 3);
  dense << 2, 1, 1,  //
      1, 3, 3,       //
      0, 1, 1;
  Eigen::MatrixXd regular = dense;
  regular(2, 2) = 5.0;
  Eigen::SparseMatrix<double> A = regular.sparseView(0.0, 0.0);
  A.makeCompressed();
  SparseLu lu;
  ASSERT_TRUE(lu.analyze(A));
  ASSERT_TRUE(lu.factorize(A));
  Eigen::SparseMatrix<double> S = dense.sparseView(0.0, 0.0);
  S.makeCompressed();
  ASSERT_EQ(S.nonZeros(), A.nonZeros());
  EXPECT_FALSE(lu.factorize(S));
  EXPECT_EQ(lu.fresh_factorisations(), 2);
  // And regular again: factorised afresh, right.
  ASSERT_TRUE(lu.factorize(A));
  expect_solves_agree(lu, A, 3);
}

}  // namespace
}  // namespace orthomech

namespace orthomech {
namespace {

// The sign of det A and min |U_kk| / max |U_kk| (the chart engine's quality on the rated sparse
// path). References: the sign of the dense full-pivoting LU's determinant; for a permuted diagonal
// matrix P D, whatever KLU's ordering, the pivots are D's entries (ratio min|d|/max|d|) and the
// sign is sign(P) · Π sign(d_k), both known here.
TEST(SparseLu, DeterminantSignAndPivotRatio) {
  std::mt19937 gen(11);
  int negative = 0;
  for (int trial = 0; trial < 40; ++trial) {
    Eigen::SparseMatrix<double> A = random_sparse(30 + trial, 3, gen);
    std::uniform_real_distribution<double> value(-1.0, 1.0);
    for (Eigen::Index k = 0; k < A.nonZeros(); ++k) A.valuePtr()[k] = value(gen);
    SparseLu lu;
    ASSERT_TRUE(lu.analyze(A));
    if (!lu.factorize(A)) continue;  // (singular draws are not the point here)
    const double det = Eigen::FullPivLU<Eigen::MatrixXd>(Eigen::MatrixXd(A)).determinant();
    ASSERT_NE(det, 0.0);
    EXPECT_EQ(lu.determinant_sign(), det > 0.0 ? 1 : -1) << trial;
    negative += det < 0.0;
    const double ratio = lu.pivot_ratio();
    EXPECT_GT(ratio, 0.0);
    EXPECT_LE(ratio, 1.0);
  }
  EXPECT_GT(negative, 5);  // both signs were met
  // A permuted diagonal matrix: row i holds d_i in column p(i).
  const int n = 7;
  const int p[n] = {3, 0, 6, 1, 2, 5, 4};  // cycles (0 3 1)(2 6 4)(5): even
  const double d[n] = {2.0, -0.5, 4.0, 1.0, -8.0, 0.25, 3.0};
  for (const int swap_first_two : {0, 1}) {
    int q[n];
    std::copy(p, p + n, q);
    if (swap_first_two) std::swap(q[0], q[1]);  // one transposition more: odd
    std::vector<Eigen::Triplet<double>> t;
    for (int i = 0; i < n; ++i) t.emplace_back(i, q[i], d[i]);
    Eigen::SparseMatrix<double> P(n, n);
    P.setFromTriplets(t.begin(), t.end());
    P.makeCompressed();
    SparseLu lu;
    ASSERT_TRUE(lu.analyze(P));
    ASSERT_TRUE(lu.factorize(P));
    // Π sign(d) = (−)(−) = +; the permutation's sign: + then −.
    EXPECT_EQ(lu.determinant_sign(), swap_first_two ? -1 : 1);
    EXPECT_DOUBLE_EQ(lu.pivot_ratio(), 0.25 / 8.0);
  }
}

}  // namespace
}  // namespace orthomech
