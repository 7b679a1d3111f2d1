#include "orthomech/model/loads.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <numbers>

#include "orthomech/check.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/constraints/spatial_joints.hpp"
#include "orthomech/model/body_kinds.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/model/general_system.hpp"
#include "orthomech/model/measures.hpp"
#include "orthomech/model/spatial.hpp"

namespace orthomech {

double table_factor(const Model& model, const Table& table, const VecX& q) {
  if (table.points.empty()) return 1.0;
  const Measure& m = model.measures[static_cast<size_t>(table.measure)];
  double x = compute_scalar(model, m.kind, q, nullptr).value;
  const auto& p = table.points;
  if (table.wrap) {  // periodic in 2π: x into [x_0, x_0 + 2π)
    constexpr double kTurn = 2.0 * std::numbers::pi;
    x = p.front().first + std::fmod(x - p.front().first, kTurn);
    if (x < p.front().first) x += kTurn;
  }
  if (x <= p.front().first) return p.front().second;
  if (x >= p.back().first) return p.back().second;
  const auto hi =
      std::upper_bound(p.begin(), p.end(), x, [](double v, const auto& e) { return v < e.first; });
  const auto lo = hi - 1;
  const double w = (x - lo->first) / (hi->first - lo->first);
  return lo->second + w * (hi->second - lo->second);
}

namespace {

// Spring-damper kinematics: length L, rate L̇, unit vector e from Pi to Pj.
struct Stretch {
  double L, Ldot;
  Vec2 e;
  PointKinematics ki, kj;
};
Stretch stretch(const Model& model, const SpringDamper& s, const State& st) {
  Stretch x;
  x.ki = point_kinematics(model, s.pi, st.q, &st.u);
  x.kj = point_kinematics(model, s.pj, st.q, &st.u);
  const Vec2 d = x.kj.r - x.ki.r;
  x.L = d.norm();
  x.e = x.L > 0.0 ? Vec2(d / x.L) : Vec2::UnitX();
  x.Ldot = x.e.dot(x.kj.v - x.ki.v);
  return x;
}

// Spatial spring-damper: length, rate, unit vector from Pi to Pj and the two points.
struct SpatialStretch {
  double L, Ldot;
  Vec3 e;
  SpatialFrame ki, kj;
  SpatialPoint pi, pj;
};
SpatialStretch stretch(const Model& model, const SpatialSpringDamper& s, const State& st) {
  SpatialStretch x;
  x.ki = spatial_frame(model, s.pi.body, st.q, &st.u);
  x.kj = spatial_frame(model, s.pj.body, st.q, &st.u);
  x.pi = spatial_point(x.ki, s.pi.s);
  x.pj = spatial_point(x.kj, s.pj.s);
  const Vec3 d = x.pj.r - x.pi.r;
  x.L = d.norm();
  x.e = x.L > 0.0 ? Vec3(d / x.L) : Vec3::UnitX();
  x.Ldot = x.e.dot(x.pj.v - x.pi.v);
  return x;
}

// The rotary spring's angle θ and rate of a spatial joint.
SpatialScalar joint_angle(const Model& model, const JointSpringDamper& l, const State& st) {
  const auto& joint = std::get<SpatialJoint>(model.joints[static_cast<size_t>(l.joint)].kind);
  return spatial_joint_coordinate(model, joint, st.q, &st.u);
}

// The rotary spring's deflection θ − θ₀. A spatial joint's angle is read within a turn (its
// orientation, not its history: joint_coordinate_wraps), so the deflection is taken within half
// a turn of the free angle, remainder(θ − θ₀, 2π): the spring's energy ½ k (θ − θ₀)² is then a
// continuous function of the pose and its moment its exact derivative. (Taking wrap(θ) − θ₀, as
// before, made the energy jump by 2π k |θ₀| at every pass through ±180°, and `simulate`'s
// balance grow by as much, issue 47.) A planar revolute's angle is continuous: no remainder.
double spring_deflection(const Model& model, const JointSpringDamper& l, double theta) {
  const Joint& joint = model.joints[static_cast<size_t>(l.joint)];
  const double d = theta - l.free_angle;
  return joint_coordinate_wraps(joint) ? std::remainder(d, 2.0 * std::numbers::pi) : d;
}

// A world force F at ρ from the centre of mass (or a world moment n, with F = 0): Q = (F, Rᵀ(ρ×F
// + n)), eq. (8) with δq̃ = B δq = (δr, δπ), δπ = 2G(e)δe the body-frame virtual rotation
// (eq. (7), docs/spatial.md §1.4).
void add_wrench(const SpatialFrame& k, const Vec3& F, const Vec3& moment, VecX& Q) {
  add_spatial_row(k, F, moment, 1.0, Q);
}

void add_angle(const Model& model, int body, double value, VecX& Q) {
  if (body == kGround) return;
  Q(model.bodies[static_cast<size_t>(body)].u_offset + 2) += value;
}

}  // namespace

bool load_active(const Model& model, const Load& load, const State& st) {
  if (load.active_while.measure < 0) return true;
  if (!st.load_on.empty()) {  // held by simulate's events: load is one of model.loads
    const std::ptrdiff_t k = &load - model.loads.data();
    check_argument(k >= 0 && static_cast<size_t>(k) < model.loads.size() &&
                       st.load_on.size() == model.loads.size(),
                   "load_active", "state.load_on", "must hold one entry per load of the model");
    return st.load_on[static_cast<size_t>(k)] != 0;
  }
  const Measure& m = model.measures[static_cast<size_t>(load.active_while.measure)];
  const double rate = compute_scalar(model, m.kind, st.q, &st.u).rate;
  return load.active_while.sign > 0 ? rate > 0.0 : rate < 0.0;
}

void add_load(const Model& model, const Load& load, const State& st, VecX& Q) {
  if (!load_active(model, load, st)) return;
  std::visit(
      [&](const auto& l) {
        using T = std::decay_t<decltype(l)>;
        if constexpr (std::is_same_v<T, Gravity>) {
          // Q = m g at the centre of mass: no moment.
          for (const Body& b : model.bodies) {
            Q(b.u_offset) += b.mass * l.g.x();
            Q(b.u_offset + 1) += b.mass * l.g.y();
          }
        } else if constexpr (std::is_same_v<T, PointForce>) {
          // Q = (∂r_P/∂u)ᵀ F (virtual work F·δr_P, eq. (8)).
          const PointKinematics k = point_kinematics(model, l.at, st.q, nullptr);
          Vec2 F = l.force * table_factor(model, l.table, st.q);
          if (l.body_fixed && l.at.body != kGround)
            F = rotation(body_angle(model, l.at.body, st.q)) * F;
          add_point_jacobian(model, l.at, k, F, 1.0, Q);
        } else if constexpr (std::is_same_v<T, Torque>) {
          add_angle(model, l.body, l.torque * table_factor(model, l.table, st.q), Q);
        } else if constexpr (std::is_same_v<T, SpringDamper>) {
          // Tension T pulls Pi towards Pj and Pj towards Pi.
          const Stretch x = stretch(model, l, st);
          const double tension = l.stiffness * (x.L - l.free_length) + l.damping * x.Ldot;
          add_point_jacobian(model, l.pi, x.ki, x.e, tension, Q);
          add_point_jacobian(model, l.pj, x.kj, x.e, -tension, Q);
        } else if constexpr (std::is_same_v<T, RotarySpringDamper>) {
          const double th = body_angle(model, l.bj, st.q) - body_angle(model, l.bi, st.q);
          const double w =
              body_angular_velocity(model, l.bj, st.u) - body_angular_velocity(model, l.bi, st.u);
          const double moment = l.stiffness * (th - l.free_angle) + l.damping * w;
          add_angle(model, l.bj, -moment, Q);
          add_angle(model, l.bi, moment, Q);
        } else if constexpr (std::is_same_v<T, SpatialGravity>) {
          for (const Body& b : model.bodies) Q.segment<3>(b.u_offset) += b.mass * l.g;
        } else if constexpr (std::is_same_v<T, SpatialPointForce>) {
          const SpatialFrame k = spatial_frame(model, l.at.body, st.q, nullptr);
          const SpatialPoint p = spatial_point(k, l.at.s);
          Vec3 F = l.force * table_factor(model, l.table, st.q);
          if (l.body_fixed) F = k.R * F;
          add_wrench(k, F, p.rho.cross(F), Q);
        } else if constexpr (std::is_same_v<T, SpatialTorque>) {
          const SpatialFrame k = spatial_frame(model, l.body, st.q, nullptr);
          Vec3 n = l.torque * table_factor(model, l.table, st.q);
          if (l.body_fixed) n = k.R * n;
          add_wrench(k, Vec3::Zero(), n, Q);
        } else if constexpr (std::is_same_v<T, SpatialSpringDamper>) {
          const SpatialStretch x = stretch(model, l, st);
          const double tension = l.stiffness * (x.L - l.free_length) + l.damping * x.Ldot;
          add_wrench(x.ki, tension * x.e, x.pi.rho.cross(tension * x.e), Q);
          add_wrench(x.kj, -tension * x.e, x.pj.rho.cross(-tension * x.e), Q);
        } else if constexpr (std::is_same_v<T, JointSpringDamper>) {
          const SpatialScalar th = joint_angle(model, l, st);
          const double moment =
              l.stiffness * spring_deflection(model, l, th.value) + l.damping * th.rate();
          th.add_row(Q, -moment);  // Q = −moment ∂θ/∂u
        }
      },
      load.kind);
}

// The velocity-dependent forces of each body's kind (model/body_kinds.hpp: the spatial body's
// gyroscopic term, eq. (16); none for planar bodies).
void add_velocity_terms(const Model& model, const State& state, VecX& Q) {
  for (const Body& b : model.bodies)
    visit_kind(b, [&](auto kind) { kind.add_velocity_forces(b, state.u, Q); });
}

void compute_applied_forces(const Model& model, const State& state, VecX& Q) {
  free_system(model).applied_forces(model, state, Q);
}

double potential_energy(const Model& model, const VecX& q) {
  double V = 0.0;
  const VecX* none = nullptr;
  for (const Load& load : model.loads) {
    if (const auto* g = std::get_if<Gravity>(&load.kind)) {
      for (const Body& b : model.bodies)
        V -= b.mass * (g->g.x() * q(b.q_offset) + g->g.y() * q(b.q_offset + 1));
    } else if (const auto* s = std::get_if<SpringDamper>(&load.kind)) {
      const Vec2 d =
          point_kinematics(model, s->pj, q, none).r - point_kinematics(model, s->pi, q, none).r;
      const double dl = d.norm() - s->free_length;
      V += 0.5 * s->stiffness * dl * dl;
    } else if (const auto* r = std::get_if<RotarySpringDamper>(&load.kind)) {
      const double th = body_angle(model, r->bj, q) - body_angle(model, r->bi, q) - r->free_angle;
      V += 0.5 * r->stiffness * th * th;
    } else if (const auto* sg = std::get_if<SpatialGravity>(&load.kind)) {
      for (const Body& b : model.bodies) V -= b.mass * sg->g.dot(q.segment<3>(b.q_offset));
    } else if (const auto* ss = std::get_if<SpatialSpringDamper>(&load.kind)) {
      const Vec3 d = spatial_point(spatial_frame(model, ss->pj.body, q, none), ss->pj.s).r -
                     spatial_point(spatial_frame(model, ss->pi.body, q, none), ss->pi.s).r;
      const double dl = d.norm() - ss->free_length;
      V += 0.5 * ss->stiffness * dl * dl;
    } else if (const auto* js = std::get_if<JointSpringDamper>(&load.kind)) {
      const auto& joint = std::get<SpatialJoint>(model.joints[static_cast<size_t>(js->joint)].kind);
      const double th =
          spring_deflection(model, *js, spatial_joint_coordinate(model, joint, q, none).value);
      V += 0.5 * js->stiffness * th * th;
    }
  }
  return V;
}

double dissipated_power(const Model& model, const State& st) {
  double P = 0.0;
  for (const Load& load : model.loads) {
    if (const auto* s = std::get_if<SpringDamper>(&load.kind)) {
      const Stretch x = stretch(model, *s, st);
      P += s->damping * x.Ldot * x.Ldot;
    } else if (const auto* r = std::get_if<RotarySpringDamper>(&load.kind)) {
      const double w =
          body_angular_velocity(model, r->bj, st.u) - body_angular_velocity(model, r->bi, st.u);
      P += r->damping * w * w;
    } else if (const auto* ss = std::get_if<SpatialSpringDamper>(&load.kind)) {
      const SpatialStretch x = stretch(model, *ss, st);
      P += ss->damping * x.Ldot * x.Ldot;
    } else if (const auto* js = std::get_if<JointSpringDamper>(&load.kind)) {
      const double w = joint_angle(model, *js, st).rate();
      P += js->damping * w * w;
    }
  }
  return P;
}

}  // namespace orthomech
