#include "orthomech/analysis/assembly.hpp"

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "../run_watch.hpp"
#include "../solvers/ipopt_nlp.hpp"
#include "orthomech/analysis/mobility.hpp"
#include "orthomech/analysis/positions.hpp"
#include "orthomech/check.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/constraints/sparse_et.hpp"
#include "orthomech/constraints/spatial_joints.hpp"
#include "orthomech/io/units.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/model/measures.hpp"
#include "orthomech/model/spatial.hpp"
#include "orthomech/model/state.hpp"
#include "orthomech/projection/dual.hpp"
#include "orthomech/projection/free_system_stage.hpp"
#include "orthomech/projection/gauss_newton.hpp"

namespace orthomech {

bool is_angular_row(const std::string& component) {
  // Planar: the angle and gear rows. Spatial: the dot-1 rows (f, g, twist, pins) are
  // dimensionless, the sine of a small misalignment angle (spatial_joints.hpp).
  return component == "angle" || component == "ratio" || component == "f" || component == "g" ||
         component == "twist" || component == "pins";
}

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

// A scalar row on a joint coordinate: a lock (lo = hi) or a limit (lo < hi).
struct CoordinateRow {
  int joint = -1;
  double lo = 0.0, hi = 0.0;
  bool lock = false;
  bool linear = true;     // revolute: s = φ_j − φ_i is linear in q (zero Hessian)
  std::vector<int> cols;  // coordinates s depends on (for its Hessian)
  // Spatial angle (revolute, cylindrical, screw: the (P5) twist angle θ ∈ (−π, π]): known only
  // modulo 2π, so the row reads s = centre + wrap(θ − centre), the value of θ nearest `centre`
  // (the lock's value; a limit's midpoint). Its gradient is θ's (docs/spatial.md §6.4: "locks use
  // the wrapped residual").                                                                  (L4)
  bool wraps = false;
  double centre = 0.0;
  int measure = -1;  // a lock on a position measure's value instead of a joint coordinate
};

// Whether a lock is on an angle (rad): a joint's angle coordinate or a measure in rad.
bool lock_is_angle(const Model& model, const JointLock& l) {
  if (l.measure >= 0)
    return model.measures[static_cast<size_t>(l.measure)].unit.rfind("rad", 0) == 0;
  return joint_coordinate_kind(model.joints[static_cast<size_t>(l.joint)]) == CoordinateKind::angle;
}

// The scalar a row reads: the joint's coordinate, or the measure's position quantity.
MeasureKind row_kind(const Model& model, const CoordinateRow& r) {
  if (r.measure >= 0) return model.measures[static_cast<size_t>(r.measure)].kind;
  return JointCoordinate{r.joint};
}

std::vector<int> body_columns(const Model& model, int body) {
  std::vector<int> c;
  if (body == kGround) return c;
  const Body& b = model.bodies[static_cast<size_t>(body)];
  for (int k = 0; k < b.nq(); ++k) c.push_back(b.q_offset + k);
  return c;
}

// Rows for locks and limits. Revolute values are matched modulo 2π nearest the guess q0 (a lock
// of 30° holds at 390° if the drawing has the crank there); limits are shifted by the same rule
// applied to their midpoint. Spatial joints: their coordinate (joint_coordinate_kind), an angle
// read by (L4).
std::vector<CoordinateRow> coordinate_rows(const Model& model, const VecX& q0,
                                           const AssemblyOptions& options) {
  std::vector<CoordinateRow> rows;
  auto make = [&](int joint, double lo, double hi, bool lock) {
    const Joint& j = model.joints.at(static_cast<size_t>(joint));
    CoordinateRow r;
    r.joint = joint;
    r.lock = lock;
    if (std::holds_alternative<SpatialJoint>(j.kind)) {
      const CoordinateKind kind = joint_coordinate_kind(j);
      if (kind == CoordinateKind::none)
        throw std::invalid_argument(
            "joint '" + j.name + "' has no coordinate to lock (a " +
            spatial_joint_spec(std::get<SpatialJoint>(j.kind).type).type +
            " joint; revolute, cylindrical and screw joints have an angle, prismatic a slide)");
      r.lo = lo;
      r.hi = hi;
      r.linear = false;
      r.wraps = kind == CoordinateKind::angle;
      r.centre = 0.5 * (lo + hi);
    } else if (std::holds_alternative<Revolute>(j.kind)) {
      const double s0 = joint_coordinate(model, joint, q0);
      const double mid = 0.5 * (lo + hi);
      const double shift = kTwoPi * std::round((s0 - mid) / kTwoPi);
      r.lo = lo + shift;
      r.hi = hi + shift;
      r.linear = true;
    } else if (const auto* pri = std::get_if<Prismatic>(&j.kind)) {
      r.lo = lo;
      r.hi = hi;
      r.linear = false;
      r.cols = body_columns(model, pri->pi.body);
      for (int c : body_columns(model, pri->pj.body)) r.cols.push_back(c);
    } else {
      throw std::invalid_argument("joint '" + j.name +
                                  "' has no scalar coordinate to lock (revolute or prismatic)");
    }
    rows.push_back(r);
  };
  for (const JointLock& l : options.locks) {
    if (l.measure < 0) {
      make(l.joint, l.value, l.value, true);
      continue;
    }
    // A measure's value (its position quantity; measures with derivative 1 or 2 name it too): a
    // joint measure is its joint's lock; others are not wrapped (spatial measure angles lie in
    // [0, π] or (−π/2, π/2]), their Hessian by (L1) over every coordinate.
    const Measure& m = model.measures.at(static_cast<size_t>(l.measure));
    if (std::holds_alternative<JointCoordinate>(m.kind)) {
      make(std::get<JointCoordinate>(m.kind).joint, l.value, l.value, true);
      continue;
    }
    CoordinateRow r;
    r.measure = l.measure;
    r.lock = true;
    r.lo = r.hi = l.value;
    r.linear = false;
    for (int k = 0; k < model.nq; ++k) r.cols.push_back(k);
    rows.push_back(r);
  }
  if (options.use_limits)
    for (size_t k = 0; k < model.joints.size(); ++k)
      if (model.joints[k].limits)
        make(static_cast<int>(k), model.joints[k].limits->x(), model.joints[k].limits->y(), false);
  return rows;
}

// s(q) and, if d is non-null, its gradient.
double eval_coordinate(const Model& model, const CoordinateRow& r, const VecX& q,
                       Eigen::Ref<VecX> d) {
  d.setZero();
  const double s = compute_scalar(model, row_kind(model, r), q, nullptr, d).value;
  return r.wraps ? r.centre + std::remainder(s - r.centre, kTwoPi) : s;  // (L4)
}

// Adds w ∇²s to H (exact): for B̃ = I the convective term ḋu of measures is uᵀ∇²s u, so the
// entries follow by polarisation over the few coordinates s depends on:
// e_aᵀ∇²s e_b = ½ (Q(e_a + e_b) − Q(e_a) − Q(e_b)), Q(u) = uᵀ∇²s u.                       (L1)
void add_coordinate_hessian(const Model& model, const CoordinateRow& r, const VecX& q, double w,
                            MatX& H, VecX& u) {
  if (r.linear || w == 0.0) return;
  auto Q = [&](int a, int b) {
    u.setZero();
    u(a) += 1.0;
    u(b) += 1.0;
    return compute_scalar(model, row_kind(model, r), q, &u).ddot_u;
  };
  std::vector<double> diag(r.cols.size());
  for (size_t i = 0; i < r.cols.size(); ++i) diag[i] = 0.25 * Q(r.cols[i], r.cols[i]);  // u = 2e
  for (size_t i = 0; i < r.cols.size(); ++i) {
    H(r.cols[i], r.cols[i]) += w * diag[i];
    for (size_t k = 0; k < i; ++k) {
      const double v = 0.5 * (Q(r.cols[i], r.cols[k]) - diag[i] - diag[k]);
      H(r.cols[i], r.cols[k]) += w * v;
      H(r.cols[k], r.cols[i]) += w * v;
    }
  }
}

// Adds Σ λ_i ∇²f_i to H, exactly: column k is Dᵀ(q, e_k)ᵀ λ, because Dᵀ(q, u) = Ėᵀ =
// Σ_k ∂Eᵀ/∂q_k u_k (eq. (76)) and Eᵀ = ∂f/∂q when B̃ = I (eq. (19)).                       (L2)
void add_constraint_hessian(const Model& model, const VecX& q, const VecX& lambda_f,
                            const std::vector<int>& rows, State& state, ConstraintWorkspace& cws,
                            MatX& H) {
  VecX lam = VecX::Zero(model.nc);
  for (size_t i = 0; i < rows.size(); ++i) lam(rows[i]) = lambda_f(static_cast<Eigen::Index>(i));
  if (lam.isZero(0.0)) return;
  state.q = q;
  for (int k = 0; k < model.n; ++k) {
    state.u.setZero();
    state.u(k) = 1.0;
    compute_constraints(model, state, cws);
    H.col(k).noalias() += cws.Dt.transpose() * lam;
  }
}

// Max violation of f (all rows), locks and limits.
double total_residual(const Model& model, const VecX& q, const std::vector<CoordinateRow>& rows,
                      VecX& f, VecX& d) {
  compute_constraint_residual(model, q, f);
  double r = f.size() ? f.cwiseAbs().maxCoeff() : 0.0;
  for (const CoordinateRow& c : rows) {
    const double s = eval_coordinate(model, c, q, d);
    r = std::max({r, c.lo - s, s - c.hi});
  }
  return std::isfinite(r) ? r : std::numeric_limits<double>::infinity();
}

// total_residual split by kind (m, rad).
ResidualSplit split_residual(const Model& model, const VecX& q,
                             const std::vector<CoordinateRow>& rows) {
  ResidualSplit out;
  VecX f(model.nc), d(model.n);
  compute_constraint_residual(model, q, f);
  std::vector<bool> angular(static_cast<size_t>(model.nc), false);
  for (const Joint& j : model.joints) {
    const auto names = j.component_names();
    for (int k = 0; k < j.rows(); ++k)
      angular[static_cast<size_t>(j.row_offset + k)] =
          is_angular_row(names[static_cast<size_t>(k)]);
  }
  for (int r = 0; r < model.nc; ++r) {
    double& to = angular[static_cast<size_t>(r)] ? out.angle : out.length;
    to = std::max(to, std::abs(f(r)));
  }
  for (const CoordinateRow& c : rows) {
    const double s = eval_coordinate(model, c, q, d);
    const bool is_angle =
        c.measure >= 0 ? model.measures[static_cast<size_t>(c.measure)].unit.rfind("rad", 0) == 0
                       : joint_coordinate_kind(model.joints[static_cast<size_t>(c.joint)]) ==
                             CoordinateKind::angle;
    double& to = is_angle ? out.angle : out.length;
    to = std::max({to, c.lo - s, s - c.hi});
  }
  if (!std::isfinite(out.length)) out.length = std::numeric_limits<double>::infinity();
  if (!std::isfinite(out.angle)) out.angle = std::numeric_limits<double>::infinity();
  return out;
}

std::vector<BodyMove> body_moves(const Model& model, const VecX& q0, const VecX& q) {
  std::vector<BodyMove> out;
  for (size_t b = 0; b < model.bodies.size(); ++b) {
    const Body& body = model.bodies[b];
    if (body.kind == BodyKind::spatial) {  // |Δr| of the frame origin, rotation 2 acos|e·e₀|
      const int bi = static_cast<int>(b);
      const Vec3 o = -body.spatial.com_local;
      BodyMove m;
      m.body = body.name;
      m.translation = (spatial_point(spatial_frame(model, bi, q, nullptr), o).r -
                       spatial_point(spatial_frame(model, bi, q0, nullptr), o).r)
                          .norm();
      const double c = std::abs(q.segment<4>(body.q_offset + 3)
                                    .normalized()
                                    .dot(q0.segment<4>(body.q_offset + 3).normalized()));
      m.rotation = 2.0 * std::acos(std::min(1.0, c));
      out.push_back(m);
      continue;
    }
    const PointRef origin{static_cast<int>(b), -body.com_local, body.name};
    BodyMove m;
    m.body = body.name;
    m.translation = (point_kinematics(model, origin, q, nullptr).r -
                     point_kinematics(model, origin, q0, nullptr).r)
                        .norm();
    if (body.kind == BodyKind::rigid) m.rotation = q(body.q_offset + 2) - q0(body.q_offset + 2);
    out.push_back(m);
  }
  return out;
}

// The assembly NLP (A1) or the least-squares fallback (A2): min ½‖f(q)‖² subject to the
// locks and limits only.
struct Problem {
  const Model& model;
  VecX q0;
  MatX W;                             // M / m_ref (same minimiser, objective scaled to O(Δq²))
  std::vector<int> f_rows;            // rows of f kept as constraints (independent ones)
  std::vector<CoordinateRow> coords;  // locks and limits
  bool least_squares = false;         // (A2) instead of (A1)
  // scratch
  mutable VecX f, d, u;
  mutable MatX Et;
  mutable State state;
  mutable ConstraintWorkspace cws;

  Problem(const Model& m, const VecX& q0_)
      : model(m), q0(q0_), f(m.nc), d(m.n), u(m.n), Et(m.nc, m.n), state(m), cws(m) {}

  int n_constraints() const {
    return (least_squares ? 0 : static_cast<int>(f_rows.size())) + static_cast<int>(coords.size());
  }

  solvers::DenseNlp nlp(const VecX& start) const {
    solvers::DenseNlp p;
    p.n = model.nq;
    p.m = n_constraints();
    p.x0 = start;
    p.g_lower.resize(p.m);
    p.g_upper.resize(p.m);
    int i = 0;
    if (!least_squares)
      for (size_t k = 0; k < f_rows.size(); ++k, ++i) p.g_lower(i) = p.g_upper(i) = 0.0;
    for (const CoordinateRow& c : coords) {
      p.g_lower(i) = c.lo;
      p.g_upper(i) = c.hi;
      ++i;
    }
    p.objective = [this](const VecX& q) {
      if (least_squares) {
        compute_constraint_residual(model, q, f);
        return 0.5 * f.squaredNorm();
      }
      const VecX dq = q - q0;
      return 0.5 * dq.dot(W * dq);
    };
    p.gradient = [this](const VecX& q, VecX& g) {
      if (least_squares) {
        compute_constraint_residual(model, q, f);
        compute_constraint_jacobian(model, q, Et);
        g.noalias() = Et.transpose() * f;
      } else {
        g.noalias() = W * (q - q0);
      }
    };
    p.constraints = [this](const VecX& q, VecX& g) {
      int r = 0;
      if (!least_squares) {
        compute_constraint_residual(model, q, f);
        for (int row : f_rows) g(r++) = f(row);
      }
      for (const CoordinateRow& c : coords) g(r++) = eval_coordinate(model, c, q, d);
    };
    p.jacobian = [this](const VecX& q, MatX& J) {
      int r = 0;
      if (!least_squares) {
        compute_constraint_jacobian(model, q, Et);
        for (int row : f_rows) J.row(r++) = Et.row(row);
      }
      for (const CoordinateRow& c : coords) {
        eval_coordinate(model, c, q, d);
        J.row(r++) = d.transpose();
      }
    };
    p.hessian = [this](const VecX& q, double sigma, const VecX& lambda, MatX& H) {
      hessian(q, sigma, lambda, H);
    };
    return p;
  }

  // σ∇²φ + Σλ∇²g, exact ((L1), (L2)).
  void hessian(const VecX& q, double sigma, const VecX& lambda, MatX& H) const {
    H.setZero();
    int r = 0;
    if (least_squares) {
      // ∇²(½‖f‖²) = E Eᵀ + Σ f_i ∇²f_i
      compute_constraint_residual(model, q, f);
      compute_constraint_jacobian(model, q, Et);
      H.noalias() = sigma * Et.transpose() * Et;
      std::vector<int> all(static_cast<size_t>(model.nc));
      for (int k = 0; k < model.nc; ++k) all[static_cast<size_t>(k)] = k;
      add_constraint_hessian(model, q, sigma * f, all, state, cws, H);
    } else {
      H = sigma * W;
      add_constraint_hessian(model, q, lambda.head(static_cast<Eigen::Index>(f_rows.size())),
                             f_rows, state, cws, H);
      r = static_cast<int>(f_rows.size());
    }
    for (const CoordinateRow& c : coords) add_coordinate_hessian(model, c, q, lambda(r++), H, u);
  }
};

// Spatial models (docs/spatial.md §6.4, the local-coordinates option): the unknowns are x ∈ Rⁿ with
// q(x) = q₀ ⊕ x, the velocity-space displacement from the guess (translation of each centre of
// mass, rotation vector θ in body axes). (A1) becomes min ½ xᵀWx, f(q(x)) = 0 — the mass metric
// of the planar problem, now exactly quadratic — with ∂f/∂x = Eᵀ(q(x)) blockdiag(I₃, J_r(θ))
// (model/spatial.hpp: exp_right_jacobian). The Hessian is Ipopt's limited-memory approximation:
// the planar exact Hessian (L2) needs B̃ = I. Valid while every |θ| < π (a body turned by less
// than half a turn from its drawing).
struct LocalProblem {
  const Model& model;
  VecX q0;
  MatX W;
  std::vector<int> f_rows;
  std::vector<CoordinateRow> coords;  // locks and limits, read by (L4) for angles
  bool least_squares = false;
  mutable VecX f, q, d;
  mutable MatX Et, EtJ;

  LocalProblem(const Model& m, const VecX& q0_)
      : model(m), q0(q0_), f(m.nc), q(m.nq), d(m.n), Et(m.nc, m.n), EtJ(m.nc, m.n) {}

  const VecX& at(const VecX& x) const {
    q = q0;
    integrate_positions(model, q, x, 1.0);
    return q;
  }
  // A velocity-space row r (∂/∂u) as a row in x: r · blockdiag(I₃, J_r(θ_b)) per body.
  template <class Rows>
  void to_local(const VecX& x, Rows&& rows) const {
    for (const Body& b : model.bodies)
      if (b.kind == BodyKind::spatial)
        rows.middleCols(b.u_offset + 3, 3) =
            (rows.middleCols(b.u_offset + 3, 3) * exp_right_jacobian(x.segment<3>(b.u_offset + 3)))
                .eval();
  }
  // ∂f/∂x = Eᵀ(q(x)) · blockdiag(I₃, J_r(θ_b)) per body.
  const MatX& jacobian(const VecX& x) const {
    compute_constraint_jacobian(model, at(x), Et);
    EtJ = Et;
    to_local(x, EtJ);
    return EtJ;
  }

  int n_f() const { return least_squares ? 0 : static_cast<int>(f_rows.size()); }

  solvers::DenseNlp nlp(const VecX& start) const {
    solvers::DenseNlp p;
    p.n = model.n;
    p.m = n_f() + static_cast<int>(coords.size());
    p.x0 = start;
    p.g_lower = VecX::Zero(p.m);
    p.g_upper = VecX::Zero(p.m);
    for (size_t k = 0; k < coords.size(); ++k) {
      p.g_lower(n_f() + static_cast<Eigen::Index>(k)) = coords[k].lo;
      p.g_upper(n_f() + static_cast<Eigen::Index>(k)) = coords[k].hi;
    }
    p.objective = [this](const VecX& x) {
      if (!least_squares) return 0.5 * x.dot(W * x);
      compute_constraint_residual(model, at(x), f);
      return 0.5 * f.squaredNorm();
    };
    p.gradient = [this](const VecX& x, VecX& g) {
      if (!least_squares) {
        g.noalias() = W * x;
        return;
      }
      compute_constraint_residual(model, at(x), f);
      g.noalias() = jacobian(x).transpose() * f;
    };
    p.constraints = [this](const VecX& x, VecX& g) {
      const VecX& qx = at(x);
      Eigen::Index r = 0;
      if (!least_squares) {
        compute_constraint_residual(model, qx, f);
        for (int row : f_rows) g(r++) = f(row);
      }
      for (const CoordinateRow& c : coords) g(r++) = eval_coordinate(model, c, qx, d);
    };
    p.jacobian = [this](const VecX& x, MatX& J) {
      Eigen::Index r = 0;
      if (!least_squares) {
        const MatX& EJ = jacobian(x);
        for (int row : f_rows) J.row(r++) = EJ.row(row);
      }
      const VecX& qx = at(x);
      for (const CoordinateRow& c : coords) {
        eval_coordinate(model, c, qx, d);
        J.row(r) = d.transpose();
        to_local(x, J.row(r++));
      }
    };
    return p;  // no Hessian: limited-memory
  }
};

// Newton on the KKT conditions of (A1) with the active rows as equalities, from Ipopt's point:
//   [H Cᵀ; C 0] [Δq; λ] = −[W(q − q₀); c]                                                   (L3)
// (complete orthogonal decomposition: redundant rows are harmless). Ipopt stops at its
// tolerance; two or three of these steps reach the rounding level (the Andrews test needs 1e-12).
int polish(const Problem& p, VecX& q, double tolerance) {
  const Model& model = p.model;
  std::vector<int> active_coords;
  for (size_t k = 0; k < p.coords.size(); ++k) {
    const CoordinateRow& c = p.coords[k];
    const double s = eval_coordinate(model, c, q, p.d);
    const double band = std::max(1e-8, 1e3 * tolerance);
    if (c.lock || s - c.lo < band || c.hi - s < band) active_coords.push_back(static_cast<int>(k));
  }
  const int nf = model.nc;
  const int m = nf + static_cast<int>(active_coords.size());
  const int n = model.nq;
  MatX K(n + m, n + m), H(n, n);
  VecX rhs(n + m), lambda = VecX::Zero(m);
  VecX work(n), f(model.nc);
  MatX Et(model.nc, model.n);
  std::vector<int> all(static_cast<size_t>(nf));
  for (int k = 0; k < nf; ++k) all[static_cast<size_t>(k)] = k;
  int steps = 0;
  double prev = total_residual(model, q, p.coords, f, work);
  for (int it = 0; it < 4; ++it) {
    // Hessian of the Lagrangian at (q, λ).
    H = p.W;
    add_constraint_hessian(model, q, lambda.head(nf), all, p.state, p.cws, H);
    for (size_t k = 0; k < active_coords.size(); ++k)
      add_coordinate_hessian(model, p.coords[static_cast<size_t>(active_coords[k])], q,
                             lambda(nf + static_cast<Eigen::Index>(k)), H, p.u);
    compute_constraint_residual(model, q, f);
    compute_constraint_jacobian(model, q, Et);
    K.setZero();
    K.topLeftCorner(n, n) = H;
    K.block(n, 0, nf, n) = Et;
    rhs.head(n) = -p.W * (q - p.q0);
    rhs.segment(n, nf) = -f;
    for (size_t k = 0; k < active_coords.size(); ++k) {
      const CoordinateRow& c = p.coords[static_cast<size_t>(active_coords[k])];
      const double s = eval_coordinate(model, c, q, work);
      const double target = c.lock ? c.lo : (s - c.lo < c.hi - s ? c.lo : c.hi);
      const int row = n + nf + static_cast<int>(k);
      K.row(row).head(n) = work.transpose();
      rhs(row) = target - s;
    }
    K.topRightCorner(n, m) = K.bottomLeftCorner(m, n).transpose();
    const Eigen::CompleteOrthogonalDecomposition<MatX> cod(K);
    const VecX sol = cod.solve(rhs);
    if (!sol.allFinite()) break;
    VecX trial = q + sol.head(n);
    const double r = total_residual(model, trial, p.coords, f, work);
    if (!(r <= std::max(prev, tolerance))) break;
    q = trial;
    lambda = sol.tail(m);
    ++steps;
    if (sol.head(n).cwiseAbs().maxCoeff() < 1e-15 * (1.0 + q.cwiseAbs().maxCoeff())) break;
    prev = r;
  }
  return steps;
}

}  // namespace

const char* to_string(AssemblyStatus s) {
  switch (s) {
    case AssemblyStatus::unchanged:
      return "unchanged";
    case AssemblyStatus::assembled:
      return "assembled";
    case AssemblyStatus::cannot_close:
      return "cannot close";
    case AssemblyStatus::not_converged:
      return "not converged";
    case AssemblyStatus::failed:
      return "failed";
    case AssemblyStatus::stopped:
      return "stopped";
  }
  return "?";
}

double joint_coordinate(const Model& model, int joint, const VecX& q) {
  return compute_scalar(model, JointCoordinate{joint}, q, nullptr).value;
}

MatX joint_coordinate_hessian(const Model& model, int joint, const VecX& q) {
  AssemblyOptions o;
  o.locks.push_back({joint, 0.0});
  o.use_limits = false;
  const std::vector<CoordinateRow> rows = coordinate_rows(model, q, o);
  MatX H = MatX::Zero(model.nq, model.nq);
  VecX u(model.n);
  add_coordinate_hessian(model, rows.front(), q, 1.0, H, u);
  return H;
}

std::vector<JointResidual> joint_residuals(const Model& model, const VecX& q) {
  VecX f(model.nc);
  compute_constraint_residual(model, q, f);
  std::vector<JointResidual> out;
  for (const Joint& j : model.joints) {
    JointResidual r;
    r.joint = j.name;
    const auto names = j.component_names();
    double gap2 = 0.0;
    for (int k = 0; k < j.rows(); ++k) {
      const double v = f(j.row_offset + k);
      r.rows.push_back(v);
      r.residual = std::max(r.residual, std::abs(v));
      if (!is_angular_row(names[static_cast<size_t>(k)])) gap2 += v * v;
    }
    r.gap = std::sqrt(gap2);
    out.push_back(std::move(r));
  }
  return out;
}

bool project_with_locks(const Model& model, VecX& q, const std::vector<JointLock>& locks,
                        double tolerance, int max_iterations) {
  AssemblyOptions o;
  o.locks = locks;
  o.use_limits = false;
  const std::vector<CoordinateRow> rows = coordinate_rows(model, q, o);
  VecX d(model.n);
  // The locks' rows: s_k(q) − value_k and ∇s_k.
  const ExtraRows lock_rows{static_cast<int>(rows.size()),
                            [&](const VecX& x, Eigen::Ref<VecX> g, Eigen::Ref<MatX> G) {
                              for (size_t k = 0; k < rows.size(); ++k) {
                                const auto i = static_cast<Eigen::Index>(k);
                                g(i) = eval_coordinate(model, rows[k], x, d) - rows[k].lo;
                                G.row(i) = d.transpose();
                              }
                            }};
  GaussNewtonOptions gn;
  gn.tolerance = tolerance;
  gn.max_iterations = max_iterations;
  gn.metric = GaussNewtonOptions::Metric::mass;  // mass-metric minimum-norm steps
  gn.descent = GaussNewtonOptions::Descent::backtrack;
  return gauss_newton_positions(model, q, lock_rows, gn).converged;
}

namespace {

// The kinetic energies of u₀, of α u₀ (v.u) and of β u₀ = u₀ − α u₀, with M x given as a function.
template <class MassTimes>
void projected_energies(const VecX& u0, VelocityProjection& v, const MassTimes& mass_times) {
  const VecX beta_u0 = u0 - v.u;  // β u₀ = (I − α) u₀
  v.kinetic_initial = 0.5 * u0.dot(mass_times(u0));
  v.kinetic = 0.5 * v.u.dot(mass_times(v.u));
  v.kinetic_removed = 0.5 * beta_u0.dot(mass_times(beta_u0));
}

// The same projection on the chart engine's sparse path, for a large model with a diagonal M
// (issue 18 item 2): Eᵀ on its pattern, the chart chosen and its block factorised sparse, F
// (n × n_a) column by column, H = Fᵀ M F; nothing of size n × n (the dense path's Workspace at
// N = 400 of the N-four-bar is 436 MB and its QR chart choice O(n³)). False when the model is not
// such a model (the dense path then answers); v.ok false when no chart is regular at q.
bool project_velocities_sparse(const Model& model, const VecX& q, int rank, const VecX& u0,
                               VelocityProjection& v) {
  if (model.n < ChartEngine::kSparseSelectFrom) return false;
  ChartEngine engine(model, rank, ChartFactorisation::sparse_when_large);
  if (!engine.sparse()) return false;
  FreeSystemWorkspace free(model, MassStorage::diagonal_if_possible);
  State s(model);
  s.q = q;
  s.u.setZero();
  compute_free_system(model, s, free);
  if (!free.diagonal_mass) return false;
  SparseEt Et(model);
  compute_constraint_jacobian(model, q, Et);
  v.ok = engine.select(Et, free.A_diag) && engine.factor(Et, free.A_sqrt) > 0.0;
  const auto mass_times = [&](const VecX& x) -> VecX { return free.M_diag.cwiseProduct(x); };
  if (v.ok) {
    MatX F = MatX::Zero(model.n, engine.na());
    VecX b(model.nc), x(model.n);
    engine.basis(Et, b, x, F);
    const MatX MF = free.M_diag.asDiagonal() * F;
    const MatX H = F.transpose() * MF;  // H = Fᵀ M F, as in compute_dual
    const Eigen::LLT<MatX> H_llt(H);
    v.ok = H_llt.info() == Eigen::Success;
    if (v.ok) v.u = F * project_velocity(MF, H_llt, u0);  // α u₀
  }
  if (!v.ok) v.u = VecX::Zero(model.n);
  projected_energies(u0, v, mass_times);
  return true;
}

}  // namespace

VelocityProjection project_velocities(const Model& model, const VecX& q, const VecX& u0) {
  VelocityProjection v;
  if (model.nc == 0) {  // no constraint: α = I, nothing removed (and no empty factorisation)
    MatX M(model.n, model.n);
    compute_mass_matrix(model, q, M);
    v.ok = true;
    v.u = u0;
    v.kinetic_initial = v.kinetic = 0.5 * u0.dot(M * u0);
    v.kinetic_removed = 0.0;
    return v;
  }
  // The dual form's projection (projection/dual.hpp) in a chart of the rank at q, so that
  // redundant constraints need no pseudo-inverse.
  const Mobility mob = compute_mobility(model, q);
  if (project_velocities_sparse(model, q, mob.rank, u0, v)) return v;
  Workspace ws(model, mob.rank);
  State s(model);
  s.q = q;
  s.u.setZero();
  compute_free_system(model, s, ws);
  compute_constraints(model, s, ws.constraints);
  auto& d = ws.dual;
  // F in a chart, then H = Fᵀ M F alone: compute_dual's other products (ψ, α, Θ) are not needed.
  v.ok = compute_basis(model, s, ws) == ProjectionStatus::ok;
  if (v.ok) {
    d.MF.noalias() = ws.free.M * d.F;
    d.H.noalias() = d.F.transpose() * d.MF;  // eq. (68)
    d.H_llt.compute(d.H);
    v.ok = d.H_llt.info() == Eigen::Success;
  }
  if (!v.ok)  // no regular chart at q (cannot happen at the rank of q): nothing admissible
    v.u = VecX::Zero(model.n);
  else
    v.u.noalias() = d.F * project_velocity(d.MF, d.H_llt, u0);  // α u₀
  const MatX& M = ws.free.M;
  projected_energies(u0, v, [&](const VecX& x) -> VecX { return M * x; });
  return v;
}

namespace {

// The guess already satisfies everything: returned bit for bit.
AssemblyResult unchanged_result(const Model& model, const VecX& q0, double residual,
                                const char* message) {
  AssemblyResult res;
  res.status = AssemblyStatus::unchanged;
  res.message = message;
  res.q = q0;
  res.residual = residual;
  res.bodies = body_moves(model, q0, q0);
  res.joints = joint_residuals(model, q0);
  return res;
}

// The rows of f that are independent at q (redundant ones would break Ipopt's constraint
// qualification), from the rank-revealing factorisation of compute_mobility.
std::vector<int> independent_rows(const Model& model, const VecX& q) {
  const Mobility mob = compute_mobility(model, q);
  std::vector<bool> redundant(static_cast<size_t>(model.nc), false);
  for (int r : mob.redundant_rows) redundant[static_cast<size_t>(r)] = true;
  std::vector<int> rows;
  for (int r = 0; r < model.nc; ++r)
    if (!redundant[static_cast<size_t>(r)]) rows.push_back(r);
  return rows;
}

// The joints that do not close at the least-squares pose q_ls, largest gap first, and their
// total gap.
void collect_gaps(const Model& model, const VecX& q_ls, double tol, AssemblyResult& res) {
  const double gap_tol = std::max(1e3 * tol, 1e-9);
  for (JointResidual& j : joint_residuals(model, q_ls))
    if (j.residual > gap_tol) res.gaps.push_back(std::move(j));
  std::sort(res.gaps.begin(), res.gaps.end(),
            [](const JointResidual& a, const JointResidual& b) { return a.gap > b.gap; });
  for (const JointResidual& j : res.gaps) res.total_gap += j.gap;
}

// The locks in words for messages: " with joint 'A0' locked at 30 deg", " with measure 'B_z'
// locked at 250 mm" (the file's units).
std::string locks_text(const Model& model, const std::vector<JointLock>& locks) {
  const UnitSystem file_units = unit_system(model.units);
  std::string out;
  for (size_t k = 0; k < locks.size(); ++k) {
    const JointLock& l = locks[k];
    const bool measure = l.measure >= 0;
    const std::string name = measure ? model.measures[static_cast<size_t>(l.measure)].name
                                     : model.joints[static_cast<size_t>(l.joint)].name;
    out += k == 0 ? " with " : k + 1 == locks.size() ? " and " : ", ";
    out += std::string(measure ? "measure '" : "joint '") + name + "' locked at " +
           format_input(l.value, lock_is_angle(model, l), file_units);
  }
  return out;
}

// The locked quantity at q: the joint's coordinate or the measure's position quantity.
double lock_value(const Model& model, const JointLock& l, const VecX& q) {
  if (l.measure < 0) return joint_coordinate(model, l.joint, q);
  return compute_scalar(model, model.measures[static_cast<size_t>(l.measure)].kind, q, nullptr)
      .value;
}

AssemblyResult assemble_spatial(const Model& model, const VecX& q0, const AssemblyOptions& options);

// The run's bounds over Ipopt's iterations (AssemblyOptions::control), through
// IpoptSettings::keep_going; the fraction of the run is the iterations' share of the budget.
class IpoptBounds {
 public:
  explicit IpoptBounds(const AssemblyOptions& options)
      : watch_(options.control), max_iterations_(std::max(1, options.max_iterations)) {}
  void attach(solvers::IpoptSettings& settings) {
    settings.keep_going = [this](int iteration) {
      return watch_.go_on(static_cast<double>(iteration) / max_iterations_);
    };
  }
  // The result of a projection a bound stopped: Ipopt's last iterate q, status stopped.
  [[nodiscard]] AssemblyResult stopped(const Model& model, const VecX& q0, const VecX& q,
                                       const std::vector<CoordinateRow>& coords, int iterations,
                                       const std::string& solver_status) const {
    AssemblyResult res;
    res.status = AssemblyStatus::stopped;
    res.stop = watch_.stop();
    res.solver_status = solver_status;
    res.iterations = iterations;
    res.q = q;
    VecX f(model.nc), d(model.n);
    res.residual = total_residual(model, q, coords, f, d);
    res.bodies = body_moves(model, q0, q);
    res.joints = joint_residuals(model, q);
    res.message = watch_.message() + " (Ipopt iteration " + std::to_string(iterations) + ")";
    return res;
  }

 private:
  RunWatch watch_;
  int max_iterations_;
};

AssemblyResult assemble_position(const Model& model, const VecX& q0,
                                 const AssemblyOptions& options) {
  if (model.nq != model.n) return assemble_spatial(model, q0, options);
  AssemblyResult res;
  const std::vector<CoordinateRow> coords = coordinate_rows(model, q0, options);
  VecX f(model.nc), d(model.n);
  const double tol = options.tolerance;

  // 1. Already assembled: return the guess bit-for-bit.
  const double r0 = total_residual(model, q0, coords, f, d);
  if (r0 <= tol)
    return unchanged_result(model, q0, r0,
                            "the design position already satisfies every joint, lock and limit");

  Problem p(model, q0);
  MatX M(model.n, model.n);
  compute_mass_matrix(model, q0, M);
  p.W = M / M.diagonal().maxCoeff();
  p.coords = coords;

  // 2. Independent rows of f (redundant ones would break Ipopt's constraint qualification) at
  //    a cheap Gauss–Newton projection of the guess (the rank is generic on the manifold).
  VecX q_start = q0;
  std::vector<JointLock> locks = options.locks;
  const bool gn = project_with_locks(model, q_start, locks, tol, 30);
  if (!gn) q_start = q0;
  p.f_rows = independent_rows(model, gn ? q_start : q0);

  // 3. Ipopt on (A1), then Newton polish (L3).
  solvers::IpoptSettings settings;
  settings.max_iter = options.max_iterations;
  settings.constr_viol_tol = std::max(tol, 1e-14);
  IpoptBounds bounds(options);
  bounds.attach(settings);
  const solvers::IpoptOutcome out = solvers::solve_with_ipopt(p.nlp(q_start), settings);
  if (out.error) std::rethrow_exception(out.error);  // a bug in a callback: after the solve
  res.solver_status = out.status;
  res.iterations = out.iterations;
  VecX q = out.x.size() == model.nq && out.x.allFinite() ? out.x : q_start;
  if (out.kind == solvers::IpoptOutcomeKind::stopped)
    return bounds.stopped(model, q0, q, coords, out.iterations, out.status);
  const bool ipopt_ok = out.kind == solvers::IpoptOutcomeKind::solved ||
                        out.kind == solvers::IpoptOutcomeKind::acceptable ||
                        out.kind == solvers::IpoptOutcomeKind::not_converged;
  int polish_steps = 0;
  if (ipopt_ok || total_residual(model, q, coords, f, d) < 1e-6) polish_steps = polish(p, q, tol);
  res.iterations += polish_steps;
  res.residual = total_residual(model, q, coords, f, d);
  if (res.residual <= tol) {
    res.status = AssemblyStatus::assembled;
    res.q = q;
    const VecX dq = q - q0;
    res.distance = std::sqrt(std::max(0.0, dq.dot(M * dq)));
    res.bodies = body_moves(model, q0, q);
    res.joints = joint_residuals(model, q);
    std::ostringstream msg;
    msg << "projected onto the constraints: Ipopt " << out.status << " in " << out.iterations
        << " iterations, then " << polish_steps << " Newton steps on the KKT system";
    res.message = msg.str();
    return res;
  }

  // 4. No feasible pose: the best least-squares pose (A2) says which joints cannot close.
  res.q = q;
  res.bodies = body_moves(model, q0, q);
  res.joints = joint_residuals(model, q);
  p.least_squares = true;
  const solvers::IpoptOutcome ls = solvers::solve_with_ipopt(p.nlp(q_start), settings);
  if (ls.error) std::rethrow_exception(ls.error);
  if (ls.kind == solvers::IpoptOutcomeKind::stopped)
    return bounds.stopped(model, q0, q, coords, res.iterations + ls.iterations, ls.status);
  res.q_least_squares = ls.x.size() == model.nq && ls.x.allFinite() ? ls.x : q;
  collect_gaps(model, res.q_least_squares, tol, res);
  std::ostringstream msg;
  msg.precision(4);
  if (res.gaps.empty()) {
    res.status = out.kind == solvers::IpoptOutcomeKind::failed ||
                         out.kind == solvers::IpoptOutcomeKind::invalid_number ||
                         out.kind == solvers::IpoptOutcomeKind::too_few_dof
                     ? AssemblyStatus::failed
                     : AssemblyStatus::not_converged;
    msg << "no assembled position found (" << out.status << "; residual " << res.residual
        << "), although a least-squares pose closes every joint";
  } else {
    res.status = AssemblyStatus::cannot_close;
    // Report the best least-squares pose, not Ipopt's last infeasible iterate.
    res.q = res.q_least_squares;
    res.residual = total_residual(model, res.q, coords, f, d);
    res.bodies = body_moves(model, q0, res.q);
    res.joints = joint_residuals(model, res.q);
    // In the file's declared units (a model built in code: SI).
    const UnitSystem file_units = unit_system(model.units);
    msg << "the mechanism cannot close" << locks_text(model, options.locks);
    msg << ": at the best least-squares pose";
    for (size_t k = 0; k < res.gaps.size(); ++k) {
      msg << (k ? "," : "") << " joint '" << res.gaps[k].joint << "' ";
      if (res.gaps[k].gap > 0.0)
        msg << "gap " << format_quantity(res.gaps[k].gap, Dimension::length, file_units);
      else
        msg << "residual " << format_quantity(res.gaps[k].residual, Dimension::angle, file_units);
    }
    msg << "; total gap " << format_quantity(res.total_gap, Dimension::length, file_units)
        << " (loop through";
    for (size_t k = 0; k < res.gaps.size(); ++k) msg << (k ? ", " : " ") << res.gaps[k].joint;
    msg << ")";
  }
  res.message = msg.str();
  return res;
}

// A length scale of a spatial mechanism (m): the largest joint-point offset from a body's centre
// of mass or from the world origin (ground points); 1 when there is none.
double spatial_length_scale(const Model& model) {
  double L = 0.0;
  for (const Joint& j : model.joints)
    if (const auto* s = std::get_if<SpatialJoint>(&j.kind))
      L = std::max({L, s->pi.s.norm(), s->pj.s.norm()});
  return L > 0.0 ? L : 1.0;
}

}  // namespace

// The start of the spatial (A1) with locks, on the branch of the guess: the guess closed without
// the locks (mass-metric Gauss–Newton, q ⊕ Δu), then each locked coordinate moved from its value
// there to the lock (an angle the short way round, (L4)) in equal steps of at most 2° or 2 % of
// the length scale, each predicted along the previous one (q_k ⊕ (q_k ⊖ q_{k−1})) and corrected
// by the same Gauss–Newton with the locks at the step's values. Small steps keep the guess's
// assembly mode and the joints' drawn branches (docs/spatial.md §2.4), as `cycle` follows them; a
// projection straight onto the locks may land on another mode. Empty when a step does not
// converge (a dead point of the locked coordinate on the way, or a lock out of reach).
std::optional<VecX> follow_locks(const Model& model, const VecX& q_guess,
                                 const std::vector<JointLock>& locks, double tol,
                                 const LockContinuation& how) {
  VecX q = q_guess;
  if (!project_with_locks(model, q, {}, tol, 60)) return std::nullopt;
  const double L = how.length_scale > 0.0 ? how.length_scale : spatial_length_scale(model);
  constexpr double kAngleStep = std::numbers::pi / 90.0;  // 2°
  std::vector<double> from, to;
  double steps = 1.0;
  for (const JointLock& l : locks) {
    const bool angle = lock_is_angle(model, l);
    const double s = lock_value(model, l, q);
    // A joint angle the short way round; a measure's value as it is.
    const double target =
        angle && l.measure < 0 ? s + std::remainder(l.value - s, kTwoPi) : l.value;
    from.push_back(s);
    to.push_back(target);
    steps = std::max(steps, std::ceil(std::abs(target - s) / (angle ? kAngleStep : 0.02 * L)));
  }
  const int n = static_cast<int>(std::min(steps, 1000.0));
  std::vector<JointLock> at = locks;
  VecX q_prev = q, dq(model.n);
  for (int k = 1; k <= n; ++k) {
    for (size_t i = 0; i < locks.size(); ++i)
      at[i].value = from[i] + (to[i] - from[i]) * static_cast<double>(k) / n;
    const VecX q_last = q;
    if (how.secant && k > 1) {  // secant predictor
      difference_positions(model, q, q_prev, dq);
      integrate_positions(model, q, dq, 1.0);
    }
    if (!project_with_locks(model, q, at, tol, 60)) return std::nullopt;
    q_prev = q_last;
  }
  return q;
}

namespace {

// Feasibility to the rounding level after Ipopt (optimality is Ipopt's): the mass-metric
// Gauss–Newton in velocity space, Δu = −A Cᵀ (C A Cᵀ)⁺ c, q ← q ⊕ Δu (docs/spatial.md §6.3), on the
// rows Ipopt kept — the independent rows of f, the locks, the limits active at q (held at their
// nearer bound). The row set is fixed: off the manifold the redundant rows of an overconstrained
// mechanism regain rank, and re-ranking them with a lock row made the step singular on the
// Bennett linkage. Returns the steps taken.
int polish_spatial(const Model& model, VecX& q, const std::vector<int>& f_rows,
                   const std::vector<CoordinateRow>& coords, double tol) {
  std::vector<const CoordinateRow*> held;
  VecX f(model.nc), d(model.n);
  for (const CoordinateRow& c : coords) {
    const double s = eval_coordinate(model, c, q, d);
    const double band = std::max(1e-8, 1e3 * tol);
    if (c.lock || s - c.lo < band || c.hi - s < band) held.push_back(&c);
  }
  // The held rows: a lock at its value, a limit at its nearer bound.
  const ExtraRows held_rows{static_cast<int>(held.size()),
                            [&](const VecX& x, Eigen::Ref<VecX> g, Eigen::Ref<MatX> G) {
                              for (size_t k = 0; k < held.size(); ++k) {
                                const CoordinateRow& h = *held[k];
                                const auto i = static_cast<Eigen::Index>(k);
                                const double s = eval_coordinate(model, h, x, d);
                                g(i) = s - (h.lock || s - h.lo < h.hi - s ? h.lo : h.hi);
                                G.row(i) = d.transpose();
                              }
                            }};
  GaussNewtonOptions gn;
  gn.tolerance = tol;
  gn.max_iterations = 10;
  gn.metric = GaussNewtonOptions::Metric::mass;
  gn.descent = GaussNewtonOptions::Descent::monotone;
  gn.f_rows = f_rows;
  gn.residual = [&](const VecX& x) { return total_residual(model, x, coords, f, d); };
  return gauss_newton_positions(model, q, held_rows, gn).steps;
}

// (A1) for spatial models in local coordinates (LocalProblem), from the guess closed and moved to
// the locks on its branch (follow_locks), then the fixed-row Gauss–Newton (polish_spatial) to
// the rounding level; (A2) in the same coordinates, locks and limits kept, when no pose closes.
AssemblyResult assemble_spatial(const Model& model, const VecX& q0_in,
                                const AssemblyOptions& options) {
  AssemblyResult res;
  VecX q0 = q0_in;
  normalize_coordinates(model, q0);
  VecX f(model.nc), d(model.n);
  const double tol = options.tolerance;
  const std::vector<CoordinateRow> coords = coordinate_rows(model, q0, options);
  const double r0 = total_residual(model, q0, coords, f, d);
  if (r0 <= tol)
    return unchanged_result(model, q0, r0,
                            coords.empty()
                                ? "the design position already satisfies every joint"
                                : "the design position already satisfies every joint, lock and "
                                  "limit");
  LocalProblem p(model, q0);
  MatX M(model.n, model.n);
  compute_mass_matrix(model, q0, M);
  p.W = M / M.diagonal().maxCoeff();
  p.coords = coords;
  // The start: the guess closed and moved to the locks on its branch; else projected straight
  // onto them; else the guess. The independent rows of f there (the rank is generic on the
  // manifold; redundant rows would break Ipopt's constraint qualification).
  VecX q_start = q0;
  bool on_manifold = false;
  if (const std::optional<VecX> followed = follow_locks(model, q0, options.locks, tol)) {
    q_start = *followed;
    on_manifold = true;
  } else {
    on_manifold = project_with_locks(model, q_start, options.locks, tol, 200);
    if (!on_manifold) q_start = q0;
  }
  p.f_rows = independent_rows(model, q_start);
  VecX x_start(model.n);
  difference_positions(model, q_start, q0, x_start);
  solvers::IpoptSettings settings;
  settings.max_iter = options.max_iterations;
  settings.constr_viol_tol = std::max(tol, 1e-14);
  IpoptBounds bounds(options);
  bounds.attach(settings);
  const solvers::IpoptOutcome out = solvers::solve_with_ipopt(p.nlp(x_start), settings);
  if (out.error) std::rethrow_exception(out.error);
  res.solver_status = out.status;
  res.iterations = out.iterations;
  const VecX x = out.x.size() == model.n && out.x.allFinite() ? out.x : x_start;
  VecX q = p.at(x);
  if (out.kind == solvers::IpoptOutcomeKind::stopped)
    return bounds.stopped(model, q0, q, coords, out.iterations, out.status);
  const int polished = polish_spatial(model, q, p.f_rows, coords, tol);
  res.iterations += polished;
  res.residual = total_residual(model, q, coords, f, d);
  if (res.residual <= tol) {
    res.status = AssemblyStatus::assembled;
    res.q = q;
    VecX dx(model.n);
    difference_positions(model, q, q0, dx);
    res.distance = std::sqrt(std::max(0.0, dx.dot(M * dx)));
    res.bodies = body_moves(model, q0, q);
    res.joints = joint_residuals(model, q);
    std::ostringstream msg;
    msg << "projected onto the constraints";
    if (!options.locks.empty())
      msg << " (from the design pose moved to the locks on its branch"
          << (on_manifold ? "" : ": not reached, from the design pose") << ")";
    msg << ": Ipopt " << out.status << " in " << out.iterations
        << " iterations (local coordinates, limited-memory Hessian), then " << polished
        << " Gauss–Newton steps";
    res.message = msg.str();
    return res;
  }
  // No feasible pose: the least-squares pose (locks and limits kept) says which joints cannot
  // close.
  p.least_squares = true;
  const solvers::IpoptOutcome ls = solvers::solve_with_ipopt(p.nlp(x_start), settings);
  if (ls.error) std::rethrow_exception(ls.error);
  if (ls.kind == solvers::IpoptOutcomeKind::stopped)
    return bounds.stopped(model, q0, q, coords, res.iterations + ls.iterations, ls.status);
  res.q_least_squares = p.at(ls.x.size() == model.n && ls.x.allFinite() ? ls.x : x);
  collect_gaps(model, res.q_least_squares, tol, res);
  res.q = res.gaps.empty() ? q : res.q_least_squares;
  res.residual = total_residual(model, res.q, coords, f, d);
  res.bodies = body_moves(model, q0, res.q);
  res.joints = joint_residuals(model, res.q);
  std::ostringstream msg;
  if (res.gaps.empty()) {
    res.status = AssemblyStatus::not_converged;
    msg << "no assembled position found" << locks_text(model, options.locks) << " (" << out.status
        << "; residual " << res.residual << "), although a least-squares pose closes every joint";
  } else {
    res.status = AssemblyStatus::cannot_close;
    const UnitSystem file_units = unit_system(model.units);
    msg << "the mechanism cannot close" << locks_text(model, options.locks)
        << ": at the best least-squares pose";
    for (size_t k = 0; k < res.gaps.size(); ++k) {
      msg << (k ? "," : "") << " joint '" << res.gaps[k].joint << "' ";
      if (res.gaps[k].gap > 0.0)
        msg << "gap " << format_quantity(res.gaps[k].gap, Dimension::length, file_units);
      else
        msg << "residual " << res.gaps[k].residual;
    }
    msg << "; total gap " << format_quantity(res.total_gap, Dimension::length, file_units);
  }
  res.message = msg.str();
  return res;
}

}  // namespace

AssemblyResult assemble(const Model& model, const VecX& q0, const AssemblyOptions& options_in) {
  check_argument(q0.size() == model.nq, "assemble", "q0", "must have model.nq coordinates");
  // A lock on a joint measure is a lock on its joint.
  AssemblyOptions options = options_in;
  for (JointLock& l : options.locks)
    if (l.measure >= 0)
      if (const auto* jc = std::get_if<JointCoordinate>(
              &model.measures.at(static_cast<size_t>(l.measure)).kind)) {
        l.joint = jc->joint;
        l.measure = -1;
      }
  AssemblyResult res = assemble_position(model, q0, options);
  const ResidualSplit split = split_residual(model, res.q, coordinate_rows(model, q0, options));
  res.residual_length = split.length;
  res.residual_angle = split.angle;
  return res;
}

ResidualSplit split_residual(const Model& model, const VecX& q, const AssemblyOptions& options) {
  return split_residual(model, q, coordinate_rows(model, q, options));
}

ResidualSplit split_residual(const Model& model, const VecX& q) {
  AssemblyOptions f_alone;
  f_alone.use_limits = false;
  return split_residual(model, q, f_alone);
}

}  // namespace orthomech
