// The small in-place LU against Eigen's FullPivLU solves (an independent algorithm) on random
// and on badly scaled matrices, plain and transposed, at every order with a kernel of its own
// (1 … kFixedLuMax) and beyond it (the general loops); in a block of a larger matrix (leading
// dimension > order); a singular matrix has quality 0 on both paths.
#include "orthomech/numerics/small_lu.hpp"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <vector>

namespace orthomech {
namespace {

TEST(SmallLu, SolvesLikeFullPivotingLu) {
  std::srand(11);
  std::vector<int> orders;
  for (int n = 1; n <= kFixedLuMax + 2; ++n) orders.push_back(n);
  orders.push_back(21);
  for (int n : orders) {
    for (int trial = 0; trial < 20; ++trial) {
      Eigen::MatrixXd A = Eigen::MatrixXd::Random(n, n);
      if (trial % 2) A.row(0) *= 1e-6;  // badly scaled rows need the pivoting
      const Eigen::VectorXd b = Eigen::VectorXd::Random(n);
      const Eigen::FullPivLU<Eigen::MatrixXd> ref(A);
      Eigen::MatrixXd LU = A;
      Eigen::VectorXi piv(n);
      ASSERT_GT(lu_factor(LU, piv), 0.0);
      Eigen::VectorXd x = b;
      lu_solve(LU, piv, x);
      const Eigen::VectorXd x_ref = ref.solve(b);
      EXPECT_LT((x - x_ref).norm(), 1e-9 * (1.0 + x_ref.norm())) << n;
      // Backward stable: ‖Ax − b‖ ≲ n ε ‖A‖ ‖x‖.
      EXPECT_LT((A * x - b).norm(), 1e-14 * n * A.norm() * x.norm() + 1e-15 * b.norm()) << n;
      Eigen::VectorXd y = b;
      lu_solve_transposed(LU, piv, y);
      const Eigen::VectorXd y_ref = ref.transpose().solve(b);
      EXPECT_LT((y - y_ref).norm(), 1e-9 * (1.0 + y_ref.norm())) << n;
    }
  }
}

// The factors in the top-left block of a larger matrix (outer stride > order): the fixed-order
// kernels index with the block's leading dimension; the rest of the matrix is left untouched.
TEST(SmallLu, FactorsAndSolvesInABlockOfALargerMatrix) {
  std::srand(12);
  for (int n : {3, 8, kFixedLuMax, kFixedLuMax + 3}) {
    const Eigen::MatrixXd A = Eigen::MatrixXd::Random(n, n);
    Eigen::MatrixXd big = Eigen::MatrixXd::Constant(n + 5, n + 2, 7.0);
    big.topLeftCorner(n, n) = A;
    auto block = big.topLeftCorner(n, n);
    Eigen::VectorXi piv(n);
    ASSERT_GT(lu_factor(block, piv), 0.0);
    const Eigen::VectorXd b = Eigen::VectorXd::Random(n);
    Eigen::VectorXd x = b;
    lu_solve(block, piv, x);
    EXPECT_LT((A * x - b).norm(), 1e-13 * n * A.norm() * x.norm()) << n;
    Eigen::VectorXd y = b;
    lu_solve_transposed(block, piv, y);
    EXPECT_LT((A.transpose() * y - b).norm(), 1e-13 * n * A.norm() * y.norm()) << n;
    EXPECT_TRUE((big.bottomRows(5).array() == 7.0).all()) << n;
    EXPECT_TRUE((big.rightCols(2).array() == 7.0).all()) << n;
  }
}

TEST(SmallLu, QualityOfSingularAndDiagonalMatrices) {
  Eigen::MatrixXd A(3, 3);
  A << 1, 2, 3, 2, 4, 6, 0, 1, 1;  // row 2 = 2 × row 1
  Eigen::VectorXi piv(3);
  EXPECT_EQ(lu_factor(A, piv), 0.0);
  Eigen::MatrixXd D = Eigen::Vector3d(4.0, -2.0, 0.5).asDiagonal();
  EXPECT_DOUBLE_EQ(lu_factor(D, piv), 0.125);  // min |U_kk| / max |U_kk|
  // The same beyond the fixed orders (the general loops).
  const int n = kFixedLuMax + 4;
  Eigen::MatrixXd S = Eigen::MatrixXd::Random(n, n);
  S.row(n - 1) = 2.0 * S.row(0);
  Eigen::VectorXi piv_n(n);
  EXPECT_EQ(lu_factor(S, piv_n), 0.0);
  Eigen::MatrixXd Dn = Eigen::VectorXd::LinSpaced(n, 1.0, 10.0).asDiagonal();
  EXPECT_DOUBLE_EQ(lu_factor(Dn, piv_n), 0.1);
}

}  // namespace
}  // namespace orthomech
