// Joint reactions (analysis/reactions.hpp) from the multipliers λ.
//
// Oracle: the generalized force E λ written by the constraint Jacobian (constraints/joints.cpp,
// checked against central differences in joints_test.cpp). For a joint J with rows R_J and
// multipliers λ_J, E_Jλ_J restricted to a body's translational velocities is the force the joint
// applies to that body, and its rotation entry is the moment about the body's centre of mass.
// compute_reactions reports the force on the joint's first body from its second (or, with the
// ground first, the reaction on the second body is its negative), in the world frame and in the
// joint's frame (the first moving body's axes, rotated here from the body's angle in q). The zoo
// mechanism (support/zoo.hpp) holds every planar joint type at a pose that is not assembled: the
// identity holds at any q.
#include "orthomech/analysis/reactions.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <string>
#include <type_traits>

#include "orthomech/constraints/joints.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "support/zoo.hpp"

namespace orthomech {
namespace {

struct JointEnds {
  int first = kGround, second = kGround;
  Vec2 first_point_local = Vec2::Zero();  // the joint's point on the first body (body frame)
};

JointEnds ends_of(const Joint& joint) {
  JointEnds e;
  std::visit(
      [&](const auto& k) {
        using T = std::decay_t<decltype(k)>;
        if constexpr (!std::is_same_v<T, SpatialJoint> && requires { k.pi; }) {
          e.first = k.pi.body;
          e.second = k.pj.body;
          e.first_point_local = k.pi.s;
        }
      },
      joint.kind);
  return e;
}

// Reported value of component `name` (e.g. "J1.Fx").
std::map<std::string, double> by_name(const std::vector<ReactionComponent>& components,
                                      const std::vector<double>& values) {
  std::map<std::string, double> out;
  for (size_t i = 0; i < components.size(); ++i) out[components[i].name] = values[i];
  return out;
}

VecX seeded_lambda(int nc) {
  VecX lambda(nc);
  for (int r = 0; r < nc; ++r) lambda(r) = 40.0 * std::sin(1.3 * r + 0.4) + 5.0;
  return lambda;
}

TEST(Reactions, ForceOnTheFirstBodyIsItsShareOfTheGeneralizedForce) {
  const Model model = parse_mechanism(test::kZooYaml, "zoo");
  const VecX q = model.design_q();
  const VecX lambda = seeded_lambda(model.nc);
  MatX Et(model.nc, model.n);
  compute_constraint_jacobian(model, q, Et);
  std::vector<double> values;
  compute_reactions(model, q, lambda, values);
  const std::vector<ReactionComponent> components = reaction_components(model);
  ASSERT_EQ(values.size(), components.size());
  const std::map<std::string, double> v = by_name(components, values);
  int checked = 0;
  for (const Joint& joint : model.joints) {
    if (!v.contains(joint.name + ".Fx")) continue;  // a gear pair: no force
    const JointEnds e = ends_of(joint);
    const VecX g = Et.middleRows(joint.row_offset, joint.rows()).transpose() *
                   lambda.segment(joint.row_offset, joint.rows());
    const Vec2 F(v.at(joint.name + ".Fx"), v.at(joint.name + ".Fy"));
    const double scale = 1e-12 * (1.0 + lambda.cwiseAbs().maxCoeff());
    if (e.first != kGround) {
      const Body& b = model.bodies[static_cast<size_t>(e.first)];
      EXPECT_NEAR(F.x(), g(b.u_offset), scale) << joint.name;
      EXPECT_NEAR(F.y(), g(b.u_offset + 1), scale) << joint.name;
    }
    if (e.second != kGround) {  // the second body takes the opposite force (action–reaction)
      const Body& b = model.bodies[static_cast<size_t>(e.second)];
      EXPECT_NEAR(-F.x(), g(b.u_offset), scale) << joint.name;
      EXPECT_NEAR(-F.y(), g(b.u_offset + 1), scale) << joint.name;
    }
    ++checked;
  }
  EXPECT_GE(checked, 6);  // revolute ×2, prismatic ×2, fixed, pin-in-slot, distance
}

// A revolute joint's moment on its first body about its centre of mass is that of the pin force
// at the pin, (R(φ) s) × F: the rotation entry of E λ.
TEST(Reactions, RevolutePinForceActsAtThePin) {
  const Model model = parse_mechanism(test::kZooYaml, "zoo");
  const VecX q = model.design_q();
  const VecX lambda = seeded_lambda(model.nc);
  MatX Et(model.nc, model.n);
  compute_constraint_jacobian(model, q, Et);
  std::vector<double> values;
  compute_reactions(model, q, lambda, values);
  const std::map<std::string, double> v = by_name(reaction_components(model), values);
  int checked = 0;
  for (const Joint& joint : model.joints) {
    if (!std::holds_alternative<Revolute>(joint.kind)) continue;
    const JointEnds e = ends_of(joint);
    if (e.first == kGround) continue;
    const Body& b = model.bodies[static_cast<size_t>(e.first)];
    const double phi = q(b.q_offset + 2);
    const Vec2 s = e.first_point_local;
    const Vec2 Rs(std::cos(phi) * s.x() - std::sin(phi) * s.y(),
                  std::sin(phi) * s.x() + std::cos(phi) * s.y());
    const Vec2 F(v.at(joint.name + ".Fx"), v.at(joint.name + ".Fy"));
    const VecX g =
        Et.middleRows(joint.row_offset, 2).transpose() * lambda.segment(joint.row_offset, 2);
    EXPECT_NEAR(Rs.x() * F.y() - Rs.y() * F.x(), g(b.u_offset + 2), 1e-11) << joint.name;
    ++checked;
  }
  EXPECT_GE(checked, 1);
}

// The joint frame: Fx_local, Fy_local are the world force in the axes of the first moving body,
// R(φ)ᵀ F (rotation written here from the angle in q).
TEST(Reactions, LocalComponentsAreTheForceInTheJointsFrame) {
  const Model model = parse_mechanism(test::kZooYaml, "zoo");
  const VecX q = model.design_q();
  std::vector<double> values;
  compute_reactions(model, q, seeded_lambda(model.nc), values);
  const std::map<std::string, double> v = by_name(reaction_components(model), values);
  int checked = 0;
  for (const Joint& joint : model.joints) {
    if (!v.contains(joint.name + ".Fx_local")) continue;
    const JointEnds e = ends_of(joint);
    const int frame = e.first != kGround ? e.first : e.second;
    const Body& b = model.bodies[static_cast<size_t>(frame)];
    const double phi = b.kind == BodyKind::rigid ? q(b.q_offset + 2) : 0.0;
    const Vec2 F(v.at(joint.name + ".Fx"), v.at(joint.name + ".Fy"));
    EXPECT_NEAR(v.at(joint.name + ".Fx_local"), std::cos(phi) * F.x() + std::sin(phi) * F.y(),
                1e-12 * (1.0 + F.norm()))
        << joint.name;
    EXPECT_NEAR(v.at(joint.name + ".Fy_local"), -std::sin(phi) * F.x() + std::cos(phi) * F.y(),
                1e-12 * (1.0 + F.norm()))
        << joint.name;
    ++checked;
  }
  EXPECT_GE(checked, 3);  // two revolutes and the fixed joint
}

// With the bodies' rotations at q already computed the values are the same as without.
TEST(Reactions, WithTheBodyPosesTheSameValues) {
  const Model model = parse_mechanism(test::kZooYaml, "zoo");
  const VecX q = model.design_q();
  const VecX lambda = seeded_lambda(model.nc);
  BodyPoses rotations(model);
  rotations.update(model, q);
  std::vector<double> plain, with_table;
  compute_reactions(model, q, lambda, plain);
  compute_reactions(model, q, rotations, lambda, with_table);
  ASSERT_EQ(plain.size(), with_table.size());
  for (size_t i = 0; i < plain.size(); ++i)
    EXPECT_NEAR(plain[i], with_table[i], 1e-13 * (1.0 + std::abs(plain[i]))) << i;
}

}  // namespace
}  // namespace orthomech
