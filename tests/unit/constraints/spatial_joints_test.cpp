// Spatial joints (docs/spatial.md §2): every row's Eᵀ, Dᵀ and Dᵀu against central differences taken
// through integrate_positions (q ⊕ t·u, the exponential map), at random poses that do not
// satisfy the joint, for body pairs (i, j), (ground, j) and (i, ground). Also the joint
// coordinates (angle, slide) and the rows' zeros at the design position.
#include "orthomech/constraints/spatial_joints.hpp"

#include <gtest/gtest.h>

#include <numbers>
#include <random>

#include "orthomech/constraints/joints.hpp"
#include "orthomech/constraints/sparse_et.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/model/loads.hpp"
#include "orthomech/model/measures.hpp"
#include "orthomech/model/spatial.hpp"
#include "support/spatial_fixtures.hpp"

namespace orthomech {
namespace {

using testing::spatial::random_state;
using testing::spatial::two_body_model;

constexpr SpatialJointType kAll[] = {
    SpatialJointType::spherical, SpatialJointType::revolute,      SpatialJointType::cylindrical,
    SpatialJointType::prismatic, SpatialJointType::fixed,         SpatialJointType::universal,
    SpatialJointType::planar,    SpatialJointType::point_on_line, SpatialJointType::point_on_plane,
    SpatialJointType::distance,  SpatialJointType::screw};

// f at q ⊕ t·du.
VecX residual_along(const Model& m, const VecX& q, const VecX& du, double t) {
  VecX qt = q;
  integrate_positions(m, qt, du, t);
  VecX f(m.nc);
  compute_constraint_residual(m, qt, f);
  return f;
}
MatX jacobian_along(const Model& m, const VecX& q, const VecX& du, double t) {
  VecX qt = q;
  integrate_positions(m, qt, du, t);
  MatX Et(m.nc, m.n);
  compute_constraint_jacobian(m, qt, Et);
  return Et;
}

struct Case {
  SpatialJointType type;
  int pair;  // 0: (body 0, body 1); 1: (ground, body 1); 2: (body 0, ground)
};

class SpatialJointRows : public ::testing::TestWithParam<Case> {};

TEST_P(SpatialJointRows, MatchCentralDifferencesThroughIntegrate) {
  const Case c = GetParam();
  const Model m = two_body_model(c.type, c.pair);
  std::mt19937_64 rng(42 + static_cast<unsigned>(c.type) * 7 + static_cast<unsigned>(c.pair));
  for (int draw = 0; draw < 5; ++draw) {
    // Near the design (the screw's wrap and the twist angle's poles stay away), not assembled.
    const State s = random_state(m, rng, 0.4);
    ConstraintWorkspace ws(m);
    compute_constraints(m, s, ws);
    const double scale = std::max(1.0, ws.Et.cwiseAbs().maxCoeff());
    // Eᵀ column k: df/dt along q ⊕ t e_k.
    const double h = 1e-6;
    for (int k = 0; k < m.n; ++k) {
      const VecX ek = VecX::Unit(m.n, k);
      const VecX fd = (residual_along(m, s.q, ek, h) - residual_along(m, s.q, ek, -h)) / (2 * h);
      EXPECT_LT((ws.Et.col(k) - fd).cwiseAbs().maxCoeff(), 1e-7 * scale)
          << spatial_joint_spec(c.type).type << " pair " << c.pair << " column " << k;
    }
    // Dᵀ: dEᵀ/dt along q ⊕ t u.
    const MatX Dt_fd = (jacobian_along(m, s.q, s.u, h) - jacobian_along(m, s.q, s.u, -h)) / (2 * h);
    const double dscale = std::max(1.0, ws.Dt.cwiseAbs().maxCoeff());
    EXPECT_LT((ws.Dt - Dt_fd).cwiseAbs().maxCoeff(), 1e-7 * dscale)
        << spatial_joint_spec(c.type).type << " pair " << c.pair;
    // Dᵀu row by row (without Dᵀ) equals Dᵀ·u.
    ConstraintWorkspace rate(m);
    compute_constraint_rate(m, s, rate);
    EXPECT_LT((rate.Dtu - ws.Dt * s.u).cwiseAbs().maxCoeff(), 1e-12 * dscale);
    // Dᵀu = f̈ along q ⊕ t u (u constant: a motion with u̇ = 0).
    const double h2 = 1e-4;
    const VecX f2 = (residual_along(m, s.q, s.u, h2) - 2.0 * residual_along(m, s.q, s.u, 0.0) +
                     residual_along(m, s.q, s.u, -h2)) /
                    (h2 * h2);
    EXPECT_LT((ws.Dtu - f2).cwiseAbs().maxCoeff(), 1e-5 * dscale)
        << spatial_joint_spec(c.type).type << " pair " << c.pair;
  }
}

std::vector<Case> all_cases() {
  std::vector<Case> cases;
  for (SpatialJointType t : kAll)
    for (int pair = 0; pair < 3; ++pair) cases.push_back({t, pair});
  return cases;
}
INSTANTIATE_TEST_SUITE_P(AllTypes, SpatialJointRows, ::testing::ValuesIn(all_cases()),
                         [](const ::testing::TestParamInfo<Case>& p) {
                           std::string name = spatial_joint_spec(p.param.type).type;
                           for (char& ch : name)
                             if (ch == '-') ch = '_';
                           return name + "_" + std::to_string(p.param.pair);
                         });

// At the design position every joint's rows vanish (the frames coincide, the points coincide,
// the distance is its length), and Eᵀ has full row rank (docs/spatial.md §2.4: rank = rows).
TEST(SpatialJointRows, VanishAtTheDesignPositionWithFullRank) {
  for (SpatialJointType t : kAll) {
    const Model m = two_body_model(t, 0);
    VecX f(m.nc);
    MatX Et(m.nc, m.n);
    const VecX q = m.design_q();
    compute_constraint_residual(m, q, f);
    compute_constraint_jacobian(m, q, Et);
    EXPECT_LT(f.cwiseAbs().maxCoeff(), 1e-14) << spatial_joint_spec(t).type;
    Eigen::FullPivLU<MatX> lu(Et);
    lu.setThreshold(1e-10);
    EXPECT_EQ(lu.rank(), spatial_joint_spec(t).rows) << spatial_joint_spec(t).type;
  }
}

// Relative degrees of freedom: the null space of Eᵀ restricted to body j with body i the ground
// (docs/spatial.md §2.4, "rel. DOF").
TEST(SpatialJointRows, RelativeDegreesOfFreedom) {
  const std::pair<SpatialJointType, int> expected[] = {
      {SpatialJointType::spherical, 3},      {SpatialJointType::revolute, 1},
      {SpatialJointType::cylindrical, 2},    {SpatialJointType::prismatic, 1},
      {SpatialJointType::fixed, 0},          {SpatialJointType::universal, 2},
      {SpatialJointType::planar, 3},         {SpatialJointType::point_on_line, 4},
      {SpatialJointType::point_on_plane, 5}, {SpatialJointType::distance, 5},
      {SpatialJointType::screw, 1}};
  for (const auto& [t, dof] : expected) {
    const Model m = two_body_model(t, 1);  // ground and body 1 (body 0 free)
    MatX Et(m.nc, m.n);
    compute_constraint_jacobian(m, m.design_q(), Et);
    Eigen::FullPivLU<MatX> lu(Et.rightCols(6));
    lu.setThreshold(1e-10);
    EXPECT_EQ(6 - lu.rank(), dof) << spatial_joint_spec(t).type;
  }
}

// The joint coordinate: a revolute turned by a known angle about its axis reads that angle; a
// prismatic moved along its axis reads the slide; rates and accelerations match differences.
TEST(SpatialJointCoordinate, AngleAndSlideAgainstKnownMotionsAndDifferences) {
  for (SpatialJointType t : {SpatialJointType::revolute, SpatialJointType::prismatic,
                             SpatialJointType::cylindrical, SpatialJointType::screw}) {
    const Model m = two_body_model(t, 1);
    const auto& joint = std::get<SpatialJoint>(m.joints[0].kind);
    const VecX q0 = m.design_q();
    const Body& b = m.bodies[1];
    // The world joint axis (ground frame_i column h) in body 1's frame.
    const Mat3 R1 = rotation_matrix(q0.segment<4>(b.q_offset + 3));
    const Vec3 axis_world = joint.frame_i.col(2);
    const Vec3 axis_body = R1.transpose() * axis_world;
    // Rotate body 1 about the joint axis through P_j by 0.3 rad (a motion of the revolute).
    VecX du = VecX::Zero(m.n);
    const bool slide = t == SpatialJointType::prismatic;
    if (slide) {
      du.segment<3>(b.u_offset) = 0.25 * axis_world;
    } else {
      du.segment<3>(b.u_offset + 3) = 0.3 * axis_body;
      // Keep P_j fixed: v = −w × ρ_j.
      du.segment<3>(b.u_offset) = -(0.3 * axis_world).cross(R1 * joint.pj.s);
    }
    VecX q = q0;
    integrate_positions(m, q, du, 1.0);
    const SpatialScalar c0 = spatial_joint_coordinate(m, joint, q0, nullptr);
    const SpatialScalar c1 = spatial_joint_coordinate(m, joint, q, nullptr);
    if (slide) {
      EXPECT_NEAR(c1.value - c0.value, 0.25, 1e-13);
    } else {
      EXPECT_NEAR(c1.value - c0.value, 0.3, 1e-13) << spatial_joint_spec(t).type;
    }
    // Rates and accelerations through the measure at a random state, against differences of
    // its value along q ⊕ t u (u̇ = 0).
    std::mt19937_64 rng(7);
    const State s = random_state(m, rng, 0.4);
    const Measure pos{"c", JointCoordinate{0}, 0, "", {}};
    const Measure vel{"c", JointCoordinate{0}, 1, "", {}};
    const Measure acc{"c", JointCoordinate{0}, 2, "", {}};
    const auto value_at = [&](double dt) {
      VecX qt = s.q;
      integrate_positions(m, qt, s.u, dt);
      return evaluate_measure(m, pos, qt, nullptr, nullptr);
    };
    const double h = 1e-5, h2 = 1e-4;
    EXPECT_NEAR(evaluate_measure(m, vel, s.q, &s.u, nullptr),
                (value_at(h) - value_at(-h)) / (2 * h), 1e-8);
    const VecX zero = VecX::Zero(m.n);
    EXPECT_NEAR(evaluate_measure(m, acc, s.q, &s.u, &zero),
                (value_at(h2) - 2 * value_at(0) + value_at(-h2)) / (h2 * h2), 1e-5);
  }
}

}  // namespace
}  // namespace orthomech

namespace orthomech {
namespace {

// Reactions (docs/spatial.md §2.6, (S7)): for random multipliers at the assembled design position,
// (1) the wrench equals body i's columns of Eλ (Eᵀ from the row writer) reduced to the joint
// point, (2) the rows are self-equilibrated (body j gets the opposite wrench), and (3) each joint
// transmits only what it should: the components of the table are zero.
TEST(SpatialJointReaction, EqualsEλAndIsSelfEquilibratedAndHasTheJointsZeros) {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> N(0.0, 1.0);
  for (SpatialJointType t : kAll) {
    const Model m = two_body_model(t, 0);
    const auto& joint = std::get<SpatialJoint>(m.joints[0].kind);
    const VecX q = m.design_q();
    MatX Et(m.nc, m.n);
    compute_constraint_jacobian(m, q, Et);
    for (int draw = 0; draw < 5; ++draw) {
      VecX lambda(m.nc);
      for (int k = 0; k < m.nc; ++k) lambda(k) = N(rng);
      const VecX El = Et.transpose() * lambda;
      const SpatialWrench w = spatial_joint_reaction(m, joint, q, lambda);
      std::array<Vec3, 2> F, M;  // world force and world moment about each centre of mass
      std::array<Vec3, 2> r;
      for (size_t b = 0; b < 2; ++b) {
        const Body& body = m.bodies[b];
        F[b] = El.segment<3>(body.u_offset);
        M[b] = rotation_matrix(q.segment<4>(body.q_offset + 3)) * El.segment<3>(body.u_offset + 3);
        r[b] = q.segment<3>(body.q_offset);
      }
      const std::string name = spatial_joint_spec(t).type;
      const bool about_pj = t == SpatialJointType::point_on_line ||
                            t == SpatialJointType::point_on_plane ||
                            t == SpatialJointType::distance;
      const SpatialFrame ki = spatial_frame(m, 0, q, nullptr), kj = spatial_frame(m, 1, q, nullptr);
      const Vec3 P = about_pj ? spatial_point(kj, joint.pj.s).r : spatial_point(ki, joint.pi.s).r;
      EXPECT_LT((w.force - F[0]).norm(), 1e-12) << name;
      EXPECT_LT((w.moment - (M[0] + (r[0] - P).cross(F[0]))).norm(), 1e-12) << name;
      EXPECT_LT((F[0] + F[1]).norm(), 1e-12) << name;
      EXPECT_LT((M[0] + (r[0] - P).cross(F[0]) + M[1] + (r[1] - P).cross(F[1])).norm(), 1e-12)
          << name;
      // What the joint cannot transmit (joint frame f, g, h of body i).
      const Vec3& Fl = w.force_local;
      const Vec3& Ml = w.moment_local;
      const double z = 1e-12;
      switch (t) {
        case SpatialJointType::spherical:
          EXPECT_LT(Ml.norm(), z) << name;
          break;
        case SpatialJointType::revolute:
          EXPECT_LT(std::abs(Ml.z()), z) << name;
          break;
        case SpatialJointType::cylindrical:
          EXPECT_LT(std::abs(Fl.z()) + std::abs(Ml.z()), z) << name;
          break;
        case SpatialJointType::prismatic:
          EXPECT_LT(std::abs(Fl.z()), z) << name;
          break;
        case SpatialJointType::universal:
          EXPECT_LT(std::abs(Ml.x()), z) << name;
          break;
        case SpatialJointType::planar:
          EXPECT_LT(std::abs(Fl.x()) + std::abs(Fl.y()) + std::abs(Ml.z()), z) << name;
          break;
        case SpatialJointType::point_on_line:
          EXPECT_LT(std::abs(Fl.z()) + Ml.norm(), z) << name;
          break;
        case SpatialJointType::point_on_plane:
          EXPECT_LT(std::abs(Fl.x()) + std::abs(Fl.y()) + Ml.norm(), z) << name;
          break;
        case SpatialJointType::distance: {
          const Vec3 d = spatial_point(kj, joint.pj.s).r - spatial_point(ki, joint.pi.s).r;
          EXPECT_LT(w.force.cross(d).norm() + Ml.norm(), z) << name;
          break;
        }
        case SpatialJointType::screw:
          EXPECT_LT(std::abs(Ml.z() + joint.pitch / (2 * std::numbers::pi) * Fl.z()), z) << name;
          break;
        case SpatialJointType::fixed:
          break;
      }
    }
  }
}

}  // namespace
}  // namespace orthomech

namespace orthomech {
namespace {

// The kinematics stage (BodyPoses) on spatial bodies: R(e_b) of each body equals the rotation
// of its quaternion (eq. (S1), evaluated here from e independently of the stage: R v = e ⊗ v ⊗ e*),
// and f, Eᵀ and Dᵀu evaluated with the stage are the values without it, bit for bit, for every
// joint type and body pair (the stage only saves the per-row quaternion products).
TEST(SpatialKinematicsStage, RotationsAndRowsEqualTheDirectEvaluation) {
  std::mt19937_64 rng(29);
  for (const SpatialJointType type : kAll) {
    for (int pair = 0; pair < 3; ++pair) {
      const Model m = two_body_model(type, pair);
      const State s = random_state(m, rng, 0.3);
      BodyPoses poses(m);
      poses.update(m, s.q);
      for (size_t b = 0; b < m.bodies.size(); ++b) {
        const Quat e = s.q.segment<4>(m.bodies[b].q_offset + 3);
        Quat conj = e;
        conj.tail<3>() = -conj.tail<3>();
        for (int c = 0; c < 3; ++c) {
          Quat v = Quat::Zero();
          v(1 + c) = 1.0;
          const Quat rotated = quaternion_multiply(quaternion_multiply(e, v), conj);
          EXPECT_LT((poses.spatial(static_cast<int>(b)).col(c) - rotated.tail<3>()).norm(), 1e-15)
              << spatial_joint_spec(type).type << " body " << b;
        }
      }
      VecX f(m.nc), f_stage(m.nc), Dtu(m.nc), Dtu_stage(m.nc);
      MatX Et(m.nc, m.n), Et_stage(m.nc, m.n);
      compute_constraint_residual_and_jacobian(m, s.q, f, Et);  // no stage
      compute_constraint_residual_and_jacobian(m, s.q, poses, f_stage, Et_stage);
      const auto& joint = std::get<SpatialJoint>(m.joints[0].kind);
      evaluate_spatial_joint<MatX>(m, joint, s.q, &s.u, 0, nullptr, nullptr, nullptr, &Dtu);
      compute_constraint_rate(m, s, poses, Dtu_stage);
      ConstraintWorkspace ws(m);  // the workspace's own stage
      compute_constraints(m, s, ws);
      const std::string type_name = spatial_joint_spec(type).type;
      EXPECT_EQ(f, f_stage) << type_name;
      EXPECT_EQ(Et, Et_stage) << type_name;
      EXPECT_EQ(Dtu, Dtu_stage) << type_name;
      EXPECT_EQ(ws.f, f) << type_name;
      EXPECT_EQ(ws.Et, Et) << type_name;
      compute_constraint_rate(m, s, ws);
      EXPECT_EQ(ws.Dtu, Dtu) << type_name;
    }
  }
}

// One angle convention, (−π, π] (issue 47): a joint at 180° whose sine is −0 (atan2(−0, −1) is
// −π) reads +π, as `cycle` takes it; just below 180° on either side the angle is continuous with
// ±π, and the exact closed form atan2(sin θ, cos θ) elsewhere.
TEST(SpatialJoints, TwistAngleIsInMinusPiToPi) {
  const Vec3 fi(1, 0, 0), gi(0, 1, 0), w = Vec3::Zero();
  EXPECT_EQ(twist_angle(fi, gi, Vec3(-1.0, -0.0, 0.0), w, w).theta, std::numbers::pi);
  EXPECT_EQ(twist_angle(fi, gi, Vec3(-1.0, 0.0, 0.0), w, w).theta, std::numbers::pi);
  for (const double theta : {-3.14, -2.0, -0.5, 0.0, 0.5, 2.0, 3.14})
    EXPECT_NEAR(twist_angle(fi, gi, Vec3(std::cos(theta), std::sin(theta), 0.0), w, w).theta, theta,
                1e-15);
}

}  // namespace
}  // namespace orthomech
