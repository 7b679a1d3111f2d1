#pragma once
// Spatial rigid bodies (docs/spatial.md §1): unit quaternions (scalar first, Hamilton product), the
// rotation matrix, B̃ and B of eq. (2), eq. (3) and eq. (19), the exponential map q ⊕ h·u, and the
// kinematics of a spatial body's frame and points shared by joints, loads and measures.
//
//   q_b = (r, e): r world position of the centre of mass, e = (e₀, ε) unit quaternion;
//   u_b = (v, ω): v = ṙ, ω the body-frame angular velocity, w = R ω the world one;
//   q̇_b = B̃ u_b, B̃ = blockdiag(I₃, ½ G(e)ᵀ)                                       (S2)
#include <Eigen/Core>
#include <Eigen/Geometry>  // cross products
#include <array>
#include <cmath>

#include "orthomech/model/model.hpp"

namespace orthomech {

using Mat34 = Eigen::Matrix<double, 3, 4>;

[[nodiscard]] inline Mat3 skew(const Vec3& a) {
  Mat3 S;
  S << 0.0, -a.z(), a.y(), a.z(), 0.0, -a.x(), -a.y(), a.x(), 0.0;
  return S;
}

// R(e) = I + (2/|e|²)(e₀ ε̃ + ε̃²), exactly orthogonal for any e ≠ 0 (docs/spatial.md (S1)).
[[nodiscard]] inline Mat3 rotation_matrix(const Quat& e) {
  const Vec3 eps = e.tail<3>();
  const Mat3 E = skew(eps);
  return Mat3::Identity() + (2.0 / e.squaredNorm()) * (e(0) * E + E * E);
}

// G(e) = [−ε, e₀I − ε̃]: ω = 2 G(e) ė (body frame), ė = ½ G(e)ᵀ ω; u = B q̇ with
// B = blockdiag(I₃, 2G(e)), eq. (2) (docs/spatial.md (S3)).
[[nodiscard]] inline Mat34 quaternion_G(const Quat& e) {
  Mat34 G;
  G.col(0) = -e.tail<3>();
  G.rightCols<3>() = e(0) * Mat3::Identity() - skew(e.tail<3>());
  return G;
}

// Hamilton product a ⊗ b.
[[nodiscard]] inline Quat quaternion_multiply(const Quat& a, const Quat& b) {
  const Vec3 av = a.tail<3>(), bv = b.tail<3>();
  Quat c;
  c(0) = a(0) * b(0) - av.dot(bv);
  c.tail<3>() = a(0) * bv + b(0) * av + av.cross(bv);
  return c;
}

// exp(½ θ): the unit quaternion of the rotation by the rotation vector θ (body frame);
// series below |θ| = 1e-8 (docs/spatial.md §6.3).
[[nodiscard]] inline Quat quaternion_exp(const Vec3& theta) {
  const double a = theta.norm();
  Quat e;
  if (a < 1e-8) {
    e(0) = 1.0 - a * a / 8.0;
    e.tail<3>() = theta * (0.5 - a * a / 48.0);
  } else {
    e(0) = std::cos(0.5 * a);
    e.tail<3>() = theta * (std::sin(0.5 * a) / a);
  }
  return e;
}

// The rotation vector θ with quaternion_exp(θ) = ±e (|θ| ≤ π): the inverse of quaternion_exp.
[[nodiscard]] inline Vec3 quaternion_log(const Quat& e_in) {
  const Quat e = e_in(0) < 0.0 ? Quat(-e_in) : e_in;  // the shorter of the two rotations
  const double s = e.tail<3>().norm();
  if (s < 1e-12) return 2.0 * e.tail<3>() / e(0);
  return 2.0 * std::atan2(s, e(0)) / s * e.tail<3>();
}

// The right Jacobian of the exponential map: exp(θ + δθ) = exp(θ) ⊗ exp(J_r(θ) δθ) + O(δθ²), so
// a body turned by exp(θ) from a reference has body-frame angular velocity ω = J_r(θ) θ̇;
// J_r = I − (1 − cos a)/a² θ̃ + (a − sin a)/a³ θ̃², a = |θ| (series below a = 1e-6).
[[nodiscard]] inline Mat3 exp_right_jacobian(const Vec3& theta) {
  const double a = theta.norm();
  const Mat3 T = skew(theta);
  double c1, c2;
  if (a < 1e-6) {
    c1 = 0.5 - a * a / 24.0;
    c2 = 1.0 / 6.0 - a * a / 120.0;
  } else {
    c1 = (1.0 - std::cos(a)) / (a * a);
    c2 = (a - std::sin(a)) / (a * a * a);
  }
  return Mat3::Identity() - c1 * T + c2 * T * T;
}

// The frame of a body at (q, u): R, the centre of mass r, v and the world angular velocity w
// (computed once per body and evaluation). The ground: R = I, r = v = w = 0.
struct SpatialFrame {
  Mat3 R = Mat3::Identity();
  Vec3 r = Vec3::Zero();
  Vec3 v = Vec3::Zero();
  Vec3 w = Vec3::Zero();  // world angular velocity, R ω
  int u_offset = -1;      // first velocity column, −1 for the ground
  [[nodiscard]] bool moving() const { return u_offset >= 0; }
};

// u may be null (velocities zero). rotations: R(e_b) of every body at this q (BodyPoses, the
// kinematics stage), or null to compute R here.
[[nodiscard]] inline SpatialFrame spatial_frame(const Model& model, int body, const VecX& q,
                                                const VecX* u, const Mat3* rotations = nullptr) {
  SpatialFrame k;
  if (body == kGround) return k;
  const Body& b = model.bodies[static_cast<size_t>(body)];
  k.u_offset = b.u_offset;
  k.r = q.segment<3>(b.q_offset);
  k.R = rotations ? rotations[body] : rotation_matrix(q.segment<4>(b.q_offset + 3));
  if (u) {
    k.v = u->segment<3>(b.u_offset);
    k.w = k.R * u->segment<3>(b.u_offset + 3);
  }
  return k;
}

// A point fixed on a body: ρ = R s (from the centre of mass), r_P = r + ρ, v_P = v + w × ρ.
// For the ground s is the world position.
struct SpatialPoint {
  Vec3 rho = Vec3::Zero();
  Vec3 r = Vec3::Zero();
  Vec3 v = Vec3::Zero();
};
[[nodiscard]] inline SpatialPoint spatial_point(const SpatialFrame& k, const Vec3& s) {
  SpatialPoint p;
  p.rho = k.R * s;
  p.r = k.r + p.rho;
  p.v = k.v + k.w.cross(p.rho);
  return p;
}

// The generic row rule (docs/spatial.md (R1)–(R3)): a row whose rate is Σ_b (g_b·v_b + h_b·w_b),
// with world vectors g_b, h_b, has Eᵀ columns [g_bᵀ | (R_bᵀh_b)ᵀ] and Dᵀ columns
// [ġ_bᵀ | (R_bᵀ(ḣ_b − w_b × h_b))ᵀ] in body b's six columns; `scale` multiplies both.
template <typename Row>
void add_spatial_row(const SpatialFrame& k, const Vec3& g, const Vec3& h, double scale, Row&& row) {
  if (!k.moving()) return;
  const Vec3 hb = k.R.transpose() * h;
  for (int a = 0; a < 3; ++a) {
    row(k.u_offset + a) += scale * g(a);
    row(k.u_offset + 3 + a) += scale * hb(a);
  }
}
template <typename Row>
void add_spatial_row_rate(const SpatialFrame& k, const Vec3& gdot, const Vec3& h, const Vec3& hdot,
                          double scale, Row&& row) {
  if (!k.moving()) return;
  const Vec3 hb = k.R.transpose() * (hdot - k.w.cross(h));
  for (int a = 0; a < 3; ++a) {
    row(k.u_offset + a) += scale * gdot(a);
    row(k.u_offset + 3 + a) += scale * hb(a);
  }
}

// A scalar s(q) of (up to) two bodies whose rate is ṡ = Σ_b (g_b·v_b + h_b·w_b) (index 0: body i,
// 1: body j): its Jacobian row is written by the generic rule and s̈ = row·u̇ + convective().
struct SpatialScalar {
  double value = 0.0;
  std::array<SpatialFrame, 2> frame;
  std::array<Vec3, 2> g{Vec3::Zero(), Vec3::Zero()}, h{Vec3::Zero(), Vec3::Zero()};
  std::array<Vec3, 2> gdot{Vec3::Zero(), Vec3::Zero()}, hdot{Vec3::Zero(), Vec3::Zero()};
  [[nodiscard]] double rate() const {
    double s = 0.0;
    for (size_t b = 0; b < 2; ++b) s += g[b].dot(frame[b].v) + h[b].dot(frame[b].w);
    return s;
  }
  // (R3): Σ_b (ġ_b·v_b + ḣ_b·w_b), the part of s̈ that does not multiply u̇.
  [[nodiscard]] double convective() const {
    double s = 0.0;
    for (size_t b = 0; b < 2; ++b) s += gdot[b].dot(frame[b].v) + hdot[b].dot(frame[b].w);
    return s;
  }
  template <typename Row>
  void add_row(Row&& row, double scale = 1.0) const {
    for (size_t b = 0; b < 2; ++b) add_spatial_row(frame[b], g[b], h[b], scale, row);
  }
  template <typename Row>
  void add_row_rate(Row&& row, double scale = 1.0) const {
    for (size_t b = 0; b < 2; ++b)
      add_spatial_row_rate(frame[b], gdot[b], h[b], hdot[b], scale, row);
  }
};

}  // namespace orthomech
