// The free system (src/model/free_system.cpp) on a rigid body and a particle, SI: M, A = M⁻¹,
// T = ½ uᵀ M u and the kinematics of points against sums written here from the body's data
// (mass, inertia about the centre of mass, points in the body frame), velocities of points
// against central differences of their positions, and the position update against q + h du.
#include "orthomech/model/free_system.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "orthomech/io/mechanism_file.hpp"

namespace orthomech {
namespace {

Model bar_and_puck() {
  return parse_mechanism(R"(orthomech: 1
name: bar-and-puck
bodies:
  - {name: bar, mass: 1.3, inertia: 0.02, com: [0.2, 0.05], pose: [0.1, -0.2, 0.4],
     points: {P: [0.4, 0.1]}}
  - {name: puck, type: particle, mass: 0.7, pose: [0.5, 0.3]}
)",
                         "bar-and-puck.yaml");
}

VecX sample_u(int n) {
  VecX u(n);
  for (int k = 0; k < n; ++k) u(k) = 1.5 * std::cos(0.9 * k + 0.3);
  return u;
}

TEST(FreeSystem, MassMatrixInverseAndKineticEnergy) {
  const Model model = bar_and_puck();
  ASSERT_EQ(model.n, 5);
  const VecX q = model.design_q();
  MatX M(5, 5), A(5, 5), Mdot(5, 5);
  compute_mass_matrix(model, q, M);
  VecX expected(5);
  expected << 1.3, 1.3, 0.02, 0.7, 0.7;  // (m, m, I) of the bar, (m, m) of the puck
  EXPECT_LT((M - MatX(expected.asDiagonal())).norm(), 1e-15);
  compute_inverse_mass_matrix(model, q, A);
  EXPECT_LT((M * A - MatX::Identity(5, 5)).norm(), 1e-14);
  const VecX u = sample_u(5);
  compute_mass_matrix_rate(model, q, u, Mdot);
  EXPECT_EQ(Mdot.norm(), 0.0);  // absolute planar coordinates: M constant
  EXPECT_TRUE(mass_matrix_is_constant(model));
  State s(model);
  s.q = q;
  s.u = u;
  const double T = 0.5 * (1.3 * (u(0) * u(0) + u(1) * u(1)) + 0.02 * u(2) * u(2) +
                          0.7 * (u(3) * u(3) + u(4) * u(4)));
  EXPECT_NEAR(kinetic_energy(model, s), T, 1e-14);
}

// q holds the centre of mass; a point P of the body frame is at pose + R(φ) P in the world.
TEST(FreeSystem, PointPositionsAndVelocities) {
  const Model model = bar_and_puck();
  const int bar = model.find_body("bar");
  ASSERT_GE(bar, 0);
  const VecX q = model.design_q();
  const double phi = 0.4;
  const Vec2 pose(0.1, -0.2), com(0.2, 0.05), P(0.4, 0.1);
  EXPECT_LT((Vec2(q(0), q(1)) - (pose + rotation(phi) * com)).norm(), 1e-15);
  EXPECT_NEAR(body_angle(model, bar, q), phi, 1e-15);
  PointRef p;
  p.body = bar;
  p.s = P - com;
  const PointKinematics k = point_kinematics(model, p, q, nullptr);
  EXPECT_LT((k.r - (pose + rotation(phi) * P)).norm(), 1e-15);
  EXPECT_TRUE(k.rotates);
  EXPECT_TRUE(k.moving);
  // Velocity against a central difference of the position along u.
  const VecX u = sample_u(model.n);
  const double h = 1e-6;
  VecX qp = q, qm = q;
  integrate_positions(model, qp, u, h);
  integrate_positions(model, qm, u, -h);
  const Vec2 v_fd =
      (point_kinematics(model, p, qp, nullptr).r - point_kinematics(model, p, qm, nullptr).r) /
      (2.0 * h);
  const PointKinematics kv = point_kinematics(model, p, q, &u);
  EXPECT_LT((kv.v - v_fd).norm(), 1e-8);
  EXPECT_EQ(kv.phidot, u(2));
  EXPECT_NEAR(body_angular_velocity(model, bar, u), u(2), 0.0);
  // The ground's points stand still.
  PointRef g;
  g.s = Vec2(0.3, -0.4);
  const PointKinematics kg = point_kinematics(model, g, q, &u);
  EXPECT_EQ(kg.r, g.s);
  EXPECT_EQ(kg.v, Vec2::Zero());
  EXPECT_FALSE(kg.moving);
}

// The Jacobian row cᵀ ∂r_P/∂u against central differences of cᵀ r_P.
TEST(FreeSystem, PointJacobianAgainstDifferences) {
  const Model model = bar_and_puck();
  const VecX q = model.design_q();
  PointRef p;
  p.body = model.find_body("bar");
  p.s = Vec2(0.2, 0.05);
  const Vec2 c(0.6, -0.8);
  VecX row = VecX::Zero(model.n);
  add_point_jacobian(model, p, point_kinematics(model, p, q, nullptr), c, 2.0, row);
  const double h = 1e-6;
  for (int j = 0; j < model.n; ++j) {
    VecX du = VecX::Zero(model.n);
    du(j) = 1.0;
    VecX qp = q, qm = q;
    integrate_positions(model, qp, du, h);
    integrate_positions(model, qm, du, -h);
    const double fd = 2.0 *
                      c.dot(point_kinematics(model, p, qp, nullptr).r -
                            point_kinematics(model, p, qm, nullptr).r) /
                      (2.0 * h);
    EXPECT_NEAR(row(j), fd, 1e-8) << "column " << j;
  }
}

// Planar coordinates: q ⊕ h du = q + h du exactly, and difference_positions inverts it.
TEST(FreeSystem, IntegrateAndDifferencePositions) {
  const Model model = bar_and_puck();
  const VecX q0 = model.design_q();
  const VecX du = sample_u(model.n);
  VecX q1 = q0;
  integrate_positions(model, q1, du, 0.25);
  EXPECT_LT((q1 - (q0 + 0.25 * du)).norm(), 1e-15);
  VecX back(model.n);
  difference_positions(model, q1, q0, back);
  EXPECT_LT((back - 0.25 * du).norm(), 1e-15);
  VecX qdot(model.nq);
  compute_coordinate_rates(model, q0, du, qdot);
  EXPECT_LT((qdot - du).norm(), 0.0 + 1e-15);  // B̃ = I for planar bodies
}

}  // namespace
}  // namespace orthomech
