// Mobility (src/analysis/mobility.cpp): rank of Eᵀ against an SVD, Grübler count, redundant
// equations named.
#include "orthomech/analysis/mobility.hpp"

#include <gtest/gtest.h>

#include <iterator>
#include <string>
#include <vector>

#include "orthomech/constraints/joints.hpp"
#include "orthomech/constraints/sparse_et.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/projection/chart_engine.hpp"
#include "orthomech/projection/primal.hpp"
#include "support/fixtures.hpp"
#include "support/projection_fixture.hpp"

namespace orthomech {
namespace {

using test::kAll;

// ---- redundancy --------------------------------------------------------------------------------
TEST(Redundancy, TripleCrankHasOneRedundantEquationAndSingularG) {
  const Model model = test::load_bundled("triple-crank");
  const VecX q = test::assembled_q(model);
  const Mobility mob = compute_mobility(model, q);
  EXPECT_EQ(mob.grubler, 0);
  EXPECT_EQ(mob.dof, 1);
  EXPECT_EQ(mob.rank, model.nc - 1);
  EXPECT_EQ(mob.rank, test::svd_rank(model, q));  // QR rank = SVD rank (independent oracle)
  ASSERT_EQ(mob.redundant.size(), 1u);
  EXPECT_NE(mob.redundant[0].find("joint '"), std::string::npos);
  // The primal form cannot invert G = EᵀAE here and says so.
  State s(model);
  s.q = q;
  Workspace ws(model, mob.rank);
  EXPECT_EQ(evaluate_primal(model, s, ws), ProjectionStatus::singular_G);
  // Away from the manifold's parallel configuration the redundancy disappears: rank is full.
  VecX off = q;
  off(2) += 0.05;  // turn the first crank alone
  EXPECT_EQ(compute_mobility(model, off).rank, model.nc);
}

TEST(Mobility, RankAgreesWithSvdOnEveryBundledMechanism) {
  for (const char* name : kAll) {
    const Model model = test::load_bundled(name);
    const VecX q = test::assembled_q(model);
    const Mobility mob = compute_mobility(model, q);
    EXPECT_EQ(mob.rank, test::svd_rank(model, q)) << name;
    EXPECT_EQ(mob.dof, 1) << name;
    EXPECT_EQ(mob.grubler, model.n - model.nc) << name;
  }
}

// The chart the mobility's dense QR chose is the one a ChartEngine selects from the same Eᵀ
// (here on its pattern, as simulate's start has it) and A at q: simulate's start takes the
// former instead of a second QR. Oracle: ChartEngine::select itself; every bundled mechanism of
// kAll and the N = 40 four-bar (n = 243, the largest bundled).
TEST(Mobility, ChartIsTheEngineSelection) {
  std::vector<std::string> names(std::begin(kAll), std::end(kAll));
  names.emplace_back("n-four-bar-40");
  for (const std::string& name : names) {
    const Model model = test::load_bundled(name.c_str());
    const VecX q = test::assembled_q(model);
    const Mobility mob = compute_mobility(model, q);
    ASSERT_EQ(mob.chart.rank(), mob.rank) << name;
    SparseEt Et(model);
    compute_constraint_jacobian(model, q, Et);
    ChartEngine engine(model, mob.rank, ChartFactorisation::sparse_when_large);
    ASSERT_TRUE(engine.select(Et, inverse_mass_diagonal(model, q))) << name;
    EXPECT_EQ(engine.chart().rows, mob.chart.rows) << name;
    EXPECT_EQ(engine.chart().dependent, mob.chart.dependent) << name;
    EXPECT_EQ(engine.chart().independent, mob.chart.independent) << name;
    EXPECT_EQ(engine.chart().row_scale, mob.chart.row_scale) << name;
  }
}

}  // namespace
}  // namespace orthomech
