// Choosing a chart (src/projection/chart.cpp): the scaled rank-revealing QR of Eᵀ. Oracles: the
// rank of a matrix built with a known dependent row, the row scale 1/‖row ⊙ √A‖ computed here,
// the dependent component of a one-row Eᵀ (the largest entry in the mass metric, so a change of
// units does not change the choice), and the partition of the components.
#include "orthomech/projection/chart.hpp"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <algorithm>
#include <numeric>
#include <vector>

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

}  // namespace
}  // namespace orthomech
