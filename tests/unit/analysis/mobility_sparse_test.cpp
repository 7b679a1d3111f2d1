// Mobility by the sparse QR (issue 18 item 2) against the dense, column-pivoted QR and against
// an independent dense SVD: the same rank, DOF and idle bodies on every bundled mechanism, a
// valid redundant set (the rows it keeps have full rank), and the closed-form mobility of large
// generated chains and N-four-bars.
#include <gtest/gtest.h>

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <set>

#include "orthomech/analysis/mobility.hpp"
#include "orthomech/analysis/positions.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/model/free_system.hpp"
#include "support/fixtures.hpp"
#include "unit/analysis/large_mechanisms.hpp"

namespace orthomech {
namespace {

// Singular values below this fraction of the largest are zero: the rank tolerance of
// ChartOptions (1e-8); the mechanisms here have no singular value between 1e-12 and 1e-3.
constexpr double kSvdRankTolerance = 1e-8;

// The rows `rows` of E, each scaled to the mass metric and normalised (the matrix whose rank the
// QR reveals), from the dense A of eq. (6): independent of mobility.cpp.
MatX scaled_rows(const Model& model, const VecX& q, const std::vector<int>& rows) {
  MatX Et(model.nc, model.n), A(model.n, model.n);
  compute_constraint_jacobian(model, q, Et);
  compute_inverse_mass_matrix(model, q, A);
  MatX S(static_cast<Eigen::Index>(rows.size()), model.n);
  for (size_t k = 0; k < rows.size(); ++k) {
    const VecX row = Et.row(rows[k]).transpose().cwiseProduct(A.diagonal().cwiseSqrt());
    const double norm = row.norm();
    S.row(static_cast<Eigen::Index>(k)) = norm > 0.0 ? VecX(row / norm) : row;
  }
  return S;
}

int svd_rank(const MatX& S) {
  if (S.rows() == 0) return 0;
  Eigen::BDCSVD<MatX> svd(S);
  svd.setThreshold(kSvdRankTolerance);
  return static_cast<int>(svd.rank());
}

std::vector<int> all_rows(const Model& model) {
  std::vector<int> rows(static_cast<size_t>(model.nc));
  for (int k = 0; k < model.nc; ++k) rows[static_cast<size_t>(k)] = k;
  return rows;
}

std::vector<int> kept_rows(const Model& model, const Mobility& m) {
  std::vector<int> kept;
  for (int k = 0; k < model.nc; ++k)
    if (!std::binary_search(m.redundant_rows.begin(), m.redundant_rows.end(), k)) kept.push_back(k);
  return kept;
}

// The redundant set m names is valid: the rows it keeps are independent (full row rank by SVD),
// as many as the rank, so removing the named rows leaves the rank and the DOF unchanged.
void expect_valid_redundant_set(const Model& model, const VecX& q, const Mobility& m) {
  const std::vector<int> kept = kept_rows(model, m);
  EXPECT_EQ(static_cast<int>(kept.size()), m.rank) << model.name;
  EXPECT_EQ(svd_rank(scaled_rows(model, q, kept)), static_cast<int>(kept.size())) << model.name;
  ASSERT_EQ(m.redundant.size(), m.redundant_rows.size());
  for (size_t k = 0; k < m.redundant_rows.size(); ++k)
    EXPECT_EQ(m.redundant[k], model.constraint_row_name(m.redundant_rows[k]));
}

void expect_same_mobility(const Model& model, const VecX& q) {
  const Mobility dense = compute_mobility(model, q, {}, RankMethod::dense);
  const Mobility sparse = compute_mobility(model, q, {}, RankMethod::sparse);
  EXPECT_FALSE(dense.sparse);
  EXPECT_TRUE(sparse.sparse);
  const int oracle = svd_rank(scaled_rows(model, q, all_rows(model)));
  EXPECT_EQ(dense.rank, oracle) << model.name;
  EXPECT_EQ(sparse.rank, oracle) << model.name;
  EXPECT_EQ(sparse.dof, dense.dof) << model.name;
  EXPECT_EQ(sparse.grubler, dense.grubler) << model.name;
  EXPECT_EQ(sparse.redundant.size(), dense.redundant.size()) << model.name;
  expect_valid_redundant_set(model, q, dense);
  expect_valid_redundant_set(model, q, sparse);
  // Distances from a rank drop: kept pivots above the tolerance, dropped ones at most it.
  if (sparse.rank > 0) {
    EXPECT_GT(sparse.smallest_pivot, sparse.tolerance) << model.name;
  }
  EXPECT_LE(sparse.largest_dropped, sparse.tolerance) << model.name;
  ASSERT_EQ(sparse.idle.size(), dense.idle.size()) << model.name;
  for (size_t k = 0; k < dense.idle.size(); ++k) {
    EXPECT_EQ(sparse.idle[k].body, dense.idle[k].body);
    EXPECT_EQ(sparse.idle[k].count, dense.idle[k].count);
  }
}

std::vector<std::string> bundled_names() {
  std::vector<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator(test::source_path("mechanisms")))
    if (e.path().extension() == ".yaml") names.push_back(e.path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

VecX projected_or_design_q(const Model& model) {
  VecX q = model.design_q();
  if (project_positions(model, q).status != SolveStatus::converged) q = model.design_q();
  return q;
}

// eq. (6): the diagonal of A without the n × n matrix equals the dense A's, bit for bit.
TEST(SparseMobility, Eq6_InverseMassDiagonalEqualsDenseDiagonal) {
  for (const std::string& name : bundled_names()) {
    const Model model = test::load_bundled(name);
    const VecX q = model.design_q();
    MatX A(model.n, model.n);
    compute_inverse_mass_matrix(model, q, A);
    EXPECT_EQ(inverse_mass_diagonal(model, q), VecX(A.diagonal())) << name;
  }
}

TEST(SparseMobility, EveryBundledMechanismSameRankDofIdleAsDenseAndValidRedundantSet) {
  const std::vector<std::string> names = bundled_names();
  ASSERT_GE(names.size(), 20u);
  int with_redundancy = 0, spatial = 0;
  for (const std::string& name : names) {
    SCOPED_TRACE(name);
    const Model model = test::load_bundled(name);
    const VecX q = projected_or_design_q(model);
    expect_same_mobility(model, q);
    if (compute_mobility(model, q).rank < model.nc) ++with_redundancy;
    if (model.dimension == 3) ++spatial;
  }
  EXPECT_GT(with_redundancy, 0);  // the redundant-set check has cases to check
  EXPECT_GT(spatial, 0);
}

// The bundled N-four-bar at its change point (every link on the x axis): N redundant rows.
TEST(SparseMobility, NFourBarChangePointSameAsDenseAndValidRedundantSet) {
  for (const int N : {2, 40, 100}) {
    const Model model = parse_mechanism(test::n_four_bar_yaml(N, 0.0), "n-four-bar.yaml");
    const VecX q = model.design_q();
    expect_same_mobility(model, q);
    const Mobility m = compute_mobility(model, q, {}, RankMethod::sparse);
    EXPECT_EQ(m.dof, N + 1);
    EXPECT_EQ(static_cast<int>(m.redundant.size()), N);
  }
}

// Above kSparseMobilityFrom the automatic method is the sparse one; a 250-link chain
// (n = 750) against the dense path and the SVD.
TEST(SparseMobility, AutomaticIsSparseForLargeModelsAndMatchesDense) {
  const Model small = test::load_bundled("n-four-bar-40");
  EXPECT_FALSE(compute_mobility(small, small.design_q()).sparse);
  const Model chain = parse_mechanism(test::pendulum_chain_yaml(250), "chain.yaml");
  ASSERT_GE(chain.n, kSparseMobilityFrom);
  EXPECT_TRUE(compute_mobility(chain, chain.design_q()).sparse);
  expect_same_mobility(chain, chain.design_q());
}

// Closed forms (large_mechanisms.hpp): the 1000-link chain has DOF 1000 and no redundancy.
TEST(SparseMobility, PendulumChain1000HasDofN) {
  const int N = 1000;
  const Model model = parse_mechanism(test::pendulum_chain_yaml(N), "chain.yaml");
  const Mobility m = compute_mobility(model, model.design_q());
  EXPECT_TRUE(m.sparse);
  EXPECT_EQ(m.n, 3 * N);
  EXPECT_EQ(m.nc, 2 * N);
  EXPECT_EQ(m.rank, 2 * N);
  EXPECT_EQ(m.dof, N);
  EXPECT_TRUE(m.redundant.empty());
  EXPECT_TRUE(m.idle.empty());
  EXPECT_GT(m.smallest_pivot, m.tolerance);
}

// Closed forms: N = 499 four-bar (999 bodies: the file format allows 1000), DOF 1 at a general
// position, N + 1 at the change point with N redundant rows (their validity is checked by SVD at
// N = 100 above).
TEST(SparseMobility, NFourBar499HasDofOneAndNPlusOneAtTheChangePoint) {
  const int N = 499;
  const Model general =
      parse_mechanism(test::n_four_bar_yaml(N, std::numbers::pi / 2 - 0.3), "n-four-bar.yaml");
  const Mobility m = compute_mobility(general, general.design_q());
  EXPECT_TRUE(m.sparse);
  EXPECT_EQ(m.rank, 2 * (3 * N + 1));
  EXPECT_EQ(m.dof, 1);
  EXPECT_TRUE(m.redundant.empty());
  const Model flat = parse_mechanism(test::n_four_bar_yaml(N, 0.0), "n-four-bar.yaml");
  const Mobility c = compute_mobility(flat, flat.design_q());
  EXPECT_EQ(c.dof, N + 1);
  EXPECT_EQ(static_cast<int>(c.redundant.size()), N);
  EXPECT_LE(c.largest_dropped, c.tolerance);
  // Each named row is a distinct row of E, named by its joint.
  EXPECT_EQ(std::set<std::string>(c.redundant.begin(), c.redundant.end()).size(),
            c.redundant.size());
}

}  // namespace
}  // namespace orthomech
