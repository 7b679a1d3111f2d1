#include "orthomech/analysis/cycle.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "orthomech/analysis/mobility.hpp"
#include "orthomech/analysis/positions.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/model/loads.hpp"
#include "orthomech/model/measures.hpp"
#include "orthomech/projection/dual.hpp"
#include "orthomech/projection/primal.hpp"

namespace orthomech {

const char* to_string(CycleStatus s) {
  switch (s) {
    case CycleStatus::completed:
      return "completed";
    case CycleStatus::stopped_at_dead_point:
      return "stopped at a dead point";
    case CycleStatus::failed:
      return "failed";
  }
  return "?";
}

DrivenWorkspace::DrivenWorkspace(const Model& model, int rank)
    : d(VecX::Zero(model.n)),
      Fdot_v(VecX::Zero(model.n)),
      R(VecX::Zero(model.n)),
      lambda_p(VecX::Zero(model.nc)),
      Er(model.n, rank),
      ErtEr(rank, rank),
      ErtEr_llt(rank),
      B(rank, model.nc - rank),
      N(MatX::Zero(model.nc, model.nc - rank)),
      NtN(model.nc - rank, model.nc - rank),
      NtN_llt(model.nc - rank),
      small(model.nc - rank),
      rhs_r(rank),
      other_rows(static_cast<size_t>(model.nc - rank)),
      J(model.n, model.n),
      J_lu(model.n),
      g(model.n),
      dq(model.n) {}

// ---- reaction components -------------------------------------------------------------------
std::vector<ReactionComponent> reaction_components(const Model& model) {
  std::vector<ReactionComponent> out;
  for (size_t j = 0; j < model.joints.size(); ++j) {
    const Joint& joint = model.joints[j];
    const int ji = static_cast<int>(j);
    auto add = [&](const std::string& c, bool global, const char* unit) {
      out.push_back({joint.name + "." + c, ji, global, unit});
    };
    switch (joint.kind.index()) {
      case 0:  // revolute
        add("Fx", true, "N"), add("Fy", true, "N"), add("Fx_local", false, "N"),
            add("Fy_local", false, "N");
        break;
      case 1:  // prismatic
        add("Fx", true, "N"), add("Fy", true, "N"), add("M", true, "N*m"), add("N", false, "N");
        break;
      case 2:  // fixed
        add("Fx", true, "N"), add("Fy", true, "N"), add("M", true, "N*m"),
            add("Fx_local", false, "N"), add("Fy_local", false, "N");
        break;
      case 3:  // pin-in-slot
        add("Fx", true, "N"), add("Fy", true, "N"), add("N", false, "N");
        break;
      case 4:  // gear
        add("lambda", false, "N*m");
        break;
      default:  // distance
        add("Fx", true, "N"), add("Fy", true, "N"), add("T", false, "N");
        break;
    }
  }
  return out;
}

// Forces and moments on the joint's first body from its second (docs/notation.md). The rows
// of λ are the generalized forces E λ: for rows written "first − second" (revolute, fixed x/y) λ is
// that force itself; for rows written "second − first" (slot normal, relative angle, rod) the
// force on the first body is −λ along the row's direction.
void compute_reactions(const Model& model, const VecX& q, const VecX& lambda,
                       std::vector<double>& out) {
  out.clear();
  const VecX* none = nullptr;
  for (const Joint& joint : model.joints) {
    const int r = joint.row_offset;
    std::visit(
        [&](const auto& k) {
          using T = std::decay_t<decltype(k)>;
          if constexpr (std::is_same_v<T, Revolute> || std::is_same_v<T, Fixed>) {
            const Vec2 F(lambda(r), lambda(r + 1));
            const Vec2 local = rotation(body_angle(model, k.pi.body, q)).transpose() * F;
            out.push_back(F.x());
            out.push_back(F.y());
            if constexpr (std::is_same_v<T, Fixed>) out.push_back(-lambda(r + 2));
            out.push_back(local.x());
            out.push_back(local.y());
          } else if constexpr (std::is_same_v<T, Prismatic> || std::is_same_v<T, PinInSlot>) {
            const Vec2 n = rotation(body_angle(model, k.pi.body, q)) * perp(k.axis_local);
            const double normal = -lambda(r);
            out.push_back(normal * n.x());
            out.push_back(normal * n.y());
            if constexpr (std::is_same_v<T, Prismatic>) out.push_back(-lambda(r + 1));
            out.push_back(normal);
          } else if constexpr (std::is_same_v<T, GearPair>) {
            out.push_back(lambda(r));
          } else {  // Distance: force on the first body = −λ d / L; tension along e = d/|d|
            const Vec2 d =
                point_kinematics(model, k.pj, q, none).r - point_kinematics(model, k.pi, q, none).r;
            const Vec2 F = -lambda(r) * d / k.length;
            out.push_back(F.x());
            out.push_back(F.y());
            out.push_back(F.dot(d.normalized()));
          }
        },
        joint.kind);
  }
}

namespace {

// Minimum-norm λ with E λ = R, and the null space N of E (redundancy directions) (C4).
void solve_multipliers(const Workspace& ws, DrivenWorkspace& w, VecX& lambda) {
  const Chart& c = ws.dual.chart;
  const MatX& Et = ws.constraints.Et;
  const int r = c.rank();
  const int k = static_cast<int>(w.other_rows.size());
  for (int i = 0; i < r; ++i) w.Er.col(i) = Et.row(c.rows[static_cast<size_t>(i)]).transpose();
  w.ErtEr.noalias() = w.Er.transpose() * w.Er;
  w.ErtEr_llt.compute(w.ErtEr);
  w.rhs_r.noalias() = w.Er.transpose() * w.R;
  w.ErtEr_llt.solveInPlace(w.rhs_r);
  lambda.setZero();
  for (int i = 0; i < r; ++i) lambda(c.rows[static_cast<size_t>(i)]) = w.rhs_r(i);
  if (k == 0) return;
  // Complement rows X, then N = [−(ErᵀEr)⁻¹ Erᵀ Ex; I] in row order.
  int next = 0;
  for (int row = 0, ci = 0; row < Et.rows(); ++row) {
    if (ci < r && c.rows[static_cast<size_t>(ci)] == row) {
      ++ci;
      continue;
    }
    w.other_rows[static_cast<size_t>(next++)] = row;
  }
  for (int j = 0; j < k; ++j) {
    w.rhs_r.noalias() = w.Er.transpose() * Et.row(w.other_rows[static_cast<size_t>(j)]).transpose();
    w.ErtEr_llt.solveInPlace(w.rhs_r);
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

}  // namespace

bool compute_driven(const Model& model, int driver_joint, double sdot, double sddot, State& state,
                    Workspace& ws, DrivenWorkspace& w, DrivenPoint& out) {
  const MeasureKind input = JointCoordinate{driver_joint};
  // Positions: F, H in the current chart (u = 0 first: F depends on q only).
  state.u.setZero();
  if (evaluate_dual(model, state, ws) != ProjectionStatus::ok) return false;
  const auto& F = ws.dual.F;
  (void)compute_scalar(model, input, state.q, nullptr, w.d);
  const double dTF = w.d.dot(F.col(0));
  const double scale = w.d.norm() * F.col(0).norm();
  out.dTF = scale > 0.0 ? dTF / scale : 0.0;
  if (!(std::abs(out.dTF) > 1e-12)) return false;  // dead point: the driver cannot drive
  // (C1) velocities.
  const double v = sdot / dTF;
  state.u.noalias() = F.col(0) * v;
  // Rate terms at (q, u): Dᵀu, Q̂(q, u), Ṁ, ḋu.
  compute_constraints(model, state, ws.constraints);
  compute_free_system(model, state, ws);
  const ScalarKinematics sk = compute_scalar(model, input, state.q, &state.u, w.d);
  solve_chart(ws, ws.constraints.Dtu, w.Fdot_v);  // x_D = (E_RDᵀ)⁻¹ (Dᵀu)_R
  w.Fdot_v = -w.Fdot_v;                           // Eᵀ (Ḟ v) = −Dᵀ u
  // (C2) accelerations.
  const double vdot = (sddot - sk.ddot_u - w.d.dot(w.Fdot_v)) / dTF;
  out.udot = F.col(0) * vdot + w.Fdot_v;
  // (C3) drive: Fᵀ(M u̇ + Ṁu − Q̂) = (Fᵀd) τ.
  w.R.noalias() = ws.free.M * out.udot;
  if (!ws.free.constant_mass) w.R.noalias() += ws.free.Mdot * state.u;
  w.R -= ws.free.Q;
  out.drive = F.col(0).dot(w.R) / dTF;
  // (C4) reactions: E λ = M u̇ + Ṁu − Q̂ − d τ.
  w.R -= out.drive * w.d;
  out.lambda.resize(model.nc);
  solve_multipliers(ws, w, out.lambda);
  out.q = state.q;
  out.u = state.u;
  return true;
}

namespace {

struct Sweep {
  const Model& model;
  int joint;
  Workspace& ws;
  DrivenWorkspace& w;

  // Newton with the input locked: [f_R(q); s(q) − target] = 0, Jacobian [E_Rᵀ; dᵀ]. A step
  // longer than max_step (a jump towards another branch or another turn of an angle) fails.
  bool locked_corrector(VecX& q, double target, double max_step) {
    const MeasureKind input = JointCoordinate{joint};
    const Chart& c = ws.dual.chart;
    const int r = c.rank();
    for (int it = 0; it < 30; ++it) {
      compute_constraint_residual(model, q, ws.constraints.f);
      const double s = compute_scalar(model, input, q, nullptr, w.d).value;
      double res = std::abs(s - target);
      for (int i = 0; i < r; ++i) {
        w.g(i) = ws.constraints.f(c.rows[static_cast<size_t>(i)]);
        res = std::max(res, std::abs(w.g(i)));
      }
      w.g(r) = s - target;
      if (res < 1e-12) return true;
      compute_constraint_jacobian(model, q, ws.constraints.Et);
      for (int i = 0; i < r; ++i)
        w.J.row(i) = ws.constraints.Et.row(c.rows[static_cast<size_t>(i)]);
      w.J.row(r) = w.d.transpose();
      w.J_lu.compute(w.J);
      const auto U = w.J_lu.matrixLU().diagonal().cwiseAbs();
      if (!(U.minCoeff() > 1e-13 * U.maxCoeff())) return false;
      w.dq = w.J_lu.solve(w.g);
      if (!(w.dq.cwiseAbs().maxCoeff() <= max_step)) return false;
      integrate_positions(model, q, w.dq, -1.0);
      if (!q.allFinite()) return false;
    }
    return false;
  }
};

}  // namespace

CycleResult run_cycle(const Model& model, const CycleOptions& options) {
  CycleResult result;
  const int joint = options.driver.joint;
  if (joint < 0 || joint >= static_cast<int>(model.joints.size())) {
    result.message = "no driver joint";
    return result;
  }
  const bool angular =
      std::holds_alternative<Revolute>(model.joints[static_cast<size_t>(joint)].kind);
  const double speed = options.driver.speed;
  if (!(std::abs(speed) > 0.0)) {
    result.message = "the driver's speed must not be zero";
    return result;
  }
  // Start: the design position projected onto f(q) = 0.
  State state(model);
  state.q = model.design_q();
  const SolveResult assembly = project_positions(model, state.q);
  if (assembly.status != SolveStatus::converged) {
    result.message = "the design position does not assemble (residual " +
                     std::to_string(assembly.residual) + ")";
    return result;
  }
  const Mobility mob = compute_mobility(model, state.q);
  result.rank = mob.rank;
  result.dof = mob.dof;
  result.redundant = model.nc - mob.rank;
  if (mob.dof != 1) {
    result.message =
        "a single driver needs a mechanism with 1 DOF; this one has " + std::to_string(mob.dof);
    return result;
  }
  Workspace ws(model, mob.rank);
  DrivenWorkspace w(model, mob.rank);
  Sweep sweep{model, joint, ws, w};
  const MeasureKind input = JointCoordinate{joint};
  (void)evaluate_dual(model, state, ws);
  double s0 = compute_scalar(model, input, state.q, nullptr).value;
  if (options.use_start) {
    if (!sweep.locked_corrector(state.q, options.start, std::numeric_limits<double>::infinity())) {
      result.message = "cannot reach the start input " + std::to_string(options.start);
      return result;
    }
    s0 = options.start;
  }
  const int steps = std::max(2, options.steps);
  double span = options.full_cycle ? (angular ? 2.0 * std::numbers::pi : 0.0) : options.end - s0;
  if (options.full_cycle && !angular) {
    result.message = "a full cycle needs a revolute driver; give the input range (start/end)";
    return result;
  }
  if (speed < 0.0 && options.full_cycle) span = -span;
  const double ds = options.full_cycle ? span / steps : span / (steps - 1);
  const double sdot = options.full_cycle ? speed : std::copysign(std::abs(speed), span);

  result.components = reaction_components(model);
  result.row_names.reserve(static_cast<size_t>(model.nc));
  for (int r = 0; r < model.nc; ++r) result.row_names.push_back(model.constraint_row_name(r));
  result.points.reserve(static_cast<size_t>(steps));

  auto evaluate_at = [&](const VecX& q, double s, DrivenPoint& p) {
    state.q = q;
    state.t = (s - s0) / sdot;
    if (!compute_driven(model, joint, sdot, 0.0, state, ws, w, p)) return false;
    p.input = s;
    p.time = state.t;
    p.singular = false;
    compute_reactions(model, state.q, p.lambda, p.reactions);
    p.measures.clear();
    for (const Measure& m : model.measures)
      p.measures.push_back(evaluate_measure(model, m, state.q, &state.u, &p.udot));
    p.kinetic = kinetic_energy(model, state);
    p.potential = potential_energy(model, state.q);
    p.dissipated = dissipated_power(model, state);
    return true;
  };

  VecX q = state.q;
  DrivenPoint point;
  if (!evaluate_at(q, s0, point)) {
    result.status = CycleStatus::stopped_at_dead_point;
    result.dead_points.push_back({s0, 0.0, "the start position is a dead point of the driver"});
    result.message = result.dead_points.back().message;
    return result;
  }
  result.points.push_back(point);
  VecX trial(model.nq);  // predictor/corrector iterate, reused across positions
  for (int k = 1; k < steps; ++k) {
    const double target = s0 + k * ds;
    const DrivenPoint& prev = result.points.back();
    // Predictor along the curve: q(s + Δs) ≈ q + (u/ṡ) Δs + ½ (u̇/ṡ²) Δs² (ṡ constant).
    // The curvature term is used only where it is smaller than the tangent step (next to a
    // singular position u̇ is unreliable).
    const double first = (ds / sdot) * prev.u.cwiseAbs().maxCoeff();
    const double second = (0.5 * ds * ds / (sdot * sdot)) * prev.udot.cwiseAbs().maxCoeff();
    const double curvature = second <= first ? 1.0 : 0.0;
    trial = prev.q + (ds / sdot) * prev.u + curvature * (0.5 * ds * ds / (sdot * sdot)) * prev.udot;
    // Corrections beyond twice the size of the tangent step would leave the branch.
    const double max_step = 2.0 * first + 1e-12;
    // Same branch: the velocity keeps its direction (a jump across a fold reverses it; the sign
    // of dᵀF alone changes with the chart's orientation).
    bool ok = sweep.locked_corrector(trial, target, max_step) &&
              evaluate_at(trial, target, point) && point.u.dot(prev.u) > 0.0;
    if (!ok) {
      // A change point (E loses rank, e.g. a parallelogram in line) is singular only exactly
      // there: the input passes. Retry just beyond it from the same predictor; a fold (dead
      // point) stays impassable.
      for (const double shift : {1e-6, 1e-4}) {
        const double shifted = target + shift * ds;
        VecX t2 = prev.q + ((shifted - prev.input) / sdot) * prev.u +
                  curvature *
                      (0.5 * (shifted - prev.input) * (shifted - prev.input) / (sdot * sdot)) *
                      prev.udot;
        if (sweep.locked_corrector(t2, shifted, max_step) && evaluate_at(t2, shifted, point) &&
            point.u.dot(prev.u) > 0.0) {
          result.singular_positions.push_back(
              {target, (target - s0) / sdot,
               "singular position (E loses rank) at input " + std::to_string(target) +
                   (angular ? " rad" : " m") +
                   ": passed, branch kept by continuity of the tangent"});
          point.singular = true;
          ok = true;
          break;
        }
      }
    }
    if (!ok) {
      // Dead point between the last good input and the target: bisection on the input.
      double lo = prev.input, hi = target;
      VecX q_lo = prev.q;
      while (std::abs(hi - lo) > options.dead_point_tolerance) {
        const double mid = 0.5 * (lo + hi);
        VecX qm = q_lo + ((mid - lo) / sdot) * prev.u;
        DrivenPoint probe;
        if (sweep.locked_corrector(qm, mid, max_step) && evaluate_at(qm, mid, probe) &&
            probe.u.dot(prev.u) > 0.0) {
          lo = mid;
          q_lo = qm;
        } else {
          hi = mid;
        }
      }
      result.dead_points.push_back(
          {lo, (lo - s0) / sdot,
           "dead point of driver joint '" + model.joints[static_cast<size_t>(joint)].name +
               "': the input cannot pass " + std::to_string(lo) + (angular ? " rad" : " m")});
      result.status = CycleStatus::stopped_at_dead_point;
      result.message = result.dead_points.back().message;
      break;
    }
    result.points.push_back(point);
  }
  if (result.status != CycleStatus::stopped_at_dead_point) result.status = CycleStatus::completed;
  result.chart_switches = ws.dual.switch_count;

  // Determinacy: component cᵀλ is unique iff Nᵀc = 0 (c from the linear map λ → components).
  const size_t nk = result.components.size();
  result.determinate.assign(nk, true);
  result.row_determinate.assign(static_cast<size_t>(model.nc), true);
  if (result.redundant > 0) {
    const VecX& q_ref = result.points.back().q;
    const MatX& N = w.N;  // from the last position; the redundancy pattern is constant on a branch
    const double tol = 1e-8 * (1.0 + N.norm());
    for (int r = 0; r < model.nc; ++r)
      result.row_determinate[static_cast<size_t>(r)] = N.row(r).norm() < tol;
    MatX C(static_cast<Eigen::Index>(nk), model.nc);
    std::vector<double> values;
    for (int r = 0; r < model.nc; ++r) {
      compute_reactions(model, q_ref, VecX::Unit(model.nc, r), values);
      for (size_t i = 0; i < nk; ++i) C(static_cast<Eigen::Index>(i), r) = values[i];
    }
    for (size_t i = 0; i < nk; ++i)
      result.determinate[i] =
          (N.transpose() * C.row(static_cast<Eigen::Index>(i)).transpose()).norm() <
          tol * (1.0 + C.row(static_cast<Eigen::Index>(i)).norm());
  }
  return result;
}

}  // namespace orthomech
