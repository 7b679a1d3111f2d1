#include "orthomech/analysis/cycle.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <numbers>
#include <stdexcept>

#include "orthomech/analysis/assembly.hpp"
#include "orthomech/analysis/mobility.hpp"
#include "orthomech/analysis/positions.hpp"
#include "orthomech/check.hpp"
#include "orthomech/constraints/constraint_system.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/constraints/rolling_disc.hpp"
#include "orthomech/constraints/sparse_et.hpp"
#include "orthomech/constraints/spatial_joints.hpp"
#include "orthomech/io/units.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/model/loads.hpp"
#include "orthomech/model/measures.hpp"
#include "orthomech/numerics/small_lu.hpp"
#include "orthomech/numerics/sparse_lu.hpp"
#include "orthomech/projection/dual.hpp"
#include "orthomech/projection/free_system_stage.hpp"
#include "orthomech/projection/primal.hpp"

namespace orthomech {

namespace {

// Size of the mechanism (the largest distance of a body's design position from the origin, at
// least 1 mm): the scale of lengths for step control and start moves.
double mechanism_size(const Model& model) {
  double size = 1e-3;
  for (const Body& b : model.bodies)
    size = std::max(size, b.kind == BodyKind::spatial ? b.spatial.design_position.norm()
                                                      : b.design_pose.head<2>().norm());
  return size;
}

}  // namespace

const char* to_string(CycleStatus s) {
  switch (s) {
    case CycleStatus::completed:
      return "completed";
    case CycleStatus::stopped_at_dead_point:
      return "stopped at a dead point";
    case CycleStatus::failed:
      return "failed";
    case CycleStatus::invalid_request:
      return "invalid request";
    case CycleStatus::stopped:
      return "stopped";
  }
  return "?";
}

// The Eᵀ and corrector of a large model (issue 18: nothing of size n_c · n or n × n).
// - Eᵀ evaluated on its pattern only: the chart (compute_basis), the multipliers and the
//   corrector read it there, and the cycle's Workspace holds no dense Eᵀ or Dᵀ
//   (WorkspaceStages::constraint_matrices; at N = 1000 of the N-four-bar they took 576 MB, and
//   zeroing the N = 400 one's dense Eᵀ, 46 MB, at every evaluation had been 30 % of its cycle).
// - Its Jacobian in compressed form: the rows A = [E_Rᵀ; dᵀ; I] (all rows of Eᵀ with redundant
//   rows), J = A or the normal matrix AᵀA, and J's LU by KLU (a fresh analysis per
//   factorisation: the corrector factorises only where its chord steps fail, a few times per
//   sweep).
struct DrivenWorkspace::SparseJacobian {
  explicit SparseJacobian(const Model& model) : Et(model) {}
  SparseEt Et;
  std::vector<Eigen::Triplet<double>> entries;
  Eigen::SparseMatrix<double> A, J;
  VecX b;  // A's right-hand side (normal equations)
  SparseLu lu;
};

namespace {
[[nodiscard]] bool uses_sparse_jacobian(const Model& model, int from) {
  return model.n >= from && constraint_system(model).structurally_sparse();
}
}  // namespace

DrivenWorkspace::DrivenWorkspace(DrivenWorkspace&&) noexcept = default;
DrivenWorkspace& DrivenWorkspace::operator=(DrivenWorkspace&&) noexcept = default;
DrivenWorkspace::~DrivenWorkspace() = default;

DrivenWorkspace::DrivenWorkspace(const Model& model, int rank, std::vector<int> idle,
                                 int sparse_jacobian_from)
    : d(VecX::Zero(model.n)),
      Fdot_v(VecX::Zero(model.n)),
      R(VecX::Zero(model.n)),
      N(MatX::Zero(model.nc, model.nc - rank)),
      NtN(model.nc - rank, model.nc - rank),
      NtN_llt(model.nc - rank),
      small(model.nc - rank),
      rhs_r(rank),
      other_rows(static_cast<size_t>(model.nc - rank)),
      J_sparse(uses_sparse_jacobian(model, sparse_jacobian_from)
                   ? std::make_unique<SparseJacobian>(model)
                   : nullptr),
      g(model.n),
      dq(model.n),
      rotations(model),
      idle_bodies(std::move(idle)),
      length_scale(mechanism_size(model)),
      friction(friction_pins(model)) {
  if (!friction.empty()) {
    R_inertia.resize(model.n);
    Q_friction.resize(model.n);
    lambda_previous.resize(model.nc);
  }
  if (!J_sparse) {
    J.resize(model.n, model.n);
    J_piv.resize(model.n);
  }
}

// ---- stored positions -----------------------------------------------------------------------
void DrivenPoints::unwrap_measure(std::size_t i) {
  const std::size_t at =
      static_cast<std::size_t>(n_tangent_ + n_q_ + 2 * n_u_ + n_lambda_) + n_reactions_ + i;
  for (std::size_t k = 1; k < size(); ++k) {
    const double before = values_[(k - 1) * stride_ + at];
    double& value = values_[k * stride_ + at];
    value = before + std::remainder(value - before, 2.0 * std::numbers::pi);
  }
}

DrivenPointView DrivenPoints::operator[](std::size_t k) const {
  const Scalars& s = scalars_[k];
  const double* v = values_.data() + k * stride_;
  const double* tangent = v;
  const double* q = tangent + n_tangent_;
  const double* u = q + n_q_;
  const double* udot = u + n_u_;
  const double* lambda = udot + n_u_;
  const double* reactions = lambda + n_lambda_;
  const double* measures = reactions + n_reactions_;
  return DrivenPointView{s.input,
                         s.time,
                         s.input_rate,
                         s.input_acceleration,
                         Eigen::Map<const VecX>(tangent, n_tangent_),
                         s.drive,
                         s.drive_frictionless,
                         s.friction_iterations,
                         s.chart_quality,
                         s.chart_sign,
                         s.chart_id,
                         s.dTF,
                         Eigen::Map<const VecX>(q, n_q_),
                         Eigen::Map<const VecX>(u, n_u_),
                         Eigen::Map<const VecX>(udot, n_u_),
                         Eigen::Map<const VecX>(lambda, n_lambda_),
                         std::span<const double>(reactions, n_reactions_),
                         std::span<const double>(measures, n_measures_),
                         s.kinetic,
                         s.potential,
                         s.dissipated,
                         s.idle_hold,
                         s.singular,
                         s.bridge};
}

void DrivenPoints::reserve(std::size_t count) {
  scalars_.reserve(count);
  if (stride_ > 0) values_.reserve(count * stride_);
}

DrivenPoints::Scalars DrivenPoints::scalars_of(const DrivenPoint& p) const {
  return {p.input,
          p.time,
          p.input_rate,
          p.input_acceleration,
          p.drive,
          p.drive_frictionless,
          p.chart_quality,
          p.dTF,
          p.kinetic,
          p.potential,
          p.dissipated,
          p.idle_hold,
          p.chart_id,
          p.chart_sign,
          p.friction_iterations,
          p.singular,
          p.bridge};
}

void DrivenPoints::check_sizes(const DrivenPoint& p) const {
  if (p.tangent.size() != n_tangent_ || p.q.size() != n_q_ || p.u.size() != n_u_ ||
      p.udot.size() != n_u_ || p.lambda.size() != n_lambda_ || p.reactions.size() != n_reactions_ ||
      p.measures.size() != n_measures_)
    throw std::logic_error("DrivenPoints: a position with other vector sizes");
}

void DrivenPoints::put_values(const DrivenPoint& p, double* v) const {
  auto put = [&v](const double* from, std::size_t count) {
    std::copy(from, from + count, v);
    v += count;
  };
  put(p.tangent.data(), static_cast<std::size_t>(n_tangent_));
  put(p.q.data(), static_cast<std::size_t>(n_q_));
  put(p.u.data(), static_cast<std::size_t>(n_u_));
  put(p.udot.data(), static_cast<std::size_t>(n_u_));
  put(p.lambda.data(), static_cast<std::size_t>(n_lambda_));
  put(p.reactions.data(), n_reactions_);
  put(p.measures.data(), n_measures_);
}

void DrivenPoints::push_back(const DrivenPoint& p) {
  if (scalars_.empty() && values_.empty()) {  // the first position fixes the sizes
    n_tangent_ = p.tangent.size(), n_q_ = p.q.size(), n_u_ = p.u.size();
    n_lambda_ = p.lambda.size(), n_reactions_ = p.reactions.size();
    n_measures_ = p.measures.size();
    stride_ = static_cast<std::size_t>(n_tangent_ + n_q_ + 2 * n_u_ + n_lambda_) + n_reactions_ +
              n_measures_;
    values_.reserve(std::max<std::size_t>(1, scalars_.capacity()) * stride_);
  }
  check_sizes(p);
  scalars_.push_back(scalars_of(p));
  const std::size_t at = values_.size();
  values_.resize(at + stride_);  // within the reserved block (amortised growth beyond it)
  put_values(p, values_.data() + at);
}

void DrivenPoints::assign(std::size_t k, const DrivenPoint& p) {
  check_sizes(p);
  scalars_.at(k) = scalars_of(p);
  put_values(p, values_.data() + k * stride_);
}

namespace {

// R = M u̇ + Ṁu − Q̂ (the free system at the state of u), (C3)–(C4). Allocation-free.
void inertia_residual(const Workspace& ws, const VecX& u, const VecX& udot, VecX& R) {
  if (ws.free.diagonal_mass)
    R = ws.free.M_diag.cwiseProduct(udot);
  else
    R.noalias() = ws.free.M * udot;
  if (!ws.free.constant_mass) R.noalias() += ws.free.Mdot * u;
  R -= ws.free.Q;
}

// Minimum-norm λ with E λ = R and the null space N of E (redundancy directions) (C4). R is in
// the range of E by (C3) (FᵀR = 0), so the chart's square block gives a particular solution λ_p
// on the chart's rows R (zero on the others): E_{D,R} λ_R = R_D with the chart's LU.
void solve_multipliers(Workspace& ws, DrivenWorkspace& w, VecX& lambda) {
  const Chart& c = ws.dual.engine.chart();
  const int r = c.rank();
  const int k = static_cast<int>(w.other_rows.size());
  solve_chart_transposed(ws, w.R, w.rhs_r);
  lambda.setZero();
  for (int i = 0; i < r; ++i) lambda(c.rows[static_cast<size_t>(i)]) = w.rhs_r(i);
  if (k == 0) return;
  // Complement rows X; column j of N: 1 on row x_j, −(E_{D,R})⁻¹ E_{D,x_j} on the chart's rows.
  int next = 0;
  for (int row = 0, ci = 0; row < ws.model->nc; ++row) {
    if (ci < r && c.rows[static_cast<size_t>(ci)] == row) {
      ++ci;
      continue;
    }
    w.other_rows[static_cast<size_t>(next++)] = row;
  }
  for (int j = 0; j < k; ++j) {
    const int row = w.other_rows[static_cast<size_t>(j)];
    if (w.sparse_jacobian()) {  // Eᵀ on its pattern
      const SparseEt& S = w.J_sparse->Et;
      const auto cols = S.row_columns(row);
      const auto vals = S.row_values(row);
      w.g.setZero();
      for (size_t t = 0; t < cols.size(); ++t) w.g(cols[t]) = vals[t];
    } else {
      w.g = ws.constraints.Et.row(row).transpose();
    }
    solve_chart_transposed(ws, w.g, w.rhs_r);
    w.N.col(j).setZero();
    for (int i = 0; i < r; ++i) w.N(c.rows[static_cast<size_t>(i)], j) = -w.rhs_r(i);
    w.N(w.other_rows[static_cast<size_t>(j)], j) = 1.0;
  }
  // λ_min = λ_p − N (NᵀN)⁻¹ Nᵀ λ_p: the solution orthogonal to null(E).
  w.NtN.noalias() = w.N.transpose() * w.N;
  w.NtN_llt.compute(w.NtN);
  w.small.noalias() = w.N.transpose() * lambda;
  w.NtN_llt.solveInPlace(w.small);
  lambda.noalias() -= w.N * w.small;
}

// The idle motions held (docs/spatial.md §6.5): the idle rows I and motions V at q, I F, and the
// held basis F z with (I F) z = 0, |z| = 1 (z's largest component positive). False when F does not
// have 1 + k columns (k idle motions) or I F has not rank k.
bool hold_idle(const Model& model, const VecX& q, const MatX& F, DrivenWorkspace& w) {
  w.idle_I = idle_rows(model, q, w.idle_bodies, &w.idle_V);
  const Eigen::Index k = w.idle_I.rows();
  if (k == 0 || F.cols() != k + 1) return false;
  w.idle_IF.noalias() = w.idle_I * F;
  const Eigen::JacobiSVD<MatX> svd(w.idle_IF, Eigen::ComputeFullV);
  if (!(svd.singularValues()(k - 1) > 1e-10 * F.norm())) return false;
  w.F_held.noalias() = F * svd.matrixV().col(k);
  Eigen::Index big = 0;
  (void)svd.matrixV().col(k).cwiseAbs().maxCoeff(&big);
  if (svd.matrixV()(big, k) < 0.0) w.F_held = -w.F_held;
  return true;
}

// İ u of the idle rows at (q, u) (they depend on q) (I1). Any basis of their span holds the
// same motions; Ĩ(q′) = I₀ P(q′), with I₀ = I(q) and P(q′) the orthogonal projector onto the span
// of I(q′), is one that is smooth in q′ whatever basis idle_rows picks there and equals I₀ at q.
// Differentiating P(q) u = 0 along the motion: I₀ u̇ = −I₀ Ṗ u (I₀ P = I₀), so İ u = I₀ Ṗ u, by
// central differences along the motion, at q ⊕ (±h u + ½h² a) with Eᵀa = −Dᵀu (a particular
// acceleration: the two positions are on f(q) = 0 to O(h³), so the rank decisions of idle_rows
// there are those at q), h turning a body by 1e-4 rad or moving it by 1e-4 of the mechanism's
// size. The rows themselves carry rounding of ~1e-12 (the kernel of a block scaled by √A), so
// İ u is good to ~1e-8 of |u|²: truncation (1e-8) and rounding (1e-12/1e-4) balance there.
// Errors in İ u change u̇ only along the idle motions (and μ), never the drive or λ: M times an
// idle motion is a multiple of an idle row, which F z and the multipliers do not see.
bool idle_rows_rate(const Model& model, const VecX& q, const VecX& u, const VecX& a,
                    DrivenWorkspace& w) {
  const Eigen::Index k = w.idle_I.rows();
  w.idle_Idot_u = VecX::Zero(k);
  double speed = 0.0;
  for (const Body& b : model.bodies) {
    const int nt = b.translations();
    speed = std::max(speed, u.segment(b.u_offset, nt).cwiseAbs().maxCoeff() / w.length_scale);
    for (int c = nt; c < b.nu(); ++c) speed = std::max(speed, std::abs(u(b.u_offset + c)));
  }
  if (!(speed > 0.0)) return true;  // at rest: İ u = 0
  const double h = 1e-4 / speed;
  VecX qh(model.nq);
  for (const double sign : {1.0, -1.0}) {
    qh = q;
    integrate_positions(model, qh, sign * h * u + 0.5 * h * h * a, 1.0);
    const MatX I = idle_rows(model, qh, w.idle_bodies);
    if (I.rows() != k) return false;
    const VecX Pu = I.transpose() * (I * I.transpose()).ldlt().solve(I * u);
    w.idle_Idot_u += sign * (w.idle_I * Pu);
  }
  w.idle_Idot_u /= 2.0 * h;  // (I1)
  return true;
}

// Eᵀ at q: a large model's on its pattern (dws.J_sparse), a small one's into ws.constraints.Et.
void write_constraint_jacobian(const Model& model, const VecX& q, Workspace& ws,
                               DrivenWorkspace& dws) {
  if (dws.sparse_jacobian())
    compute_constraint_jacobian(model, q, dws.J_sparse->Et);
  else
    compute_constraint_jacobian(model, q, ws.constraints.Et);
}

// The chart and F (compute_basis) at the Eᵀ write_constraint_jacobian left.
ProjectionStatus basis_at_jacobian(const Model& model, const State& state, Workspace& ws,
                                   const DrivenWorkspace& dws) {
  return dws.sparse_jacobian() ? compute_basis(model, state, ws, dws.J_sparse->Et)
                               : compute_basis(model, state, ws);
}

// (C3)–(C4) from dws.R = M u̇ + Ṁu − Q̂ (− Q_f): the drive τ = Fᵀ R / (Fᵀd), the forces holding
// the idle motions, and the minimum-norm multipliers of E λ = R − d τ.
void drive_and_multipliers(Workspace& ws, DrivenWorkspace& dws, const Eigen::Ref<const VecX>& F,
                           double dTF, bool idle, DrivenPoint& out) {
  out.drive = F.dot(dws.R) / dTF;
  // (C4) reactions: E λ = M u̇ + Ṁu − Q̂ − d τ.
  dws.R -= out.drive * dws.d;
  out.idle_hold = 0.0;
  if (idle) {  // − Iᵀ μ, the forces holding the idle motions: (I F)ᵀ μ = Fᵀ(R − d τ)
    dws.idle_mu = (dws.idle_IF * dws.idle_IF.transpose())
                      .ldlt()
                      .solve(dws.idle_IF * (ws.dual.F.transpose() * dws.R));
    dws.R.noalias() -= dws.idle_I.transpose() * dws.idle_mu;
    // Their work per unit rate of each idle motion (V: unit angular rate).
    const VecX work = dws.idle_V.transpose() * (dws.idle_I.transpose() * dws.idle_mu);
    for (Eigen::Index j = 0; j < work.size(); ++j)
      if (std::abs(work(j)) > std::abs(out.idle_hold)) out.idle_hold = work(j);
  }
  solve_multipliers(ws, dws, out.lambda);
}

// The joints' friction (analysis/friction.hpp): E λ + d τ = M u̇ + Ṁu − Q̂ − Q_f(λ, u) by
// fixed-point iteration from the frictionless λ in out. The iterations taken, −1 when λ still
// moved by more than kFrictionTolerance of its size after kFrictionIterations.
int add_friction(const State& state, Workspace& ws, DrivenWorkspace& dws,
                 const Eigen::Ref<const VecX>& F, double dTF, bool idle, DrivenPoint& out) {
  for (int it = 1; it <= kFrictionIterations; ++it) {
    dws.lambda_previous = out.lambda;
    dws.Q_friction.setZero();
    add_friction_forces(dws.friction, state.u, out.lambda, dws.Q_friction);
    dws.R = dws.R_inertia - dws.Q_friction;
    drive_and_multipliers(ws, dws, F, dTF, idle, out);
    const double size = out.lambda.cwiseAbs().maxCoeff();
    if ((out.lambda - dws.lambda_previous).cwiseAbs().maxCoeff() <= kFrictionTolerance * size)
      return it;
  }
  return -1;
}

}  // namespace

bool compute_driven(const Model& model, int driver_joint, double sdot, double sddot, State& state,
                    Workspace& ws, DrivenWorkspace& dws, DrivenPoint& out,
                    DrivenJacobian jacobian) {
  check_argument(driver_joint >= 0 && static_cast<size_t>(driver_joint) < model.joints.size(),
                 "compute_driven", "driver_joint", "is not a joint of the model");
  check_argument(state.q.size() == model.nq && state.u.size() == model.n, "compute_driven", "state",
                 "must have model.nq coordinates and model.n velocities");
  check_argument(ws.model == &model, "compute_driven", "ws", "was built for another Model");
  check_argument(dws.rotations.table().size() == model.bodies.size(), "compute_driven", "dws",
                 "was built for another Model");
  const MeasureKind input = JointCoordinate{driver_joint};
  // Positions: the chart and F at q (F depends on q only). The chart's scaling A comes from the
  // free system; with a constant mass matrix it is computed once.
  if (!ws.free.mass_ready || !ws.free.constant_mass) {
    state.u.setZero();
    compute_free_system(model, state, ws);
  }
  if (jacobian == DrivenJacobian::evaluate) {
    write_constraint_jacobian(model, state.q, ws, dws);
    dws.rotations.update(model, state.q);
  }
  if (jacobian != DrivenJacobian::current_with_gradient)
    (void)compute_scalar(model, input, state.q, nullptr, dws.d);  // d: the input's gradient
  if (basis_at_jacobian(model, state, ws, dws) != ProjectionStatus::ok) return false;
  // With idle degrees of freedom, the basis that holds them: F z, I F z = 0 (docs/spatial.md §6.5).
  const bool idle = !dws.idle_bodies.empty();
  if (idle && !hold_idle(model, state.q, ws.dual.F, dws)) return false;
  const Eigen::Ref<const VecX> F =
      idle ? Eigen::Ref<const VecX>(dws.F_held) : Eigen::Ref<const VecX>(ws.dual.F.col(0));
  const double dTF = dws.d.dot(F);
  const double scale = dws.d.norm() * F.norm();
  out.dTF = scale > 0.0 ? dTF / scale : 0.0;
  if (!(std::abs(out.dTF) > 1e-12)) return false;  // dead point: the driver cannot drive
  out.tangent = F / dTF;                           // dq/ds along the branch
  // (C1) velocities.
  const double v = sdot / dTF;
  state.u.noalias() = F * v;
  // Rate terms at (q, u): Dᵀu, Q̂(q, u), Ṁ, ḋu.
  compute_constraint_rate(model, state, dws.rotations, ws.constraints);
  compute_free_system(model, state, ws);
  const ScalarKinematics sk = compute_scalar(model, input, state.q, &state.u, dws.d);
  out.input = sk.value;
  solve_chart(ws, ws.constraints.Dtu, dws.Fdot_v);  // x_D = (E_RDᵀ)⁻¹ (Dᵀu)_R
  dws.Fdot_v = -dws.Fdot_v;                         // Eᵀ (Ḟ v) = −Dᵀ u
  if (idle) {  // and I (Ḟ v) = −İ u: add F y with (I F) y = −İ u − I (Ḟ v), y the least-norm one
    if (!idle_rows_rate(model, state.q, state.u, dws.Fdot_v, dws)) return false;
    const VecX rhs = -dws.idle_Idot_u - dws.idle_I * dws.Fdot_v;
    dws.Fdot_v.noalias() += ws.dual.F * (dws.idle_IF.transpose() *
                                         (dws.idle_IF * dws.idle_IF.transpose()).ldlt().solve(rhs));
  }
  // (C2) accelerations.
  const double vdot = (sddot - sk.ddot_u - dws.d.dot(dws.Fdot_v)) / dTF;
  out.udot = F * vdot + dws.Fdot_v;
  // (C3) drive: Fᵀ(M u̇ + Ṁu − Q̂) = (Fᵀd) τ.
  inertia_residual(ws, state.u, out.udot, dws.R);
  out.lambda.resize(model.nc);
  if (dws.friction.empty()) {
    drive_and_multipliers(ws, dws, F, dTF, idle, out);
    out.drive_frictionless = out.drive;
  } else {
    dws.R_inertia = dws.R;
    drive_and_multipliers(ws, dws, F, dTF, idle, out);
    out.drive_frictionless = out.drive;
    out.friction_iterations = add_friction(state, ws, dws, F, dTF, idle, out);
  }
  out.q = state.q;
  out.u = state.u;
  out.input_rate = sdot;
  out.input_acceleration = sddot;
  return true;
}

void compute_driven_outputs(const Model& model, const State& state, const VecX& lambda,
                            const VecX& udot, const BodyPoses& rotations, DrivenOutputs out) {
  compute_reactions(model, state.q, rotations, lambda, out.reactions);
  out.measures.clear();
  for (const Measure& m : model.measures)
    out.measures.push_back(evaluate_measure(model, m, state.q, &state.u, &udot, rotations));
  out.kinetic = kinetic_energy(model, state);
  out.potential = potential_energy(model, state.q);
  out.dissipated = dissipated_power(model, state);
}

bool compute_multi_driven(const Model& model, const std::vector<int>& joints, const VecX& sdot,
                          const VecX& sddot, State& state, Workspace& ws, DrivenWorkspace& dws,
                          MultiDrivenPoint& out) {
  const Eigen::Index m = static_cast<Eigen::Index>(joints.size());
  out.conditioning = 0.0;
  state.u.setZero();
  compute_free_system(model, state, ws);
  write_constraint_jacobian(model, state.q, ws, dws);
  if (basis_at_jacobian(model, state, ws, dws) != ProjectionStatus::ok) return false;
  const MatX& F = ws.dual.F;
  if (F.cols() != m) return false;
  MatX Ds(m, model.n);
  VecX row(model.n);
  for (Eigen::Index i = 0; i < m; ++i) {
    (void)compute_scalar(model, JointCoordinate{joints[static_cast<size_t>(i)]}, state.q, nullptr,
                         row);
    Ds.row(i) = row.transpose();
  }
  const MatX G = Ds * F;
  const Eigen::JacobiSVD<MatX> svd(G);
  const VecX& sv = svd.singularValues();
  out.conditioning = sv.size() && sv(0) > 0.0 ? sv(sv.size() - 1) / sv(0) : 0.0;
  if (!(out.conditioning > 1e-12)) return false;  // the drivers cannot move the mechanism here
  const Eigen::PartialPivLU<MatX> lu(G);
  // (C1) velocities.
  state.u.noalias() = F * lu.solve(sdot);
  // Rate terms at (q, u).
  compute_constraint_rate(model, state, ws.constraints);
  compute_free_system(model, state, ws);
  VecX ddot_u(m);
  for (Eigen::Index i = 0; i < m; ++i)
    ddot_u(i) = compute_scalar(model, JointCoordinate{joints[static_cast<size_t>(i)]}, state.q,
                               &state.u, row)
                    .ddot_u;
  solve_chart(ws, ws.constraints.Dtu, dws.Fdot_v);  // x_D = (E_RDᵀ)⁻¹ (Dᵀu)_R
  dws.Fdot_v = -dws.Fdot_v;                         // Eᵀ w = −Dᵀ u
  // (C2) accelerations.
  const VecX vdot = lu.solve(sddot - ddot_u - Ds * dws.Fdot_v);
  out.udot = F * vdot + dws.Fdot_v;
  // (C3) the drivers' forces: Fᵀ R = Gᵀ τ.
  inertia_residual(ws, state.u, out.udot, dws.R);
  out.drives = G.transpose().partialPivLu().solve(F.transpose() * dws.R);
  // (C4) reactions: E λ = R − D_sᵀ τ.
  dws.R.noalias() -= Ds.transpose() * out.drives;
  out.lambda.resize(model.nc);
  solve_multipliers(ws, dws, out.lambda);
  out.q = state.q;
  out.u = state.u;
  out.input_rates = sdot;
  out.input_accelerations = sddot;
  return true;
}

namespace {

// The driver's input as a function of time, s(t), ṡ(t), s̈(t). A constant-speed law can be
// re-anchored (reversed at a dead point): s = s_ref + ω (t − t_ref).
struct InputLaw {
  Profile profile = Profile::constant_speed;
  double s_ref = 0.0, t_ref = 0.0, omega = 0.0;  // constant speed
  double initial = 0.0, amplitude = 0.0, frequency = 0.0;
  const std::vector<double>* coefficients = nullptr;

  void at(double t, double& s, double& sdot, double& sddot) const {
    switch (profile) {
      case Profile::constant_speed:
        s = s_ref + omega * (t - t_ref), sdot = omega, sddot = 0.0;
        return;
      case Profile::harmonic: {
        const double w = 2.0 * std::numbers::pi * frequency;
        s = initial + amplitude * std::sin(w * t);
        sdot = amplitude * w * std::cos(w * t);
        sddot = -amplitude * w * w * std::sin(w * t);
        return;
      }
      case Profile::polynomial: {
        s = sdot = sddot = 0.0;
        const auto& c = *coefficients;
        for (size_t k = c.size(); k-- > 0;) {  // Horner for s, ṡ, s̈
          sddot = sddot * t + 2.0 * sdot;
          sdot = sdot * t + s;
          s = s * t + c[k];
        }
        return;
      }
    }
  }
};

// The law of the driver's input (anchored at s_ref = 0, t_ref = 0).
InputLaw input_law(const Driver& driver) {
  InputLaw law;
  law.profile = driver.profile;
  law.omega = driver.speed;
  law.initial = driver.initial;
  law.amplitude = driver.amplitude;
  law.frequency = driver.frequency;
  law.coefficients = &driver.coefficients;
  return law;
}

// max |v_i| (NaN if an entry is NaN): the corrector's tolerances and step bounds. A plain loop:
// Eigen's vectorised cwiseAbs().maxCoeff() took 81 instructions per call at n = 9 (callgrind),
// 5 calls per position of the sweep.
double max_abs(const VecX& v) {
  double m = 0.0;
  for (Eigen::Index i = 0; i < v.size(); ++i) {
    const double a = std::abs(v(i));
    if (!(a <= m)) {
      if (std::isnan(a)) return a;
      m = a;
    }
  }
  return m;
}

// `value` unwrapped to the turn of `near` (a spatial joint angle is read in (−π, π]).
double unwrap_near(double value, double near) {
  return near + std::remainder(value - near, 2.0 * std::numbers::pi);
}

}  // namespace

void driver_law(const Driver& driver, double s0, double t, double& s, double& sdot, double& sddot) {
  InputLaw law = input_law(driver);
  law.s_ref = s0;
  law.at(t, s, sdot, sddot);
}

namespace {

struct Sweep {
  const Model& model;
  int joint;
  Workspace& ws;
  DrivenWorkspace& w;
  // What the corrector's last evaluation left at the q it returned, for compute_driven: nothing
  // (`evaluate`), Eᵀ and the rotation table (`current`), and also the input's gradient in w.d
  // (`current_with_gradient`).
  DrivenJacobian at_q = DrivenJacobian::evaluate;
  long factorisations = 0;  // of the corrector's own Jacobian (chord steps use the chart's)
  VecX offset = VecX::Zero(model.n);  // q − q_ref for the linear lock
  MatX idle_at = MatX(0, 0);          // idle rows at the corrector's first iterate
  // The input's coordinate at q, on the turn of `near` where it is read modulo 2π.
  [[nodiscard]] double input_at(const VecX& q, double near) const {
    return on_turn(compute_scalar(model, JointCoordinate{joint}, q, nullptr).value, near);
  }
  // A value of the input's coordinate as the joint reads it, on the turn of `near`.
  [[nodiscard]] double on_turn(double value, double near) const {
    return joint_coordinate_wraps(model.joints[static_cast<size_t>(joint)])
               ? unwrap_near(value, near)
               : value;
  }

  // One iterate of the locked-input corrector: f, Eᵀ (and the rotation table) at q in one pass —
  // at the converged q they are then ready for compute_driven — and the lock's value s: the input
  // (its gradient into w.d) or, with `row`, rowᵀ(q − q_ref). Returns max(|s − target|, max |f|).
  // `jacobian` false: f without Eᵀ (a chord's first iterate, the predictor's: unless the predictor
  // is already exact it is not the last one, and only the last one's Eᵀ is used).
  double evaluate_iterate(const VecX& q, double target, double& s, const VecX* row = nullptr,
                          const VecX* q_ref = nullptr, bool jacobian = true) {
    w.rotations.update(model, q);
    if (jacobian && w.sparse_jacobian()) {
      DrivenWorkspace::SparseJacobian& S = *w.J_sparse;
      compute_constraint_residual_and_jacobian(model, q, w.rotations, ws.constraints.f, S.Et);
    } else if (jacobian)
      compute_constraint_residual_and_jacobian(model, q, w.rotations, ws.constraints.f,
                                               ws.constraints.Et);
    else
      compute_constraint_residual(model, q, w.rotations, ws.constraints.f);
    at_q = !jacobian ? DrivenJacobian::evaluate
           : row     ? DrivenJacobian::current
                     : DrivenJacobian::current_with_gradient;
    if (row) {
      difference_positions(model, q, *q_ref, offset);
      s = row->dot(offset);
    } else {
      s = compute_scalar(model, JointCoordinate{joint}, q, nullptr, w.d).value;
      if (joint_coordinate_wraps(model.joints[static_cast<size_t>(joint)]))
        s = unwrap_near(s, target);
    }
    const double f_max = max_abs(ws.constraints.f);  // NaN stays NaN (never converged)
    return std::isnan(f_max) ? f_max : std::max(std::abs(s - target), f_max);
  }
  // The corrector's tolerance: a few ulps of the coordinates (next to a singular position a
  // residual of 1e-12 still leaves q 1e-10 off the branch along the nearly singular direction).
  [[nodiscard]] static bool converged(double residual, const VecX& q) {
    return residual < 1e-14 * (1.0 + max_abs(q));
  }

  // The corrector's first steps: chord steps with the chart's factorisation where compute_driven
  // left it (the previous position) and that position's tangent τ (E_Rᵀ τ = 0, dᵀτ = 1 there).
  // The step solving [E_Rᵀ; dᵀ] Δq = [f_R; s − target] with E_R from there is
  // x + τ (s − target − dᵀx)/(dᵀτ), x = (E_RDᵀ)⁻¹ f_R on D (x_I = 0): one chart solve, no
  // factorisation. Convergence is judged on every row of f at the iterate, as in `corrector`.
  // Returns 1: converged (f, Eᵀ, the rotation table and d at the returned q); −1: q not finite
  // (fails as in `corrector`); 0: the residual did not fall tenfold in an iteration, a step would
  // be longer than max_step (not taken), or dᵀτ is far from 1 (the previous position is not a
  // good model here) — q is the last iterate and `corrector` goes on from it with its own
  // factorisation.
  int chord(VecX& q, double target, double max_step, const VecX& tau) {
    double previous = std::numeric_limits<double>::infinity();
    for (int it = 0; it < 4; ++it) {
      double s = 0.0;
      const double res = evaluate_iterate(q, target, s, nullptr, nullptr, it > 0);
      if (converged(res, q)) return 1;
      if (!(res <= 0.1 * previous)) return 0;
      previous = res;
      ws.dual.engine.solve(ws.constraints.f, w.dq);
      const double dtau = w.d.dot(tau);  // 1 at the previous position
      if (!(std::abs(dtau - 1.0) < 0.5)) return 0;
      w.dq += ((s - target - w.d.dot(w.dq)) / dtau) * tau;
      if (!(max_abs(w.dq) <= max_step)) return 0;
      integrate_positions(model, q, w.dq, -1.0);
      at_q = DrivenJacobian::evaluate;
      if (!q.allFinite()) return -1;
    }
    return 0;
  }

  // Newton on [f_R(q); s(q) − target] = 0 with Jacobian [E_Rᵀ; dᵀ] (the input locked), or, when
  // `row` is given, on [f_R(q); rowᵀ(q − q_ref) − target] (a linear lock, for the pseudo-arclength
  // step across a dead point). A step longer than max_step (a jump towards another branch or
  // another turn of an angle) fails. Idle degrees of freedom (w.idle_bodies): rows I of their
  // motions, taken at the first iterate, with zero right-hand side (the steps do not move along
  // them; docs/spatial.md §6.5). With `tau` (the previous position's tangent, the chart factorised
  // there) the chord steps above come first; the Jacobian is factorised here only when they do
  // not converge (CycleResult::corrector_factorisations counts those).
  bool corrector(VecX& q, double target, double max_step, const VecX* row = nullptr,
                 const VecX* q_ref = nullptr, const VecX* tau = nullptr) {
    if (tau && !row && w.idle_bodies.empty() && ws.dual.engine.ready()) {
      const int c = chord(q, target, max_step, *tau);
      if (c != 0) return c > 0;
    }
    const Chart& c = ws.dual.engine.chart();
    const int r = c.rank();
    const int nc = model.nc;
    // With redundant rows, Gauss–Newton on all of them: next to a change point the chart's rows
    // alone do not imply the others, and q could leave the mechanism by 1e-7 while f_R = 0.
    const bool all_rows = nc > r;
    const Eigen::Index k = static_cast<Eigen::Index>(w.idle_bodies.size()) > 0
                               ? (idle_at = idle_rows(model, q, w.idle_bodies)).rows()
                               : 0;
    if (!all_rows && r + 1 + k != model.n) return false;
    // Chord Newton: the Jacobian is factored at the first iterate and kept while the residual
    // falls at least tenfold per iteration (the predictor is close: usually one factorisation).
    bool factored = false;
    double previous = std::numeric_limits<double>::infinity();
    for (int it = 0; it < 30; ++it) {
      double s = 0.0;
      const double res = evaluate_iterate(q, target, s, row, q_ref);
      if (converged(res, q)) return true;
      const VecX& lock = row ? *row : w.d;
      if (!factored || res > 0.1 * previous) {
        ++factorisations;
        const double ratio = w.sparse_jacobian() ? factor_sparse(all_rows, c, lock, k)
                                                 : factor_dense(all_rows, c, lock, k);
        if (!(ratio > (all_rows ? 1e-26 : 1e-13))) return false;
        factored = true;
      }
      previous = res;
      newton_step(all_rows, c, lock, s - target, k);
      if (!(max_abs(w.dq) <= max_step)) return false;
      integrate_positions(model, q, w.dq, -1.0);
      at_q = DrivenJacobian::evaluate;
      if (!q.allFinite()) return false;
    }
    return false;
  }

  // The corrector's Jacobian [E_Rᵀ; lockᵀ; I] (k idle rows), or with redundant rows the normal
  // matrix of [Eᵀ; lockᵀ; I], factorised densely in w.J. Returns the LU's pivot ratio.
  double factor_dense(bool all_rows, const Chart& c, const VecX& lock, Eigen::Index k) {
    const int r = c.rank();
    if (all_rows) {
      w.J.noalias() = ws.constraints.Et.transpose() * ws.constraints.Et;
      w.J.noalias() += lock * lock.transpose();
      if (k > 0) w.J.noalias() += idle_at.transpose() * idle_at;
    } else {
      for (int i = 0; i < r; ++i)
        w.J.row(i) = ws.constraints.Et.row(c.rows[static_cast<size_t>(i)]);
      w.J.row(r) = lock.transpose();
      if (k > 0) w.J.bottomRows(k) = idle_at;
    }
    return lu_factor(w.J, w.J_piv);
  }

  // The same in compressed form, factorised by KLU (large models: w.sparse_jacobian()), from Eᵀ
  // on its pattern (the iterate's, evaluated by evaluate_iterate).
  double factor_sparse(bool all_rows, const Chart& c, const VecX& lock, Eigen::Index k) {
    DrivenWorkspace::SparseJacobian& S = *w.J_sparse;
    const int r = c.rank();
    const int m = all_rows ? model.nc : r;  // rows of A taken from Eᵀ
    S.entries.clear();
    for (int i = 0; i < m; ++i) {
      const int row = all_rows ? i : c.rows[static_cast<size_t>(i)];
      const auto cols = S.Et.row_columns(row);
      const auto vals = S.Et.row_values(row);
      for (size_t t = 0; t < cols.size(); ++t) S.entries.emplace_back(i, cols[t], vals[t]);
    }
    for (Eigen::Index j = 0; j < model.n; ++j) {
      if (lock(j) != 0.0) S.entries.emplace_back(m, static_cast<int>(j), lock(j));
      for (Eigen::Index i = 0; i < k; ++i)
        if (idle_at(i, j) != 0.0)
          S.entries.emplace_back(m + 1 + static_cast<int>(i), static_cast<int>(j), idle_at(i, j));
    }
    S.A.resize(m + 1 + k, model.n);
    S.A.setFromTriplets(S.entries.begin(), S.entries.end());
    if (all_rows)
      S.J = S.A.transpose() * S.A;
    else
      S.J = S.A;
    S.J.makeCompressed();
    if (!S.lu.analyze(S.J) || !S.lu.factorize(S.J)) return 0.0;
    return S.lu.pivot_ratio();
  }

  // The Newton step into w.dq: J Δq = [f_R; s − target; 0] (or the normal equations' right-hand
  // side [Eᵀ; lockᵀ; I]ᵀ [f; s − target; 0]), solved with the factorisation above.
  void newton_step(bool all_rows, const Chart& c, const VecX& lock, double lock_residual,
                   Eigen::Index k) {
    DrivenWorkspace::SparseJacobian* S = w.J_sparse.get();
    if (all_rows && S) {
      S->b.setZero(S->A.rows());
      S->b.head(model.nc) = ws.constraints.f;
      S->b(model.nc) = lock_residual;
      w.dq.noalias() = S->A.transpose() * S->b;
    } else if (all_rows) {
      w.dq.noalias() = ws.constraints.Et.transpose() * ws.constraints.f;
      w.dq += lock_residual * lock;
    } else {
      const int r = c.rank();
      for (int i = 0; i < r; ++i) w.dq(i) = ws.constraints.f(c.rows[static_cast<size_t>(i)]);
      w.dq(r) = lock_residual;
      w.dq.tail(k).setZero();  // the idle rows
    }
    if (S)
      S->lu.solve_in_place(w.dq.data());
    else
      lu_solve(w.J, w.J_piv, w.dq);
  }
};

// Predicted q at input s from a converged point p: q + τ Δs + ½ q'' Δs², with q'' = d²q/ds² =
// (u̇ − τ s̈)/ṡ². The curvature term is used only where it is smaller than the tangent step (next
// to a singular position u̇ is unreliable) and where ṡ ≠ 0.

// Indices of the measures that read a spatial joint angle (modulo 2π): unwrapped by continuity
// over the sweep.
std::vector<size_t> wrapped_measures(const Model& model) {
  std::vector<size_t> out;
  for (size_t i = 0; i < model.measures.size(); ++i) {
    const Measure& m = model.measures[i];
    if (m.derivative != 0) continue;
    if (const auto* c = std::get_if<JointCoordinate>(&m.kind))
      if (joint_coordinate_wraps(model.joints[static_cast<size_t>(c->joint)])) out.push_back(i);
  }
  return out;
}

void unwrap_measures(CycleResult& result, const std::vector<size_t>& wrapped) {
  for (const size_t i : wrapped) result.points.unwrap_measure(i);
}

// The step is taken in velocity space and applied through integrate_positions (q ⊕ step).
void predict(const Model& model, const DrivenPoint& p, double s, VecX& step, VecX& q) {
  const double ds = s - p.input;
  step = ds * p.tangent;
  if (std::abs(p.input_rate) > 0.0) {
    const double first = std::abs(ds) * p.tangent.cwiseAbs().maxCoeff();
    const double c = 0.5 * ds * ds / (p.input_rate * p.input_rate);
    const double second = c * (p.udot - p.input_acceleration * p.tangent).cwiseAbs().maxCoeff();
    if (second <= first) step += c * (p.udot - p.input_acceleration * p.tangent);
  }
  q = p.q;
  integrate_positions(model, q, step, 1.0);
}

// ---- run_cycle, step by step ----------------------------------------------------------------
// run_cycle: the request checked (request_error), the start assembled (assemble_start) and its
// mobility read (record_mobility); then a CycleRun reaches the requested start along the branch,
// sets the time grid, sweeps it by continuation (predictor + locked-input corrector, change
// points passed, dead points stopped at or reversed), bridges the change points and finishes the
// result. Each position's kinetostatics are compute_driven's.

// Points next to a change point (E loses rank): every chart of E is ill-conditioned there and
// the multipliers, which grow without bound, are not meaningful.
constexpr double kSingularQuality = 1e-4;
// Scale of each coordinate for step-length control: lengths by the mechanism's size, angles by
// 1 rad. One internal step may move no coordinate by more than kMaxMove of its scale (5.7°, a
// tenth of the size); longer grid steps are split into sub-steps that are not output.
constexpr double kMaxMove = 0.1;

// What the request fixes before any position is known: the driver joint, the law of its input
// (not yet anchored at the start), and the units in which messages quote inputs.
struct CycleRequest {
  int joint;
  const std::string& joint_name;
  bool angular;
  UnitSystem file_units;  // the file's declared units (a model built in code: SI)
  InputLaw law;
  bool constant;  // a constant-speed driver
};

CycleRequest make_request(const Model& model, const CycleOptions& options) {
  const int joint = options.driver.joint;
  const Joint& j = model.joints[static_cast<size_t>(joint)];
  return {joint,
          j.name,
          joint_coordinate_kind(j) == CoordinateKind::angle,
          unit_system(model.units),
          input_law(options.driver),
          options.driver.profile == Profile::constant_speed};
}

// A result with the reaction components and the constraint rows named, each determinate until
// a redundancy shows otherwise.
CycleResult named_result(const Model& model) {
  CycleResult result;
  result.components = reaction_components(model);
  result.determinate.assign(result.components.size(), true);
  result.row_determinate.assign(static_cast<size_t>(model.nc), true);
  for (int r = 0; r < model.nc; ++r) result.row_names.push_back(model.constraint_row_name(r));
  return result;
}

// Why the options give no cycle (nullptr when they do): a law without one, a start, end or
// reversal the law cannot take, a mechanism whose positions do not follow from the input.
const char* request_error(const Model& model, const CycleOptions& options, bool angular) {
  const Driver& driver = options.driver;
  const bool constant = driver.profile == Profile::constant_speed;
  if (constant && !(std::abs(driver.speed) > 0.0)) return "the driver's speed must not be zero";
  if (driver.profile == Profile::harmonic &&
      !(driver.frequency > 0.0 && std::abs(driver.amplitude) > 0.0))
    return "a harmonic driver needs a non-zero amplitude and a positive frequency";
  if (driver.profile == Profile::polynomial)
    return "a polynomial driver has no cycle to sweep; give a constant speed (--speed)";
  if (!constant && (!options.full_cycle || options.use_start))
    return "a start or an end input (--from, --to) needs a constant-speed driver: give --speed "
           "too";
  if (!model.knife_edges.empty() || !model.rolling_discs.empty())
    return "the mechanism has nonholonomic constraints (knife edges, rolling discs): its positions "
           "do not follow from the input alone, so it has no driven cycle; use simulate";
  if (options.reverse_at_dead_point && !constant)
    return "reversing at a dead point needs a constant-speed driver: give --speed too";
  if (constant && options.full_cycle && !angular)
    return "a prismatic driver has no full turn: give the end of the input range (--to)";
  return nullptr;
}

// Bodies moved from their drawn pose by more than the tolerances to close the joints: listed in
// result.start_moves and warned about.
void warn_start_moves(const Model& model, const CycleRequest& request, const VecX& q,
                      const VecX& drawn, CycleResult& result) {
  const double size = mechanism_size(model);
  VecX moved(model.n);
  difference_positions(model, q, drawn, moved);
  for (const Body& b : model.bodies) {
    // Translation and rotation of the body (u-space: planar x, y, φ; spatial v, ω).
    const double distance = moved.segment(b.u_offset, b.translations()).norm();
    const double angle = moved.segment(b.u_offset + b.translations(), b.rotations()).norm();
    if (distance <= kStartMoveTolerance * size && angle <= kStartTurnTolerance) continue;
    result.start_moves.push_back({b.name, distance, angle});
    result.warnings.push_back("the design position does not close as drawn: body '" + b.name +
                              "' moved by " + format_input(distance, false, request.file_units) +
                              " and " + format_input(angle, true, request.file_units) +
                              " to close the joints");
  }
}

// The drawn position closed onto f(q) = 0, `hold` kept (none: every coordinate free): by the
// mass-metric Gauss–Newton of project_positions, and where that fails by `assemble`'s own
// projection (Ipopt, eq. (20)), so that the cycle starts wherever `assemble` would say the
// mechanism assembles (one criterion for both commands). Joint limits are not imposed (the sweep
// reports where a joint leaves them). False, with assemble's account of the gaps in `why`, when
// neither closes it.
bool close_drawn_position(const Model& model, const VecX& drawn, const PositionOptions& hold,
                          VecX& q, std::string& why) {
  q = drawn;
  if (project_positions(model, q, hold).status == SolveStatus::converged) return true;
  AssemblyOptions ao;
  ao.use_limits = false;
  if (hold.locked_joint >= 0) ao.locks.push_back({hold.locked_joint, hold.locked_value});
  const AssemblyResult a = assemble(model, drawn, ao);
  if (a.status == AssemblyStatus::assembled || a.status == AssemblyStatus::unchanged) {
    q = a.q;
    return true;
  }
  q = a.q;  // the best least-squares pose when it cannot close (AssemblyResult::q)
  why = a.message;
  return false;
}

// Start: the design position closed with the driven joint held at its drawn value (as
// `assemble --lock`); only where it cannot be held (a dead point of the driver, or the joints
// close only with the driver moved) is it closed freely (close_drawn_position). Bodies moved by
// more than the tolerances are listed and warned about. False (the message set) when it does not
// assemble.
bool assemble_start(const Model& model, const CycleRequest& request, State& state,
                    CycleResult& result) {
  const int joint = request.joint;
  const UnitSystem& units = request.file_units;
  const VecX drawn = model.design_q();
  PositionOptions hold;
  hold.locked_joint = joint;
  hold.locked_value = compute_scalar(model, JointCoordinate{joint}, drawn, nullptr).value;
  std::string why;
  bool closed = close_drawn_position(model, drawn, hold, state.q, why);
  if (!closed) {
    closed = close_drawn_position(model, drawn, PositionOptions{}, state.q, why);
    if (closed)
      result.warnings.push_back(
          "the design position closes only with driver joint '" + request.joint_name +
          "' moved from its drawn " + format_input(hold.locked_value, request.angular, units) +
          " to " +
          format_input(compute_scalar(model, JointCoordinate{joint}, state.q, nullptr).value,
                       request.angular, units));
  }
  if (!closed) {
    const ResidualSplit left = split_residual(model, state.q);
    result.message = "the design position does not assemble (residual " +
                     format_quantity(left.length, Dimension::length, units) + ", " +
                     format_quantity(left.angle, Dimension::angle, units) + ")" +
                     (why.empty() ? "" : ": " + why);
    return false;
  }
  warn_start_moves(model, request, state.q, drawn, result);
  return true;
}

// The start's mobility into the result. Idle degrees of freedom (a coupler's spin between two
// spherical joints) are held at zero rate: the driver moves the others. False (the message set)
// unless exactly one is left to drive.
bool record_mobility(const Model& model, const Mobility& mob, CycleResult& result) {
  result.rank = mob.rank;
  result.dof = mob.dof;
  result.redundant = model.nc - mob.rank;
  result.idle = mob.idle;
  int idle_dof = 0;
  for (const Mobility::Idle& i : mob.idle) idle_dof += i.count;
  if (mob.dof - idle_dof == 1) return true;
  const int driven = mob.dof - idle_dof;
  std::string& m = result.message;
  m = "a single driver needs a mechanism with 1 DOF; this one has ";
  m.append(std::to_string(mob.dof));
  if (idle_dof > 0) {
    m.append(" (").append(std::to_string(idle_dof)).append(" idle, held at zero rate: ");
    m.append(std::to_string(driven)).append(" to drive)");
  }
  if (driven > 1) m.append(" (drive every degree of freedom: cycle --drivers A,B,…)");
  return false;
}

// The scale of each velocity component for kMaxMove (the tangent is dq/ds in u-space, planar
// x, y, φ; spatial v, ω): the mechanism's size for lengths, 1 rad for angles.
VecX step_scale(const Model& model) {
  VecX scale = VecX::Constant(model.n, mechanism_size(model));
  for (const Body& b : model.bodies)
    scale.segment(b.u_offset + b.translations(), b.rotations()).setConstant(1.0);
  return scale;
}

// A converged step keeps the branch when the tangent dq/ds keeps its direction (a jump across
// a fold reverses it).
bool same_branch(const VecX& a, const VecX& b) { return a.dot(b) > 0.0; }

// Holding an idle motion at zero rate takes no force when the motion is idle dynamically too
// (the body's spin about the line of its joints with its centre of mass on it and its inertia
// symmetric about it). Otherwise the reactions are those of the motion held, not free: warned.
void warn_idle_hold(CycleResult& result, const UnitSystem& units) {
  double drive_peak = 0.0;
  for (const DrivenPointView& p : result.points) {
    result.idle_hold_peak = std::max(result.idle_hold_peak, std::abs(p.idle_hold));
    drive_peak = std::max(drive_peak, std::abs(p.drive));
  }
  if (!(result.idle_hold_peak > 1e-8 * drive_peak)) return;
  std::string bodies;
  for (const Mobility::Idle& i : result.idle)
    bodies += (bodies.empty() ? "'" : ", '") + i.body + "'";
  result.warnings.push_back(
      "holding the idle motion of " + bodies + " at zero rate takes up to " +
      format_quantity(result.idle_hold_peak, Dimension::moment, units) +
      " (a torque about the motion's axis): it is not idle dynamically (a centre of mass off "
      "the line of its joints, or an inertia not symmetric about it); the reactions are those "
      "with it held");
}

class ChangePointBridger;

// One sweep of the driven cycle from an assembled start with one degree of freedom to drive:
// the former locals of run_cycle as members, its phases as the public methods (in the order
// run_cycle calls them), the continuation's steps as the private ones. Work buffers are sized
// in the constructor and set_time_grid; the steps allocate nothing but the stored positions.
class CycleRun {
 public:
  CycleRun(const Model& model, const CycleOptions& options, const CycleRequest& request,
           State start, const Mobility& mob, CycleResult& result);
  CycleRun(const CycleRun&) = delete;
  CycleRun& operator=(const CycleRun&) = delete;
  CycleRun(CycleRun&&) = delete;
  CycleRun& operator=(CycleRun&&) = delete;
  ~CycleRun() = default;

  [[nodiscard]] bool reach_start();
  [[nodiscard]] bool set_time_grid();
  [[nodiscard]] bool start_sweep();
  void sweep();
  void bridge_change_points();
  void finish();

 private:
  friend class ChangePointBridger;
  enum class Jump { failed, passed, output };

  [[nodiscard]] double start_input() const;
  [[nodiscard]] double move_size(const VecX& tangent, double ds) const {
    return (tangent.cwiseAbs().cwiseQuotient(scale_)).maxCoeff() * std::abs(ds);
  }
  bool evaluate_at(const VecX& q, double t, DrivenPoint& p,
                   DrivenJacobian jacobian = DrivenJacobian::evaluate);
  bool try_step(const DrivenPoint& from, double t, DrivenPoint& out);
  void update_determinacy(const DrivenPoint& p);
  void record_singular(double s_at, double t_at);
  bool closed_after_reversal(double t);
  bool stopped_by_control(double fraction);
  bool reach_grid_time(double t, double& h);
  void locate_sign_change(const DrivenPoint& from);
  Jump jump_change_point(double t);
  bool pass_dead_point(double t, double h, long& k);
  DrivenPoint bisect_dead_point(double t, double h);
  bool pass_fold(const DrivenPoint& at_lo, double s_dead, VecX& q_cur);
  bool reverse_input(const DrivenPoint& at_lo, double s_dead, const VecX& q_cur,
                     const std::string& msg, long& k);
  void stop_at_dead_point(double s_dead, double t_dead, const std::string& msg);

  const Model& model_;
  const CycleOptions& options_;
  const CycleRequest& request_;
  CycleResult& result_;
  InputLaw law_;  // anchored at the start by set_time_grid, re-anchored at each reversal
  State state_;
  Workspace ws_;
  DrivenWorkspace w_;
  Sweep sweep_;
  double s0_ = 0.0;     // the start's input
  VecX start_tangent_;  // set when the start was reached along the branch
  // The time grid (set_time_grid).
  int steps_ = 0, last_index_ = 0, max_positions_ = 0;
  RunMonitor
      monitor_;  // CycleOptions::control over the sweep (its positions: no budget of its own)
  double period_ = 0.0, dt_ = 0.0, omega0_ = 0.0;
  // The sweep's work buffers (set_time_grid).
  VecX scale_;                   // of each velocity component, for kMaxMove
  VecX trial_;                   // predictor/corrector iterate, reused across positions
  std::vector<size_t> wrapped_;  // measures read modulo 2π (wrapped_measures)
  VecX du_;                      // the predictor's step in velocity space
  DrivenPoint anchor_;           // the last converged point: the predictor starts from it
  VecX good_tangent_;            // of the last regular point: used next to a change point
  DrivenPoint probe_, sub_, check_;
  std::vector<double> null_values_;
  int reversals_ = 0;
};

CycleRun::CycleRun(const Model& model, const CycleOptions& options, const CycleRequest& request,
                   State start, const Mobility& mob, CycleResult& result)
    : model_(model),
      options_(options),
      request_(request),
      result_(result),
      law_(request.law),
      state_(std::move(start)),
      ws_(model, mob.rank, ChartFactorisation::rated_sparse_when_large,
          {.mass = MassStorage::diagonal_if_possible,
           .primal = false,
           .dual_projections = false,
           .constraint_matrices = !uses_sparse_jacobian(model, options.sparse_jacobian_from)}),
      w_(model, mob.rank, idle_body_indices(model, mob), options.sparse_jacobian_from),
      sweep_{model, request.joint, ws_, w_},
      monitor_(options.control, 0) {
  // The free system, f, Eᵀ and the chart with F at the start (the stages the cycle uses).
  compute_free_system(model_, state_, ws_);
  compute_constraint_residual(model_, state_.q, ws_.constraints.f);
  write_constraint_jacobian(model_, state_.q, ws_, w_);
  (void)basis_at_jacobian(model_, state_, ws_, w_);
  s0_ = compute_scalar(model_, JointCoordinate{request_.joint}, state_.q, nullptr).value;
}

// The input the sweep starts from: the design position's, the law's at t = 0, or the requested
// one. For a full turn that is the input the full cycle has there, X' = s₀ + σ ((σ(X − s₀)) mod
// 2π) with σ the direction of the drive (so X' may differ from X by whole turns).
double CycleRun::start_input() const {
  double start_target = s0_;
  if (!request_.constant) {
    double sd = 0.0, sdd = 0.0;
    law_.at(0.0, start_target, sd, sdd);
  } else if (options_.use_start) {
    start_target = options_.start;
  }
  if (request_.constant && options_.use_start && options_.full_cycle && request_.angular) {
    const double sigma = options_.driver.speed > 0.0 ? 1.0 : -1.0;
    double ahead = std::fmod(sigma * (start_target - s0_), 2.0 * std::numbers::pi);
    if (ahead < 0.0) ahead += 2.0 * std::numbers::pi;
    if (ahead < 1e-12 || 2.0 * std::numbers::pi - ahead < 1e-12) ahead = 0.0;
    start_target = s0_ + sigma * ahead;
  }
  return start_target;
}

// A start elsewhere is reached by continuation along the design position's branch (the same
// circuit, every angle unwrapped continuously): a range sweep from the design input to it, so
// that the cycle from X equals the full cycle at X. False (the message set) when it cannot be.
bool CycleRun::reach_start() {
  const double start_target = start_input();
  if (start_target == s0_) return true;
  CycleOptions reach;
  reach.driver = options_.driver;
  reach.driver.profile = Profile::constant_speed;
  reach.driver.speed = request_.constant ? std::abs(options_.driver.speed) : 1.0;
  reach.full_cycle = false;
  reach.end = start_target;
  // Positions every 2° (or 1/180 of the range for a prismatic joint): each is converged, and
  // longer steps are split by the sweep itself.
  const double per_step = request_.angular ? 2.0 * std::numbers::pi / 180.0 : 0.0;
  const double span = std::abs(start_target - s0_);
  reach.steps = per_step > 0.0
                    ? std::clamp(static_cast<int>(std::ceil(span / per_step)) + 1, 2, 100000)
                    : 181;
  reach.bridge_change_points = false;  // only its last position (a converged one) is used
  const CycleResult path = run_cycle(model_, reach);
  if (path.status != CycleStatus::completed || path.points.empty()) {
    result_.message = "cannot reach the start input " +
                      format_input(start_target, request_.angular, request_.file_units) +
                      " from the design position along its branch: " + path.message;
    return false;
  }
  state_.q = path.points.back().q;
  // The branch's tangent where the path arrived (its last regular position): the first step
  // from a start on a change point predicts with it.
  for (const DrivenPointView& p : path.points)
    if (!p.singular && p.chart_quality >= 1e-3) start_tangent_ = p.tangent;
  s0_ = start_target;
  return true;
}

// Period and time grid; the law anchored at the start; the storage of the positions and the
// work buffers sized. False (the message set) for an empty input range.
bool CycleRun::set_time_grid() {
  const Driver& driver = options_.driver;
  steps_ = std::max(2, options_.steps);
  if (request_.constant && options_.full_cycle) {
    period_ = 2.0 * std::numbers::pi / std::abs(driver.speed);
  } else if (request_.constant) {
    const double span = options_.end - s0_;
    if (!(std::abs(span) > 0.0)) {
      result_.status = CycleStatus::invalid_request;
      result_.message = "the input range is empty: the end (--to) equals the start";
      return false;
    }
    law_.omega = std::copysign(std::abs(driver.speed), span);
    period_ = std::abs(span) / std::abs(driver.speed);
  } else {
    period_ = 1.0 / driver.frequency;
  }
  law_.s_ref = s0_;
  dt_ = options_.full_cycle ? period_ / steps_ : period_ / (steps_ - 1);
  last_index_ = steps_;  // grid times k = 0 … steps − 1
  omega0_ = law_.omega;
  max_positions_ = 4 * steps_;  // bound on a reversing sweep that does not close
  // The positions' storage, then the sweep's work buffers.
  result_.points.reserve(static_cast<size_t>(steps_));
  scale_ = step_scale(model_);
  trial_.resize(model_.nq);
  wrapped_ = wrapped_measures(model_);
  du_.resize(model_.n);
  return true;
}

// The driven position at q and time t into p: compute_driven, then the input, the chart's
// quality, sign and identity, and the outputs (reactions, measures, energies) from the rotation
// table compute_driven filled at this q (no sin/cos in reactions and measures).
bool CycleRun::evaluate_at(const VecX& q, double t, DrivenPoint& p, DrivenJacobian jacobian) {
  double s = 0.0, sdot = 0.0, sddot = 0.0;
  law_.at(t, s, sdot, sddot);
  state_.q = q;
  state_.t = t;
  if (!compute_driven(model_, request_.joint, sdot, sddot, state_, ws_, w_, p, jacobian))
    return false;
  p.input = sweep_.on_turn(p.input, s);  // compute_driven read it at q
  p.time = t;
  p.chart_quality = ws_.dual.engine.quality();
  // Sign of det of the chart's block and the chart it belongs to: a sign change within one
  // chart is a change point passed between positions.
  p.chart_sign = ws_.dual.engine.determinant_sign();
  p.chart_id = ws_.dual.engine.switch_count();
  p.singular = ws_.dual.engine.quality() < kSingularQuality;
  compute_driven_outputs(model_, state_, p.lambda, p.udot, w_.rotations,
                         {p.reactions, p.measures, p.kinetic, p.potential, p.dissipated});
  return true;
}

// One continuation step from a converged point to time t: predictor, corrector with the input
// locked, evaluation; false if it does not converge on the same branch or is too long. From a
// point next to a change point (whose F is unreliable) the last regular tangent is used.
bool CycleRun::try_step(const DrivenPoint& from, double t, DrivenPoint& out) {
  double target = 0.0, sd = 0.0, sdd = 0.0;
  law_.at(t, target, sd, sdd);
  const VecX& tangent = from.singular ? good_tangent_ : from.tangent;
  const double ds = target - from.input;
  if (move_size(tangent, ds) > kMaxMove) return false;
  if (from.singular) {
    trial_ = from.q;
    integrate_positions(model_, trial_, good_tangent_, ds);
  } else {
    predict(model_, from, target, du_, trial_);
  }
  // Corrections beyond twice the size of the tangent step would leave the branch.
  const double max_step = 2.0 * std::abs(ds) * max_abs(tangent) + 1e-12;
  return sweep_.corrector(trial_, target, max_step, nullptr, nullptr,
                          from.singular ? nullptr : &from.tangent) &&
         evaluate_at(trial_, t, out, sweep_.at_q) && same_branch(out.tangent, tangent);
}

// Determinacy (docs/design.md §3): component cᵀλ is unique iff Nᵀc = 0 for the null space N of E.
// The values of the components for λ = N_j are exactly (Nᵀc)_j; a component is determinate when
// they vanish at every regular position of the sweep.
void CycleRun::update_determinacy(const DrivenPoint& p) {
  if (result_.redundant == 0 || p.singular) return;
  for (Eigen::Index j = 0; j < w_.N.cols(); ++j) {
    const double tol = 1e-8 * w_.N.col(j).norm();
    compute_reactions(model_, p.q, w_.rotations, w_.N.col(j), null_values_);
    for (size_t i = 0; i < null_values_.size(); ++i)
      if (std::abs(null_values_[i]) > tol) result_.determinate[i] = false;
    for (int r = 0; r < model_.nc; ++r)
      if (std::abs(w_.N(r, j)) > tol) result_.row_determinate[static_cast<size_t>(r)] = false;
  }
}

// A change point passed at input s_at, time t_at (once per 2 grid steps).
void CycleRun::record_singular(double s_at, double t_at) {
  if (!result_.singular_positions.empty() &&
      std::abs(result_.singular_positions.back().time - t_at) < 2.0 * dt_)
    return;
  result_.singular_positions.push_back(
      {s_at, t_at,
       "singular position (E loses rank) at input " +
           format_input(s_at, request_.angular, request_.file_units) +
           ": passed, branch kept by continuity of the tangent"});
}

// The first position: a dead point or a singular position (not reached along the branch) stops
// the sweep before it starts (false, the result says why).
bool CycleRun::start_sweep() {
  if (!evaluate_at(state_.q, 0.0, anchor_)) {
    result_.status = CycleStatus::stopped_at_dead_point;
    result_.dead_points.push_back(
        {s0_, 0.0,
         "the start position is a dead point of driver joint '" + request_.joint_name + "'"});
    result_.message = result_.dead_points.back().message;
    return false;
  }
  if (anchor_.singular && start_tangent_.size() == 0) {
    result_.message =
        "the start position is a singular position (E loses rank there); start "
        "the sweep elsewhere";
    return false;
  }
  update_determinacy(anchor_);
  result_.points.push_back(anchor_);
  good_tangent_ = anchor_.tangent;
  if (anchor_.singular) {  // a start on a change point, reached along the branch: its tangent
    good_tangent_ = start_tangent_;
    result_.singular_positions.push_back(
        {s0_, 0.0,
         "singular position (E loses rank) at input " +
             format_input(s0_, request_.angular, request_.file_units) +
             ": the start; passed, branch kept by continuity of the tangent"});
  }
  result_.status = CycleStatus::completed;  // unless the sweep says otherwise
  return true;
}

// The sweep over the time grid: each grid time reached from the anchor (reach_grid_time);
// where that is stuck, a change point is jumped over (jump_change_point) and a dead point
// stopped at or passed by reversing the input (pass_dead_point).
void CycleRun::sweep() {
  for (long k = 1;; ++k) {
    if (reversals_ == 0 && k >= last_index_) break;
    if (static_cast<int>(result_.points.size()) >= max_positions_) {
      result_.message = "stopped after " + std::to_string(max_positions_) +
                        " positions: the reversing sweep did not return to its start";
      break;
    }
    if (stopped_by_control(std::min(1.0, static_cast<double>(k) * dt_ / period_))) break;
    const double t = static_cast<double>(k) * dt_;
    if (closed_after_reversal(t)) break;
    double h = 0.0;
    if (reach_grid_time(t, h)) {
      if (!probe_.singular) update_determinacy(probe_);
      result_.points.push_back(probe_);
      std::swap(anchor_, probe_);
      continue;
    }
    // Stuck just after `sub`. A change point (E loses rank; the driver still drives: dᵀF stays
    // finite) is jumped over; a fold of the input (dᵀF → 0) is a dead point.
    if (std::abs(sub_.dTF) > 1e-2) {
      const Jump jump = jump_change_point(t);
      if (jump == Jump::failed) break;
      if (jump == Jump::passed) --k;  // continue towards the same grid time from past the point
      continue;
    }
    if (!pass_dead_point(t, h, k)) break;
  }
}

// The run's bounds (CycleOptions::control), once per grid position: a bound met ends the sweep
// with status `stopped` and the positions reached.
bool CycleRun::stopped_by_control(double fraction) {
  const StopReason stop = monitor_.tick(fraction);
  if (stop == StopReason::none) return false;
  result_.status = CycleStatus::stopped;
  result_.stop = stop;
  result_.message = monitor_.stop_message(stop, fraction, "position", "--steps") + "; " +
                    std::to_string(result_.points.size()) + " positions swept";
  return true;
}

// After a reversal the cycle closes when the input passes its start again, moving in the
// original direction on the starting branch.
bool CycleRun::closed_after_reversal(double t) {
  double target = 0.0, sd = 0.0, sdd = 0.0;
  law_.at(t, target, sd, sdd);
  if (reversals_ > 0 && law_.omega == omega0_ && (anchor_.input - s0_) * omega0_ < 0.0 &&
      (target - s0_) * omega0_ >= 0.0) {
    result_.message = "the cycle closed after " + std::to_string(reversals_) + " reversals";
    return true;
  }
  return false;
}

// Reach t from the anchor: the whole step, else sub-steps (halved on failure, doubled again
// on success; not output) from `sub`. True with the position at t in probe_; else stuck, failing
// within 2h (h the last step tried) after sub_.
bool CycleRun::reach_grid_time(double t, double& h) {
  const DrivenPoint* from = &anchor_;  // the anchor itself until a sub-step is taken (no copy)
  h = t - from->time;
  while (true) {
    const double t_next = from->time + h >= t - 1e-9 * dt_ ? t : from->time + h;
    if (try_step(*from, t_next, probe_)) {
      if (!from->singular && !probe_.singular && from->chart_id == probe_.chart_id &&
          from->chart_sign != probe_.chart_sign)
        locate_sign_change(*from);
      if (probe_.singular)
        record_singular(probe_.input, probe_.time);
      else
        good_tangent_ = probe_.tangent;
      if (t_next == t) return true;
      std::swap(sub_, probe_);
      from = &sub_;
      h = std::min(2.0 * h, t - sub_.time);
      continue;
    }
    h *= 0.5;
    if (h < 1e-7 * dt_) break;
  }
  if (from != &sub_) sub_ = anchor_;  // stuck at the anchor: what follows works on `sub`
  return false;
}

// The chart's determinant changed sign between `from` and probe_ (one chart): |det| ∝ distance,
// so the change point is interpolated between them.
void CycleRun::locate_sign_change(const DrivenPoint& from) {
  const double a = from.chart_quality / (from.chart_quality + probe_.chart_quality);
  const double t_a = from.time + a * (probe_.time - from.time);
  // A change point only if E loses rank there: the best chart's quality at t_a is far
  // below both neighbours' (a chart whose own block degenerated between two positions
  // of a coarse grid, with E regular, is not one). The check re-selects the chart, so
  // the next interval is not compared across it.
  const bool confirmed =
      !try_step(from, t_a, check_) ||
      check_.chart_quality < 0.1 * std::min(from.chart_quality, probe_.chart_quality);
  if (confirmed) record_singular(from.input + a * (probe_.input - from.input), t_a);
  // The workspace back at the probe (its null space N feeds the determinacy update).
  trial_ = probe_.q;
  const long id = probe_.chart_id;
  (void)evaluate_at(trial_, probe_.time, probe_);  // succeeded there a moment ago
  probe_.chart_id = -1 - id;                       // no sign comparison across the check
}

// A change point just after sub_ jumped over: the first of growing jumps that converges becomes
// the anchor (output when past the grid time t); failed (the result says why) when none does.
CycleRun::Jump CycleRun::jump_change_point(double t) {
  const double t_stuck = sub_.time;
  for (const double jump : {1e-5, 1e-4, 1e-3, 1e-2, 0.1}) {
    const double tj = t_stuck + jump * dt_;
    if (!try_step(sub_, tj, probe_)) continue;
    record_singular(sub_.input, t_stuck);
    if (!probe_.singular) good_tangent_ = probe_.tangent;
    // Past the grid time: the grid position is the singular one; it is reported just
    // past it, flagged (its multipliers are not meaningful there).
    const bool output = tj >= t;
    if (output) {
      probe_.singular = true;
      result_.points.push_back(probe_);
    }
    std::swap(anchor_, probe_);
    return output ? Jump::output : Jump::passed;
  }
  result_.status = CycleStatus::failed;
  result_.message = "the continuation cannot proceed at input " +
                    format_input(sub_.input, request_.angular, request_.file_units) +
                    " (neither a dead point nor a singular position of E); the positions "
                    "before it are reported";
  return Jump::failed;
}

// A dead point just after sub_ (the grid time t, h the last step tried): located, then the sweep
// stops there, or, reversing at dead points, passes the fold and drives the input back (k: the
// grid index the sweep resumes after). False when the sweep stops.
bool CycleRun::pass_dead_point(double t, double h, long& k) {
  const DrivenPoint at_lo = bisect_dead_point(t, h);
  const double s_dead = at_lo.input;
  std::string msg = "dead point of driver joint '" + request_.joint_name + "' at input " +
                    format_input(s_dead, request_.angular, request_.file_units) +
                    ": the driver cannot move the mechanism past it";
  if (!(options_.reverse_at_dead_point && request_.constant)) {
    stop_at_dead_point(s_dead, at_lo.time, msg);
    return false;
  }
  VecX q_cur = at_lo.q;
  if (!pass_fold(at_lo, s_dead, q_cur)) {
    msg += "; could not pass it to reverse";
    stop_at_dead_point(s_dead, at_lo.time, msg);
    return false;
  }
  return reverse_input(at_lo, s_dead, q_cur, msg, k);
}

void CycleRun::stop_at_dead_point(double s_dead, double t_dead, const std::string& msg) {
  result_.dead_points.push_back({s_dead, t_dead, msg});
  result_.status = CycleStatus::stopped_at_dead_point;
  result_.message = msg;
}

// Dead point: bisection in time between the last good time and the failing one. The last
// position reached before it.
DrivenPoint CycleRun::bisect_dead_point(double t, double h) {
  DrivenPoint at_lo = sub_;
  double lo = sub_.time, hi = std::min(sub_.time + 2.0 * h + 1e-7 * dt_, t);
  while (hi - lo > 1e-15 * (1.0 + std::abs(hi))) {
    const double mid = 0.5 * (lo + hi);
    double s_mid = 0.0, sd = 0.0, sdd = 0.0;
    law_.at(mid, s_mid, sd, sdd);
    if (std::abs(s_mid - at_lo.input) < options_.dead_point_tolerance) break;
    if (try_step(at_lo, mid, probe_)) {
      lo = mid;
      std::swap(at_lo, probe_);
    } else {
      hi = mid;
    }
  }
  return at_lo;
}

// Reverse: pass the fold along the curve (pseudo-arclength steps: predictor along the
// direction of motion n, corrector with nᵀ(q − q_pred) = 0) from q_cur until the input has
// turned back. False when it does not within 40 steps.
bool CycleRun::pass_fold(const DrivenPoint& at_lo, double s_dead, VecX& q_cur) {
  VecX dir = at_lo.tangent * at_lo.input_rate;  // direction of motion dq/dt
  dir.normalize();
  difference_positions(model_, anchor_.q, at_lo.q, du_);
  double arc = std::max(du_.norm(), 1e-9);
  VecX q_pred(model_.nq);
  for (int attempt = 0; attempt < 40; ++attempt) {
    q_pred = q_cur;
    integrate_positions(model_, q_pred, dir, arc);
    trial_ = q_pred;
    if (!sweep_.corrector(trial_, 0.0, 0.5 * arc, &dir, &q_pred)) {
      arc *= 0.5;
      continue;
    }
    // New direction of motion: F at the new point, oriented along the old direction.
    state_.q = trial_;
    write_constraint_jacobian(model_, state_.q, ws_, w_);
    if (basis_at_jacobian(model_, state_, ws_, w_) != ProjectionStatus::ok) {
      arc *= 0.5;
      continue;
    }
    if (!w_.idle_bodies.empty() && !hold_idle(model_, state_.q, ws_.dual.F, w_)) {
      arc *= 0.5;
      continue;
    }
    VecX f = (w_.idle_bodies.empty() ? VecX(ws_.dual.F.col(0)) : w_.F_held).normalized();
    if (f.dot(dir) < 0.0) f = -f;
    const double s_new = sweep_.input_at(trial_, s_dead);
    q_cur = trial_;
    dir = f;
    if ((s_new - s_dead) * law_.omega < -options_.dead_point_tolerance) return true;
  }
  return false;
}

// The input reversed at the dead point (s_dead at at_lo.time): the law re-anchored there, the
// anchor on the far side (q_cur) at its time on the reversed law, the grid resumed after it.
bool CycleRun::reverse_input(const DrivenPoint& at_lo, double s_dead, const VecX& q_cur,
                             const std::string& msg, long& k) {
  ++reversals_;
  result_.dead_points.push_back({s_dead, at_lo.time, msg + "; the input reverses"});
  law_.s_ref = s_dead;
  law_.t_ref = at_lo.time;
  law_.omega = -law_.omega;
  // Re-anchor on the far side: its time on the reversed law, then resume on the time grid.
  const double s_p = sweep_.input_at(q_cur, s_dead);
  const double t_p = at_lo.time + (s_p - s_dead) / law_.omega;
  if (!evaluate_at(q_cur, t_p, anchor_)) {
    result_.status = CycleStatus::failed;
    result_.message = msg + "; lost the branch after reversing";
    return false;
  }
  if (!anchor_.singular) good_tangent_ = anchor_.tangent;
  k = static_cast<long>(std::floor(t_p / dt_));  // the loop's ++k gives the next grid time
  return true;
}

// ---- Change points bridged on the branch -----------------------------------------------
// Next to a change point the direct evaluation at the computed q loses accuracy like
// ε/quality³: q satisfies f(q) = O(ε), and the level set through it is, near the crossing of
// two branches, a hyperbola whose curvature at a distance δ is ε/δ³ — what u̇, and so the drive
// and the reactions, are computed from (measured on the triple-crank: 3e-5 N·m 0.01° from the
// change point, 0.16 N·m at 0.001°). The branch itself is smooth there. So the positions with
// quality < kBridgeQuality take their values from the branch (ChangePointBridge): a degree-7
// polynomial in time through 8 positions at t* ± {1, 2, 3, 4} ρ, reached by continuation from
// the stored positions on each side, where the quality is ≥ kBridgeQuality and every value is
// accurate. With the nodes outside the gap on both sides its Lebesgue constant is 2.7 and its
// error ~ (4ρ)⁸ f⁽⁸⁾/8!. (L1)

constexpr int kNodes = 8;
constexpr double kNodeDistance[4] = {1.0, 2.0, 3.0, 4.0};
constexpr unsigned kAll = (1u << kNodes) - 1;

// Every value of a position as one vector (and back), for the interpolation.
void pack(const DrivenPoint& p, VecX& v) {
  const Eigen::Index nr = static_cast<Eigen::Index>(p.reactions.size());
  const Eigen::Index nm = static_cast<Eigen::Index>(p.measures.size());
  v.resize(p.q.size() + 3 * p.u.size() + p.lambda.size() + nr + nm + 5);
  Eigen::Index at = 0;
  auto put = [&](const auto& x) {
    for (Eigen::Index i = 0; i < static_cast<Eigen::Index>(x.size()); ++i)
      v(at++) = x[static_cast<size_t>(i)];
  };
  put(p.q), put(p.u), put(p.udot), put(p.tangent), put(p.lambda);
  put(p.reactions), put(p.measures);
  v(at++) = p.drive, v(at++) = p.kinetic, v(at++) = p.potential, v(at++) = p.dissipated;
  v(at++) = p.drive_frictionless;
}

void unpack(const VecX& v, DrivenPoint& p) {
  Eigen::Index at = 0;
  auto get = [&](auto& x) {
    for (Eigen::Index i = 0; i < static_cast<Eigen::Index>(x.size()); ++i)
      x[static_cast<size_t>(i)] = v(at++);
  };
  get(p.q), get(p.u), get(p.udot), get(p.tangent), get(p.lambda);
  get(p.reactions), get(p.measures);
  p.drive = v(at++), p.kinetic = v(at++), p.potential = v(at++), p.dissipated = v(at++);
  p.drive_frictionless = v(at++);
}

// Lagrange basis at `at` of the nodes x whose bit is set in `used`.
void lagrange_basis(const double* x, double at, unsigned used, double* l) {
  for (int i = 0; i < kNodes; ++i) {
    l[i] = 0.0;
    if (!(used >> i & 1u)) continue;
    double li = 1.0;
    for (int j = 0; j < kNodes; ++j)
      if (j != i && (used >> j & 1u)) li *= (at - x[j]) / (x[i] - x[j]);
    l[i] = li;
  }
}

// The bridging of a finished sweep (without reversals): its candidates (find_candidates), and
// for each the first radius factor whose bridge has a consistent drive (bridge_at).
class ChangePointBridger {
 public:
  explicit ChangePointBridger(CycleRun& run)
      : run_(run),
        model_(run.model_),
        result_(run.result_),
        np_(result_.points.size()),
        reactions_at_(model_.nq + 3 * model_.n + model_.nc) {}

  void bridge() {
    find_candidates();
    for (size_t j = 0; j < candidates_.size(); ++j)
      for (const double factor : {1.0, 0.5, 2.0, 4.0})  // the first with a consistent drive
        if (bridge_at(j, factor)) break;
  }

 private:
  struct Candidate {
    double time, input;
    bool listed;  // a change point the sweep located (else a dip of the quality)
  };

  void find_candidates();
  bool advance(const DrivenPoint& from, double t, DrivenPoint& out);
  bool bridge_at(size_t j, double radius_factor);
  [[nodiscard]] double quality_slope(double ts) const;
  [[nodiscard]] double bridge_radius(size_t j, double radius_factor, double slope) const;
  bool compute_nodes(double ts, double rho);
  void unwrap_nodes();
  void interpolate(double at, unsigned used, VecX& out);
  bool estimate_errors(double ts);
  void mark_diverging(ChangePointBridge& b);
  void write_bridged(double ts, double rho, int index);

  CycleRun& run_;
  const Model& model_;
  CycleResult& result_;
  const size_t np_;  // the stored positions
  const Eigen::Index reactions_at_;
  std::vector<Candidate> candidates_;
  DrivenPoint cur_, nxt_;
  std::vector<VecX> node_values_ = std::vector<VecX>(kNodes);
  VecX value_, loo_error_, node_scale_;
  DrivenPoint base_, node_, bridged_;
  double x_[kNodes] = {};  // the nodes' times, increasing
  double l_[kNodes] = {};  // a Lagrange basis at them
};

// The change points to bridge: those the sweep listed, and any other dip of the chart
// quality well below kBridgeQuality among the stored positions (a change point passed within
// one step together with a chart switch, or a near one: the direct values are as inaccurate).
void ChangePointBridger::find_candidates() {
  for (const DeadPoint& sp : result_.singular_positions)
    candidates_.push_back({sp.time, sp.input, true});
  for (size_t k = 0; k < np_; ++k) {
    const DrivenPointView p = result_.points[k];
    // (Below a fifth of it: a chart about to be switched can sit just below kBridgeQuality.)
    if (!(p.chart_quality < 0.2 * kBridgeQuality)) continue;
    if ((k > 0 && result_.points[k - 1].chart_quality < p.chart_quality) ||
        (k + 1 < np_ && result_.points[k + 1].chart_quality < p.chart_quality))
      continue;             // not the dip's lowest position
    size_t lo = k, hi = k;  // the run of poor positions around it
    while (lo > 0 && result_.points[lo - 1].chart_quality < kBridgeQuality) --lo;
    while (hi + 1 < np_ && result_.points[hi + 1].chart_quality < kBridgeQuality) ++hi;
    const double t_lo = result_.points[lo].time - run_.dt_,
                 t_hi = result_.points[hi].time + run_.dt_;
    bool listed = false;
    for (const Candidate& c : candidates_) listed = listed || (c.time > t_lo && c.time < t_hi);
    if (!listed) candidates_.push_back({p.time, p.input, false});
  }
}

// Reaches time t on the branch from a regular position: whole step, else sub-steps (halved on
// failure, doubled again on success).
bool ChangePointBridger::advance(const DrivenPoint& from, double t, DrivenPoint& out) {
  cur_ = from;
  double h = t - cur_.time;
  for (int guard = 0; guard < 200; ++guard) {
    const bool last = std::abs(t - cur_.time) <= std::abs(h) * (1.0 + 1e-12);
    const double t_next = last ? t : cur_.time + h;
    if (run_.try_step(cur_, t_next, nxt_) && !nxt_.singular) {
      if (last) {
        out = nxt_;
        return true;
      }
      std::swap(cur_, nxt_);
      h = std::copysign(std::min(2.0 * std::abs(h), std::abs(t - cur_.time)), h);
      continue;
    }
    h *= 0.5;
    if (std::abs(h) < 1e-7 * run_.dt_) return false;
  }
  return false;
}

// One change point: false when it cannot be bridged (its positions then stay as they are:
// flagged singular ones are not reported).
bool ChangePointBridger::bridge_at(size_t j, double radius_factor) {
  const double ts = candidates_[j].time;
  const double slope = quality_slope(ts);
  if (!std::isfinite(slope) || !(slope > 0.0)) return false;
  const double rho = bridge_radius(j, radius_factor, slope);
  // Only where a stored position needs it: one in the gap whose quality is below
  // kBridgeQuality (a coarse grid that passes the change point far from every position, or a
  // chart that degenerated between two positions, has none: its values are accurate as
  // they are, and nothing is flagged).
  bool needed = false;
  for (const DrivenPointView& p : result_.points)
    needed = needed || (std::abs(p.time - ts) < rho && p.chart_quality < kBridgeQuality);
  if (!needed) return true;                        // nothing to do: not an attempt that failed
  for (size_t i = 0; i < candidates_.size(); ++i)  // one change point only
    if (i != j && std::abs(candidates_[i].time - ts) < 6.0 * rho) return false;
  if (!compute_nodes(ts, rho)) return false;
  unwrap_nodes();
  if (!estimate_errors(ts)) return false;
  ChangePointBridge b;
  b.input = candidates_[j].input;
  b.time = ts;
  b.time_from = ts - rho;
  b.time_to = ts + rho;
  b.drive_error = loo_error_(node_values_[0].size() - 4);
  mark_diverging(b);
  write_bridged(ts, rho, static_cast<int>(result_.bridges.size()));
  for (size_t c = 0; c < result_.components.size(); ++c)
    if (b.diverging[c]) result_.diverging[c] = true;
  result_.bridges.push_back(std::move(b));
  return true;
}

// The rate at which the chart quality, ∝ the distance to the change point at ts, grows: from
// the nearest stored position on each side whose quality is ≥ 1e-3 (infinite: none).
double ChangePointBridger::quality_slope(double ts) const {
  double slope = std::numeric_limits<double>::infinity();
  for (const int side : {-1, 1}) {
    double best = std::numeric_limits<double>::infinity(), q_at = 0.0;
    for (const DrivenPointView& p : result_.points) {
      const double d = (p.time - ts) * side;
      if (d > 0.0 && d < best && p.chart_quality >= 1e-3) best = d, q_at = p.chart_quality;
    }
    // A position's quality is that of its chart, within the hysteresis factor of the best
    // one below the switching threshold: the larger slope is the better estimate.
    if (std::isfinite(best))
      slope = std::isfinite(slope) ? std::max(slope, q_at / best) : q_at / best;
  }
  return slope;
}

// ρ: where the quality reaches kBridgeQuality (times radius_factor), widened so that every
// position of the run of poor ones around ts lies in the gap.
double ChangePointBridger::bridge_radius(size_t j, double radius_factor, double slope) const {
  const double ts = candidates_[j].time;
  double rho = radius_factor * kBridgeQuality / slope;
  for (const DrivenPointView& p : result_.points)  // a dip locates ts only to about this
    if (!candidates_[j].listed && std::abs(p.time - ts) < run_.dt_ &&
        p.chart_quality < kBridgeQuality)
      rho = std::max(rho, radius_factor * kBridgeQuality / slope + p.chart_quality / slope);
  size_t nearest = 0;
  for (size_t k = 1; k < np_; ++k)
    if (std::abs(result_.points[k].time - ts) < std::abs(result_.points[nearest].time - ts))
      nearest = k;
  for (const int step : {-1, 1})
    for (long k = static_cast<long>(nearest);
         k >= 0 && k < static_cast<long>(np_) &&
         result_.points[static_cast<size_t>(k)].chart_quality < kBridgeQuality;
         k += step)
      rho = std::max(rho, 1.05 * std::abs(result_.points[static_cast<size_t>(k)].time - ts));
  return rho;
}

// The nodes: by continuation from the stored position on each side nearest to them (any
// not next to the change point will do: the corrector makes each node exact). A side with
// no stored position (a sweep that ends or starts next to the change point) is reached
// from the other side's inner node, across the change point (the step the sweep itself
// takes there: predictor along the tangent, bounded corrector, same branch).
bool ChangePointBridger::compute_nodes(double ts, double rho) {
  long from[2] = {-1, -1};
  for (const int side : {-1, 1}) {
    double best = std::numeric_limits<double>::infinity();
    for (size_t k = 0; k < np_; ++k) {
      const DrivenPointView p = result_.points[k];
      const double d = (p.time - ts) * side;
      const double off = std::max({0.0, rho - d, d - 4.0 * rho});
      if (d > 0.0 && off < best && p.chart_quality >= 1e-3 && !p.singular)
        best = off, from[side > 0] = static_cast<long>(k);
    }
  }
  if (from[0] < 0 && from[1] < 0) return false;
  const int first_side = from[0] >= 0 ? -1 : 1;
  DrivenPoint first_inner;  // the first side's inner node
  for (const int side : {first_side, -first_side}) {
    const long f = from[side > 0];
    if (f >= 0) {
      const DrivenPointView p = result_.points[static_cast<size_t>(f)];
      if (!run_.evaluate_at(VecX(p.q), p.time, base_)) return false;
    } else {
      base_ = first_inner;
    }
    for (int a = 0; a < 4; ++a) {
      const int i = side < 0 ? 3 - a : 4 + a;  // nodes in increasing time
      x_[i] = ts + side * kNodeDistance[a] * rho;
      // (The quality is that of the chart's block, relative to its own largest pivot: on a
      // long chain such as the N-four-bar with N = 40 it stays below kBridgeQuality well
      // away from a change point. A node's accuracy is checked by the error estimate below.)
      if (!advance(base_, x_[i], node_) || node_.chart_quality < 0.1 * kBridgeQuality) return false;
      pack(node_, node_values_[static_cast<size_t>(i)]);
      if (a == 0 && side == first_side) first_inner = node_;
    }
  }
  return true;
}

// Wrapped angles (spatial joints) on one turn across the nodes.
void ChangePointBridger::unwrap_nodes() {
  const Eigen::Index measures_at =
      reactions_at_ + static_cast<Eigen::Index>(result_.components.size());
  for (const size_t m : run_.wrapped_)
    for (int i = 1; i < kNodes; ++i) {
      const Eigen::Index at = measures_at + static_cast<Eigen::Index>(m);
      node_values_[static_cast<size_t>(i)](at) =
          unwrap_near(node_values_[static_cast<size_t>(i)](at), node_values_[0](at));
    }
}

void ChangePointBridger::interpolate(double at, unsigned used, VecX& out) {
  lagrange_basis(x_, at, used, l_);
  out = VecX::Zero(node_values_[0].size());
  for (int i = 0; i < kNodes; ++i) out += l_[i] * node_values_[static_cast<size_t>(i)];
}

// Error estimate per value (loo_error_; node_scale_ their sizes at the nodes): the two inner
// nodes against the degree-6 interpolant through the other seven. False when the drive's
// exceeds kBridgeTolerance of its size.
bool ChangePointBridger::estimate_errors(double ts) {
  loo_error_ = VecX::Zero(node_values_[0].size());
  node_scale_ = VecX::Zero(node_values_[0].size());
  for (int i = 0; i < kNodes; ++i)
    node_scale_ = node_scale_.cwiseMax(node_values_[static_cast<size_t>(i)].cwiseAbs());
  for (const int inner : {3, 4}) {
    interpolate(x_[inner], kAll & ~(1u << inner), value_);
    loo_error_ =
        loo_error_.cwiseMax((value_ - node_values_[static_cast<size_t>(inner)]).cwiseAbs());
  }
  // At the change point itself: against the degree-5 interpolant through the six inner
  // nodes (the error of the lower degree, so an upper estimate).
  VecX centre;
  interpolate(ts, kAll, centre);
  interpolate(ts, kAll & ~1u & ~(1u << (kNodes - 1)), value_);
  const Eigen::Index drive_at = node_values_[0].size() - 4;
  loo_error_(drive_at) =
      std::max(loo_error_(drive_at), std::abs(centre(drive_at) - value_(drive_at)));
  return loo_error_(drive_at) <= kBridgeTolerance * node_scale_(drive_at) + 1e-300;
}

// A component diverges when its estimate exceeds kBridgeTolerance of its size at the
// nodes (floored at 1e-6 of the largest component of the same unit, so that components
// at rounding level are not called diverging).
void ChangePointBridger::mark_diverging(ChangePointBridge& b) {
  std::map<std::string, double> unit_scale;
  for (size_t c = 0; c < result_.components.size(); ++c) {
    double& us = unit_scale[result_.components[c].unit];
    us = std::max(us, node_scale_(reactions_at_ + static_cast<Eigen::Index>(c)));
  }
  b.diverging.assign(result_.components.size(), false);
  for (size_t c = 0; c < result_.components.size(); ++c) {
    const Eigen::Index at = reactions_at_ + static_cast<Eigen::Index>(c);
    const double size_c = std::max(node_scale_(at), 1e-6 * unit_scale[result_.components[c].unit]);
    b.diverging[c] = !(loo_error_(at) <= kBridgeTolerance * size_c);
  }
}

// The positions in the gap: their values at their grid time from the polynomial.
void ChangePointBridger::write_bridged(double ts, double rho, int index) {
  for (size_t k = 0; k < np_; ++k) {
    const DrivenPointView p = result_.points[k];
    if (!(std::abs(p.time - ts) < rho)) continue;
    const double t = static_cast<double>(k) * run_.dt_;  // its grid time (exactly on a change
                                                         // point it was evaluated just past it)
    bridged_ = run_.anchor_;                             // sizes
    bridged_.time = t;
    run_.law_.at(t, bridged_.input, bridged_.input_rate, bridged_.input_acceleration);
    interpolate(t, kAll, value_);
    unpack(value_, bridged_);
    normalize_coordinates(model_, bridged_.q);  // unit quaternions again
    bridged_.chart_quality = p.chart_quality;
    bridged_.chart_sign = p.chart_sign;
    bridged_.chart_id = p.chart_id;
    bridged_.dTF = p.dTF;
    bridged_.idle_hold = p.idle_hold;
    bridged_.singular = p.singular;
    bridged_.bridge = index;
    result_.points.assign(k, bridged_);
  }
}

void CycleRun::bridge_change_points() {
  result_.diverging.assign(result_.components.size(), false);
  if (reversals_ != 0 || !options_.bridge_change_points) return;
  ChangePointBridger(*this).bridge();
}

// Angles unwrapped over the sweep, the idle motions' hold checked, the counts recorded.
void CycleRun::finish() {
  unwrap_measures(result_, wrapped_);
  if (!result_.idle.empty()) warn_idle_hold(result_, request_.file_units);
  result_.chart_switches = ws_.dual.engine.switch_count();
  result_.corrector_factorisations = sweep_.factorisations;
  result_.reversals = reversals_;
}

}  // namespace

CycleResult run_cycle(const Model& model, const CycleOptions& options) {
  CycleResult result = named_result(model);
  const int joint = options.driver.joint;
  if (joint < 0 || joint >= static_cast<int>(model.joints.size())) {
    result.message = "no driver joint";
    return result;
  }
  const CycleRequest request = make_request(model, options);
  if (const char* error = request_error(model, options, request.angular)) {
    result.status = CycleStatus::invalid_request;
    result.message = error;
    return result;
  }
  State state(model);
  if (!assemble_start(model, request, state, result)) return result;
  const Mobility mob = compute_mobility(model, state.q);
  if (!record_mobility(model, mob, result)) return result;
  CycleRun run(model, options, request, std::move(state), mob, result);
  if (!run.reach_start() || !run.set_time_grid() || !run.start_sweep()) return result;
  run.sweep();
  run.bridge_change_points();
  run.finish();
  return result;
}

bool drive_reported(const DrivenPointView& p) { return p.bridge >= 0 || !p.singular; }

bool rates_reported(const DrivenPointView& p) { return drive_reported(p); }

bool measure_reported(const Model& model, const DrivenPointView& p, std::size_t measure) {
  return model.measures.at(measure).derivative == 0 || rates_reported(p);
}

bool component_reported(const CycleResult& result, const DrivenPointView& p,
                        std::size_t component) {
  if (p.bridge < 0) return !p.singular;
  const auto& diverging = result.bridges.at(static_cast<size_t>(p.bridge)).diverging;
  return !diverging.at(component);
}

std::vector<ReactionMagnitude> reaction_magnitudes(const CycleResult& result) {
  std::vector<ReactionMagnitude> out;
  const auto& comps = result.components;
  for (size_t i = 0; i < comps.size();) {
    const int joint = comps[i].joint;
    const std::string prefix = comps[i].name.substr(0, comps[i].name.rfind('.'));
    // The force's magnitude from its world components (planar Fx, Fy; spatial Fx, Fy, Fz), a
    // spatial joint's moment's from Mx, My, Mz; every other component on its own.
    ReactionMagnitude force{prefix + ".|F|", "N", joint, {}, true};
    ReactionMagnitude moment{prefix + ".|M|", "N*m", joint, {}, true};
    std::vector<ReactionMagnitude> others;
    for (; i < comps.size() && comps[i].joint == joint; ++i) {
      if (!comps[i].global) continue;
      const std::string c = comps[i].name.substr(comps[i].name.rfind('.') + 1);
      const bool det = result.determinate.empty() || result.determinate[i];
      ReactionMagnitude* group = c == "Fx" || c == "Fy" || c == "Fz"   ? &force
                                 : c == "Mx" || c == "My" || c == "Mz" ? &moment
                                                                       : nullptr;
      if (group) {
        group->components.push_back(static_cast<int>(i));
        group->determinate = group->determinate && det;
      } else {
        others.push_back(
            {prefix + ".|" + c + "|", comps[i].unit, joint, {static_cast<int>(i)}, det});
      }
    }
    if (!force.components.empty()) out.push_back(std::move(force));
    if (!moment.components.empty()) out.push_back(std::move(moment));
    for (auto& o : others) out.push_back(std::move(o));
  }
  // A gear's reaction is its one (joint-frame) multiplier.
  for (size_t i = 0; i < comps.size(); ++i)
    if (!comps[i].global && comps[i].name.size() > 7 &&
        comps[i].name.compare(comps[i].name.size() - 7, 7, ".lambda") == 0)
      out.push_back({comps[i].name.substr(0, comps[i].name.size() - 7) + ".|lambda|",
                     comps[i].unit,
                     comps[i].joint,
                     {static_cast<int>(i)},
                     result.determinate.empty() || result.determinate[i]});
  std::stable_sort(
      out.begin(), out.end(),
      [](const ReactionMagnitude& a, const ReactionMagnitude& b) { return a.joint < b.joint; });
  return out;
}

bool magnitude_reported(const CycleResult& result, const DrivenPointView& p,
                        const ReactionMagnitude& m) {
  for (const int c : m.components)
    if (!component_reported(result, p, static_cast<size_t>(c))) return false;
  return true;
}

double magnitude_at(const DrivenPointView& p, const ReactionMagnitude& m) {
  double sum = 0.0;
  for (const int c : m.components)
    sum += p.reactions[static_cast<size_t>(c)] * p.reactions[static_cast<size_t>(c)];
  return std::sqrt(sum);
}

namespace {

// A fresh summary of one series (name, unit, determinacy; everything else accumulated).
SeriesSummary series(std::string name, std::string unit, bool determinate) {
  SeriesSummary s;
  s.name = std::move(name);
  s.unit = std::move(unit);
  s.determinate = determinate;
  return s;
}

// Max, min, peak |x| and RMS of value(k) over the positions k where reported(k).
template <class Value, class Reported>
SeriesSummary summarize_series(const CycleResult& result, SeriesSummary s, Value value,
                               Reported reported) {
  double sum2 = 0.0;
  for (size_t k = 0; k < result.points.size(); ++k) {
    if (!reported(k)) continue;
    const DrivenPointView p = result.points[k];
    const double v = value(k);
    sum2 += v * v;
    const bool first = s.samples++ == 0;
    if (first || std::abs(v) > s.peak) {
      s.peak = std::abs(v);
      s.peak_input = p.input;
      s.peak_time = p.time;
    }
    if (first || v > s.max.value) s.max = {v, p.input, p.time};
    if (first || v < s.min.value) s.min = {v, p.input, p.time};
  }
  s.rms = s.samples > 0 ? std::sqrt(sum2 / s.samples) : 0.0;
  return s;
}

}  // namespace

std::vector<SeriesSummary> summarize_cycle(const CycleResult& result,
                                           const std::vector<ReactionMagnitude>& magnitudes,
                                           const std::string& drive_unit) {
  std::vector<SeriesSummary> out;
  out.push_back(summarize_series(
      result, series("drive", drive_unit, true), [&](size_t k) { return result.points[k].drive; },
      [&](size_t k) { return drive_reported(result.points[k]); }));
  for (const ReactionMagnitude& m : magnitudes) {
    SeriesSummary s = series(m.name, m.unit, m.determinate);
    for (const int c : m.components)
      if (!result.diverging.empty() && result.diverging[static_cast<size_t>(c)]) s.diverges = true;
    out.push_back(summarize_series(
        result, std::move(s), [&](size_t k) { return magnitude_at(result.points[k], m); },
        [&](size_t k) { return magnitude_reported(result, result.points[k], m); }));
  }
  return out;
}

std::vector<SeriesSummary> summarize_components(const CycleResult& result) {
  std::vector<SeriesSummary> out;
  for (size_t i = 0; i < result.components.size(); ++i) {
    SeriesSummary s = series(result.components[i].name, result.components[i].unit,
                             result.determinate.empty() || result.determinate[i]);
    s.diverges = !result.diverging.empty() && result.diverging[i];
    out.push_back(summarize_series(
        result, std::move(s), [&](size_t k) { return result.points[k].reactions[i]; },
        [&](size_t k) { return component_reported(result, result.points[k], i); }));
  }
  return out;
}

SeriesSummary summarize_values(const CycleResult& result, std::string name, std::string unit,
                               const std::vector<double>& values,
                               const std::vector<bool>& reported) {
  check_argument(values.size() == result.points.size() && reported.size() == values.size(),
                 "summarize_values", "values", "must have one value per position");
  return summarize_series(
      result, series(std::move(name), std::move(unit), true), [&](size_t k) { return values[k]; },
      [&](size_t k) { return static_cast<bool>(reported[k]); });
}

}  // namespace orthomech
