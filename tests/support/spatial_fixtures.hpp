#pragma once
// Small spatial models built in code (no file reader): two spatial bodies with full (non-diagonal)
// inertia tensors at general design poses, and one joint of a given type between body 0 and
// body 1, the ground and body 1, or body 0 and the ground, assembled at the design position.
#include <random>

#include "orthomech/constraints/spatial_joints.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/model/model.hpp"
#include "orthomech/model/spatial.hpp"
#include "orthomech/model/state.hpp"

namespace orthomech::testing::spatial {

inline Quat unit_quaternion(double e0, double e1, double e2, double e3) {
  return Quat(e0, e1, e2, e3).normalized();
}

// A spatial body: frame origin `origin`, orientation e, com offset, full inertia tensor.
inline Body body(const std::string& name, double mass, const Vec3& origin, const Quat& e,
                 const Vec3& com, const Mat3& inertia) {
  Body b;
  b.name = name;
  b.kind = BodyKind::spatial;
  b.mass = mass;
  b.spatial.inertia = inertia;
  b.spatial.com_local = com;
  b.spatial.design_position = origin;
  b.spatial.design_orientation = e;
  return b;
}

inline Mat3 inertia_a() {
  Mat3 J;
  J << 0.30, 0.02, -0.01, 0.02, 0.25, 0.03, -0.01, 0.03, 0.12;
  return J;
}
inline Mat3 inertia_b() {
  Mat3 J;
  J << 0.08, -0.01, 0.005, -0.01, 0.11, 0.0, 0.005, 0.0, 0.05;
  return J;
}

// The point of body b (or the ground) at world position p at the design pose: s from the
// centre of mass in body axes.
inline SpatialPointRef point_at(const Model& m, int b, const Vec3& p) {
  SpatialPointRef r;
  r.body = b;
  if (b == kGround) {
    r.s = p;
    return r;
  }
  const VecX q = m.design_q();
  const Body& body = m.bodies[static_cast<size_t>(b)];
  const Mat3 R = rotation_matrix(q.segment<4>(body.q_offset + 3));
  r.s = R.transpose() * (p - q.segment<3>(body.q_offset));
  return r;
}

inline Mat3 frame_in(const Model& m, int b, const Mat3& world) {
  if (b == kGround) return world;
  const VecX q = m.design_q();
  return rotation_matrix(q.segment<4>(m.bodies[static_cast<size_t>(b)].q_offset + 3)).transpose() *
         world;
}

// pair 0: (body 0, body 1); 1: (ground, body 1); 2: (body 0, ground).
inline Model two_body_model(SpatialJointType type, int pair) {
  Model m;
  m.name = "two-body";
  m.dimension = 3;
  m.bodies.push_back(body("a", 2.0, Vec3(0.1, -0.3, 0.4), unit_quaternion(0.9, 0.2, -0.3, 0.1),
                          Vec3(0.05, 0.02, -0.04), inertia_a()));
  m.bodies.push_back(body("b", 1.5, Vec3(0.5, 0.2, 0.1), unit_quaternion(0.7, -0.4, 0.3, 0.5),
                          Vec3(-0.03, 0.06, 0.01), inertia_b()));
  finalize_model(m);  // offsets, so that design_q works below
  const int bi = pair == 1 ? kGround : 0;
  const int bj = pair == 2 ? kGround : 1;
  const Vec3 P(0.3, -0.2, 0.5);
  // The joint frame in world: h along (0.2, 0.5, 0.84), f perpendicular.
  const Vec3 h = Vec3(0.2, 0.5, 0.84).normalized();
  const Vec3 f = h.unitOrthogonal();
  Mat3 A;
  A << f, h.cross(f), h;
  SpatialJoint j;
  j.type = type;
  j.pi = point_at(m, bi, P);
  const Vec3 Pj = type == SpatialJointType::distance ? Vec3(P + Vec3(0.1, 0.2, -0.15)) : P;
  j.pj = point_at(m, bj, Pj);
  j.frame_i = frame_in(m, bi, A);
  j.frame_j = frame_in(m, bj, A);
  j.ref_j = j.frame_j.col(0);
  j.pitch = 0.05;
  j.length = (Pj - P).norm();
  Joint joint;
  joint.name = "J";
  joint.kind = j;
  m.joints.push_back(joint);
  finalize_model(m);
  return m;
}

// A state near the design position: q = q_design ⊕ δ with δ uniform in ±amplitude, u normal.
inline State random_state(const Model& m, std::mt19937_64& rng, double amplitude) {
  std::uniform_real_distribution<double> U(-amplitude, amplitude);
  std::normal_distribution<double> N(0.0, 1.0);
  State s(m);
  s.q = m.design_q();
  VecX d(m.n);
  for (int k = 0; k < m.n; ++k) d(k) = U(rng);
  integrate_positions(m, s.q, d, 1.0);
  for (int k = 0; k < m.n; ++k) s.u(k) = N(rng);
  return s;
}

}  // namespace orthomech::testing::spatial
