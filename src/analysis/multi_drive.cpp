#include "orthomech/analysis/multi_drive.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "orthomech/analysis/assembly.hpp"
#include "orthomech/analysis/mobility.hpp"
#include "orthomech/analysis/positions.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/model/measures.hpp"
#include "orthomech/projection/dual.hpp"

namespace orthomech {

const char* to_string(MultiDriveStatus s) {
  switch (s) {
    case MultiDriveStatus::completed:
      return "completed";
    case MultiDriveStatus::invalid_request:
      return "invalid_request";
    case MultiDriveStatus::stopped:
      return "stopped";
    case MultiDriveStatus::failed:
      return "failed";
  }
  return "?";
}

namespace {

// The sweep's state: the model, the drivers' joints and laws, the workspaces.
struct MultiSweep {
  const Model& model;
  const MultiDriveOptions& options;
  std::vector<int> joints;
  VecX s0;  // the driven coordinates at the design position (constant-speed laws start there)
  Workspace& ws;
  DrivenWorkspace& w;
  State state;
  PositionOptions hold;

  void targets(double t, VecX& s, VecX& sdot, VecX& sddot) const {
    const Eigen::Index m = static_cast<Eigen::Index>(joints.size());
    s.resize(m), sdot.resize(m), sddot.resize(m);
    for (Eigen::Index i = 0; i < m; ++i)
      driver_law(options.drivers[static_cast<size_t>(i)], s0(i), t, s(i), sdot(i), sddot(i));
  }

  // Everything at a converged q and time t; false where the drivers cannot move the mechanism.
  bool evaluate(const VecX& q, double t, MultiDrivenPoint& p) {
    VecX s, sdot, sddot;
    targets(t, s, sdot, sddot);
    state.q = q;
    state.t = t;
    if (!compute_multi_driven(model, joints, sdot, sddot, state, ws, w, p)) return false;
    p.time = t;
    p.inputs = s;
    w.rotations.update(model, state.q);
    compute_driven_outputs(model, state, p.lambda, p.udot, w.rotations,
                           {p.reactions, p.measures, p.kinetic, p.potential, p.dissipated});
    return true;
  }

  // Projects q onto f(q) = 0 with every driven joint held at s(t).
  bool hold_at(VecX& q, double t) {
    VecX s, sdot, sddot;
    targets(t, s, sdot, sddot);
    for (size_t i = 0; i < joints.size(); ++i)
      hold.locks[i].value = s(static_cast<Eigen::Index>(i));
    return project_positions(model, q, hold).status == SolveStatus::converged;
  }

  // One step from a converged point to time t: predictor q ⊕ (u h + ½ u̇ h²), projection with the
  // inputs held; refused when the correction is not small against the step (a jump to another
  // assembly mode).
  bool step(const MultiDrivenPoint& from, double t, MultiDrivenPoint& out) {
    const double h = t - from.time;
    const VecX du = h * from.u + 0.5 * h * h * from.udot;
    VecX q = from.q;
    integrate_positions(model, q, du, 1.0);
    const VecX predicted = q;
    if (!hold_at(q, t)) return false;
    VecX correction(model.n);
    difference_positions(model, q, predicted, correction);
    if (!(correction.norm() <= 0.25 * du.norm() + 1e-12)) return false;
    return evaluate(q, t, out);
  }
};

// Where the Gauss–Newton hold does not close the drawn position (a rough sketch), `assemble`'s
// own projection (Ipopt, eq. (20)) with the drivers locked at their values at t = 0 and no
// limits, then the hold from there: the sweep starts wherever `assemble --lock` says the
// mechanism assembles (one criterion, as the single-driver cycle). False with assemble's account
// of the gaps in `why`.
bool close_with_assemble(const Model& model, const VecX& drawn, MultiSweep& sweep, VecX& q,
                         std::string& why) {
  AssemblyOptions ao;
  ao.use_limits = false;
  for (const PositionOptions::Lock& l : sweep.hold.locks) ao.locks.push_back({l.joint, l.value});
  const AssemblyResult a = assemble(model, drawn, ao);
  if (a.status != AssemblyStatus::assembled && a.status != AssemblyStatus::unchanged) {
    why = a.message;
    return false;
  }
  q = a.q;
  return sweep.hold_at(q, 0.0);
}

std::string joint_list(const Model& model, const std::vector<int>& joints) {
  std::string s;
  for (const int j : joints)
    s += (s.empty() ? "'" : ", '") + model.joints[static_cast<size_t>(j)].name + "'";
  return s;
}

}  // namespace

MultiDriveResult run_multi_drive(const Model& model, const MultiDriveOptions& options) {
  MultiDriveResult result;
  result.components = reaction_components(model);
  result.determinate.assign(result.components.size(), true);
  const size_t m = options.drivers.size();
  if (m == 0) {
    result.status = MultiDriveStatus::invalid_request;
    result.message = "no drivers";
    return result;
  }
  std::vector<int> joints;
  for (const Driver& d : options.drivers) {
    if (d.joint < 0 || d.joint >= static_cast<int>(model.joints.size()) ||
        joint_coordinate_kind(model.joints[static_cast<size_t>(d.joint)]) == CoordinateKind::none) {
      result.status = MultiDriveStatus::invalid_request;
      result.message = "driver '" + d.name + "' needs a joint with a coordinate";
      return result;
    }
    if (std::find(joints.begin(), joints.end(), d.joint) != joints.end()) {
      result.status = MultiDriveStatus::invalid_request;
      result.message =
          "two drivers on joint '" + model.joints[static_cast<size_t>(d.joint)].name + "'";
      return result;
    }
    if (d.profile == Profile::constant_speed && !(std::abs(d.speed) > 0.0)) {
      result.status = MultiDriveStatus::invalid_request;
      result.message = "driver '" + d.name + "': the speed must not be zero";
      return result;
    }
    joints.push_back(d.joint);
  }
  if (!model.knife_edges.empty() || !model.rolling_discs.empty()) {
    result.status = MultiDriveStatus::invalid_request;
    result.message =
        "the mechanism has nonholonomic constraints: its positions do not follow from the inputs";
    return result;
  }
  // The sweep's end: given, else one period of the slowest law.
  double period = 0.0;
  for (size_t i = 0; i < m; ++i) {
    const Driver& d = options.drivers[i];
    const bool angular = joint_coordinate_kind(model.joints[static_cast<size_t>(joints[i])]) ==
                         CoordinateKind::angle;
    if (d.profile == Profile::harmonic)
      period = std::max(period, 1.0 / d.frequency);
    else if (d.profile == Profile::constant_speed && angular)
      period = std::max(period, 2.0 * std::numbers::pi / std::abs(d.speed));
  }
  result.t_end = options.t_end > 0.0 ? options.t_end : period;
  if (!(result.t_end > 0.0)) {
    result.status = MultiDriveStatus::invalid_request;
    result.message =
        "no driver has a period (polynomial laws, constant-speed slides): give the end time "
        "(--t-end)";
    return result;
  }
  const int steps = std::max(2, options.steps);

  // Start: the design position with every driven joint held at s(0).
  State start(model);
  const VecX drawn = model.design_q();
  VecX s0(static_cast<Eigen::Index>(m));
  for (size_t i = 0; i < m; ++i)
    s0(static_cast<Eigen::Index>(i)) =
        compute_scalar(model, JointCoordinate{joints[i]}, drawn, nullptr).value;
  const Mobility mob0 = compute_mobility(model, drawn);
  Workspace ws(model, mob0.rank);
  DrivenWorkspace w(model, mob0.rank);
  MultiSweep sweep{model, options, joints, s0, ws, w, State(model), {}};
  sweep.hold.tolerance = 1e-13;
  for (const int j : joints) sweep.hold.locks.push_back({j, 0.0});
  VecX q = drawn;
  std::string why;
  if (!sweep.hold_at(q, 0.0) && !close_with_assemble(model, drawn, sweep, q, why)) {
    result.status = MultiDriveStatus::failed;
    result.message = "the design position does not assemble with the drivers " +
                     joint_list(model, joints) + " at their values at t = 0" +
                     (why.empty() ? "" : ": " + why);
    return result;
  }
  const Mobility mob = compute_mobility(model, q);
  result.dof = mob.dof;
  result.rank = mob.rank;
  result.redundant = model.nc - mob.rank;
  if (mob.dof != static_cast<int>(m)) {
    result.status = MultiDriveStatus::invalid_request;
    result.message = std::to_string(m) + " drivers need a mechanism with " + std::to_string(m) +
                     " DOF; this one has " + std::to_string(mob.dof);
    return result;
  }
  if (mob.rank != mob0.rank) {  // the workspaces are sized by the rank
    result.status = MultiDriveStatus::failed;
    result.message =
        "the rank of the constraints changes between the drawn and the assembled "
        "position";
    return result;
  }
  MultiDrivenPoint point, next;
  if (!sweep.evaluate(q, 0.0, point)) {
    result.status = MultiDriveStatus::stopped;
    result.message = "the start is a singular position of the drivers " +
                     joint_list(model, joints) + ": they cannot move the mechanism there";
    return result;
  }
  // Determinacy (as `cycle`): component cᵀλ is unique iff it vanishes for every λ in null(E).
  std::vector<double> null_values;
  auto update_determinacy = [&](const MultiDrivenPoint& p) {
    for (Eigen::Index j = 0; j < w.N.cols(); ++j) {
      const double tol = 1e-8 * w.N.col(j).norm();
      compute_reactions(model, p.q, w.N.col(j), null_values);
      for (size_t i = 0; i < null_values.size(); ++i)
        if (std::abs(null_values[i]) > tol) result.determinate[i] = false;
    }
  };
  update_determinacy(point);
  result.points.push_back(point);
  const double dt = result.t_end / (steps - 1);
  result.status = MultiDriveStatus::completed;
  for (int k = 1; k < steps; ++k) {
    const double t = k == steps - 1 ? result.t_end : k * dt;
    // Reach t: the whole step, else halved sub-steps (doubled again after a success).
    MultiDrivenPoint cur = result.points.back();
    double h = t - cur.time;
    bool reached = false;
    for (int guard = 0; guard < 200 && !reached; ++guard) {
      const bool last = cur.time + h >= t - 1e-12 * dt;
      const double t_next = last ? t : cur.time + h;
      if (sweep.step(cur, t_next, next)) {
        if (last) {
          reached = true;
          break;
        }
        cur = next;
        h = std::min(2.0 * h, t - cur.time);
        continue;
      }
      h *= 0.5;
      if (h < 1e-9 * dt) break;
    }
    if (!reached) {
      result.status = MultiDriveStatus::stopped;
      result.message = "the drivers " + joint_list(model, joints) +
                       " cannot move the mechanism past t = " + std::to_string(cur.time) +
                       " s (a singular position of the drivers, or the joints cannot close); "
                       "the positions before it are reported";
      break;
    }
    update_determinacy(next);
    result.points.push_back(next);
  }
  return result;
}

}  // namespace orthomech
