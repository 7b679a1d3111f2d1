// Eᵀ on its structural pattern (constraints/sparse_et.hpp, issue 18) against the dense Eᵀ of the
// same writers (eq. (23), itself tested against central differences in joints_test.cpp and
// spatial_joints_test.cpp): bitwise the same values at generic positions of every bundled and
// test mechanism (so the recorded pattern holds every entry that is non-zero anywhere), the
// column access consistent with the rows, the general system's full pattern, and a write
// outside the pattern refused.
#include "orthomech/constraints/sparse_et.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "orthomech/constraints/joints.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/model/free_system.hpp"
#include "support/andrews_relative.hpp"
#include "support/fixtures.hpp"

namespace orthomech {
namespace {

namespace fs = std::filesystem;

// Every mechanism file of mechanisms/ and tests/data/ that loads (the invalid ones of the
// robustness tests do not, by design).
std::vector<std::string> loadable_files() {
  std::vector<std::string> files;
  for (const char* dir : {"mechanisms", "tests/data"}) {
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(test::source_path(dir), ec))
      if (e.path().extension() == ".yaml") files.push_back(e.path().string());
  }
  return files;
}

// A generic position near the design one (reached through integrate, so quaternions stay unit):
// no coordinate at a value where an entry of Eᵀ happens to vanish.
VecX generic_q(const Model& model, double scale) {
  VecX q = model.design_q();
  VecX du(model.n);
  for (int k = 0; k < model.n; ++k) du(k) = scale * (1.0 + std::sin(1.7 * k + 0.3));
  integrate_positions(model, q, du, 1.0);
  return q;
}

// The sparse Eᵀ, f and Dᵀu against the dense ones at q; returns the number of non-zero entries.
int expect_same_as_dense(const Model& model, const VecX& q, const std::string& what) {
  MatX dense(model.nc, model.n);
  VecX f_dense(model.nc), f_sparse(model.nc);
  compute_constraint_residual_and_jacobian(model, q, f_dense, dense);
  SparseEt Et(model);
  compute_constraint_residual_and_jacobian(model, q, f_sparse, Et);
  int non_zero = 0;
  for (int i = 0; i < model.nc; ++i)
    for (int j = 0; j < model.n; ++j) {
      EXPECT_EQ(Et.coeff(i, j), dense(i, j)) << what << ": entry (" << i << ", " << j << ")";
      if (dense(i, j) != 0.0) ++non_zero;
    }
  EXPECT_EQ(f_sparse, f_dense) << what;
  // The overload with the rotations computed by the caller writes the same values.
  SparseEt again(model);
  BodyPoses rotations(model);
  rotations.update(model, q);
  compute_constraint_residual_and_jacobian(model, q, rotations, f_sparse, again);
  for (int k = 0; k < Et.nonZeros(); ++k) EXPECT_EQ(again.values()[k], Et.values()[k]) << what;
  // Dᵀu row by row against the dense workspace's Dᵀ u.
  State s(model);
  s.q = q;
  for (int k = 0; k < model.n; ++k) s.u(k) = std::cos(0.9 * k + 0.2);
  ConstraintWorkspace ws(model);
  compute_constraints(model, s, ws);
  VecX Dtu(model.nc);
  compute_constraint_rate(model, s, rotations, Dtu);
  for (int i = 0; i < model.nc; ++i)
    EXPECT_NEAR(Dtu(i), ws.Dtu(i), 1e-12 * (1.0 + std::abs(ws.Dtu(i)))) << what << ", row " << i;
  return non_zero;
}

TEST(SparseEt, Eq23_SameValuesAsTheDenseEtOnEveryMechanism) {
  const std::vector<std::string> files = loadable_files();
  ASSERT_GE(files.size(), 15U);
  int models = 0;
  for (const std::string& file : files) {
    Model model;
    try {
      model = load_mechanism(file);
    } catch (const std::exception&) {
      continue;  // an invalid file of the robustness tests
    }
    if (model.nc == 0) continue;
    ++models;
    const SparseEt Et(model);
    EXPECT_EQ(Et.rows(), model.nc);
    EXPECT_EQ(Et.cols(), model.n);
    for (const double scale : {0.0137, -0.0291, 0.31})
      (void)expect_same_as_dense(model, generic_q(model, scale), file);
  }
  EXPECT_GE(models, 15);
}

TEST(SparseEt, ThePatternOfALargeMechanismIsLinearInItsSize) {
  // The N-four-bar: each revolute touches two bodies (≤ 6 columns per row).
  const Model model = test::load_bundled("n-four-bar-40");
  const SparseEt Et(model);
  for (int i = 0; i < model.nc; ++i) EXPECT_LE(Et.row_columns(i).size(), 6U) << "row " << i;
  EXPECT_LE(Et.nonZeros(), 6 * model.nc);
  EXPECT_LT(Et.nonZeros(), model.nc * model.n / 10);
}

TEST(SparseEt, ColumnsAndRowsAgree) {
  const Model model = test::load_bundled("andrews-squeezer");
  SparseEt Et(model);
  compute_constraint_jacobian(model, generic_q(model, 0.05), Et);
  MatX dense;
  Et.to_dense(dense);
  int seen = 0;
  for (int j = 0; j < model.n; ++j) {
    int previous = -1;
    for (const SparseEt::Entry& e : Et.column(j)) {
      EXPECT_GT(e.row, previous) << "column " << j << ": rows ascending";
      previous = e.row;
      EXPECT_EQ(Et.values()[e.index], dense(e.row, j));
      ++seen;
    }
  }
  EXPECT_EQ(seen, Et.nonZeros());
  for (int i = 0; i < model.nc; ++i) {
    const auto cols = Et.row_columns(i);
    const auto vals = Et.row_values(i);
    ASSERT_EQ(cols.size(), vals.size());
    for (size_t t = 0; t < cols.size(); ++t) {
      if (t > 0) {
        EXPECT_GT(cols[t], cols[t - 1]);
      }
      EXPECT_EQ(vals[t], dense(i, cols[t]));
    }
  }
  // Products through matrix(): Eᵀu and Eλ.
  const VecX u = VecX::LinSpaced(model.n, -1.0, 2.0);
  const VecX lambda = VecX::LinSpaced(model.nc, 0.5, -1.5);
  EXPECT_LT((Et.matrix() * u - dense * u).cwiseAbs().maxCoeff(), 1e-13);
  EXPECT_LT((Et.matrix().transpose() * lambda - dense.transpose() * lambda).cwiseAbs().maxCoeff(),
            1e-13);
}

// copy_values_to writes the pattern's entries only: into a zeroed dense matrix it gives the
// dense evaluation bit for bit at a second position after a first (the cycle's corrector on a
// large model), and an entry outside the pattern keeps whatever it holds.
TEST(SparseEt, CopyValuesToWritesThePatternOnly) {
  const Model model = test::load_bundled("andrews-squeezer");
  SparseEt Et(model);
  MatX copied = MatX::Zero(model.nc, model.n);
  for (const double scale : {0.05, -0.11}) {
    const VecX q = generic_q(model, scale);
    compute_constraint_jacobian(model, q, Et);
    Et.copy_values_to(copied);
    MatX dense(model.nc, model.n);
    compute_constraint_jacobian(model, q, dense);
    EXPECT_EQ((copied - dense).cwiseAbs().maxCoeff(), 0.0) << scale;
  }
  const auto cols = Et.row_columns(0);
  int outside = 0;
  while (std::find(cols.begin(), cols.end(), outside) != cols.end()) ++outside;
  ASSERT_LT(outside, model.n);
  copied(0, outside) = 7.0;
  Et.copy_values_to(copied);
  EXPECT_EQ(copied(0, outside), 7.0);
}

TEST(SparseEt, AGeneralSystemHasTheFullPatternAndItsFunctionsValues) {
  const Model model = test::andrews_relative();
  SparseEt Et(model);
  EXPECT_EQ(Et.nonZeros(), model.nc * model.n);
  const VecX q = model.design_q();
  compute_constraint_jacobian(model, q, Et);
  MatX dense(model.nc, model.n);
  model.general->jacobian(q, dense);
  for (int i = 0; i < model.nc; ++i)
    for (int j = 0; j < model.n; ++j) EXPECT_EQ(Et.coeff(i, j), dense(i, j));
}

TEST(SparseEt, AWriteOutsideThePatternIsRefused) {
  const Model model = test::load_bundled("crank-rocker");
  SparseEt Et(model);
  // Row 0 (the ground pivot's x row) touches the crank's columns only.
  const auto cols = Et.row_columns(0);
  ASSERT_FALSE(cols.empty());
  int outside = 0;
  while (std::find(cols.begin(), cols.end(), outside) != cols.end()) ++outside;
  ASSERT_LT(outside, model.n);
  EXPECT_THROW(Et.row(0)(outside) += 1.0, std::logic_error);
  EXPECT_NO_THROW(Et.row(0)(cols[0]) += 1.0);
  EXPECT_EQ(Et.coeff(0, cols[0]), 1.0);
  Et.setZero();
  EXPECT_EQ(Et.coeff(0, cols[0]), 0.0);
}

TEST(SparseEt, AnotherModelsMatrixOrAWrongSizeIsRefused) {
  const Model small = test::load_bundled("crank-rocker");
  const Model large = test::load_bundled("andrews-squeezer");
  SparseEt Et(small);
  VecX f(large.nc);
  EXPECT_THROW(compute_constraint_jacobian(large, large.design_q(), Et), std::invalid_argument);
  EXPECT_THROW(compute_constraint_residual_and_jacobian(large, large.design_q(), f, Et),
               std::invalid_argument);
  State s(large);
  s.q = large.design_q();
  BodyPoses rotations(large);
  rotations.update(large, s.q);
  VecX Dtu(small.nc);
  EXPECT_THROW(compute_constraint_rate(large, s, rotations, Dtu), std::invalid_argument);
}

}  // namespace
}  // namespace orthomech
