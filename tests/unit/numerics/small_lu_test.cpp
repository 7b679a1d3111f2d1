// The small in-place LU against Eigen's FullPivLU solves (an independent algorithm) on random
// and on badly scaled matrices, plain and transposed; a singular matrix has quality 0.
#include "orthomech/numerics/small_lu.hpp"

#include <gtest/gtest.h>

#include <Eigen/LU>

namespace orthomech {
namespace {

TEST(SmallLu, SolvesLikeFullPivotingLu) {
  std::srand(11);
  for (int n : {1, 2, 5, 8, 9, 21}) {
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

TEST(SmallLu, QualityOfSingularAndDiagonalMatrices) {
  Eigen::MatrixXd A(3, 3);
  A << 1, 2, 3, 2, 4, 6, 0, 1, 1;  // row 2 = 2 × row 1
  Eigen::VectorXi piv(3);
  EXPECT_EQ(lu_factor(A, piv), 0.0);
  Eigen::MatrixXd D = Eigen::Vector3d(4.0, -2.0, 0.5).asDiagonal();
  EXPECT_DOUBLE_EQ(lu_factor(D, piv), 0.125);  // min |U_kk| / max |U_kk|
}

}  // namespace
}  // namespace orthomech
