#include "orthomech/constraints/spatial_joints.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "orthomech/constraints/sparse_et.hpp"

namespace orthomech {

namespace {

using P = SpatialPrimitive;
constexpr SpatialRowSpec kX{P::point, 0, 0, "x"}, kY{P::point, 1, 0, "y"}, kZ{P::point, 2, 0, "z"};
constexpr SpatialRowSpec kF{P::dot1, 0, 2, "f"}, kG{P::dot1, 1, 2, "g"};
constexpr SpatialRowSpec kTwist{P::dot1, 1, 0, "twist"}, kPins{P::dot1, 0, 1, "pins"};
constexpr SpatialRowSpec kLineF{P::dot2, 0, 0, "line f"}, kLineG{P::dot2, 1, 0, "line g"};
constexpr SpatialRowSpec kNormal{P::dot2, 2, 0, "n"};
constexpr SpatialRowSpec kLength{P::length, 0, 0, "length"}, kScrew{P::screw, 0, 0, "screw"};

// Indexed by SpatialJointType (model.hpp), docs/spatial.md §2.4.
const std::array<SpatialJointSpec, 11> kSpecs{{
    {"spherical", 3, {kX, kY, kZ}, SpatialCoordinate::none},
    {"revolute", 5, {kX, kY, kZ, kF, kG}, SpatialCoordinate::angle},
    {"cylindrical", 4, {kLineF, kLineG, kF, kG}, SpatialCoordinate::angle},
    {"prismatic", 5, {kLineF, kLineG, kF, kG, kTwist}, SpatialCoordinate::slide},
    {"fixed", 6, {kX, kY, kZ, kF, kG, kTwist}, SpatialCoordinate::none},
    {"universal", 4, {kX, kY, kZ, kPins}, SpatialCoordinate::none},
    {"planar", 3, {kNormal, kF, kG}, SpatialCoordinate::none},
    {"point-on-line", 2, {kLineF, kLineG}, SpatialCoordinate::none},
    {"point-on-plane", 1, {kNormal}, SpatialCoordinate::none},
    {"distance", 1, {kLength}, SpatialCoordinate::none},
    {"screw", 5, {kLineF, kLineG, kF, kG, kScrew}, SpatialCoordinate::angle},
}};

// The rate of a row as Σ_b (g_b·v_b + h_b·w_b) and its time derivative (docs/spatial.md §2.2);
// index 0 is body i, 1 body j.
struct RowTerms {
  double f = 0.0;
  std::array<Vec3, 2> g{Vec3::Zero(), Vec3::Zero()}, h{Vec3::Zero(), Vec3::Zero()};
  std::array<Vec3, 2> gdot{Vec3::Zero(), Vec3::Zero()}, hdot{Vec3::Zero(), Vec3::Zero()};
};

// Everything a joint's rows share: the two frames, points, joint axes in world components.
struct JointKinematics {
  std::array<SpatialFrame, 2> k;
  std::array<SpatialPoint, 2> p;
  Mat3 Ai, Aj;          // joint frames in world components (columns f, g, h)
  Mat3 Ai_dot, Aj_dot;  // their rates w × a
  Vec3 d, ddot;         // r_Pj − r_Pi and its rate

  JointKinematics(const Model& model, const SpatialJoint& j, const VecX& q, const VecX* u,
                  const Mat3* rotations = nullptr)
      : k{spatial_frame(model, j.pi.body, q, u, rotations),
          spatial_frame(model, j.pj.body, q, u, rotations)} {
    p[0] = spatial_point(k[0], j.pi.s);
    p[1] = spatial_point(k[1], j.pj.s);
    Ai = k[0].R * j.frame_i;
    Aj = k[1].R * j.frame_j;
    Ai_dot = skew(k[0].w) * Ai;
    Aj_dot = skew(k[1].w) * Aj;
    d = p[1].r - p[0].r;
    ddot = p[1].v - p[0].v;
  }
};

// (P1) point component along world axis c.
RowTerms point_row(const JointKinematics& x, int axis) {
  const Vec3 c = Vec3::Unit(axis);
  RowTerms t;
  t.f = -c.dot(x.d);  // c·(r_Pi − r_Pj), eq. (20)
  t.g[0] = c;
  t.h[0] = x.p[0].rho.cross(c);
  t.hdot[0] = x.k[0].w.cross(x.p[0].rho).cross(c);
  t.g[1] = -c;
  t.h[1] = -x.p[1].rho.cross(c);
  t.hdot[1] = -x.k[1].w.cross(x.p[1].rho).cross(c);
  return t;
}

// (P2) dot-1: a_i·a_j.
RowTerms dot1_row(const Vec3& ai, const Vec3& aj, const Vec3& ai_dot, const Vec3& aj_dot) {
  RowTerms t;
  t.f = ai.dot(aj);
  const Vec3 c = ai.cross(aj);
  const Vec3 cdot = ai_dot.cross(aj) + ai.cross(aj_dot);
  t.h[0] = c;
  t.hdot[0] = cdot;
  t.h[1] = -c;
  t.hdot[1] = -cdot;
  return t;
}

// (P3) dot-2: a_i·d, the force acting at P_j on both bodies.
RowTerms dot2_row(const JointKinematics& x, const Vec3& ai, const Vec3& ai_dot) {
  RowTerms t;
  t.f = ai.dot(x.d);
  const Vec3 arm = x.p[1].r - x.k[0].r;  // from i's centre of mass to P_j
  const Vec3 arm_dot = x.p[1].v - x.k[0].v;
  t.g[0] = -ai;
  t.h[0] = ai.cross(arm);
  t.gdot[0] = -ai_dot;
  t.hdot[0] = ai_dot.cross(arm) + ai.cross(arm_dot);
  t.g[1] = ai;
  t.h[1] = x.p[1].rho.cross(ai);
  t.gdot[1] = ai_dot;
  t.hdot[1] = x.k[1].w.cross(x.p[1].rho).cross(ai) + x.p[1].rho.cross(ai_dot);
  return t;
}

// (P4) distance (|d|² − L²)/(2L).
RowTerms length_row(const JointKinematics& x, double L) {
  RowTerms t;
  t.f = (x.d.squaredNorm() - L * L) / (2.0 * L);
  for (int s = 0; s < 2; ++s) {
    const double sign = s == 0 ? -1.0 : 1.0;
    const Vec3& rho = x.p[s].rho;
    t.g[s] = sign * x.d / L;
    t.h[s] = sign * rho.cross(x.d) / L;
    t.gdot[s] = sign * x.ddot / L;
    t.hdot[s] = sign * (x.k[s].w.cross(rho).cross(x.d) + rho.cross(x.ddot)) / L;
  }
  return t;
}

// (S6) screw: (p/2π) wrap(2π z/p − θ); its rows are dot-2(h_i) − (p/2π)·(twist angle rows).
RowTerms screw_row(const JointKinematics& x, double pitch) {
  RowTerms t = dot2_row(x, x.Ai.col(2), x.Ai_dot.col(2));
  const TwistAngle th = twist_angle(x.Ai.col(0), x.Ai.col(1), x.Aj.col(0), x.k[0].w, x.k[1].w);
  const double c = pitch / (2.0 * std::numbers::pi);
  const double a = t.f / c - th.theta;
  t.f = c * std::atan2(std::sin(a), std::cos(a));
  t.h[0] -= c * th.k;
  t.hdot[0] -= c * th.kdot;
  t.h[1] += c * th.k;
  t.hdot[1] += c * th.kdot;
  return t;
}

RowTerms row_terms(const JointKinematics& x, const SpatialJoint& j, const SpatialRowSpec& spec) {
  switch (spec.primitive) {
    case P::point:
      return point_row(x, spec.a);
    case P::dot1:
      return dot1_row(x.Ai.col(spec.a), x.Aj.col(spec.b), x.Ai_dot.col(spec.a),
                      x.Aj_dot.col(spec.b));
    case P::dot2:
      return dot2_row(x, x.Ai.col(spec.a), x.Ai_dot.col(spec.a));
    case P::length:
      return length_row(x, j.length);
    case P::screw:
      return screw_row(x, j.pitch);
  }
  return {};
}

}  // namespace

const SpatialJointSpec& spatial_joint_spec(SpatialJointType type) {
  return kSpecs[static_cast<size_t>(type)];
}

bool find_spatial_joint_type(const std::string& name, SpatialJointType& type) {
  for (size_t k = 0; k < kSpecs.size(); ++k) {
    if (name == kSpecs[k].type) {
      type = static_cast<SpatialJointType>(k);
      return true;
    }
  }
  return false;
}

TwistAngle twist_angle(const Vec3& fi, const Vec3& gi, const Vec3& fj, const Vec3& wi,
                       const Vec3& wj) {
  TwistAngle a;
  const double x = fi.dot(fj), y = gi.dot(fj);
  a.theta = std::atan2(y, x);
  // One convention for every command, (−π, π]: atan2 gives −π for y = −0 (a joint drawn at
  // 180° read −180° in `assemble` and `info`, +180° in `cycle`).
  if (a.theta <= -std::numbers::pi) a.theta = std::numbers::pi;
  const Vec3 cx = fi.cross(fj), cy = gi.cross(fj);
  const double r2 = x * x + y * y;
  const Vec3 N = x * cy - y * cx;
  a.k = N / r2;  // θ̇ = (w_i − w_j)·k
  const Vec3 dw = wi - wj;
  const double xd = dw.dot(cx), yd = dw.dot(cy);
  const Vec3 fi_d = wi.cross(fi), gi_d = wi.cross(gi), fj_d = wj.cross(fj);
  const Vec3 Nd = xd * cy + x * (gi_d.cross(fj) + gi.cross(fj_d)) - yd * cx -
                  y * (fi_d.cross(fj) + fi.cross(fj_d));
  a.kdot = Nd / r2 - 2.0 * N * (x * xd + y * yd) / (r2 * r2);
  return a;
}

template <typename EtT>
void evaluate_spatial_joint(const Model& model, const SpatialJoint& joint, const VecX& q,
                            const VecX* u, int r, VecX* f, EtT* Et, MatX* Dt, VecX* Dtu,
                            const Mat3* rotations) {
  const JointKinematics x(model, joint, q, u, rotations);
  const SpatialJointSpec& spec = spatial_joint_spec(joint.type);
  for (int k = 0; k < spec.rows; ++k) {
    const RowTerms t = row_terms(x, joint, spec.row[static_cast<size_t>(k)]);
    if (f) (*f)(r + k) = t.f;  // eq. (20)
    if (Et) {
      auto e = Et->row(r + k);
      for (int s = 0; s < 2; ++s) add_spatial_row(x.k[s], t.g[s], t.h[s], 1.0, e);  // eq. (23)
    }
    if (Dt) {
      auto e = Dt->row(r + k);
      for (int s = 0; s < 2; ++s)
        add_spatial_row_rate(x.k[s], t.gdot[s], t.h[s], t.hdot[s], 1.0, e);  // eq. (76)
    }
    if (Dtu) {
      double sum = 0.0;  // (R3): Σ_b ġ_b·v_b + ḣ_b·w_b
      for (int s = 0; s < 2; ++s) sum += t.gdot[s].dot(x.k[s].v) + t.hdot[s].dot(x.k[s].w);
      (*Dtu)(r + k) = sum;
    }
  }
}

// The three targets of the writers (constraints/sparse_et.hpp).
template void evaluate_spatial_joint<MatX>(const Model&, const SpatialJoint&, const VecX&,
                                           const VecX*, int, VecX*, MatX*, MatX*, VecX*,
                                           const Mat3*);
template void evaluate_spatial_joint<SparseEt>(const Model&, const SpatialJoint&, const VecX&,
                                               const VecX*, int, VecX*, SparseEt*, MatX*, VecX*,
                                               const Mat3*);
template void evaluate_spatial_joint<EtRecorder>(const Model&, const SpatialJoint&, const VecX&,
                                                 const VecX*, int, VecX*, EtRecorder*, MatX*, VecX*,
                                                 const Mat3*);

SpatialWrench spatial_joint_reaction(const Model& model, const SpatialJoint& joint, const VecX& q,
                                     const Eigen::Ref<const VecX>& lambda) {
  const JointKinematics x(model, joint, q, nullptr);
  const SpatialJointSpec& spec = spatial_joint_spec(joint.type);
  // The body whose share is taken: i, or j (negated) when i is the ground.
  const size_t b = x.k[0].moving() ? 0 : 1;
  const double sign = b == 0 ? 1.0 : -1.0;
  Vec3 F = Vec3::Zero(), M_com = Vec3::Zero();  // world force, world moment about b's centre
  for (int k = 0; k < spec.rows; ++k) {
    const RowTerms t = row_terms(x, joint, spec.row[static_cast<size_t>(k)]);
    F += lambda(k) * t.g[b];      // (R1): λ·row is the world force λ g_b on body b …
    M_com += lambda(k) * t.h[b];  // … and the world moment λ h_b about its centre of mass
  }
  const bool about_pj = joint.type == SpatialJointType::point_on_line ||
                        joint.type == SpatialJointType::point_on_plane ||
                        joint.type == SpatialJointType::distance;
  const Vec3 point = about_pj ? x.p[1].r : x.p[0].r;
  SpatialWrench w;
  w.force = sign * F;
  w.moment = sign * (M_com + (x.k[b].r - point).cross(F));  // (S7)
  w.force_local = x.Ai.transpose() * w.force;
  w.moment_local = x.Ai.transpose() * w.moment;
  return w;
}

SpatialScalar spatial_joint_coordinate(const Model& model, const SpatialJoint& joint, const VecX& q,
                                       const VecX* u) {
  const SpatialCoordinate kind = spatial_joint_spec(joint.type).coordinate;
  if (kind == SpatialCoordinate::none)
    throw std::invalid_argument(std::string("a ") + spatial_joint_spec(joint.type).type +
                                " joint has no coordinate");
  const JointKinematics x(model, joint, q, u);
  RowTerms t;
  if (kind == SpatialCoordinate::slide) {
    t = dot2_row(x, x.Ai.col(2), x.Ai_dot.col(2));
  } else {
    const TwistAngle a =
        twist_angle(x.Ai.col(0), x.Ai.col(1), x.k[1].R * joint.ref_j, x.k[0].w, x.k[1].w);
    t.f = a.theta;
    t.h[0] = a.k;
    t.hdot[0] = a.kdot;
    t.h[1] = -a.k;
    t.hdot[1] = -a.kdot;
  }
  SpatialScalar s;
  s.value = t.f;
  s.frame = x.k;
  s.g = t.g;
  s.h = t.h;
  s.gdot = t.gdot;
  s.hdot = t.hdot;
  return s;
}

}  // namespace orthomech
