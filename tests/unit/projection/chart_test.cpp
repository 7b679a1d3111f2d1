// Choosing a chart (src/projection/chart.cpp): the scaled rank-revealing QR of Eᵀ. Oracles: the
// rank of a matrix built with a known dependent row, the row scale 1/‖row ⊙ √A‖ computed here,
// the dependent component of a one-row Eᵀ (the largest entry in the mass metric, so a change of
// units does not change the choice), and the partition of the components.
#include "orthomech/projection/chart.hpp"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <numeric>
#include <vector>

#include "orthomech/analysis/mobility.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "unit/analysis/large_mechanisms.hpp"

namespace orthomech {
namespace {

void expect_partition(const Chart& c, int n) {
  std::vector<int> all = c.dependent;
  all.insert(all.end(), c.independent.begin(), c.independent.end());
  std::sort(all.begin(), all.end());
  std::vector<int> expected(static_cast<size_t>(n));
  std::iota(expected.begin(), expected.end(), 0);
  EXPECT_EQ(all, expected);
  EXPECT_TRUE(std::is_sorted(c.dependent.begin(), c.dependent.end()));
  EXPECT_TRUE(std::is_sorted(c.independent.begin(), c.independent.end()));
}

TEST(Chart, FullRankRowsAndScales) {
  MatX Et(3, 5);
  Et << 1, 2, 0, -1, 0.5,  //
      0, 1, 3, 0.2, -1,    //
      2, 0, 1, 1, 1;
  VecX A_diag(5);
  A_diag << 4, 1, 0.25, 1, 9;
  ChartSelector selector(3, 5);
  Chart c;
  EXPECT_EQ(selector.select(Et, A_diag, ChartOptions{}, c), 3);
  EXPECT_EQ(c.rows, (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(c.rank(), 3);
  ASSERT_EQ(c.row_scale.size(), 3);
  for (int k = 0; k < 3; ++k)
    EXPECT_NEAR(c.row_scale(k), 1.0 / Et.row(k).cwiseProduct(A_diag.cwiseSqrt().transpose()).norm(),
                1e-15);
  ASSERT_EQ(c.dependent.size(), 3u);
  expect_partition(c, 5);
  EXPECT_DOUBLE_EQ(selector.row_pivots()(0), 1.0);
}

TEST(Chart, DependentRowIsDropped) {
  MatX Et(3, 4);
  Et << 1, 2, 0, -1,  //
      0, 1, 3, 0.2,   //
      1, 3, 3, -0.8;  // row 0 + row 1
  ChartSelector selector(3, 4);
  Chart c;
  EXPECT_EQ(selector.select(Et, VecX::Ones(4), ChartOptions{}, c), 2);
  EXPECT_EQ(c.rows.size(), 2u);
  EXPECT_EQ(c.dependent.size(), 2u);
  expect_partition(c, 4);
  EXPECT_LE(selector.row_pivots()(2), ChartOptions{}.rank_tolerance);
  // Any two of the three rows are independent: the rows kept span the same space.
  MatX kept(2, 4);
  for (int i = 0; i < 2; ++i) kept.row(i) = Et.row(c.rows[static_cast<size_t>(i)]);
  EXPECT_EQ(Eigen::FullPivLU<MatX>(kept).rank(), 2);
}

// One row: the dependent component is the one with the largest |E_k| √A_k (the best 1 × 1 block in
// the mass metric). Making component 0 a thousand times heavier (√A × 1e-3) moves the choice.
TEST(Chart, DependentComponentIsBestConditionedInTheMassMetric) {
  MatX Et(1, 3);
  Et << 1.0, 0.0, 0.01;
  ChartSelector selector(1, 3);
  Chart c;
  ASSERT_EQ(selector.select(Et, VecX::Ones(3), ChartOptions{}, c), 1);
  EXPECT_EQ(c.dependent, std::vector<int>{0});
  EXPECT_EQ(c.independent, (std::vector<int>{1, 2}));
  VecX A_diag(3);
  A_diag << 1e-6, 1.0, 1.0;  // |E_0| √A_0 = 1e-3 < |E_2| √A_2 = 1e-2
  ASSERT_EQ(selector.select(Et, A_diag, ChartOptions{}, c), 1);
  EXPECT_EQ(c.dependent, std::vector<int>{2});
}

TEST(Chart, NoConstraintsEveryComponentIndependent) {
  ChartSelector selector(0, 3);
  Chart c;
  EXPECT_EQ(selector.select(MatX(0, 3), VecX::Ones(3), ChartOptions{}, c), 0);
  EXPECT_TRUE(c.rows.empty());
  EXPECT_TRUE(c.dependent.empty());
  EXPECT_EQ(c.independent, (std::vector<int>{0, 1, 2}));
}

// ---- The sparse selection (select_sparse, sparse_row_rank) ----------------------------------

using SparseMat = Eigen::SparseMatrix<double>;

// The tangent basis is orthonormal and admissible: (E ⊙ √A) x = 0, computed here densely.
void expect_tangent(const MatX& Et, const VecX& A_diag, const SparseRowRank& s) {
  const Eigen::Index n = Et.cols();
  ASSERT_EQ(s.tangent.rows(), n);
  ASSERT_EQ(s.tangent.cols(), n - s.rank);
  const MatX I = MatX::Identity(s.tangent.cols(), s.tangent.cols());
  EXPECT_LT((s.tangent.transpose() * s.tangent - I).cwiseAbs().maxCoeff(), 1e-12);
  const MatX S = Et * A_diag.cwiseSqrt().asDiagonal();
  EXPECT_LT((S * s.tangent).cwiseAbs().maxCoeff(), 1e-12 * std::max(1.0, S.cwiseAbs().maxCoeff()));
}

TEST(ChartSparse, DependentRowIsDroppedAndTheTangentIsTheNullSpace) {
  MatX Et(3, 4);
  Et << 1, 2, 0, -1,  //
      0, 1, 3, 0.2,   //
      1, 3, 3, -0.8;  // row 0 + row 1
  VecX A_diag(4);
  A_diag << 1.0, 0.5, 2.0, 0.25;
  const SparseRowRank s = sparse_row_rank(Et.sparseView(), A_diag, 1e-8, {.tangent = true});
  EXPECT_EQ(s.rank, 2);
  ASSERT_EQ(s.redundant_rows.size(), 1U);
  EXPECT_LE(s.largest_dropped, 1e-12);
  expect_tangent(Et, A_diag, s);
  ChartSelector selector(3, 4);
  Chart c;
  ASSERT_EQ(selector.select_sparse(Et.sparseView(), A_diag, ChartOptions{}, c), 2);
  expect_partition(c, 4);
  MatX block(2, 2);  // the chart's block is nonsingular
  for (int i = 0; i < 2; ++i)
    for (int k = 0; k < 2; ++k)
      block(i, k) = Et(c.rows[static_cast<size_t>(i)], c.dependent[static_cast<size_t>(k)]);
  EXPECT_EQ(Eigen::FullPivLU<MatX>(block).rank(), 2);
  for (int k = 0; k < 2; ++k) {
    const int row = c.rows[static_cast<size_t>(k)];
    EXPECT_NEAR(c.row_scale(k),
                1.0 / Et.row(row).cwiseProduct(A_diag.cwiseSqrt().transpose()).norm(), 1e-15);
  }
}

// The same choice as the dense QR on one row: the dependent component has the largest
// |E_k| √A_k, and a heavier component 0 moves it.
TEST(ChartSparse, DependentComponentIsBestConditionedInTheMassMetric) {
  MatX Et(1, 3);
  Et << 1.0, 0.0, 0.01;
  ChartSelector selector(1, 3);
  Chart c;
  ASSERT_EQ(selector.select_sparse(Et.sparseView(), VecX::Ones(3), ChartOptions{}, c), 1);
  EXPECT_EQ(c.dependent, std::vector<int>{0});
  VecX A_diag(3);
  A_diag << 1e-6, 1.0, 1.0;
  ASSERT_EQ(selector.select_sparse(Et.sparseView(), A_diag, ChartOptions{}, c), 1);
  EXPECT_EQ(c.dependent, std::vector<int>{2});
  ASSERT_EQ(selector.select_sparse(SparseMat(0, 3), VecX::Ones(3), ChartOptions{}, c), 0);
  EXPECT_EQ(c.independent, (std::vector<int>{0, 1, 2}));
}

// A required rank that the QR does not find returns that rank and leaves the chart as it was
// (the chart engine takes only a chart of its own rank); the required rank found gives the same
// chart as no requirement.
TEST(ChartSparse, RequiredRankNotFoundLeavesTheChartUnchanged) {
  MatX Et(2, 3);
  Et << 1.0, 0.0, 0.01,  //
      2.0, 0.0, 0.02;    // the first row twice: rank 1
  ChartSelector selector(2, 3);
  Chart free, required, before;
  ASSERT_EQ(selector.select_sparse(Et.sparseView(), VecX::Ones(3), ChartOptions{}, free), 1);
  ASSERT_EQ(selector.select_sparse(Et.sparseView(), VecX::Ones(3), ChartOptions{}, required, 1), 1);
  EXPECT_EQ(required.rows, free.rows);
  EXPECT_EQ(required.dependent, free.dependent);
  EXPECT_EQ(required.independent, free.independent);
  // A chart no selection would give (so that one written at rank 1 would show).
  required.rows = {1};
  required.dependent = {1};
  required.independent = {0, 2};
  before = required;
  EXPECT_EQ(selector.select_sparse(Et.sparseView(), VecX::Ones(3), ChartOptions{}, required, 2), 1);
  EXPECT_EQ(required.rows, before.rows);
  EXPECT_EQ(required.dependent, before.dependent);
  EXPECT_EQ(required.independent, before.independent);
  // sparse_row_rank: no tangent at another rank, and largest_dropped only when asked.
  const SparseRowRank other =
      sparse_row_rank(Et.sparseView(), VecX::Ones(3), 1e-8, {.tangent = true, .tangent_rank = 2});
  EXPECT_EQ(other.rank, 1);
  EXPECT_EQ(other.tangent.size(), 0);
  MatX Et_off = Et;
  // The second row (2, 1e-3, 0.02): its part outside the first's span is (0, 1e-3, 0), and the
  // rows enter the QR normalised, so the dropped part is 1e-3 / ‖(2, 1e-3, 0.02)‖ (≈ 5e-4).
  Et_off(1, 1) = 1e-3;
  const SparseRowRank loose = sparse_row_rank(Et_off.sparseView(), VecX::Ones(3), 1e-2, {});
  ASSERT_EQ(loose.rank, 1);
  EXPECT_NEAR(loose.largest_dropped, 1e-3 / Et_off.row(1).norm(), 1e-12);
  const SparseRowRank skipped =
      sparse_row_rank(Et_off.sparseView(), VecX::Ones(3), 1e-2, {.largest_dropped = false});
  EXPECT_EQ(skipped.redundant_rows, loose.redundant_rows);
  EXPECT_EQ(skipped.largest_dropped, 0.0);
}

// 2-norm condition number of the chart's scaled block S_R E_RD S_D (an SVD here).
double block_condition(const MatX& Et, const VecX& A_diag, const Chart& c) {
  const auto r = static_cast<Eigen::Index>(c.rows.size());
  MatX G(r, r);
  for (Eigen::Index i = 0; i < r; ++i)
    for (Eigen::Index k = 0; k < r; ++k) {
      const int d = c.dependent[static_cast<size_t>(k)];
      G(i, k) = c.row_scale(i) * Et(c.rows[static_cast<size_t>(i)], d) * std::sqrt(A_diag(d));
    }
  const VecX sv = Eigen::BDCSVD<MatX>(G).singularValues();
  return sv(0) / sv(sv.size() - 1);
}

// A large mechanism (the N-four-bar N = 100, n = 603, where simulate uses the sparse choice):
// the sparse chart has the dense chart's rank, and its block is within 20× of the dense block's
// conditioning, at a regular position and next to the change point (links at 2°).
TEST(ChartSparse, LargeFourBarBlockAsWellConditionedAsTheDenseChoice) {
  for (const double theta : {0.7, 0.035}) {
    const Model model = parse_mechanism(test::n_four_bar_yaml(100, theta), "n-four-bar-100");
    ASSERT_GE(model.n, 600);
    const VecX q = model.design_q();
    MatX Et(model.nc, model.n);
    compute_constraint_jacobian(model, q, Et);
    const VecX A_diag = inverse_mass_diagonal(model, q);
    ChartSelector selector(model.nc, model.n);
    Chart dense, sparse;
    const int rank = selector.select(Et, A_diag, ChartOptions{}, dense);
    ASSERT_EQ(selector.select_sparse(Et.sparseView(), A_diag, ChartOptions{}, sparse), rank);
    expect_partition(sparse, model.n);
    EXPECT_EQ(sparse.rows, dense.rows);
    const double k_dense = block_condition(Et, A_diag, dense);
    const double k_sparse = block_condition(Et, A_diag, sparse);
    EXPECT_LT(k_sparse, 20.0 * k_dense) << "theta " << theta << ": dense " << k_dense;
    const SparseRowRank s = sparse_row_rank(Et.sparseView(), A_diag, 1e-8, {.tangent = true});
    expect_tangent(Et, A_diag, s);
  }
}

// The switching rule on a falling quality with every candidate refused, then a recovery: retried at
// every evaluation below the threshold (the cycle), or only after a further fall by the factor
// (simulate), and back to the threshold once the quality has recovered by the factor.
TEST(ChartSwitchRule, RetriesAsItsPolicySays) {
  using Retry = ChartSwitchRule::Retry;
  ChartSwitchRule every(0.25, 2.0, Retry::every_time);
  ChartSwitchRule later(0.25, 2.0, Retry::after_further_fall);
  EXPECT_FALSE(every.due(0.3));
  EXPECT_FALSE(later.due(0.3));
  EXPECT_TRUE(every.due(0.2));
  EXPECT_TRUE(later.due(0.2));
  every.refused(0.2);
  later.refused(0.2);  // next attempt below 0.1
  EXPECT_TRUE(every.due(0.15));
  EXPECT_FALSE(later.due(0.15));
  EXPECT_FALSE(later.due(0.101));
  EXPECT_TRUE(later.due(0.099));
  later.refused(0.099);  // below 0.0495 now
  EXPECT_DOUBLE_EQ(later.retry_below(), 0.0495);
  // Recovery: above twice the threshold it follows the quality up, capped at 0.25.
  EXPECT_FALSE(later.due(0.12));  // 0.12 > 2 · 0.0495: the threshold becomes 0.06
  EXPECT_DOUBLE_EQ(later.retry_below(), 0.06);
  EXPECT_TRUE(later.due(0.059));
  EXPECT_FALSE(later.due(0.9));
  EXPECT_DOUBLE_EQ(later.retry_below(), 0.25);
  EXPECT_TRUE(later.due(0.24));
  // A switch puts the threshold back at once; the candidate must be better by the factor.
  later.refused(0.01);
  later.switched();
  EXPECT_TRUE(later.due(0.24));
  EXPECT_TRUE(later.better(0.21, 0.1));
  EXPECT_FALSE(later.better(0.2, 0.1));
  EXPECT_DOUBLE_EQ(every.retry_below(), 0.25);
}

}  // namespace
}  // namespace orthomech
