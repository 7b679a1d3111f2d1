// G = B diag(a) Bᵀ on its fixed pattern (include/orthomech/numerics/weighted_gram.hpp) against
// the dense product written here and Eigen's dense LDLT of it: G's entries (through the order
// the class reports), solves, new values and weights on the same pattern, and dependent rows
// (G singular) reported. One B is the N = 40 four-bar's Eᵀ, the matrix simulate gives it.
#include "orthomech/numerics/weighted_gram.hpp"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <random>
#include <vector>

#include "orthomech/constraints/sparse_et.hpp"
#include "support/fixtures.hpp"

namespace orthomech {
namespace {

using RowMajor = WeightedGram::RowMajorMatrix;

RowMajor random_rows(int m, int n, int per_row, std::mt19937& gen) {
  std::uniform_real_distribution<double> value(-1.0, 1.0);
  std::uniform_int_distribution<int> col(0, n - 1);
  std::vector<Eigen::Triplet<double>> entries;
  for (int i = 0; i < m; ++i) {
    entries.emplace_back(i, i % n, 2.0 + value(gen));  // rows independent in practice
    for (int k = 0; k < per_row; ++k) entries.emplace_back(i, col(gen), value(gen));
  }
  RowMajor B(m, n);
  B.setFromTriplets(entries.begin(), entries.end());
  B.makeCompressed();
  return B;
}

Eigen::VectorXd random_weights(Eigen::Index n, std::mt19937& gen) {
  std::uniform_real_distribution<double> w(0.1, 10.0);
  Eigen::VectorXd a(n);
  for (Eigen::Index k = 0; k < n; ++k) a(k) = w(gen);
  return a;
}

// G's entries and x = G⁻¹ b against the dense product and a dense LDLᵀ.
void expect_matches_dense(WeightedGram& gram, const RowMajor& B, const Eigen::VectorXd& a,
                          std::mt19937& gen) {
  const Eigen::MatrixXd Bd = Eigen::MatrixXd(B);
  const Eigen::MatrixXd G = Bd * a.asDiagonal() * Bd.transpose();
  const Eigen::MatrixXd Gp = Eigen::MatrixXd(gram.permuted_upper());
  const auto& pos = gram.order();
  for (Eigen::Index i = 0; i < G.rows(); ++i)
    for (Eigen::Index j = i; j < G.cols(); ++j) {
      const int r = std::min(pos[i], pos[j]), s = std::max(pos[i], pos[j]);
      EXPECT_NEAR(Gp(r, s), G(i, j), 1e-13 * G.norm()) << i << ", " << j;
    }
  std::uniform_real_distribution<double> value(-1.0, 1.0);
  Eigen::VectorXd b(B.rows());
  for (Eigen::Index i = 0; i < b.size(); ++i) b(i) = value(gen);
  Eigen::VectorXd x(B.rows());
  gram.solve(b, x);
  const Eigen::VectorXd x_ref = G.ldlt().solve(b);
  EXPECT_LT((x - x_ref).norm(), 1e-9 * x_ref.norm());
  EXPECT_LT((G * x - b).norm(), 1e-12 * G.norm() * x.norm());
}

TEST(WeightedGram, FormsAndSolvesGOnItsPatternAsTheDenseProduct) {
  std::mt19937 gen(5);
  RowMajor B = random_rows(40, 70, 3, gen);
  WeightedGram gram;
  gram.analyze(B);
  for (int k = 0; k < 4; ++k) {  // new values and weights on the same pattern
    if (k > 0)
      for (Eigen::Index i = 0; i < B.nonZeros(); ++i) B.valuePtr()[i] *= 1.0 + 0.3 * k;
    const Eigen::VectorXd a = random_weights(B.cols(), gen);
    ASSERT_TRUE(gram.factorize(B, a)) << k;
    expect_matches_dense(gram, B, a, gen);
  }
}

TEST(WeightedGram, NFourBarConstraintJacobian) {
  const Model model = test::load_bundled("n-four-bar-40");
  SparseEt Et(model);
  compute_constraint_jacobian(model, model.design_q(), Et);
  std::mt19937 gen(6);
  WeightedGram gram;
  gram.analyze(Et.matrix());
  const Eigen::VectorXd a = random_weights(model.n, gen);
  // The bundled chain's constraints are independent at the design position: G is regular.
  ASSERT_TRUE(gram.factorize(Et.matrix(), a));
  expect_matches_dense(gram, Et.matrix(), a, gen);
}

// Two equal rows: G = B A Bᵀ is singular, reported.
TEST(WeightedGram, ReportsDependentRows) {
  std::mt19937 gen(7);
  RowMajor B = random_rows(6, 9, 2, gen);
  Eigen::MatrixXd Bd = Eigen::MatrixXd(B);
  Bd.row(4) = Bd.row(1);
  RowMajor S = Bd.sparseView(0.0, 0.0);
  S.makeCompressed();
  WeightedGram gram;
  gram.analyze(S);
  EXPECT_FALSE(gram.factorize(S, random_weights(9, gen)));
}

}  // namespace
}  // namespace orthomech
