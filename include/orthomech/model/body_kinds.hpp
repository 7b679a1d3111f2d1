#pragma once
// Each body kind defined in one place (paper §2; docs/spatial.md §1, §6.3): its coordinates q (nq)
// and velocity parameters u (nu, translations first, then rotations), q ⊕ h·du, q₁ ⊖ q₀,
// q̇ = B̃u (eq. (19)), its blocks of M and A = M⁻¹, its kinetic energy, its velocity-dependent
// forces (the −C p u term of eq. (16)), the rates of its momenta (analysis/shaking.hpp) and its
// coordinates at the design pose. The free system of bodies (model/free_system.cpp), the loads
// (model/loads.cpp) and the shaking force (analysis/shaking.cpp) visit each body's kind with
// visit_kind; nothing else switches on the kind for these.
#include <Eigen/Core>
#include <cmath>

#include "orthomech/model/model.hpp"
#include "orthomech/model/spatial.hpp"

namespace orthomech {

// A body's block of M (eq. (4)) or of A = M⁻¹ (eq. (6)) in the top-left nu × nu corner.
using BodyBlock = Eigen::Matrix<double, 6, 6>;

namespace detail {
// The centre of mass of a planar body at its design pose (x, y, φ of the body frame).
inline Vec2 planar_design_com(const Body& b) {
  const double phi = b.design_pose.z();
  const double c = std::cos(phi), s = std::sin(phi);
  return {b.design_pose.x() + c * b.com_local.x() - s * b.com_local.y(),
          b.design_pose.y() + s * b.com_local.x() + c * b.com_local.y()};
}

// A planar body's centre of mass (q's first two entries, accelerations u̇'s): Ṗ += m a,
// Ḣ_O += ((r − O) × m a)_z.
inline void add_planar_com_momentum_rate(const Body& b, const VecX& q, const VecX& udot,
                                         const Vec3& about, Vec3& p_dot, Vec3& h_dot) {
  const double max = b.mass * udot(b.u_offset), may = b.mass * udot(b.u_offset + 1);
  const double rx = q(b.q_offset) - about.x(), ry = q(b.q_offset + 1) - about.y();
  p_dot.x() += max;
  p_dot.y() += may;
  h_dot.z() += rx * may - ry * max;
}

// Coordinates whose velocity parameters are their rates (B̃ = I on these nq = nu entries).
template <int N>
struct Cartesian {
  static void integrate(const Body& b, VecX& q, const VecX& du, double h) {
    for (int k = 0; k < N; ++k) q(b.q_offset + k) += h * du(b.u_offset + k);
  }
  static void difference(const Body& b, const VecX& q1, const VecX& q0, VecX& du) {
    for (int k = 0; k < N; ++k) du(b.u_offset + k) = q1(b.q_offset + k) - q0(b.q_offset + k);
  }
  static void rates(const Body& b, const Eigen::Ref<const VecX>& /*q*/, const VecX& u,
                    Eigen::Ref<VecX> qdot) {
    for (int k = 0; k < N; ++k) qdot(b.q_offset + k) = u(b.u_offset + k);
  }
  static void normalize(const Body& /*b*/, Eigen::Ref<VecX> /*q*/) {}
};
}  // namespace detail

// Planar rigid body: q = u-coordinates (x, y) of the centre of mass and the angle φ; B̃ = I;
// M = diag(m, m, J_c).
struct PlanarRigidKind : detail::Cartesian<body_layout(BodyKind::rigid).nq> {
  static constexpr BodyLayout layout = body_layout(BodyKind::rigid);
  static constexpr int nq = layout.nq, nu = layout.nu;
  static constexpr const char* velocity_names[nu] = {"x", "y", "phi"};
  static BodyBlock mass_block(const Body& b, bool inverse) {
    BodyBlock B = BodyBlock::Zero();
    B(0, 0) = B(1, 1) = inverse ? 1.0 / b.mass : b.mass;  // eq. (4): T = ½ m |v|² + ½ J φ̇²
    B(2, 2) = inverse ? 1.0 / b.inertia : b.inertia;
    return B;
  }
  static void add_kinetic_energy(const Body& b, const VecX& u, double& T) {
    const int o = b.u_offset;
    T += 0.5 * b.mass * (u(o) * u(o) + u(o + 1) * u(o + 1));
    T += 0.5 * b.inertia * u(o + 2) * u(o + 2);
  }
  // None: T does not depend on q and B̃ = I.
  static void add_velocity_forces(const Body& /*b*/, const VecX& /*u*/, VecX& /*Q*/) {}
  // Ṗ += m a and Ḣ_O += (r − O) × m a + J φ̈ (z) (analysis/shaking.hpp).
  static void add_momentum_rate(const Body& b, const VecX& q, const VecX& /*u*/, const VecX& udot,
                                const Vec3& about, Vec3& p_dot, Vec3& h_dot) {
    detail::add_planar_com_momentum_rate(b, q, udot, about, p_dot, h_dot);
    h_dot.z() += b.inertia * udot(b.u_offset + 2);
  }
  static void design_coordinates(const Body& b, VecX& q) {
    const Vec2 com = detail::planar_design_com(b);
    q(b.q_offset) = com.x();
    q(b.q_offset + 1) = com.y();
    q(b.q_offset + 2) = b.design_pose.z();
  }
};

// Planar particle: q = u = (x, y); M = diag(m, m).
struct ParticleKind : detail::Cartesian<body_layout(BodyKind::particle).nq> {
  static constexpr BodyLayout layout = body_layout(BodyKind::particle);
  static constexpr int nq = layout.nq, nu = layout.nu;
  static constexpr const char* velocity_names[nu] = {"x", "y"};
  static BodyBlock mass_block(const Body& b, bool inverse) {
    BodyBlock B = BodyBlock::Zero();
    B(0, 0) = B(1, 1) = inverse ? 1.0 / b.mass : b.mass;  // eq. (4): T = ½ m |v|²
    return B;
  }
  static void add_kinetic_energy(const Body& b, const VecX& u, double& T) {
    const int o = b.u_offset;
    T += 0.5 * b.mass * (u(o) * u(o) + u(o + 1) * u(o + 1));
  }
  static void add_velocity_forces(const Body& /*b*/, const VecX& /*u*/, VecX& /*Q*/) {}
  // Ṗ += m a and Ḣ_O += (r − O) × m a (z) (analysis/shaking.hpp).
  static void add_momentum_rate(const Body& b, const VecX& q, const VecX& /*u*/, const VecX& udot,
                                const Vec3& about, Vec3& p_dot, Vec3& h_dot) {
    detail::add_planar_com_momentum_rate(b, q, udot, about, p_dot, h_dot);
  }
  static void design_coordinates(const Body& b, VecX& q) {
    const Vec2 com = detail::planar_design_com(b);
    q(b.q_offset) = com.x();
    q(b.q_offset + 1) = com.y();
  }
};

// Spatial rigid body: q = (r, e), r the centre of mass, e a unit quaternion (scalar first);
// u = (v, ω), ω in the body frame; q̇ = B̃u with B̃ = blockdiag(I₃, ½G(e)ᵀ); M = diag(m I₃, J).
struct SpatialKind {
  static constexpr BodyLayout layout = body_layout(BodyKind::spatial);
  static constexpr int nq = layout.nq, nu = layout.nu;
  static constexpr const char* velocity_names[nu] = {"vx", "vy", "vz", "wx", "wy", "wz"};
  // q ⊕ h·du: r += h v; e ← e ⊗ exp(½ h ω), renormalised (docs/spatial.md §6.3). Exact for a
  // constant body-frame ω, so q ⊕ t·u is a motion with u̇ = 0.
  static void integrate(const Body& b, VecX& q, const VecX& du, double h) {
    q.segment<3>(b.q_offset) += h * du.segment<3>(b.u_offset);
    const Quat e = quaternion_multiply(q.segment<4>(b.q_offset + 3),
                                       quaternion_exp(h * du.segment<3>(b.u_offset + 3)));
    q.segment<4>(b.q_offset + 3) = e / e.norm();
  }
  // e₁ = e₀ ⊗ exp(½ θ): θ = log(e₀* ⊗ e₁), the shorter rotation.
  static void difference(const Body& b, const VecX& q1, const VecX& q0, VecX& du) {
    du.segment<3>(b.u_offset) = q1.segment<3>(b.q_offset) - q0.segment<3>(b.q_offset);
    Quat conj = q0.segment<4>(b.q_offset + 3);
    conj.tail<3>() = -conj.tail<3>();
    du.segment<3>(b.u_offset + 3) =
        quaternion_log(quaternion_multiply(conj, q1.segment<4>(b.q_offset + 3)));
  }
  // eq. (19): q̇ = B̃u, ṙ = v, ė = ½ G(e)ᵀ ω (S2).
  static void rates(const Body& b, const Eigen::Ref<const VecX>& q, const VecX& u,
                    Eigen::Ref<VecX> qdot) {
    qdot.segment<3>(b.q_offset) = u.segment<3>(b.u_offset);
    const Mat34 G = quaternion_G(q.segment<4>(b.q_offset + 3));
    qdot.segment<4>(b.q_offset + 3) =
        0.5 * G.transpose() * u.segment<3>(b.u_offset + 3);  // eq. (3)
  }
  // |e| = 1 is a first integral of q̇ = B̃u; this removes round-off and truncation drift.
  static void normalize(const Body& b, Eigen::Ref<VecX> q) {
    q.segment<4>(b.q_offset + 3).normalize();
  }
  static BodyBlock mass_block(const Body& b, bool inverse) {  // A_b = diag(I₃/m, J⁻¹)
    BodyBlock B = BodyBlock::Zero();
    B(0, 0) = B(1, 1) = B(2, 2) = inverse ? 1.0 / b.mass : b.mass;
    B.block<3, 3>(3, 3) = inverse ? Mat3(b.spatial.inertia.inverse()) : b.spatial.inertia;
    return B;
  }
  static void add_kinetic_energy(const Body& b, const VecX& u, double& T) {
    const int o = b.u_offset;
    T += 0.5 * b.mass * (u(o) * u(o) + u(o + 1) * u(o + 1));
    const Vec3 w = u.segment<3>(o + 3);
    T += 0.5 * b.mass * u(o + 2) * u(o + 2) + 0.5 * w.dot(b.spatial.inertia * w);
  }
  // T = ½ m vᵀv + ½ ωᵀJω does not depend on q, so ∂T/∂q̃ = 0 (eq. (9)); the structure
  // coefficients of the frame B̃ are C^{3+c}_{3+a,3+b} = ε_abc and zero otherwise (eq. (10),
  // checked against differences of B in
  // SpatialBody.EquationTenFromDifferencesOfBIsTheGyroscopicTerm), so the Euler–Lagrange equations,
  // eq. (13), become Euler's J ω̇ + ω × Jω = n and m v̇ = F.
  static void add_velocity_forces(const Body& b, const VecX& u, VecX& Q) {
    const Vec3 w = u.segment<3>(b.u_offset + 3);
    Q.segment<3>(b.u_offset + 3) -= w.cross(b.spatial.inertia * w);  // eq. (16): −C p u (S5)
  }
  // Ṗ += m a and Ḣ_O += (r − O) × m a + d/dt(R J ω) with d/dt(R J ω) = R (J ω̇ + ω × J ω), ω
  // in the body frame (analysis/shaking.hpp).
  static void add_momentum_rate(const Body& b, const VecX& q, const VecX& u, const VecX& udot,
                                const Vec3& about, Vec3& p_dot, Vec3& h_dot) {
    const Vec3 ma = b.mass * udot.segment<3>(b.u_offset);
    const Vec3 w = u.segment<3>(b.u_offset + 3);
    const Vec3 spin_rate =
        b.spatial.inertia * udot.segment<3>(b.u_offset + 3) + w.cross(b.spatial.inertia * w);
    p_dot += ma;
    h_dot += (q.segment<3>(b.q_offset) - about).cross(ma) +
             rotation_matrix(q.segment<4>(b.q_offset + 3)) * spin_rate;
  }
  // q = (r, e): the centre of mass and the orientation of the design pose.
  static void design_coordinates(const Body& b, VecX& q) {
    const Quat e = b.spatial.design_orientation.normalized();
    q.segment<3>(b.q_offset) = b.spatial.design_position + rotation_matrix(e) * b.spatial.com_local;
    q.segment<4>(b.q_offset + 3) = e;
  }
};

// f(Kind{}) for the body's kind.
template <typename F>
decltype(auto) visit_kind(const Body& b, F&& f) {
  switch (b.kind) {
    case BodyKind::rigid:
      return f(PlanarRigidKind{});
    case BodyKind::particle:
      return f(ParticleKind{});
    case BodyKind::spatial:
      break;
  }
  return f(SpatialKind{});
}

}  // namespace orthomech
