#include "orthomech/model/measures.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include "dot_row.hpp"
#include "orthomech/constraints/spatial_joints.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/model/spatial.hpp"

namespace orthomech {

namespace {

// Sink: where the row d goes (Eigen::Ref<VecX>, or DotRow for its product with a vector).
template <class Sink>
struct Evaluator {
  const Model& model;
  const VecX& q;
  const VecX* u;
  Sink* d;                           // may be null
  const Eigen::Matrix2d* rotations;  // R(φ_b) per body at q, or null
  const Mat3* rotations3 = nullptr;  // R(e_b) per body at q (spatial), or null

  [[nodiscard]] SpatialFrame frame(int body) const {
    return spatial_frame(model, body, q, u, rotations3);
  }

  [[nodiscard]] PointKinematics point(const PointRef& p) const {
    return detail::point_kinematics_at(model, p, q, u, rotations);
  }
  [[nodiscard]] Eigen::Matrix2d rotation_of(int body) const {
    return rotations && body != kGround ? rotations[body] : rotation(body_angle(model, body, q));
  }

  void add_angle(int body, double scale) const {
    // Particles have no angle (body_angle is 0 for them): nothing to add, and no column to write.
    if (body == kGround || d == nullptr) return;
    const Body& b = model.bodies[static_cast<size_t>(body)];
    if (b.kind != BodyKind::rigid) return;
    (*d)(b.u_offset + 2) += scale;
  }

  ScalarKinematics angle_difference(int bi, int bj) const {
    ScalarKinematics s;
    s.value = body_angle(model, bj, q) - body_angle(model, bi, q);
    if (u) s.rate = body_angular_velocity(model, bj, *u) - body_angular_velocity(model, bi, *u);
    add_angle(bj, 1.0);
    add_angle(bi, -1.0);
    return s;
  }

  ScalarKinematics operator()(const BodyAngle& m) const { return angle_difference(m.bi, m.bj); }

  ScalarKinematics operator()(const PointCoordinate& m) const {
    const PointKinematics k = point(m.point);
    const Vec2 c = m.axis == 0 ? Vec2::UnitX() : Vec2::UnitY();
    ScalarKinematics s;
    s.value = c.dot(k.r);
    s.rate = c.dot(k.v);
    s.ddot_u = -k.phidot * k.phidot * c.dot(k.Rs);  // d/dt[I, perp(Rs)] u = −φ̇² Rs
    if (d) add_point_jacobian(model, m.point, k, c, 1.0, *d);
    return s;
  }

  // |r_Pj − r_Pi|: ṡ = eᵀ ḋ, s̈ = eᵀ d̈ + (|ḋ|² − (eᵀḋ)²)/s with e = d/s.
  ScalarKinematics operator()(const PointDistance& m) const {
    const PointKinematics ki = point(m.pi);
    const PointKinematics kj = point(m.pj);
    const Vec2 dv = kj.r - ki.r;
    const Vec2 dd = kj.v - ki.v;
    ScalarKinematics s;
    s.value = dv.norm();
    // Where the points coincide |d| has no gradient; the one-sided limit along the relative
    // velocity is taken (e = ḋ/|ḋ|, ṡ = |ḋ|; the (|ḋ|² − (eᵀḋ)²)/s term vanishes with e ∥ ḋ),
    // and e = x̂ when ḋ = 0 too: finite values, never an exception, at such an isolated position.
    const bool coincident = !(s.value > 0.0);
    const double dd_norm = dd.norm();
    const Vec2 e = !coincident     ? Vec2(dv / s.value)
                   : dd_norm > 0.0 ? Vec2(dd / dd_norm)
                                   : Vec2::UnitX();
    s.rate = e.dot(dd);
    s.ddot_u = (coincident ? 0.0 : (dd.squaredNorm() - s.rate * s.rate) / s.value) -
               kj.phidot * kj.phidot * e.dot(kj.Rs) + ki.phidot * ki.phidot * e.dot(ki.Rs);
    if (d) {
      add_point_jacobian(model, m.pj, kj, e, 1.0, *d);
      add_point_jacobian(model, m.pi, ki, e, -1.0, *d);
    }
    return s;
  }

  ScalarKinematics spatial(const SpatialScalar& x) const {
    if (d) x.add_row(*d);
    return {x.value, x.rate(), x.convective()};
  }

  // World x, y or z of a spatial point: g = c, h = ρ × c, ḣ = (w × ρ) × c.
  ScalarKinematics operator()(const SpatialPointCoordinate& m) const {
    SpatialScalar x;
    x.frame[0] = frame(m.point.body);
    const SpatialPoint p = spatial_point(x.frame[0], m.point.s);
    const Vec3 c = Vec3::Unit(m.axis);
    x.value = c.dot(p.r);
    x.g[0] = c;
    x.h[0] = p.rho.cross(c);
    x.hdot[0] = x.frame[0].w.cross(p.rho).cross(c);
    return spatial(x);
  }

  // |d|, d = r_Pj − r_Pi: e = d/|d|, ė = (ḋ − e (e·ḋ))/|d|; body j: g = e, h = ρ_j × e (−, ρ_i
  // for i). Coincident points: the one-sided limit along ḋ, as the planar measure.
  ScalarKinematics operator()(const SpatialPointDistance& m) const {
    SpatialScalar x;
    x.frame = {frame(m.pi.body), frame(m.pj.body)};
    const std::array<SpatialPoint, 2> p{spatial_point(x.frame[0], m.pi.s),
                                        spatial_point(x.frame[1], m.pj.s)};
    const Vec3 dv = p[1].r - p[0].r, dd = p[1].v - p[0].v;
    x.value = dv.norm();
    const bool coincident = !(x.value > 0.0);
    const Vec3 e = !coincident       ? Vec3(dv / x.value)
                   : dd.norm() > 0.0 ? Vec3(dd.normalized())
                                     : Vec3::UnitX();
    const Vec3 edot = coincident ? Vec3::Zero() : Vec3((dd - e * e.dot(dd)) / x.value);
    for (size_t b = 0; b < 2; ++b) {
      const double sign = b == 0 ? -1.0 : 1.0;
      const Vec3& rho = p[b].rho;
      x.g[b] = sign * e;
      x.h[b] = sign * rho.cross(e);
      x.gdot[b] = sign * edot;
      x.hdot[b] = sign * (x.frame[b].w.cross(rho).cross(e) + rho.cross(edot));
    }
    return spatial(x);
  }

  // Angle between a_i (fixed in i) and a_j (fixed in j): θ = atan2(|c|, a_i·a_j), c = a_i × a_j;
  // θ̇ = (w_i − w_j)·k with k = −c/|c| (undefined where the vectors are parallel).
  ScalarKinematics operator()(const VectorAngle& m) const {
    SpatialScalar x;
    x.frame = {frame(m.bi), frame(m.bj)};
    const Vec3 ai = x.frame[0].R * m.ai, aj = x.frame[1].R * m.aj;
    const Vec3 c = ai.cross(aj);
    const double sn = c.norm();
    x.value = std::atan2(sn, ai.dot(aj));
    const Vec3 cdot = x.frame[0].w.cross(ai).cross(aj) + ai.cross(x.frame[1].w.cross(aj));
    const Vec3 k = sn > 0.0 ? Vec3(-c / sn) : Vec3::Zero();
    const Vec3 kdot = sn > 0.0 ? Vec3(-(cdot - c * c.dot(cdot) / (sn * sn)) / sn) : Vec3::Zero();
    x.h = {k, -k};
    x.hdot = {kdot, -kdot};
    return spatial(x);
  }

  // Camber c = −asin(s_z), s = R a (ṡ = w × s): ċ = w·h with h = (ẑ × s)/√(1 − s_z²).
  // Toe t = atan2(s_x, σ s_y), σ = sign(s_y): ṫ = w·h with h = N/r², N = σ s × (s_y, −s_x, 0),
  // r² = s_x² + s_y² (the (P5) pattern of atan2). ḣ by differentiating h along ṡ.
  ScalarKinematics operator()(const WheelAngle& m) const {
    SpatialScalar x;
    x.frame[0] = frame(m.body);
    const Vec3 s = x.frame[0].R * m.axis;
    const Vec3 sd = x.frame[0].w.cross(s);
    const Vec3 z = Vec3::UnitZ();
    if (m.which == WheelAngle::Which::camber) {
      const double sz = std::clamp(s.z(), -1.0, 1.0);
      const double cz = std::sqrt(1.0 - sz * sz);  // 0 only for a vertical spin axis
      x.value = 0.0 - std::asin(sz);               // not −asin: +0, never −0, at zero camber
      x.h[0] = z.cross(s) / cz;
      x.hdot[0] = z.cross(sd) / cz + z.cross(s) * (sz * sd.z() / (cz * cz * cz));
    } else {
      const double sigma = s.y() < 0.0 ? -1.0 : 1.0;
      const double r2 = s.x() * s.x() + s.y() * s.y();
      x.value = std::atan2(s.x(), sigma * s.y());
      const Vec3 mv(s.y(), -s.x(), 0.0), md(sd.y(), -sd.x(), 0.0);
      const Vec3 N = sigma * s.cross(mv);
      const Vec3 Nd = sigma * (sd.cross(mv) + s.cross(md));
      x.h[0] = N / r2;
      x.hdot[0] = Nd / r2 - N * (2.0 * (s.x() * sd.x() + s.y() * sd.y()) / (r2 * r2));
    }
    return spatial(x);
  }

  ScalarKinematics operator()(const JointCoordinate& m) const {
    const Joint& joint = model.joints[static_cast<size_t>(m.joint)];
    if (const auto* sj = std::get_if<SpatialJoint>(&joint.kind))
      return spatial(spatial_joint_coordinate(model, *sj, q, u));
    if (const auto* r = std::get_if<Revolute>(&joint.kind))
      return angle_difference(r->pi.body, r->pj.body);
    if (const auto* p = std::get_if<Prismatic>(&joint.kind)) {
      // s = aᵀ d with a = R_i axis, d = r_Pj − r_Pi. ȧ = φ̇_i perp(a).
      const PointKinematics ki = point(p->pi);
      const PointKinematics kj = point(p->pj);
      const double w_i = u ? body_angular_velocity(model, p->pi.body, *u) : 0.0;
      const Vec2 a = rotation_of(p->pi.body) * p->axis_local;
      const Vec2 dv = kj.r - ki.r;
      const Vec2 dd = kj.v - ki.v;
      ScalarKinematics s;
      s.value = a.dot(dv);
      s.rate = a.dot(dd) + w_i * perp(a).dot(dv);
      // ḋu = 2 ȧᵀḋ + aᵀ(−φ̇_j² R_j s_j + φ̇_i² R_i s_i) + äᵀ d (ä from φ̇_i only: −φ̇_i² a)
      s.ddot_u = 2.0 * w_i * perp(a).dot(dd) - kj.phidot * kj.phidot * a.dot(kj.Rs) +
                 ki.phidot * ki.phidot * a.dot(ki.Rs) - w_i * w_i * a.dot(dv);
      if (d) {
        add_point_jacobian(model, p->pj, kj, a, 1.0, *d);
        add_point_jacobian(model, p->pi, ki, a, -1.0, *d);
        add_angle(p->pi.body, perp(a).dot(dv));
      }
      return s;
    }
    throw std::invalid_argument("joint '" + joint.name + "' has no scalar coordinate");
  }
};

}  // namespace

ScalarKinematics compute_scalar(const Model& model, const MeasureKind& kind, const VecX& q,
                                const VecX* u, Eigen::Ref<VecX> d) {
  d.setZero();
  Eigen::Ref<VecX>* dp = &d;
  return std::visit(Evaluator<Eigen::Ref<VecX>>{model, q, u, dp, nullptr}, kind);
}

ScalarKinematics compute_scalar(const Model& model, const MeasureKind& kind, const VecX& q,
                                const VecX* u) {
  return std::visit(Evaluator<Eigen::Ref<VecX>>{model, q, u, nullptr, nullptr}, kind);
}

namespace {
double evaluate_measure_at(const Model& model, const Measure& m, const VecX& q, const VecX* u,
                           const VecX* udot, const BodyPoses* poses) {
  using Plain = Evaluator<Eigen::Ref<VecX>>;
  const Eigen::Matrix2d* r2 = poses ? poses->table().data() : nullptr;
  const Mat3* r3 = poses ? poses->spatial_table() : nullptr;
  if (m.derivative == 0) return std::visit(Plain{model, q, nullptr, nullptr, r2, r3}, m.kind).value;
  if (m.derivative == 1) return std::visit(Plain{model, q, u, nullptr, r2, r3}, m.kind).rate;
  // s̈ = d u̇ + ḋu, with d u̇ accumulated as d is written (no row buffer).
  DotRow d_udot{*udot};
  const ScalarKinematics s = std::visit(Evaluator<DotRow>{model, q, u, &d_udot, r2, r3}, m.kind);
  return d_udot.sum + s.ddot_u;
}
}  // namespace

double evaluate_measure(const Model& model, const Measure& m, const VecX& q, const VecX* u,
                        const VecX* udot) {
  return evaluate_measure_at(model, m, q, u, udot, nullptr);
}

double evaluate_measure(const Model& model, const Measure& m, const VecX& q, const VecX* u,
                        const VecX* udot, const BodyPoses& rotations) {
  return evaluate_measure_at(model, m, q, u, udot, &rotations);
}

}  // namespace orthomech
