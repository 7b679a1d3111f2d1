// The Workspace (projection/workspace.hpp) and its stage 1, the free system
// (projection/free_system_stage.hpp): M, A = M⁻¹ and the applied forces Q̂ at a state.
//
// Oracles written here: for planar bodies in absolute coordinates M = diag(m, m, J_c) per rigid
// body and diag(m, m) per particle (eq. (4)), from the file's masses and inertias; A M = I;
// gravity's generalized force (0, m g_y, 0) per body and a body torque τ on its angle (eq. (17)).
#include "orthomech/projection/workspace.hpp"

#include <gtest/gtest.h>

#include <set>
#include <stdexcept>
#include <string>

#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/projection/free_system_stage.hpp"

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
