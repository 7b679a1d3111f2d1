#include "orthomech/model/free_system.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <variant>

#include "orthomech/check.hpp"
#include "orthomech/constraints/constraint_system.hpp"
#include "orthomech/model/body_kinds.hpp"
#include "orthomech/model/general_system.hpp"
#include "orthomech/model/loads.hpp"
#include "orthomech/model/spatial.hpp"

namespace orthomech {

namespace {

// ---- Bodies: each body's kind (model/body_kinds.hpp) --------------------------------------------
class BodySystem final : public FreeSystem {
 public:
  void mass(const Model& model, const VecX& /*q*/, MatX& M) const override {
    fill_block_diagonal(model, false, M);
  }
  void inverse_mass(const Model& model, const VecX& /*q*/, MatX& A) const override {
    fill_block_diagonal(model, true, A);  // eq. (6): block-diagonal inverse
  }
  void mass_rate(const Model& /*model*/, const VecX& /*q*/, const VecX& /*u*/,
                 MatX& Mdot) const override {
    Mdot.setZero();  // absolute coordinates: M constant
  }
  bool mass_constant(const Model& /*model*/) const override { return true; }
  bool mass_diagonal(const Model& model) const override {
    for (const Body& b : model.bodies) {
      if (b.kind != BodyKind::spatial) continue;
      const Mat3& J = b.spatial.inertia;
      if (J(0, 1) != 0.0 || J(0, 2) != 0.0 || J(1, 2) != 0.0 || J(1, 0) != 0.0 || J(2, 0) != 0.0 ||
          J(2, 1) != 0.0)
        return false;
    }
    return true;
  }
  VecX mass_diagonal_entries(const Model& model, const VecX& /*q*/, bool inverse) const override {
    VecX d(model.n);
    for (const Body& b : model.bodies)
      d.segment(b.u_offset, b.nu()) = block(b, inverse).diagonal().head(b.nu());
    return d;
  }
  void integrate(const Model& model, VecX& q, const VecX& du, double h) const override {
    for (const Body& b : model.bodies)
      visit_kind(b, [&](auto kind) { kind.integrate(b, q, du, h); });
  }
  void difference(const Model& model, const VecX& q1, const VecX& q0, VecX& du) const override {
    for (const Body& b : model.bodies)
      visit_kind(b, [&](auto kind) { kind.difference(b, q1, q0, du); });
  }
  void coordinate_rates(const Model& model, const Eigen::Ref<const VecX>& q, const VecX& u,
                        Eigen::Ref<VecX> qdot) const override {
    for (const Body& b : model.bodies)
      visit_kind(b, [&](auto kind) { kind.rates(b, q, u, qdot); });  // eq. (19): q̇ = B̃u
  }
  void normalize(const Model& model, Eigen::Ref<VecX> q) const override {
    for (const Body& b : model.bodies) visit_kind(b, [&](auto kind) { kind.normalize(b, q); });
  }
  double kinetic_energy(const Model& model, const State& state) const override {
    double T = 0.0;  // eq. (4): T = ½ uᵀ M u, body by body
    for (const Body& b : model.bodies)
      visit_kind(b, [&](auto kind) { kind.add_kinetic_energy(b, state.u, T); });
    return T;
  }
  VecX design_q(const Model& model) const override {
    VecX q(model.nq);
    for (const Body& b : model.bodies)
      visit_kind(b, [&](auto kind) { kind.design_coordinates(b, q); });
    return q;
  }
  std::string velocity_name(const Model& model, int k) const override {
    for (const Body& b : model.bodies) {
      if (k < b.u_offset || k >= b.u_offset + b.nu()) continue;
      std::string name = b.name;
      name.push_back('.');
      name.append(visit_kind(b, [&](auto kind) { return kind.velocity_names[k - b.u_offset]; }));
      return name;
    }
    return "?";
  }
  void applied_forces(const Model& model, const State& state, VecX& Q) const override {
    Q.setZero();
    for (const Load& load : model.loads) add_load(model, load, state, Q);
    add_velocity_terms(model, state, Q);
  }
  // The point forces and torques (given functions of time, not of q) and the dampers.
  double nonconservative_power(const Model& model, const State& state, const VecX& /*Q*/,
                               const MatX& /*Mdot*/, VecX& scratch) const override {
    if (!has_dampers(model) &&
        std::none_of(model.loads.begin(), model.loads.end(), load_is_nonconservative))
      return 0.0;  // conservative: nothing to add up
    scratch.setZero();
    for (const Load& l : model.loads)
      if (load_is_nonconservative(l)) add_load(model, l, state, scratch);
    return scratch.dot(state.u) - dissipated_power(model, state);
  }
  bool forces_time_invariant() const override { return true; }
  const ConstraintSystem& constraints() const override { return joint_constraints(); }

 private:
  static bool load_is_nonconservative(const Load& l) {
    return std::holds_alternative<PointForce>(l.kind) || std::holds_alternative<Torque>(l.kind) ||
           std::holds_alternative<SpatialPointForce>(l.kind) ||
           std::holds_alternative<SpatialTorque>(l.kind);
  }
  static bool has_dampers(const Model& model) {
    for (const Load& l : model.loads) {
      if (const auto* s = std::get_if<SpringDamper>(&l.kind); s && s->damping != 0.0) return true;
      if (const auto* s = std::get_if<RotarySpringDamper>(&l.kind); s && s->damping != 0.0)
        return true;
      if (const auto* s = std::get_if<SpatialSpringDamper>(&l.kind); s && s->damping != 0.0)
        return true;
      if (const auto* s = std::get_if<JointSpringDamper>(&l.kind); s && s->damping != 0.0)
        return true;
    }
    return false;
  }
  static BodyBlock block(const Body& b, bool inverse) {
    return visit_kind(b, [&](auto kind) { return kind.mass_block(b, inverse); });
  }
  // The bodies' blocks into the n × n matrix X.
  static void fill_block_diagonal(const Model& model, bool inverse, MatX& X) {
    X.setZero();
    for (const Body& b : model.bodies)
      X.block(b.u_offset, b.u_offset, b.nu(), b.nu()) =
          block(b, inverse).topLeftCorner(b.nu(), b.nu());
  }
};

// ---- A general system given by functions (model/general_system.hpp): q̇ = u ------------------
class GeneralFreeSystem final : public FreeSystem {
 public:
  void mass(const Model& model, const VecX& q, MatX& M) const override {
    model.general->mass(q, M);  // eq. (4): M(q)
  }
  void inverse_mass(const Model& model, const VecX& q, MatX& A) const override {
    MatX M(model.n, model.n);
    model.general->mass(q, M);
    A = M.llt().solve(MatX::Identity(model.n, model.n));  // eq. (6)
  }
  void mass_rate(const Model& model, const VecX& q, const VecX& u, MatX& Mdot) const override {
    model.general->mass_rate(q, u, Mdot);
  }
  bool mass_constant(const Model& /*model*/) const override { return false; }
  bool mass_diagonal(const Model& /*model*/) const override { return false; }
  VecX mass_diagonal_entries(const Model& model, const VecX& q, bool inverse) const override {
    MatX X(model.n, model.n);
    if (inverse) {
      inverse_mass(model, q, X);
    } else {
      model.general->mass(q, X);
    }
    return X.diagonal();
  }
  void integrate(const Model& /*model*/, VecX& q, const VecX& du, double h) const override {
    q += h * du;  // q̇ = u
  }
  void difference(const Model& /*model*/, const VecX& q1, const VecX& q0, VecX& du) const override {
    du = q1 - q0;
  }
  void coordinate_rates(const Model& /*model*/, const Eigen::Ref<const VecX>& /*q*/, const VecX& u,
                        Eigen::Ref<VecX> qdot) const override {
    qdot = u;
  }
  void normalize(const Model& /*model*/, Eigen::Ref<VecX> /*q*/) const override {}
  double kinetic_energy(const Model& model, const State& state) const override {
    MatX M(model.n, model.n);
    model.general->mass(state.q, M);
    return 0.5 * state.u.dot(M * state.u);  // eq. (4)
  }
  VecX design_q(const Model& model) const override { return model.general->q0; }
  std::string velocity_name(const Model& model, int k) const override {
    return model.general->coordinates[static_cast<size_t>(k)];
  }
  void applied_forces(const Model& model, const State& state, VecX& Q) const override {
    model.general->forces(state.q, state.u, state.t, Q);  // its Q̂(q, u, t)
  }
  // Q̂ = Q + ∂T/∂q and ∂T/∂q · u = ½ uᵀṀu, so the power of the applied forces is
  // Q̂ᵀu − ½ uᵀṀu (dT/dt = uᵀṗ − ½ uᵀṀu, uᵀR = 0); all of Q counts as non-conservative.
  double nonconservative_power(const Model& /*model*/, const State& state, const VecX& Q,
                               const MatX& Mdot, VecX& scratch) const override {
    scratch.noalias() = Mdot * state.u;
    return Q.dot(state.u) - 0.5 * state.u.dot(scratch);
  }
  bool forces_time_invariant() const override { return false; }
  const ConstraintSystem& constraints() const override { return general_constraints(); }
};

const BodySystem kBodies;
const GeneralFreeSystem kGeneral;

}  // namespace

const FreeSystem& free_system(const Model& model) {
  if (model.general) return kGeneral;
  return kBodies;
}

const ConstraintSystem& constraint_system(const Model& model) {
  return free_system(model).constraints();
}

void compute_mass_matrix(const Model& model, const VecX& q, MatX& M) {
  free_system(model).mass(model, q, M);
}

void compute_inverse_mass_matrix(const Model& model, const VecX& q, MatX& A) {
  free_system(model).inverse_mass(model, q, A);
}

void compute_mass_matrix_rate(const Model& model, const VecX& q, const VecX& u, MatX& Mdot) {
  free_system(model).mass_rate(model, q, u, Mdot);
}

bool mass_matrix_is_constant(const Model& model) { return free_system(model).mass_constant(model); }

bool mass_matrix_is_diagonal(const Model& model) { return free_system(model).mass_diagonal(model); }

VecX mass_matrix_diagonal(const Model& model, const VecX& q) {
  return free_system(model).mass_diagonal_entries(model, q, false);
}

VecX inverse_mass_diagonal(const Model& model, const VecX& q) {
  return free_system(model).mass_diagonal_entries(model, q, true);
}

void integrate_positions(const Model& model, VecX& q, const VecX& du, double h) {
  free_system(model).integrate(model, q, du, h);
}

void difference_positions(const Model& model, const VecX& q1, const VecX& q0, VecX& du) {
  free_system(model).difference(model, q1, q0, du);
}

void compute_coordinate_rates(const Model& model, const Eigen::Ref<const VecX>& q, const VecX& u,
                              Eigen::Ref<VecX> qdot) {
  free_system(model).coordinate_rates(model, q, u, qdot);
}

void normalize_coordinates(const Model& model, Eigen::Ref<VecX> q) {
  free_system(model).normalize(model, q);
}

double kinetic_energy(const Model& model, const State& state) {
  return free_system(model).kinetic_energy(model, state);
}

void body_rotations(const Model& model, const VecX& q, std::span<Eigen::Matrix2d> rotations) {
  ORTHOMECH_CHECK(rotations.size() == model.bodies.size(), "one rotation per body");
  for (size_t b = 0; b < model.bodies.size(); ++b) {
    const Body& body = model.bodies[b];
    rotations[b] =
        body.kind == BodyKind::rigid ? rotation(q(body.q_offset + 2)) : Eigen::Matrix2d::Identity();
  }
}

BodyPoses::BodyPoses(const Model& model)
    : R_(model.bodies.size(), Eigen::Matrix2d::Identity()),
      S_(model.dimension == 3 ? model.bodies.size() : 0, Mat3::Identity()) {}

void BodyPoses::update(const Model& model, const VecX& q) {
  body_rotations(model, q, R_);
  if (S_.empty()) return;
  for (size_t b = 0; b < model.bodies.size(); ++b) {
    const Body& body = model.bodies[b];
    if (body.kind == BodyKind::spatial) S_[b] = rotation_matrix(q.segment<4>(body.q_offset + 3));
  }
}

}  // namespace orthomech
