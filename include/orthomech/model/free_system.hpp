#pragma once
// The free system (paper §2): M(q) (eq. (4)), A = M⁻¹ (eq. (6)), Ṁ, q̇ = B̃ u (eq. (19)), and the
// kinematics of points fixed on bodies, shared by joints, loads and measures.
//
// Bodies have a constant M; planar bodies have B̃ = I, spatial ones do not (nq = 7, n = 6). Every
// function takes q (and u) so that configuration-dependent systems fit the same calls.
#include <Eigen/Core>
#include <span>
#include <string>
#include <vector>

#include "orthomech/model/model.hpp"
#include "orthomech/model/state.hpp"

namespace orthomech {

class ConstraintSystem;  // constraints/constraint_system.hpp

// The free system is one of two alternatives, fixed when the Model is built: bodies, each of
// its kind (model/body_kinds.hpp), or a general system given by functions with M(q)
// (model/general_system.hpp, Model::general). free_system(model) is the one place that
// chooses; the functions below go through it. Every member takes the Model (the bodies'
// implementation is stateless, so copies of a Model need nothing rebound).
class FreeSystem {
 public:
  virtual ~FreeSystem() = default;
  virtual void mass(const Model& model, const VecX& q, MatX& M) const = 0;          // eq. (4)
  virtual void inverse_mass(const Model& model, const VecX& q, MatX& A) const = 0;  // eq. (6)
  virtual void mass_rate(const Model& model, const VecX& q, const VecX& u, MatX& Mdot) const = 0;
  [[nodiscard]] virtual bool mass_constant(const Model& model) const = 0;
  [[nodiscard]] virtual bool mass_diagonal(const Model& model) const = 0;
  // The diagonal of M (inverse: of A) at q.
  [[nodiscard]] virtual VecX mass_diagonal_entries(const Model& model, const VecX& q,
                                                   bool inverse) const = 0;
  virtual void integrate(const Model& model, VecX& q, const VecX& du, double h) const = 0;
  virtual void difference(const Model& model, const VecX& q1, const VecX& q0, VecX& du) const = 0;
  virtual void coordinate_rates(const Model& model, const Eigen::Ref<const VecX>& q, const VecX& u,
                                Eigen::Ref<VecX> qdot) const = 0;
  virtual void normalize(const Model& model, Eigen::Ref<VecX> q) const = 0;
  [[nodiscard]] virtual double kinetic_energy(const Model& model, const State& state) const = 0;
  [[nodiscard]] virtual VecX design_q(const Model& model) const = 0;
  // "crank.phi", "top.wz", or a general system's coordinate name: velocity component k.
  [[nodiscard]] virtual std::string velocity_name(const Model& model, int k) const = 0;
  // Q̂(q, u, t) of eq. (17) without the constraint forces: the loads and each body's velocity
  // terms (loads.hpp), or a general system's forces function.
  virtual void applied_forces(const Model& model, const State& state, VecX& Q) const = 0;
  // The power of the non-conservative forces at the state (simulate's energy balance), given
  // Q̂ and Ṁ there; scratch is an n-vector of work space.
  [[nodiscard]] virtual double nonconservative_power(const Model& model, const State& state,
                                                     const VecX& Q, const MatX& Mdot,
                                                     VecX& scratch) const = 0;
  // True when Q̂ does not depend on t (the loads of bodies; a general system's forces may).
  [[nodiscard]] virtual bool forces_time_invariant() const = 0;
  // The constraints of the same alternative (the joints of the bodies, or the general system's
  // functions).
  [[nodiscard]] virtual const ConstraintSystem& constraints() const = 0;
};
[[nodiscard]] const FreeSystem& free_system(const Model& model);

// M(q), eq. (4) (dense n × n; block diagonal for bodies).
void compute_mass_matrix(const Model& model, const VecX& q, MatX& M);
// A = M⁻¹, eq. (6).
void compute_inverse_mass_matrix(const Model& model, const VecX& q, MatX& A);
// Ṁ = dM/dt along u (zero for bodies in absolute coordinates).
void compute_mass_matrix_rate(const Model& model, const VecX& q, const VecX& u, MatX& Mdot);
[[nodiscard]] bool mass_matrix_is_constant(const Model& model);
// True when M is diagonal whatever q, known from the model alone: bodies (not a model given by
// functions, Model::general) whose spatial inertias, if any, are diagonal in the body frame.
[[nodiscard]] bool mass_matrix_is_diagonal(const Model& model);
// The diagonal of M (eq. (4)) and of A = M⁻¹ (eq. (6)) at q, without forming the n × n matrix
// (except for a model given by functions). Equal, bit for bit, to the dense matrices' diagonals.
[[nodiscard]] VecX mass_matrix_diagonal(const Model& model, const VecX& q);
[[nodiscard]] VecX inverse_mass_diagonal(const Model& model, const VecX& q);
// q ← q ⊕ h·du: moves the coordinates along a velocity (exact for planar bodies; the exponential
// map for spatial bodies' quaternions, renormalised). Every change of q by a velocity-sized
// vector goes through this (nq ≠ n for spatial bodies).
void integrate_positions(const Model& model, VecX& q, const VecX& du, double h);
// du with q0 ⊕ du = q1 (the inverse of integrate_positions with h = 1; for quaternions the
// shorter rotation). du has size n.
void difference_positions(const Model& model, const VecX& q1, const VecX& q0, VecX& du);
// q̇ = B̃(q) u, eq. (19) (size nq).
void compute_coordinate_rates(const Model& model, const Eigen::Ref<const VecX>& q, const VecX& u,
                              Eigen::Ref<VecX> qdot);
// Renormalises every spatial body's quaternion (|e| = 1 is a first integral of q̇ = B̃u; this
// removes round-off and truncation drift). No-op for planar models.
void normalize_coordinates(const Model& model, Eigen::Ref<VecX> q);
// Kinetic energy T = ½ uᵀ M u, eq. (4).
[[nodiscard]] double kinetic_energy(const Model& model, const State& state);

// ---- Point kinematics: r_P = r + R(φ) s. -------------------------------------------------------
struct PointKinematics {
  Vec2 r = Vec2::Zero();   // world position
  Vec2 Rs = Vec2::Zero();  // R(φ) s (world vector from the centre of mass)
  Vec2 v = Vec2::Zero();   // world velocity
  double phidot = 0.0;     // angular velocity of the body (0 for particles and ground)
  bool rotates = false;    // body has an angle coordinate
  bool moving = false;     // not the ground
};
// R(φ_b) of every body b at q into rotations[0 … bodies.size()) (the identity for particles and
// spatial bodies). Allocation-free; rotations.size() must be model.bodies.size().
void body_rotations(const Model& model, const VecX& q, std::span<Eigen::Matrix2d> rotations);

// The kinematics stage of one position: the rotation of every body at q — R(φ_b) (2 × 2) of a
// planar body, R(e_b) (3 × 3, eq. (S1)) of a spatial one — computed once (update) and read by
// every point of every joint row, measure and reaction at that q, instead of a sin/cos or a
// quaternion product per point. With the positions in q they are the bodies' poses; their
// twists follow from u where a row reads them (planar: u itself; spatial: v and the world
// ω = R ω_b, spatial_frame). Sized at construction (its only allocation: the 3 × 3 table only
// for a spatial model); update is allocation-free. ConstraintWorkspace holds one
// (compute_constraints), cycle's DrivenWorkspace and simulate theirs.
class BodyPoses {
 public:
  explicit BodyPoses(const Model& model);
  void update(const Model& model, const VecX& q);
  // R(φ_b) of a planar body (the identity for a particle).
  [[nodiscard]] const Eigen::Matrix2d& operator[](int body) const {
    return R_[static_cast<size_t>(body)];
  }
  // R(e_b) of a spatial body (its model must be spatial).
  [[nodiscard]] const Mat3& spatial(int body) const { return S_[static_cast<size_t>(body)]; }
  // The spatial table, or null for a planar model (spatial_frame's argument).
  [[nodiscard]] const Mat3* spatial_table() const { return S_.empty() ? nullptr : S_.data(); }
  [[nodiscard]] std::span<const Eigen::Matrix2d> table() const { return R_; }

 private:
  std::vector<Eigen::Matrix2d> R_;
  std::vector<Mat3> S_;  // spatial bodies' rotations (empty for a planar model)
};

namespace detail {
// point_kinematics with the bodies' rotations from `table` (R(φ_b) per body at q), or computed
// here when table is null (the writers of joints.cpp and measures.cpp hold such a table).
[[nodiscard]] inline PointKinematics point_kinematics_at(const Model& model, const PointRef& p,
                                                         const VecX& q, const VecX* u,
                                                         const Eigen::Matrix2d* table);
}  // namespace detail

// u may be null: then only r and Rs are filled (velocities zero). Inline: it is called for every
// point of every joint row and measure.
[[nodiscard]] inline PointKinematics point_kinematics(const Model& model, const PointRef& p,
                                                      const VecX& q, const VecX* u) {
  return detail::point_kinematics_at(model, p, q, u, nullptr);
}
// The same with the bodies' rotations at this q already computed (no sin/cos).
[[nodiscard]] inline PointKinematics point_kinematics(const Model& model, const PointRef& p,
                                                      const VecX& q, const VecX* u,
                                                      const BodyPoses& rotations) {
  return detail::point_kinematics_at(model, p, q, u, rotations.table().data());
}
// Inline: read for every angle row, measure and reaction (a call cost more than the read).
[[nodiscard]] inline double body_angle(const Model& model, int body, const VecX& q) {
  if (body == kGround) return 0.0;
  const Body& b = model.bodies[static_cast<size_t>(body)];
  return b.kind == BodyKind::rigid ? q(b.q_offset + 2) : 0.0;
}
[[nodiscard]] inline double body_angular_velocity(const Model& model, int body, const VecX& u) {
  if (body == kGround) return 0.0;
  const Body& b = model.bodies[static_cast<size_t>(body)];
  return b.kind == BodyKind::rigid ? u(b.u_offset + 2) : 0.0;
}
[[nodiscard]] inline Vec2 perp(const Vec2& a) { return Vec2(-a.y(), a.x()); }  // rotate by +90°
[[nodiscard]] inline Eigen::Matrix2d rotation(double phi) {
  Eigen::Matrix2d R;
  const double c = std::cos(phi), s = std::sin(phi);
  R << c, -s, s, c;
  return R;
}

inline PointKinematics detail::point_kinematics_at(const Model& model, const PointRef& p,
                                                   const VecX& q, const VecX* u,
                                                   const Eigen::Matrix2d* table) {
  PointKinematics k;
  if (p.body == kGround) {
    k.r = p.s;
    return k;
  }
  const Body& b = model.bodies[static_cast<size_t>(p.body)];
  k.moving = true;
  const Vec2 c(q(b.q_offset), q(b.q_offset + 1));
  if (b.kind == BodyKind::rigid) {
    k.rotates = true;
    k.Rs = (table ? table[p.body] : rotation(q(b.q_offset + 2))) * p.s;
    if (u) k.phidot = (*u)(b.u_offset + 2);
  }
  k.r = c + k.Rs;
  if (u) k.v = Vec2((*u)(b.u_offset), (*u)(b.u_offset + 1)) + k.phidot * perp(k.Rs);
  return k;
}

// Adds w₁·(∂r_P/∂u)ᵀ… : writes the 1 × n row c ᵀ ∂r_P/∂u (the Jacobian of cᵀ r_P w.r.t. u) scaled
// by `scale` into `row` (accumulating). ∂r_P/∂(x, y, φ) = [I, R'(φ) s] = [I, perp(R s)].
template <typename Row>
void add_point_jacobian(const Model& model, const PointRef& p, const PointKinematics& k,
                        const Vec2& c, double scale, Row&& row) {
  if (p.body == kGround) return;
  const Body& b = model.bodies[static_cast<size_t>(p.body)];
  row(b.u_offset) += scale * c.x();
  row(b.u_offset + 1) += scale * c.y();
  if (k.rotates) row(b.u_offset + 2) += scale * c.dot(perp(k.Rs));
}
// Time derivative of that row: d/dt (∂r_P/∂u) = [0, −R s φ̇].
template <typename Row>
void add_point_jacobian_rate(const Model& model, const PointRef& p, const PointKinematics& k,
                             const Vec2& c, double scale, Row&& row) {
  if (p.body == kGround || !k.rotates) return;
  const Body& b = model.bodies[static_cast<size_t>(p.body)];
  row(b.u_offset + 2) += -scale * k.phidot * c.dot(k.Rs);
}

}  // namespace orthomech
