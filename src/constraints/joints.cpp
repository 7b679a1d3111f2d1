#include "orthomech/constraints/joints.hpp"

#include <array>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "../model/dot_row.hpp"
#include "orthomech/check.hpp"
#include "orthomech/constraints/constraint_system.hpp"
#include "orthomech/constraints/rolling_disc.hpp"
#include "orthomech/constraints/sparse_et.hpp"
#include "orthomech/constraints/spatial_joints.hpp"
#include "orthomech/model/free_system.hpp"

namespace orthomech {

ConstraintWorkspace::ConstraintWorkspace(const Model& model, bool matrices)
    : f(VecX::Zero(model.nc)),
      Et(MatX::Zero(matrices ? model.nc : 0, matrices ? model.n : 0)),
      Dt(MatX::Zero(matrices ? model.nc : 0, matrices ? model.n : 0)),
      Dtu(VecX::Zero(model.nc)),
      poses(model) {}

namespace {

// Adds ±1 to the angle column of a body (rows of angle constraints).
template <typename Row>
void add_angle(const Model& model, int body, double scale, Row&& row) {
  if (body == kGround) return;
  const Body& b = model.bodies[static_cast<size_t>(body)];
  row(b.u_offset + 2) += scale;
}

// One joint: writes its rows of f (if f) and Dᵀu (if Dtu), adds into its rows of Eᵀ (if Et) and
// Dᵀ (if Dt), which are zero on entry (evaluate).
// Revolute and fixed x/y rows are written (point on i) − (point on j); the slot-normal, angle,
// gear and distance rows are written for j relative to i (docs/notation.md gives each row).
// EtT: MatX (dense Eᵀ), SparseEt (its structural pattern) or EtRecorder (records the pattern):
// every write goes through EtT::row(i)(j) += …, so one writer serves the three.
template <typename EtT>
struct JointEvaluator {
  const Model& model;
  const VecX& q;
  const VecX* u;  // null when only f or Eᵀ are wanted
  int r;          // first row
  VecX* f;
  EtT* Et;
  MatX* Dt;
  VecX* Dtu;                   // Dᵀu row by row, without Dt (needs u)
  const Eigen::Matrix2d* rot;  // R(φ_b) per body at q, or null
  const Mat3* rot3;            // R(e_b) per body at q (spatial), or null

  template <typename Rows>
  auto row(Rows* m, int k) {
    return m->row(r + k);
  }

  [[nodiscard]] bool rate() const { return Dt || Dtu; }
  // Row k of Dᵀ from `fill(row)` (accumulating writes): into Dt and/or its product with u.
  template <typename Fill>
  void rate_row(int k, Fill&& fill) {
    if (Dt) {
      auto e = row(Dt, k);  // zero on entry (evaluate zeroes Dᵀ once)
      fill(e);
    }
    if (Dtu) {
      DotRow e{*u};
      fill(e);
      (*Dtu)(r + k) = e.sum;  // eq. (76)
    }
  }

  // Revolute, eq. (20): f = r_Pi − r_Pj; Eᵀ = [J_Pi, −J_Pj]; Dᵀ = [J̇_Pi, −J̇_Pj].
  void operator()(const Revolute& j) { point_coincidence(j.pi, j.pj); }

  // Fixed: the revolute rows plus the angle row φ_j − φ_i − φ0.
  void operator()(const Fixed& j) {
    point_coincidence(j.pi, j.pj);
    relative_angle(j.pi.body, j.pj.body, j.phi0, 2);
  }

  // Prismatic: the line row of the pin-in-slot plus the angle row.
  void operator()(const Prismatic& j) {
    point_on_line(j.pi, j.pj, j.axis_local, 0);
    relative_angle(j.pi.body, j.pj.body, j.phi0, 1);
  }

  void operator()(const PinInSlot& j) { point_on_line(j.pi, j.pj, j.axis_local, 0); }

  // Spatial joints: rows from the primitives (constraints/spatial_joints.hpp).
  void operator()(const SpatialJoint& j) {
    evaluate_spatial_joint(model, j, q, u, r, f, Et, Dt, Dtu, rot3);
  }

  // Gear pair: f = (φ_j − φ_c) − k (φ_i − φ_c) − c0; Eᵀ constant, Dᵀ = 0.
  void operator()(const GearPair& j) {
    if (f) {
      const double pc = body_angle(model, j.carrier, q);
      (*f)(r) =
          (body_angle(model, j.bj, q) - pc) - j.ratio * (body_angle(model, j.bi, q) - pc) - j.c0;
    }
    if (Et) {
      auto e = row(Et, 0);
      add_angle(model, j.bj, 1.0, e);
      add_angle(model, j.bi, -j.ratio, e);
      add_angle(model, j.carrier, j.ratio - 1.0, e);
    }
    if (rate()) rate_row(0, [](auto&) {});
  }

  // Distance: f = (dᵀd − L²)/(2L), d = r_Pj − r_Pi; Eᵀ = dᵀ ∂d/∂u / L;
  // Dᵀ = (ḋᵀ ∂d/∂u + dᵀ d/dt(∂d/∂u)) / L.
  void operator()(const Distance& j) {
    const PointKinematics ki = detail::point_kinematics_at(model, j.pi, q, u, rot);
    const PointKinematics kj = detail::point_kinematics_at(model, j.pj, q, u, rot);
    const Vec2 d = kj.r - ki.r;
    const Vec2 dd = kj.v - ki.v;
    const double L = j.length;
    if (f) (*f)(r) = (d.squaredNorm() - L * L) / (2.0 * L);
    if (Et) {
      auto e = row(Et, 0);
      add_point_jacobian(model, j.pj, kj, d, 1.0 / L, e);
      add_point_jacobian(model, j.pi, ki, d, -1.0 / L, e);
    }
    if (rate())
      rate_row(0, [&](auto& e) {
        add_point_jacobian(model, j.pj, kj, dd, 1.0 / L, e);
        add_point_jacobian(model, j.pi, ki, dd, -1.0 / L, e);
        add_point_jacobian_rate(model, j.pj, kj, d, 1.0 / L, e);
        add_point_jacobian_rate(model, j.pi, ki, d, -1.0 / L, e);
      });
  }

  void point_coincidence(const PointRef& pi, const PointRef& pj) {
    const PointKinematics ki = detail::point_kinematics_at(model, pi, q, u, rot);
    const PointKinematics kj = detail::point_kinematics_at(model, pj, q, u, rot);
    if (f) (*f).segment<2>(r) = ki.r - kj.r;  // eq. (20)
    if (Et) {  // eq. (23): add_point_jacobian with c = x̂, ŷ written out: [I, perp(R s)] per point
      auto ex = row(Et, 0), ey = row(Et, 1);
      auto add = [&](const PointRef& p, const PointKinematics& k, double scale) {
        if (p.body == kGround) return;
        const int o = model.bodies[static_cast<size_t>(p.body)].u_offset;
        ex(o) += scale;
        ey(o + 1) += scale;
        if (k.rotates) {
          ex(o + 2) += -scale * k.Rs.y();
          ey(o + 2) += scale * k.Rs.x();
        }
      };
      add(pi, ki, 1.0);
      add(pj, kj, -1.0);
    }
    if (Dtu && !Dt) {  // Dᵀu alone: J̇_P u = −φ̇² R s per point, the products of the rows below
      for (int a = 0; a < 2; ++a) {  // in their order (the same bits as through rate_row)
        double sum = 0.0;
        if (ki.rotates) sum += (-ki.phidot * ki.Rs(a)) * ki.phidot;
        if (kj.rotates) sum += (kj.phidot * kj.Rs(a)) * kj.phidot;
        (*Dtu)(r + a) = sum;
      }
      return;
    }
    for (int a = 0; a < 2; ++a) {
      const Vec2 c = a == 0 ? Vec2::UnitX() : Vec2::UnitY();
      if (rate())
        rate_row(a, [&](auto& e) {
          add_point_jacobian_rate(model, pi, ki, c, 1.0, e);  // eq. (76)
          add_point_jacobian_rate(model, pj, kj, c, -1.0, e);
        });
    }
  }

  void relative_angle(int bi, int bj, double phi0, int k) {
    if (f) (*f)(r + k) = body_angle(model, bj, q) - body_angle(model, bi, q) - phi0;
    if (Et) {
      auto e = row(Et, k);
      add_angle(model, bj, 1.0, e);
      add_angle(model, bi, -1.0, e);
    }
    if (rate()) rate_row(k, [](auto&) {});
  }

  // Point Pj on the line through Pi along axis a (body i): f = nᵀ d, n = R_i perp(a),
  // d = r_Pj − r_Pi. With ṅ = φ̇_i perp(n):
  //   ∂f/∂u  = nᵀ ∂d/∂u + (perp(n)ᵀ d) e_φi                                   (L1)
  //   d/dt   = ṅᵀ ∂d/∂u + nᵀ d/dt(∂d/∂u) + (−φ̇_i nᵀ d + perp(n)ᵀ ḋ) e_φi        (L2)
  void point_on_line(const PointRef& pi, const PointRef& pj, const Vec2& axis, int k) {
    const PointKinematics ki = detail::point_kinematics_at(model, pi, q, u, rot);
    const PointKinematics kj = detail::point_kinematics_at(model, pj, q, u, rot);
    const double phi_i = body_angle(model, pi.body, q);
    const double w_i = (u ? body_angular_velocity(model, pi.body, *u) : 0.0);
    const Vec2 n = (rot && pi.body != kGround ? rot[pi.body] : rotation(phi_i)) * perp(axis);
    const Vec2 d = kj.r - ki.r;
    const Vec2 dd = kj.v - ki.v;
    if (f) (*f)(r + k) = n.dot(d);
    const bool i_rotates = pi.body != kGround;
    if (Et) {
      auto e = row(Et, k);
      add_point_jacobian(model, pj, kj, n, 1.0, e);  // (L1)
      add_point_jacobian(model, pi, ki, n, -1.0, e);
      if (i_rotates) add_angle(model, pi.body, perp(n).dot(d), e);
    }
    if (rate())
      rate_row(k, [&](auto& e) {
        const Vec2 ndot = w_i * perp(n);
        add_point_jacobian(model, pj, kj, ndot, 1.0, e);  // (L2)
        add_point_jacobian(model, pi, ki, ndot, -1.0, e);
        add_point_jacobian_rate(model, pj, kj, n, 1.0, e);
        add_point_jacobian_rate(model, pi, ki, n, -1.0, e);
        if (i_rotates) add_angle(model, pi.body, -w_i * n.dot(d) + perp(n).dot(dd), e);
      });
  }
};

// Knife edge (nonholonomic): nᵀ v_P = 0 with n = R(φ) perp(a) (a: blade direction, body frame).
//   f = 0 (no geometric residual: docs/design.md §3);
//   Eᵀ = nᵀ ∂r_P/∂u;
//   Dᵀ = ṅᵀ ∂r_P/∂u + nᵀ d/dt(∂r_P/∂u), ṅ = φ̇ perp(n)                                   (L3)
template <typename EtT>
void knife_edge(const Model& model, const KnifeEdge& k, const VecX& q, const VecX* u, VecX* f,
                EtT* Et, MatX* Dt, VecX* Dtu) {
  const PointKinematics kp = point_kinematics(model, k.at, q, u);
  const Vec2 n = rotation(body_angle(model, k.at.body, q)) * perp(k.axis_local);
  if (f) (*f)(k.row_offset) = 0.0;
  if (Et) {
    auto e = Et->row(k.row_offset);
    add_point_jacobian(model, k.at, kp, n, 1.0, e);
  }
  auto fill = [&](auto& e) {
    add_point_jacobian(model, k.at, kp, kp.phidot * perp(n), 1.0, e);  // (L3)
    add_point_jacobian_rate(model, k.at, kp, n, 1.0, e);
  };
  if (Dt) {
    auto e = Dt->row(k.row_offset);
    fill(e);
  }
  if (Dtu) {
    DotRow e{*u};
    fill(e);
    (*Dtu)(k.row_offset) = e.sum;
  }
}

// The joints, knife edges and rolling discs of a model of bodies (the ConstraintSystem below).
// Dtu: Dᵀu row by row (needs u), without forming Dᵀ.
// poses: the caller's kinematics stage at q (the bodies' rotations), if any.
template <typename EtT>
void evaluate_joints(const Model& model, const VecX& q, const VecX* u, VecX* f, EtT* Et, MatX* Dt,
                     VecX* Dtu, const BodyPoses* poses) {
  // The writers below accumulate into their rows: Eᵀ and Dᵀ are zeroed here, once and
  // contiguously (a row of a column-major matrix is strided: zeroing it row by row cost 30 % of
  // a projected rosenbrock4 step on the N = 40 four-bar).
  if (Et) Et->setZero();  // SparseEt: its pattern's values only
  if (Dt) Dt->setZero();
  // Each body's rotation once (sin/cos dominate small evaluations); particles keep the identity.
  constexpr size_t kTable = 64;
  std::array<Eigen::Matrix2d, kTable> table;
  const Eigen::Matrix2d* rot = poses ? poses->table().data() : nullptr;
  const Mat3* rot3 = poses ? poses->spatial_table() : nullptr;
  if (!rot && model.bodies.size() <= kTable) {
    body_rotations(model, q, std::span(table.data(), model.bodies.size()));
    rot = table.data();
  }
  for (const Joint& joint : model.joints) {
    JointEvaluator<EtT> ev{model, q, u, joint.row_offset, f, Et, Dt, Dtu, rot, rot3};
    std::visit(ev, joint.kind);
  }
  for (const KnifeEdge& k : model.knife_edges) knife_edge(model, k, q, u, f, Et, Dt, Dtu);
  for (const RollingDisc& d : model.rolling_discs)
    evaluate_rolling_disc(model, d, q, u, f, Et, Dt, Dtu);
}

class JointConstraints final : public ConstraintSystem {
 public:
  void evaluate(const Model& model, const VecX& q, const VecX* u, VecX* f, MatX* Et, MatX* Dt,
                VecX* Dtu, const BodyPoses* poses) const override {
    evaluate_joints(model, q, u, f, Et, Dt, Dtu, poses);
  }
  void evaluate(const Model& model, const VecX& q, const VecX* u, VecX* f, SparseEt* Et, MatX* Dt,
                VecX* Dtu, const BodyPoses* poses) const override {
    evaluate_joints(model, q, u, f, Et, Dt, Dtu, poses);
  }
  void record_pattern(const Model& model, EtRecorder& recorder) const override {
    evaluate_joints(model, model.design_q(), nullptr, nullptr, &recorder, nullptr, nullptr,
                    nullptr);
  }
  bool structurally_sparse() const override { return true; }
  std::string row_name(const Model& model, int row) const override {
    for (const Joint& j : model.joints) {
      if (row >= j.row_offset && row < j.row_offset + j.rows()) {
        return "joint '" + j.name + "', " +
               j.component_names()[static_cast<size_t>(row - j.row_offset)];
      }
    }
    for (const KnifeEdge& k : model.knife_edges)
      if (row == k.row_offset) return "knife edge '" + k.name + "', lateral";
    for (const RollingDisc& d : model.rolling_discs) {
      static const char* rows[] = {"t1", "t2", "n"};
      if (row >= d.row_offset && row < d.row_offset + 3)
        return "rolling disc '" + d.name + "', " + rows[row - d.row_offset];
    }
    throw_invalid_argument("constraint_row_name", "row", "is out of range [0, nc)");
  }
};

const JointConstraints kJointConstraints;

template <typename EtT>
void evaluate(const Model& model, const VecX& q, const VecX* u, VecX* f, EtT* Et, MatX* Dt,
              VecX* Dtu = nullptr, const BodyPoses* poses = nullptr) {
  constraint_system(model).evaluate(model, q, u, f, Et, Dt, Dtu, poses);
}

// A SparseEt of another model would be written out of its rows: refused.
void check_shape(const Model& model, const SparseEt& Et, const VecX* f) {
  if (Et.rows() != model.nc || Et.cols() != model.n || (f && f->size() != model.nc))
    throw std::invalid_argument("constraint evaluation: Eᵀ is " + std::to_string(Et.rows()) +
                                " × " + std::to_string(Et.cols()) + ", the model's " +
                                std::to_string(model.nc) + " × " + std::to_string(model.n));
}

}  // namespace

const ConstraintSystem& joint_constraints() { return kJointConstraints; }

void compute_constraint_residual(const Model& model, const VecX& q, VecX& f) {
  evaluate<MatX>(model, q, nullptr, &f, nullptr, nullptr);
}

void compute_constraint_residual(const Model& model, const VecX& q, const BodyPoses& rotations,
                                 VecX& f) {
  evaluate<MatX>(model, q, nullptr, &f, nullptr, nullptr, nullptr, &rotations);
}

void compute_constraint_jacobian(const Model& model, const VecX& q, MatX& Et) {
  evaluate(model, q, nullptr, nullptr, &Et, nullptr);
}

void compute_constraint_residual_and_jacobian(const Model& model, const VecX& q, VecX& f,
                                              MatX& Et) {
  evaluate(model, q, nullptr, &f, &Et, nullptr);
}

void compute_constraint_residual_and_jacobian(const Model& model, const VecX& q,
                                              const BodyPoses& rotations, VecX& f, MatX& Et) {
  evaluate(model, q, nullptr, &f, &Et, nullptr, nullptr, &rotations);
}

void compute_constraint_jacobian(const Model& model, const VecX& q, SparseEt& Et) {
  check_shape(model, Et, nullptr);
  evaluate(model, q, nullptr, nullptr, &Et, nullptr);
}

void compute_constraint_residual_and_jacobian(const Model& model, const VecX& q, VecX& f,
                                              SparseEt& Et) {
  check_shape(model, Et, &f);
  evaluate(model, q, nullptr, &f, &Et, nullptr);
}

void compute_constraint_residual_and_jacobian(const Model& model, const VecX& q,
                                              const BodyPoses& rotations, VecX& f, SparseEt& Et) {
  check_shape(model, Et, &f);
  evaluate(model, q, nullptr, &f, &Et, nullptr, nullptr, &rotations);
}

void compute_constraint_rate(const Model& model, const State& state, const BodyPoses& rotations,
                             VecX& Dtu) {
  if (Dtu.size() != model.nc)
    throw std::invalid_argument("compute_constraint_rate: Dtu has " + std::to_string(Dtu.size()) +
                                " entries, the model " + std::to_string(model.nc) + " rows");
  evaluate<MatX>(model, state.q, &state.u, nullptr, nullptr, nullptr, &Dtu, &rotations);
}

void record_constraint_pattern(const Model& model, EtRecorder& recorder) {
  constraint_system(model).record_pattern(model, recorder);
}

void compute_constraint_rate(const Model& model, const State& state, ConstraintWorkspace& ws) {
  // The convective term Dᵀu, eq. (76), row by row: Dᵀ itself is not formed (ws.Dt untouched).
  ws.poses.update(model, state.q);
  evaluate<MatX>(model, state.q, &state.u, nullptr, nullptr, nullptr, &ws.Dtu, &ws.poses);
}

void compute_constraint_rate(const Model& model, const State& state, const BodyPoses& rotations,
                             ConstraintWorkspace& ws) {
  evaluate<MatX>(model, state.q, &state.u, nullptr, nullptr, nullptr, &ws.Dtu, &rotations);
}

void compute_constraints(const Model& model, const State& state, ConstraintWorkspace& ws) {
  if (ws.Et.rows() != model.nc || ws.Et.cols() != model.n)
    throw std::logic_error("compute_constraints: the ConstraintWorkspace holds no Eᵀ and Dᵀ");
  ws.poses.update(model, state.q);
  evaluate(model, state.q, &state.u, &ws.f, &ws.Et, &ws.Dt, nullptr, &ws.poses);
  ws.Dtu.noalias() = ws.Dt * state.u;  // convective term Dᵀu, eq. (76)
}

CoordinateKind joint_coordinate_kind(const Joint& joint) {
  if (const auto* s = std::get_if<SpatialJoint>(&joint.kind)) {
    switch (spatial_joint_spec(s->type).coordinate) {
      case SpatialCoordinate::angle:
        return CoordinateKind::angle;
      case SpatialCoordinate::slide:
        return CoordinateKind::slide;
      case SpatialCoordinate::none:
        return CoordinateKind::none;
    }
  }
  if (std::holds_alternative<Revolute>(joint.kind)) return CoordinateKind::angle;
  if (std::holds_alternative<Prismatic>(joint.kind)) return CoordinateKind::slide;
  return CoordinateKind::none;
}

bool joint_coordinate_wraps(const Joint& joint) {
  return std::holds_alternative<SpatialJoint>(joint.kind) &&
         joint_coordinate_kind(joint) == CoordinateKind::angle;
}

}  // namespace orthomech
