#include "orthomech/model/free_system.hpp"

#include <Eigen/Cholesky>

#include "orthomech/check.hpp"
#include "orthomech/model/general_system.hpp"
#include "orthomech/model/spatial.hpp"

namespace orthomech {

namespace {
// One body's block of M (eq. (4)) or of A = M⁻¹ (eq. (6)) in the top-left nu × nu corner: the
// one place that lays out a body's masses, read by the dense matrices and by their diagonals.
using BodyBlock = Eigen::Matrix<double, 6, 6>;
BodyBlock body_mass_block(const Body& b, bool inverse) {
  BodyBlock B = BodyBlock::Zero();
  const double m = inverse ? 1.0 / b.mass : b.mass;
  B(0, 0) = B(1, 1) = m;  // eq. (4): T = ½ m |v|² + ½ J φ̇²
  if (b.kind == BodyKind::rigid) B(2, 2) = inverse ? 1.0 / b.inertia : b.inertia;
  if (b.kind == BodyKind::spatial) {  // M_b = diag(m I₃, J), A_b = diag(I₃/m, J⁻¹)
    B(2, 2) = m;
    B.block<3, 3>(3, 3) = inverse ? Mat3(b.spatial.inertia.inverse()) : b.spatial.inertia;
  }
  return B;
}

// The bodies' blocks into the n × n matrix X.
void fill_block_diagonal(const Model& model, bool inverse, MatX& X) {
  X.setZero();
  for (const Body& b : model.bodies)
    X.block(b.u_offset, b.u_offset, b.nu(), b.nu()) =
        body_mass_block(b, inverse).topLeftCorner(b.nu(), b.nu());
}

// Their diagonals (size n).
VecX block_diagonal_entries(const Model& model, bool inverse) {
  VecX d(model.n);
  for (const Body& b : model.bodies)
    d.segment(b.u_offset, b.nu()) = body_mass_block(b, inverse).diagonal().head(b.nu());
  return d;
}
}  // namespace

void compute_mass_matrix(const Model& model, const VecX& q, MatX& M) {
  if (model.general) {
    model.general->mass(q, M);  // eq. (4): M(q)
    return;
  }
  fill_block_diagonal(model, false, M);
}

void compute_inverse_mass_matrix(const Model& model, const VecX& q, MatX& A) {
  if (model.general) {
    MatX M(model.n, model.n);
    model.general->mass(q, M);
    A = M.llt().solve(MatX::Identity(model.n, model.n));  // eq. (6)
    return;
  }
  fill_block_diagonal(model, true, A);  // eq. (6): block-diagonal inverse
}

void compute_mass_matrix_rate(const Model& model, const VecX& q, const VecX& u, MatX& Mdot) {
  if (model.general) {
    model.general->mass_rate(q, u, Mdot);
    return;
  }
  Mdot.setZero();  // absolute coordinates of planar bodies: M constant
}

bool mass_matrix_is_constant(const Model& model) { return !model.general; }

bool mass_matrix_is_diagonal(const Model& model) {
  if (model.general) return false;
  for (const Body& b : model.bodies) {
    if (b.kind != BodyKind::spatial) continue;
    const Mat3& J = b.spatial.inertia;
    if (J(0, 1) != 0.0 || J(0, 2) != 0.0 || J(1, 2) != 0.0 || J(1, 0) != 0.0 || J(2, 0) != 0.0 ||
        J(2, 1) != 0.0)
      return false;
  }
  return true;
}

VecX mass_matrix_diagonal(const Model& model, const VecX& q) {
  if (model.general) {
    MatX M(model.n, model.n);
    model.general->mass(q, M);
    return M.diagonal();
  }
  return block_diagonal_entries(model, false);
}

VecX inverse_mass_diagonal(const Model& model, const VecX& q) {
  if (model.general) {
    MatX A(model.n, model.n);
    compute_inverse_mass_matrix(model, q, A);
    return A.diagonal();
  }
  return block_diagonal_entries(model, true);
}

void integrate_positions(const Model& model, VecX& q, const VecX& du, double h) {
  if (model.general) {
    q += h * du;  // q̇ = u
    return;
  }
  for (const Body& b : model.bodies) {
    if (b.kind == BodyKind::spatial) {
      // q ⊕ h·du: r += h v; e ← e ⊗ exp(½ h ω), renormalised (spatial.md §6.3). Exact for a
      // constant body-frame ω, so q ⊕ t·u is a motion with u̇ = 0.
      q.segment<3>(b.q_offset) += h * du.segment<3>(b.u_offset);
      const Quat e = quaternion_multiply(q.segment<4>(b.q_offset + 3),
                                         quaternion_exp(h * du.segment<3>(b.u_offset + 3)));
      q.segment<4>(b.q_offset + 3) = e / e.norm();
      continue;
    }
    // Planar bodies: B̃ = I and nq == n, eq. (1).
    for (int k = 0; k < b.nq(); ++k) q(b.q_offset + k) += h * du(b.u_offset + k);
  }
}

void difference_positions(const Model& model, const VecX& q1, const VecX& q0, VecX& du) {
  if (model.general) {
    du = q1 - q0;
    return;
  }
  for (const Body& b : model.bodies) {
    if (b.kind == BodyKind::spatial) {  // e₁ = e₀ ⊗ exp(½ θ): θ = log(e₀* ⊗ e₁)
      du.segment<3>(b.u_offset) = q1.segment<3>(b.q_offset) - q0.segment<3>(b.q_offset);
      Quat conj = q0.segment<4>(b.q_offset + 3);
      conj.tail<3>() = -conj.tail<3>();
      du.segment<3>(b.u_offset + 3) =
          quaternion_log(quaternion_multiply(conj, q1.segment<4>(b.q_offset + 3)));
      continue;
    }
    for (int k = 0; k < b.nq(); ++k) du(b.u_offset + k) = q1(b.q_offset + k) - q0(b.q_offset + k);
  }
}

void compute_coordinate_rates(const Model& model, const Eigen::Ref<const VecX>& q, const VecX& u,
                              Eigen::Ref<VecX> qdot) {
  if (model.general) {
    qdot = u;
    return;
  }
  for (const Body& b : model.bodies) {
    if (b.kind == BodyKind::spatial) {  // eq. (19): q̇ = B̃u, ṙ = v, ė = ½ G(e)ᵀ ω (S2)
      qdot.segment<3>(b.q_offset) = u.segment<3>(b.u_offset);
      const Mat34 G = quaternion_G(q.segment<4>(b.q_offset + 3));
      qdot.segment<4>(b.q_offset + 3) =
          0.5 * G.transpose() * u.segment<3>(b.u_offset + 3);  // eq. (3)
      continue;
    }
    for (int k = 0; k < b.nq(); ++k) qdot(b.q_offset + k) = u(b.u_offset + k);
  }
}

void normalize_coordinates(const Model& model, Eigen::Ref<VecX> q) {
  for (const Body& b : model.bodies)
    if (b.kind == BodyKind::spatial) q.segment<4>(b.q_offset + 3).normalize();
}

double kinetic_energy(const Model& model, const State& state) {
  if (model.general) {
    MatX M(model.n, model.n);
    model.general->mass(state.q, M);
    return 0.5 * state.u.dot(M * state.u);  // eq. (4)
  }
  double T = 0.0;
  for (const Body& b : model.bodies) {
    const int o = b.u_offset;
    T += 0.5 * b.mass * (state.u(o) * state.u(o) + state.u(o + 1) * state.u(o + 1));
    if (b.kind == BodyKind::spatial) {
      const Vec3 w = state.u.segment<3>(o + 3);
      T += 0.5 * b.mass * state.u(o + 2) * state.u(o + 2) + 0.5 * w.dot(b.spatial.inertia * w);
    }
    if (b.kind == BodyKind::rigid) T += 0.5 * b.inertia * state.u(o + 2) * state.u(o + 2);
  }
  return T;
}

void body_rotations(const Model& model, const VecX& q, std::span<Eigen::Matrix2d> rotations) {
  ORTHOMECH_CHECK(rotations.size() == model.bodies.size(), "one rotation per body");
  for (size_t b = 0; b < model.bodies.size(); ++b) {
    const Body& body = model.bodies[b];
    rotations[b] =
        body.kind == BodyKind::rigid ? rotation(q(body.q_offset + 2)) : Eigen::Matrix2d::Identity();
  }
}

BodyRotations::BodyRotations(const Model& model)
    : R_(model.bodies.size(), Eigen::Matrix2d::Identity()) {}

}  // namespace orthomech
