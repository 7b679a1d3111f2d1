// The ConstraintSystem alternatives (constraints/constraint_system.hpp): a model of bodies gets
// its joints, a general system its functions, and every model-level function reaches them
// through constraint_system(model). References: the general system's own functions called here,
// and an SVD rank of Eᵀ computed here.
#include <gtest/gtest.h>

#include <Eigen/SVD>
#include <cmath>
#include <stdexcept>
#include <string>

#include "orthomech/analysis/mobility.hpp"
#include "orthomech/constraints/constraint_system.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/constraints/sparse_et.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/model/general_system.hpp"
#include "support/andrews_relative.hpp"
#include "support/fixtures.hpp"

namespace orthomech {
namespace {

TEST(GeneralConstraints, EachModelGetsTheAlternativeOfItsFreeSystem) {
  const Model bodies = test::load_bundled("crank-rocker");
  const Model general = test::andrews_relative();
  EXPECT_EQ(&constraint_system(bodies), &joint_constraints());
  EXPECT_EQ(&constraint_system(general), &general_constraints());
  EXPECT_TRUE(constraint_system(bodies).structurally_sparse());
  EXPECT_FALSE(constraint_system(general).structurally_sparse());
  for (int row = 0; row < general.nc; ++row)
    EXPECT_EQ(general.constraint_row_name(row),
              "constraint '" + general.general->rows[static_cast<size_t>(row)] + "'");
  EXPECT_EQ(bodies.constraint_row_name(0).rfind("joint '", 0), 0U) << bodies.constraint_row_name(0);
  EXPECT_THROW((void)general.constraint_row_name(general.nc), std::invalid_argument);
  EXPECT_THROW((void)bodies.constraint_row_name(bodies.nc), std::invalid_argument);
}

// f, Eᵀ (dense and on its pattern), Dᵀ and Dᵀu of a general system through the model-level
// functions equal its functions evaluated directly (Dᵀu = Dᵀ · u formed here).
TEST(GeneralConstraints, AGeneralSystemsRowsAreItsFunctions) {
  const Model model = test::andrews_relative();
  State s(model);
  s.q = model.design_q() + VecX::LinSpaced(model.n, 0.01, -0.02);
  s.u = VecX::LinSpaced(model.n, 1.0, -2.0);
  VecX f_ref(model.nc);
  MatX Et_ref(model.nc, model.n), Dt_ref(model.nc, model.n);
  model.general->residual(s.q, f_ref);
  model.general->jacobian(s.q, Et_ref);
  model.general->jacobian_rate(s.q, s.u, Dt_ref);

  ConstraintWorkspace cw(model);
  compute_constraints(model, s, cw);
  EXPECT_EQ(cw.f, f_ref);
  EXPECT_EQ(cw.Et, Et_ref);
  EXPECT_EQ(cw.Dt, Dt_ref);
  EXPECT_LT((cw.Dtu - Dt_ref * s.u).cwiseAbs().maxCoeff(), 1e-12);

  SparseEt sparse(model);
  VecX f(model.nc);
  compute_constraint_residual_and_jacobian(model, s.q, f, sparse);
  EXPECT_EQ(f, f_ref);
  for (int i = 0; i < model.nc; ++i)
    for (int j = 0; j < model.n; ++j) EXPECT_EQ(sparse.coeff(i, j), Et_ref(i, j));
  BodyPoses poses(model);
  VecX Dtu(model.nc);
  compute_constraint_rate(model, s, poses, Dtu);
  EXPECT_LT((Dtu - Dt_ref * s.u).cwiseAbs().maxCoeff(), 1e-12);
}

// The sparse rank (through Eᵀ's pattern, full for a general system) and the dense one agree on a
// general system, and with the rank of Eᵀ's singular values.
TEST(GeneralConstraints, AGeneralSystemsRankIsTheSameOnEitherPath) {
  const Model model = test::andrews_relative();
  const VecX q = model.design_q();
  const Mobility dense = compute_mobility(model, q, {}, RankMethod::dense);
  const Mobility sparse = compute_mobility(model, q, {}, RankMethod::sparse);
  MatX Et(model.nc, model.n);
  model.general->jacobian(q, Et);
  const Eigen::JacobiSVD<MatX> svd(Et);
  const VecX& sv = svd.singularValues();
  int rank = 0;
  for (Eigen::Index k = 0; k < sv.size(); ++k)
    if (sv(k) > 1e-9 * sv(0)) ++rank;
  EXPECT_EQ(dense.rank, rank);
  EXPECT_EQ(sparse.rank, rank);
  EXPECT_EQ(sparse.dof, dense.dof);
  EXPECT_EQ(sparse.redundant.size(), dense.redundant.size());
  EXPECT_FALSE(dense.sparse);
  EXPECT_TRUE(sparse.sparse);
  EXPECT_TRUE(dense.idle.empty());
}

// The non-conservative power of a general system: Q̂ᵀu − ½ uᵀṀu (general_system.hpp), formed
// here from its functions.
TEST(GeneralConstraints, AGeneralSystemsNonconservativePowerIsItsForcesLessTheMassRateTerm) {
  const Model model = test::andrews_relative();
  State s(model);
  s.q = model.design_q();
  s.u = VecX::LinSpaced(model.n, 0.5, -1.0);
  s.t = 1e-3;
  VecX Q(model.n);
  MatX Mdot(model.n, model.n);
  model.general->forces(s.q, s.u, s.t, Q);
  model.general->mass_rate(s.q, s.u, Mdot);
  VecX scratch(model.n);
  const double P = free_system(model).nonconservative_power(model, s, Q, Mdot, scratch);
  EXPECT_NEAR(P, Q.dot(s.u) - 0.5 * s.u.dot(Mdot * s.u), 1e-12 * (1.0 + std::abs(Q.dot(s.u))));
  EXPECT_FALSE(free_system(model).forces_time_invariant());
  EXPECT_TRUE(free_system(test::load_bundled("crank-rocker")).forces_time_invariant());
}

}  // namespace
}  // namespace orthomech
