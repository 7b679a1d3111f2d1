// The Workspace (projection/workspace.hpp) and its stage 1, the free system
// (projection/free_system_stage.hpp): M, A = M⁻¹ and the applied forces Q̂ at a state.
//
// Oracles written here: for planar bodies in absolute coordinates M = diag(m, m, J_c) per rigid
// body and diag(m, m) per particle (eq. (4)), from the file's masses and inertias; A M = I;
// gravity's generalized force (0, m g_y, 0) per body and a body torque τ on its angle (eq. (17)).
#include "orthomech/projection/workspace.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <set>
#include <stdexcept>
#include <string>

#include "orthomech/analysis/mobility.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/constraints/sparse_et.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/projection/dual.hpp"
#include "orthomech/projection/free_system_stage.hpp"
#include "orthomech/projection/primal.hpp"
#include "support/fixtures.hpp"
#include "unit/analysis/large_mechanisms.hpp"

namespace orthomech {
namespace {

const std::string kTwoBodies = R"(
orthomech: 1
name: two-bodies
units: {length: m, angle: rad, mass: kg, time: s, force: N}
ground:
  points: {O: [0, 0]}
bodies:
  - {name: bar, mass: 2.5, inertia: 0.3, com: [0.2, 0], pose: [0.1, 0.2, 0.7],
     points: {O: [0, 0], P: [0.4, 0]}}
  - {name: p, type: particle, mass: 0.8, pose: [0.5, 0.3]}
joints:
  - {name: A, type: revolute, connects: [ground.O, bar.O]}
  - {name: rod, type: distance, connects: [bar.P, p.origin], length: 0.2}
loads:
  - {name: weight, type: gravity, g: [0, -9.81]}
  - {name: motor, type: torque, body: bar, torque: 1.7}
)";

TEST(Workspace, FreeSystemStageMassInverseAndAppliedForces) {
  const Model model = parse_mechanism(kTwoBodies, "two-bodies");
  Workspace ws(model, model.nc);
  State s(model);
  s.q = model.design_q();
  compute_free_system(model, s, ws);
  const Body& bar = model.bodies[static_cast<size_t>(model.find_body("bar"))];
  const Body& p = model.bodies[static_cast<size_t>(model.find_body("p"))];
  ASSERT_EQ(model.n, 5);
  VecX m_expected(5);
  m_expected.setZero();
  m_expected(bar.u_offset) = m_expected(bar.u_offset + 1) = 2.5;
  m_expected(bar.u_offset + 2) = 0.3;
  m_expected(p.u_offset) = m_expected(p.u_offset + 1) = 0.8;
  EXPECT_LT((ws.free.M - MatX(m_expected.asDiagonal())).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_LT((ws.free.A * ws.free.M - MatX::Identity(5, 5)).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_LT((ws.free.A_sqrt.cwiseAbs2() - ws.free.A.diagonal()).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_TRUE(ws.free.diagonal_mass);
  EXPECT_TRUE(ws.free.constant_mass);
  EXPECT_TRUE(ws.free.mass_ready);
  VecX Q_expected = VecX::Zero(5);
  Q_expected(bar.u_offset + 1) = -9.81 * 2.5;
  Q_expected(bar.u_offset + 2) = 1.7;
  Q_expected(p.u_offset + 1) = -9.81 * 0.8;
  EXPECT_LT((ws.free.Q - Q_expected).cwiseAbs().maxCoeff(), 1e-12);
}

// The stage alone (simulate holds no projection matrices) against the same oracle.
TEST(Workspace, FreeSystemStageAloneMassAndAppliedForces) {
  const Model model = parse_mechanism(kTwoBodies, "two-bodies");
  FreeSystemWorkspace fs(model);
  State s(model);
  s.q = model.design_q();
  compute_free_system(model, s, fs);
  const Body& bar = model.bodies[static_cast<size_t>(model.find_body("bar"))];
  const Body& p = model.bodies[static_cast<size_t>(model.find_body("p"))];
  VecX m_expected = VecX::Zero(model.n);
  m_expected(bar.u_offset) = m_expected(bar.u_offset + 1) = 2.5;
  m_expected(bar.u_offset + 2) = 0.3;
  m_expected(p.u_offset) = m_expected(p.u_offset + 1) = 0.8;
  EXPECT_LT((fs.M - MatX(m_expected.asDiagonal())).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_LT((fs.A * fs.M - MatX::Identity(model.n, model.n)).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_TRUE(fs.diagonal_mass && fs.mass_ready);
  VecX Q_expected = VecX::Zero(model.n);
  Q_expected(bar.u_offset + 1) = -9.81 * 2.5;
  Q_expected(bar.u_offset + 2) = 1.7;
  Q_expected(p.u_offset + 1) = -9.81 * 0.8;
  EXPECT_LT((fs.Q - Q_expected).cwiseAbs().maxCoeff(), 1e-12);
}

// MassStorage::diagonal_if_possible (simulate's stage): on a model whose M is diagonal whatever q,
// M, A and Ṁ are not held (0 × 0) and the diagonals, the square roots and Q̂ are those of the dense
// stage bit for bit; on any other model (a spatial inertia with a product of inertia) the stage is
// the dense one. Oracle: the dense stage (compute_mass_matrix, compute_inverse_mass_matrix) and its
// own off-diagonal test of M.
void expect_storage_agrees(const Model& model, const std::string& name) {
  SCOPED_TRACE(name);
  State s(model);
  s.q = model.design_q();
  s.u = VecX::LinSpaced(model.n, -0.3, 0.7);
  FreeSystemWorkspace dense(model), diagonal(model, MassStorage::diagonal_if_possible);
  compute_free_system(model, s, dense);
  compute_free_system(model, s, diagonal);
  const bool off_diagonal_zero =
      (dense.M - MatX(dense.M.diagonal().asDiagonal())).cwiseAbs().maxCoeff() == 0.0;
  EXPECT_EQ(mass_matrix_is_diagonal(model), off_diagonal_zero);
  EXPECT_EQ(diagonal.dense_mass, !off_diagonal_zero);
  EXPECT_EQ(diagonal.diagonal_mass, dense.diagonal_mass);
  if (!diagonal.dense_mass) {
    EXPECT_EQ(diagonal.M.size() + diagonal.A.size() + diagonal.Mdot.size(), 0);
  } else {
    EXPECT_EQ(diagonal.M, dense.M);
    EXPECT_EQ(diagonal.A, dense.A);
  }
  EXPECT_EQ(diagonal.M_diag, VecX(dense.M.diagonal()));
  EXPECT_EQ(diagonal.A_diag, VecX(dense.A.diagonal()));
  EXPECT_EQ(diagonal.A_sqrt, dense.A_sqrt);
  EXPECT_EQ(diagonal.Q, dense.Q);
  EXPECT_TRUE(diagonal.mass_ready);
}

TEST(Workspace, DiagonalMassStorageEqualsTheDenseStageOnEveryBundledMechanism) {
  int diagonal = 0, total = 0;
  for (const auto& e : std::filesystem::directory_iterator(test::source_path("mechanisms"))) {
    if (e.path().extension() != ".yaml") continue;
    const Model model = test::load_bundled(e.path().stem().string());
    expect_storage_agrees(model, e.path().stem().string());
    diagonal += mass_matrix_is_diagonal(model) ? 1 : 0;
    ++total;
  }
  EXPECT_GE(total, 20);
  EXPECT_EQ(diagonal, total - 1);  // all but the double wishbone, whose bodies have products
  EXPECT_FALSE(mass_matrix_is_diagonal(test::load_bundled("double-wishbone")));
  Model top = test::load_bundled("heavy-top");
  Body& b = top.bodies[static_cast<size_t>(top.find_body("top"))];
  b.spatial.inertia(0, 1) = b.spatial.inertia(1, 0) = -1e-4;  // a product of inertia
  expect_storage_agrees(top, "heavy-top with J_xy");
  EXPECT_FALSE(mass_matrix_is_diagonal(top));
}

// dense_workspace_bytes counts the Workspace's n × n, n_c × n and n_c × n_c matrices (oracle: their
// sizes as allocated); a model whose count exceeds kMaxDenseWorkspaceBytes is refused with
// ModelTooLarge, naming its file and sizes. A 1900-link chain (n = 5700, n_c = 3800: 4.58 GB) is
// over the limit; the loader itself takes it (at most 2500 bodies).
TEST(Workspace, DenseBytesCountTheMatricesAndATooLargeModelIsRefused) {
  const Model model = parse_mechanism(kTwoBodies, "two-bodies");
  const Workspace ws(model, model.nc);
  const Eigen::Index counted =
      ws.free.M.size() + ws.free.A.size() + ws.free.Mdot.size() + ws.constraints.Et.size() +
      ws.constraints.Dt.size() + ws.primal.AE.size() + ws.primal.G.size() +
      ws.primal.GinvEt.size() + ws.primal.pi.size() + ws.primal.alpha.size() +
      ws.primal.beta.size() + ws.primal.GinvDt.size() + ws.primal.Omega.size() +
      ws.primal.omega.size() + ws.dual.psi.size() + ws.dual.alpha.size() + ws.dual.beta.size() +
      ws.dual.Theta.size() + ws.dual.theta.size();
  EXPECT_EQ(dense_workspace_bytes(model), 8.0 * static_cast<double>(counted));

  const Model chain = parse_mechanism(test::pendulum_chain_yaml(1900), "chain-1900.yaml");
  ASSERT_EQ(chain.n, 5700);
  EXPECT_GT(dense_workspace_bytes(chain), kMaxDenseWorkspaceBytes);
  try {
    const Workspace too_large(chain, chain.nc);
    ADD_FAILURE() << "a 1900-link chain's dense workspace was built";
  } catch (const ModelTooLarge& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("chain-1900.yaml"), std::string::npos) << what;
    EXPECT_NE(what.find("5700 velocity components"), std::string::npos) << what;
  }
  const Model n_four_bar = parse_mechanism(test::n_four_bar_yaml(1000, 0.5), "n-four-bar.yaml");
  EXPECT_EQ(n_four_bar.bodies.size(), 2001u);  // IFToMM A02 at N = 1000 loads
  EXPECT_GT(dense_workspace_bytes(n_four_bar), kMaxDenseWorkspaceBytes);
}

// The stages a command uses (WorkspaceStages, what `cycle` builds): the byte count is that of the
// matrices as allocated (oracle: their sizes, summed here), compute_basis gives the F of the full
// Workspace bit for bit (the same chart engine on the same Eᵀ), compute_primal and compute_dual
// refuse a Workspace without their stage, and the IFToMM A02 four-bar at N = 1000, over the limit
// with every stage, is within it with the cycle's.
TEST(Workspace, StagesAllocateOnlyWhatTheyCountAndTheBasisIsUnchanged) {
  const WorkspaceStages cycle_stages{
      .mass = MassStorage::diagonal_if_possible, .primal = false, .dual_projections = false};
  const Model model = test::load_bundled("crank-rocker");
  Workspace full(model, model.nc);
  Workspace reduced(model, model.nc, ChartFactorisation::dense, cycle_stages);
  const Eigen::Index counted =
      reduced.free.M.size() + reduced.free.A.size() + reduced.free.Mdot.size() +
      reduced.constraints.Et.size() + reduced.constraints.Dt.size() + reduced.primal.AE.size() +
      reduced.primal.G.size() + reduced.primal.GinvEt.size() + reduced.primal.pi.size() +
      reduced.primal.alpha.size() + reduced.primal.beta.size() + reduced.primal.GinvDt.size() +
      reduced.primal.Omega.size() + reduced.primal.omega.size() + reduced.dual.psi.size() +
      reduced.dual.alpha.size() + reduced.dual.beta.size() + reduced.dual.Theta.size() +
      reduced.dual.theta.size();
  EXPECT_EQ(counted, 2 * model.nc * model.n);  // Eᵀ and Dᵀ: M is diagonal
  EXPECT_EQ(dense_workspace_bytes(model, cycle_stages), 8.0 * static_cast<double>(counted));
  EXPECT_LT(dense_workspace_bytes(model, cycle_stages), dense_workspace_bytes(model));

  State s(model);
  s.q = model.design_q();
  for (Workspace* ws : {&full, &reduced}) {
    compute_free_system(model, s, *ws);
    compute_constraints(model, s, ws->constraints);
    ASSERT_EQ(compute_basis(model, s, *ws), ProjectionStatus::ok);
  }
  EXPECT_EQ(reduced.dual.F, full.dual.F);
  EXPECT_LT((full.constraints.Et * reduced.dual.F).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_EQ(compute_dual(model, s, full), ProjectionStatus::ok);
  EXPECT_THROW((void)compute_dual(model, s, reduced), std::logic_error);
  EXPECT_THROW((void)compute_primal(model, s, reduced), std::logic_error);

  const Model n_four_bar = parse_mechanism(test::n_four_bar_yaml(1000, 0.5), "n-four-bar.yaml");
  EXPECT_GT(dense_workspace_bytes(n_four_bar), kMaxDenseWorkspaceBytes);
  EXPECT_LT(dense_workspace_bytes(n_four_bar, cycle_stages), kMaxDenseWorkspaceBytes);
}

// Without the constraint matrices (WorkspaceStages::constraint_matrices = false: the cycle of a
// large model, whose Eᵀ is on its pattern) Eᵀ and Dᵀ are 0 × 0 and not counted, compute_constraints
// refuses the Workspace, and compute_basis from Eᵀ on its pattern gives the F of the full
// Workspace bit for bit (the same chart engine, the same values) on every bundled mechanism with a
// degree of freedom.
TEST(Workspace, WithoutConstraintMatricesTheBasisComesFromThePattern) {
  const WorkspaceStages lean{.mass = MassStorage::diagonal_if_possible,
                             .primal = false,
                             .dual_projections = false,
                             .constraint_matrices = false};
  const WorkspaceStages with_matrices{
      .mass = MassStorage::diagonal_if_possible, .primal = false, .dual_projections = false};
  int compared = 0;
  for (const auto& e : std::filesystem::directory_iterator(test::source_path("mechanisms"))) {
    if (e.path().extension() != ".yaml") continue;
    const std::string name = e.path().stem().string();
    const Model model = test::load_bundled(name);
    const Mobility mob = compute_mobility(model, model.design_q());
    if (mob.dof < 1) continue;
    EXPECT_EQ(dense_workspace_bytes(model, with_matrices) - dense_workspace_bytes(model, lean),
              16.0 * model.nc * model.n)
        << name;
    Workspace full(model, mob.rank);
    Workspace reduced(model, mob.rank, ChartFactorisation::dense, lean);
    EXPECT_EQ(reduced.constraints.Et.size(), 0) << name;
    EXPECT_EQ(reduced.constraints.Dt.size(), 0) << name;
    State s(model);
    s.q = model.design_q();
    compute_free_system(model, s, full);
    compute_free_system(model, s, reduced);
    compute_constraints(model, s, full.constraints);
    EXPECT_THROW(compute_constraints(model, s, reduced.constraints), std::logic_error) << name;
    SparseEt Et(model);
    compute_constraint_jacobian(model, s.q, Et);
    const ProjectionStatus status = compute_basis(model, s, full);
    EXPECT_EQ(compute_basis(model, s, reduced, Et), status) << name;
    if (status != ProjectionStatus::ok) continue;
    EXPECT_EQ(reduced.dual.F, full.dual.F) << name;
    ++compared;
  }
  // All 23 bundled mechanisms when written (each has a DOF and a regular chart at its design).
  EXPECT_GT(compared, 10);
  const Model other = parse_mechanism(kTwoBodies, "two-bodies");
  const Model model = test::load_bundled("crank-rocker");
  Workspace ws(model, model.nc - 1, ChartFactorisation::dense, lean);
  State s(model);
  EXPECT_THROW((void)compute_basis(model, s, ws, SparseEt(other)), std::invalid_argument);
}

TEST(Workspace, RefusesARankOutOfRangeAndAnotherModel) {
  const Model model = parse_mechanism(kTwoBodies, "two-bodies");
  EXPECT_THROW(Workspace(model, -1), std::invalid_argument);
  EXPECT_THROW(Workspace(model, model.nc + 1), std::invalid_argument);
  const Model other = parse_mechanism(kTwoBodies, "two-bodies");
  Workspace ws(other, other.nc);
  State s(model);
  s.q = model.design_q();
  EXPECT_THROW(compute_free_system(model, s, ws), std::invalid_argument);
}

TEST(Workspace, EveryProjectionStatusHasItsOwnText) {
  std::set<std::string> texts;
  for (ProjectionStatus st : {ProjectionStatus::ok, ProjectionStatus::singular_G,
                              ProjectionStatus::singular_chart, ProjectionStatus::singular_H})
    texts.insert(to_string(st));
  EXPECT_EQ(texts.size(), 4u);
}

}  // namespace
}  // namespace orthomech
