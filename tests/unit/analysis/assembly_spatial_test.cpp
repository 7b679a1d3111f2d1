// assemble on spatial models (issue 12 item 6): Ipopt in local coordinates q = q₀ ⊕ x with the
// exact Jacobian Eᵀ·blockdiag(I, J_r(θ)), limited-memory Hessian. Checked: the right Jacobian of
// the exponential map against differences; the assembled pose closes every joint and is a KKT
// point of min ½ xᵀWx, f(q₀ ⊕ x) = 0 with the constraint Jacobian taken by central differences
// in x (independent of the code's J_r); a mechanism that cannot close names the joint.
#include <gtest/gtest.h>

#include <random>

#include "orthomech/analysis/assembly.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/model/spatial.hpp"
#include "support/spatial_fixtures.hpp"

namespace orthomech {
namespace {

using testing::spatial::two_body_model;

TEST(SpatialAssembly, RightJacobianOfTheExponentialMapMatchesDifferences) {
  for (const Vec3& theta : {Vec3(0.3, -1.2, 0.7), Vec3(1e-8, 2e-8, -1e-8), Vec3(2.5, 0.1, -0.4)}) {
    const Mat3 Jr = exp_right_jacobian(theta);
    const Quat e = quaternion_exp(theta);
    Quat conj = e;
    conj.tail<3>() = -conj.tail<3>();
    const double h = 1e-6;
    for (int k = 0; k < 3; ++k) {
      const Vec3 dk = Vec3::Unit(k) * h;
      const Vec3 wp = quaternion_log(quaternion_multiply(conj, quaternion_exp(theta + dk)));
      const Vec3 wm = quaternion_log(quaternion_multiply(conj, quaternion_exp(theta - dk)));
      EXPECT_LT((Jr.col(k) - (wp - wm) / (2 * h)).norm(), 1e-8) << theta.transpose();
    }
  }
}

TEST(SpatialAssembly, ClosesTheJointsAtAKktPointOfTheMassMetric) {
  for (SpatialJointType t : {SpatialJointType::revolute, SpatialJointType::universal,
                             SpatialJointType::screw, SpatialJointType::prismatic}) {
    const Model m = two_body_model(t, 1);  // ground and body 1
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> U(-0.05, 0.05);
    VecX q0 = m.design_q(), delta(m.n);
    for (int k = 0; k < m.n; ++k) delta(k) = U(rng);
    integrate_positions(m, q0, delta, 1.0);
    const AssemblyResult r = assemble(m, q0);
    ASSERT_EQ(r.status, AssemblyStatus::assembled) << r.message;
    VecX f(m.nc);
    compute_constraint_residual(m, r.q, f);
    EXPECT_LT(f.cwiseAbs().maxCoeff(), 1e-12);
    VecX x(m.n);
    difference_positions(m, r.q, q0, x);
    MatX M(m.n, m.n);
    compute_mass_matrix(m, q0, M);
    EXPECT_NEAR(r.distance, std::sqrt(x.dot(M * x)), 1e-12);
    // KKT: W x = Cᵀλ with C = ∂f/∂x by central differences at x.
    MatX C(m.nc, m.n);
    const double h = 1e-7;
    for (int k = 0; k < m.n; ++k) {
      VecX qp = q0, qm = q0;
      integrate_positions(m, qp, x + h * VecX::Unit(m.n, k), 1.0);
      integrate_positions(m, qm, x - h * VecX::Unit(m.n, k), 1.0);
      VecX fp(m.nc), fm(m.nc);
      compute_constraint_residual(m, qp, fp);
      compute_constraint_residual(m, qm, fm);
      C.col(k) = (fp - fm) / (2 * h);
    }
    const VecX g = M * x;
    const VecX lambda = C.transpose().completeOrthogonalDecomposition().solve(g);
    EXPECT_LT((C.transpose() * lambda - g).norm(), 1e-6 * g.norm())
        << spatial_joint_spec(t).type << ": not a stationary point";
    // And the guess moved: not the trivial answer.
    EXPECT_GT(x.norm(), 1e-3);
  }
}

TEST(SpatialAssembly, ARodLongerThanTheGapBetweenItsPivotsCannotClose) {
  Model m;
  m.name = "rod";
  m.dimension = 3;
  m.bodies.push_back(testing::spatial::body("rod", 1.0, Vec3(0.2, 0.0, 0.0), Quat(1, 0, 0, 0),
                                            Vec3::Zero(), testing::spatial::inertia_b()));
  finalize_model(m);
  auto spherical = [&](const std::string& name, const Vec3& ground, const Vec3& on_rod) {
    SpatialJoint s;
    s.type = SpatialJointType::spherical;
    s.pi = testing::spatial::point_at(m, kGround, ground);
    s.pj = testing::spatial::point_at(m, 0, on_rod);
    Joint j;
    j.name = name;
    j.kind = s;
    return j;
  };
  // The rod's ends are 0.4 m apart, its pivots 0.3 m: a 0.1 m gap whatever the pose.
  m.joints.push_back(spherical("A", Vec3(0.0, 0.0, 0.0), Vec3(0.0, 0.0, 0.0)));
  m.joints.push_back(spherical("B", Vec3(0.3, 0.0, 0.0), Vec3(0.4, 0.0, 0.0)));
  finalize_model(m);
  const AssemblyResult r = assemble(m, m.design_q());
  EXPECT_EQ(r.status, AssemblyStatus::cannot_close) << r.message;
  ASSERT_FALSE(r.gaps.empty());
  EXPECT_NEAR(r.total_gap, 0.1, 1e-6);
}

}  // namespace
}  // namespace orthomech

namespace orthomech {
namespace {

// A revolute whose axis is tilted by δ about its point (the points still coincide) has an angular
// residual of about δ and no length residual: the dot-1 rows are angles, not lengths.
TEST(SpatialAssembly, TiltedRevoluteAxisIsAnAngularResidual) {
  const Model m = testing::spatial::two_body_model(SpatialJointType::revolute, 1);
  const auto& joint = std::get<SpatialJoint>(m.joints[0].kind);
  const Body& b = m.bodies[1];
  VecX q = m.design_q();
  const Mat3 R = rotation_matrix(q.segment<4>(b.q_offset + 3));
  const Vec3 tilt_world = joint.frame_i.col(0);  // perpendicular to the axis h
  const double delta = 1e-3;
  VecX du = VecX::Zero(m.n);
  du.segment<3>(b.u_offset + 3) = delta * (R.transpose() * tilt_world);
  const Vec3 P = q.segment<3>(b.q_offset) + R * joint.pj.s;
  integrate_positions(m, q, du, 1.0);
  q.segment<3>(b.q_offset) = P - rotation_matrix(q.segment<4>(b.q_offset + 3)) * joint.pj.s;
  const ResidualSplit r = split_residual(m, q);
  EXPECT_NEAR(r.angle, std::sin(delta), 1e-9);
  EXPECT_LT(r.length, 1e-9);
}

}  // namespace
}  // namespace orthomech
