#include "orthomech/dynamics/simulate.hpp"

#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "dynamics.hpp"
#include "events.hpp"
#include "integrator.hpp"
#include "orthomech/analysis/assembly.hpp"
#include "orthomech/analysis/cycle_metrics.hpp"
#include "orthomech/analysis/mobility.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/constraints/sparse_et.hpp"
#include "orthomech/dynamics/equations.hpp"
#include "orthomech/io/units.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/model/loads.hpp"
#include "orthomech/model/measures.hpp"
#include "orthomech/model/spatial.hpp"
#include "orthomech/numerics/weighted_gram.hpp"
#include "orthomech/projection/dual.hpp"
#include "orthomech/projection/free_system_stage.hpp"
#include "orthomech/projection/primal.hpp"
#include "stop_contacts.hpp"

namespace orthomech {

const char* to_string(SimulateStatus s) {
  switch (s) {
    case SimulateStatus::completed:
      return "completed";
    case SimulateStatus::failed_assembly:
      return "failed_assembly";
    case SimulateStatus::failed_step:
      return "failed_step";
    case SimulateStatus::singular:
      return "singular";
    case SimulateStatus::energy_drift:
      return "energy_drift";
    case SimulateStatus::stopped:
      return "stopped";
    case SimulateStatus::sliding:
      return "sliding";
    case SimulateStatus::resting:
      return "resting";
  }
  return "?";
}

double energy_drift_limit(double rtol) {
  return std::max(kEnergyDriftFloor, kEnergyDriftFactor * rtol);
}

std::string request_problem(const SimulateOptions& o) {
  if (!(o.max_steps > 0) || o.max_steps > kMaxMaxSteps)
    return "the step budget (--max-steps) must be from 1 to " + std::to_string(kMaxMaxSteps);
  if (o.max_step > 0.0 && o.t_end / o.max_step > static_cast<double>(o.max_steps)) {
    char need[32];
    std::snprintf(need, sizeof need, "%.3g", o.t_end / o.max_step);
    return std::string("--t-end / --max-step needs at least ") + need +
           " steps, more than the step budget of " + std::to_string(o.max_steps) +
           " (--max-steps): give a larger --max-step or a larger --max-steps";
  }
  if (!(o.control.time_limit >= 0.0) || !std::isfinite(o.control.time_limit))
    return "the time limit (--time-limit) must be a finite number of seconds, 0 for none";
  return "";
}

const char* to_string(Integrator i) {
  switch (i) {
    case Integrator::dopri5:
      return "dopri5";
    case Integrator::rkf78:
      return "rkf78";
    case Integrator::bulirsch_stoer:
      return "bulirsch-stoer";
    case Integrator::rosenbrock4:
      return "rosenbrock4";
  }
  return "?";
}

bool parse_integrator(const std::string& name, Integrator& out) {
  for (const Integrator i :
       {Integrator::dopri5, Integrator::rkf78, Integrator::bulirsch_stoer, Integrator::rosenbrock4})
    if (name == to_string(i)) {
      out = i;
      return true;
    }
  return false;
}

namespace {

using detail::Dynamics;
using detail::Events;
using detail::SingularEvaluation;
using detail::StopContacts;
using detail::StopHit;
using detail::time_text;

detail::OdeStepper ode_stepper(Integrator i) {
  switch (i) {
    case Integrator::dopri5:
      return detail::OdeStepper::dopri5;
    case Integrator::rkf78:
      return detail::OdeStepper::rkf78;
    case Integrator::bulirsch_stoer:
      return detail::OdeStepper::bulirsch_stoer;
    case Integrator::rosenbrock4:
      return detail::OdeStepper::rosenbrock4;
  }
  return detail::OdeStepper::dopri5;
}

// Chart monitor (dual form): re-select the chart when an entry of F in the mass metric exceeds
// this (a dependent velocity then moves 4 times faster, in energy terms, than the independent
// ones). The new chart is chosen from the current F (ChartEngine::select_from_tangent), whose
// entries are then ≤ 1 for n_a = 1: the hysteresis is the factor 4.
constexpr double kSpreadLimit = 4.0;
// Per-step position correction: a Newton step more than this many times the residual means the
// chart's dependent block is nearly singular (a change point, IFToMM A02): the step is then
// left uncorrected (its residual is the integrator's local error) rather than risk a jump to
// another branch; counted in SimulateResult::uncorrected_steps.
constexpr double kMaxCorrectionGain = 1e4;
// A step ends at most this fraction of the way to the chart's singularity extrapolated from the
// spread (1/spread linear in t next to it).
constexpr double kChartStepFraction = 0.5;
// Within kWatchQuality a step ends at most this fraction of σ̂ / max |dσ̂/dt| ahead
// (limit_step_by_quality): 1, the earliest σ̂ could reach 0. It costs the N = 40 bar 5–20 % more
// steps (rkf78 at rtol 1e-8: 0.19 → 0.22 s; 0.5 gave 0.24 s), mostly after each landing, where
// σ̂ rises from 1e-3 and the limit lets the steps only double.
constexpr double kQualityStepFraction = 1.0;

// Where the tangents σ̂₀ + σ̂'₀τ and σ̂₁ + σ̂'₁(τ − h) of σ̂ at the ends of a step of length h
// meet (σ̂'₀ < 0 < σ̂'₁: a V through a change point), τ in [0, h].
[[nodiscard]] double tangents_meet(double s0, double d0, double s1, double d1, double h) {
  return std::clamp((s0 - s1 + d1 * h) / (d1 - d0), 0.0, h);
}

// Change points (docs/theory.md, "Change points"; (C1)–(C6) there). σ̂ is the chart quality,
// σ_min of the chart's dependent block in the mass metric relative to the largest mass-scaled
// column norm of Eᵀ at the start; it falls linearly to 0 at a change point.
// Watch: below this σ̂, a falling σ̂ is extrapolated to its zero t* (C1).
constexpr double kWatchQuality = 0.3;
// Reach: t* within this many of the last step sizes is within reach of the next step (odeint's
// controllers grow a step by at most 5): the integrator is stopped and the point approached.
constexpr double kReachSteps = 6.0;
// Pass: at σ̂ ≤ pass_quality the point is passed by one passage step (C3)–(C5), first tried at
// kPassQuality. A passage whose checks fail is tried again from 4 times closer (its truncation
// error, O(h⁵), falls 1000-fold; a branch jump does not), down to kPassQualityFloor, where the
// run stops. Closer is not always better: off f(q) = 0 by c, F bends by ~c/σ² (rounding c):
// the passage's own noise grows as σ̂ falls.
constexpr double kPassQuality = 1e-3;
constexpr double kPassQualityFloor = 1e-6;
// Inverse iterations per accepted step for the primal form's chart-free σ̂ (warm-started: the
// eigenvector moves little between steps, and next to a change point λ_min is far below the
// rest of G's spectrum, where one iteration already gains that ratio).
constexpr int kPrimalQualityIterations = 3;
// The primal form stops ahead of a change point when its σ̂ = √λ_min(G)/σ_ref falls to this (or
// the point is within kReachSteps steps). Below kPassQuality: the chart-free σ̂ of a regular
// mechanism may sit there for a whole run (the RSSR of mechanisms/rssr.yaml: about 5e-4 in
// metres and kilograms, E regular), and G's solves keep ~ε/σ̂² ≈ 2e-8 of their accuracy at 1e-4.
// Not lower: rosenbrock4 evaluates G at stages beyond the step, which fail on a singular G
// within ~1e-5 of the point (N-four-bar of N = 40, PrimalAtChangePoint).
constexpr double kPrimalStopQuality = 1e-4;
constexpr double kRetry = 0.25;  // 4 times closer (above)
// A passage that fails only its energy balance (C6 (v)) is tried again from 2 times closer: its
// step halves, its truncation error (O(h⁷)) falls ~128-fold, its rounding noise (~ε/σ̂²) grows
// only 4-fold.
constexpr double kTruncationRetry = 0.5;
// A passage whose velocity jump fails its bound while its energy balance (the truncation) is
// well below the jump fails by the landing's rounding noise, which grows as σ̂ falls (~1/σ̂: on the
// triple-crank 1.1e-9 from σ̂ = 1e-3, 1.7e-8 from 2e-4, 1e-12 … 1e-11 from 1e-2): it is tried again
// from the last step end with σ̂ in [kFarPassQuality, kFarPassQualityMax] (the approach's steps end
// about 4 times apart in σ̂), at most kMaxFartherRetries times per change point.
constexpr double kFarPassQuality = 3e-3;
constexpr double kFarPassQualityMax = 3e-2;
constexpr int kMaxFartherRetries = 2;
// Approach: each approach segment covers at most this fraction of the way to t* and aims at
// kApproachTarget · pass_quality.
constexpr double kApproachFraction = 0.75;
constexpr double kApproachTarget = 0.8;
// Steps of an approach segment at most this fraction of the estimated distance to t*: far from
// the point σ̂ is not yet linear and t* is rough; every step re-estimates it (C2). 0.5 rather
// than 0.25: over 216 runs (bennett, n-four-bar-2 and -40, triple-crank; dopri5, rkf78,
// bulirsch-stoer; rtol 1e-5 … 1e-10; outputs every 0.01, 1, 20 s; 20 s each) 1 to 13 % fewer
// evaluations per mechanism, the energy drift unchanged on average (its log10 −0.04), and the
// triple-crank passes every point in all 54 of its runs (three stopped at t ≈ 5.15 s with
// 0.25); 0.75 saved 1 to 9 % more but let one run's drift grow 90-fold (bennett rkf78 1e-8).
constexpr double kApproachStep = 0.5;
constexpr int kMaxApproaches = 60;
// A falling σ̂ whose parabola through the last three values bottoms out above this fraction of
// the current value is heading for a minimum above 0 (a well-conditioned position), not for a
// change point (where σ̂ is linear in t near its zero).
constexpr double kMinimumAboveZero = 0.5;
// (C2') a V of σ̂ through 0 across two steps: the third σ̂ within this fraction of the V's.
constexpr double kVShapeTolerance = 1.0;
// (C2'') a change point inside one step: the tangents of σ̂ at its ends meet below this fraction
// of the smaller end value (≈ 0 at a change point, where σ̂ ≈ a |t − t*|; ≈ the minimum at a
// regular minimum that the step resolves). Undone at most kMaxCrossingRewinds times in a row.
constexpr double kCrossingVertex = 0.5;
constexpr int kMaxCrossingRewinds = 30;
// Passage checks (C6). Velocity jump: the quadrature velocity at the landing is admissible up
// to the step's truncation and rounding error; a landing on another branch removes the
// velocity's component normal to that branch's tangent (8e-2 relative on the N = 40 bar with
// link0 held, O(1) in general). The bound is rtol/10 within [1e-9, 1e-7]: the passage is then
// about as accurate as the steps around it (20 passages with 3e-9 put B0 of the N = 40 bar 3e-6
// off at 20 s), and a branch jump is still refused by decades.
// Where the passage's own rounding noise is larger (the corrector stalls above 1e-10: 4e-10 on
// the triple-crank), the bound is 10× that noise, up to kPassageJumpCeiling.
constexpr double kPassageJumpCeiling = 1e-7;
// A velocity jump above this is a landing on another branch (1e-2 … 1 measured), below it (and
// above the bound) an accurate-enough passage was not achieved: the messages tell them apart.
constexpr double kBranchJump = 1e-3;
[[nodiscard]] double passage_velocity_jump_bound(double rtol) {
  return std::clamp(0.1 * rtol, 1e-9, kPassageJumpCeiling);
}
constexpr int kPassageIterations = 8;
// Corrector: iterated until the change of u (relative) is below kPassageConverged or stalls at
// the rounding noise of the stages (~1e-10 … 4e-10 measured next to the point); accepted if the
// last change is below kPassageConvergence, 10× under the jump bound's floor.
constexpr double kPassageConverged = 1e-11;
constexpr double kPassageConvergence = 1e-9;
// Landing: σ̂ after the passage at least this fraction of σ̂ before (beyond the point, regular).
constexpr double kLandingQualityRatio = 0.2;
// An ordinary step whose velocity changes by more than this (relative, mass metric) when made
// admissible at its corrected position left its branch (its own error is ~rtol).
constexpr double kStepVelocityJump = 1e-2;

// "K1.phi": the user's name of a velocity component.
std::string velocity_name(const Model& model, int k) {
  return free_system(model).velocity_name(model, k);
}

std::string chart_name(const Model& model, const Chart& c) {
  std::string s;
  for (size_t k = 0; k < c.independent.size(); ++k) {
    if (k) s.push_back(',');
    s.append(velocity_name(model, c.independent[k]));
  }
  return s;
}

// ---- The run, step by step -------------------------------------------------------------------

// 1. Consistent positions: mass-metric Gauss–Newton projection of the given position (q), and
// the rank of E there. False (result's status and message set) when the start is refused.
bool consistent_start(const Model& model, const State& initial, const SimulateOptions& options,
                      VecX& q, int& rank, Chart& chart, SimulateResult& result) {
  q = initial.q;
  PositionOptions popt;
  popt.tolerance = options.position_tolerance;
  result.assembly = project_positions(model, q, popt);
  if (result.assembly.status != SolveStatus::converged) {
    result.status = SimulateStatus::failed_assembly;
    result.message = "the initial position does not assemble: " + result.assembly.message;
    return false;
  }
  Mobility mob = compute_mobility(model, q);
  rank = mob.rank;
  chart = std::move(mob.chart);
  // A start on a change point: E has lost rank there, so the velocity has more admissible
  // directions than on any branch through it and no branch is defined by the start. Refused
  // when the rank is below that at the design position (the generic rank of the file).
  if (initial.q.size() == model.nq && initial.q != model.design_q()) {
    VecX qd = model.design_q();
    if (project_positions(model, qd, popt).status == SolveStatus::converged) {
      const int generic = compute_mobility(model, qd).rank;
      if (rank < generic) {
        result.status = SimulateStatus::singular;
        result.message =
            "the initial position is a change point: rank E = " + std::to_string(rank) +
            " there, " + std::to_string(generic) +
            " at the design position (the motion's branch is not defined there)";
        return false;
      }
    }
  }
  return true;
}

// The 4-stage Lobatto IIIA collocation method (order 6) [Hairer, Nørsett & Wanner, Solving ODEs
// II, §IV.5]: nodes c = (0, (5 ∓ √5)/10, 1), coefficients L.
struct LobattoIIIA {
  double r5 = std::sqrt(5.0);
  double c[4] = {0.0, (5.0 - r5) / 10.0, (5.0 + r5) / 10.0, 1.0};
  double L[4][4] = {{0.0, 0.0, 0.0, 0.0},
                    {(11 + r5) / 120, (25 - r5) / 120, (25 - 13 * r5) / 120, (-1 + r5) / 120},
                    {(11 - r5) / 120, (25 + 13 * r5) / 120, (25 + r5) / 120, (-1 - r5) / 120},
                    {1.0 / 12, 5.0 / 12, 5.0 / 12, 1.0 / 12}};
};

// One run of simulate() from a consistent start (q, rank): the run's state as members, its
// steps as methods, in the order run() calls them:
//   2. start_chart, consistent_velocities: the chart, F and u = α u₀ (eq. (70)) at the start;
//   3. initial_ode_state, start_monitor, set_up_problem, start_energy: the ODE, the output
//      grid, the change-point monitor and the energy balance;
//   drive: the integration in segments (run_to; accept after every step), undoing steps that
//      crossed a change point (rewind), approaching (approach) and passing (pass) change points;
//   finish: the final sample and status.
class Simulation {
 public:
  Simulation(const Model& model, const State& initial, const SimulateOptions& options,
             const VecX& q, int rank, Chart mobility_chart, SimulateResult result)
      : model_(model),
        mobility_chart_(std::move(mobility_chart)),
        initial_(initial),
        options_(options),
        result_(std::move(result)),
        primal_(options.form == DynamicsForm::primal),
        n_(model.n),
        nq_(model.nq),
        na_(model.n - rank),
        rank_(rank),
        nx_(primal_ ? model.nq + model.n + 1 : model.nq + model.n - rank + 1),
        dyn_(model, rank, options),
        q_(q),
        x_(nx_),
        f_(model.nc),
        dq_(model.n),
        u_step_(VecX::Zero(model.n)),
        T0_(initial.t),
        T1_(initial.t + options.t_end),
        dt_out_(options.dt_out > 0.0 ? options.dt_out : options.t_end / 100.0),
        grid_slack_(1e-12 * std::max(1.0, std::abs(T1_))),
        end_slack_(1e-14 * std::max(1.0, std::abs(T1_))),
        t_last_accept_(initial.t),
        events_(model, options.t_end),
        contacts_(model),
        rate_x_(VecX::Zero(model.n)),
        rate_plus_(VecX::Zero(model.nc)),
        rate_minus_(VecX::Zero(model.nc)),
        rate_state_(model),
        rate_rotations_(model),
        angular_row_(static_cast<size_t>(model.nc), 0),
        local_passage_(model.nq != model.n),
        monitor_run_(options.control, options.max_steps),
        window_t_(initial.t),
        t_now_(initial.t) {
    for (size_t j = 0; j < model.joints.size(); ++j)
      // (A joint with end stops stays within them, to the events' tolerance.)
      if (model.joints[j].limits && !model.joints[j].stop_restitution)
        limited_.push_back(static_cast<int>(j));
    limit_exits_.resize(limited_.size());
    result_.components = reaction_components(model);
  }

  [[nodiscard]] SimulateResult run() {
    // 2. Chart and F at q; velocities u = α u₀ (eq. (70)), then the requested rates.
    if (!start_chart()) {
      result_.status = SimulateStatus::singular;
      result_.message = "the initial position is singular (E loses rank there)";
      return std::move(result_);
    }
    const VecX v = consistent_velocities();
    initial_ode_state(v);
    start_monitor();
    set_up_problem();
    start_energy(v);
    drive();
    finish();
    deliver(true);
    return std::move(result_);
  }

 private:
  struct MonitorPoint {
    bool valid = false;
    double t = 0.0, sigma = 0.0;
    double rate = std::numeric_limits<double>::quiet_NaN();  // dσ̂/dt (NaN: unknown)
  };
  struct Request {
    bool pending = false;
    double t_star = 0.0, sigma = 0.0;
  };
  // The last two accepted states (with their charts): a step that crossed a change point
  // unannounced (C2') is undone back to the last state before it.
  struct SavedState {
    bool valid = false;
    double t = 0.0, sigma = 0.0, rate = 0.0;  // σ̂ and dσ̂/dt in `chart`
    double spread = 0.0;                      // the chart's spread (dual form; 0: unknown)
    VecX x;
    Chart chart;
    std::vector<std::uint8_t> load_on;  // the switched loads' modes (State::load_on)
    std::vector<StopHit> held;          // the stops held as resting contacts (Events::held)
    std::vector<double> pin_sign;       // the friction pins' held signs (Events::pin_signs)
  };
  // What the events ask of the run after a step (dynamics/events.hpp): nothing, a
  // restart of the integrator at the step's end (loads switched or an impact there), or the
  // location of a crossing inside the undone step.
  enum class EventRequest { none, restart, locate };

  // ---- 2. The start: chart, F and velocities ------------------------------------------------

  // The mobility's dense QR chose its chart at this q from the same Eᵀ with the same scaling
  // (A's diagonal) and options as the engine's select would (below kSparseSelectFrom the
  // engine's choice is that dense QR too): taken as it is rather than a second O(n³) QR
  // (N-four-bar-40: 4 of the 29 ms before the first step).
  [[nodiscard]] bool reuse_mobility_chart() const {
    return !mobility_chart_.rows.empty() && model_.n < ChartEngine::kSparseSelectFrom &&
           mobility_chart_.rank() == rank_ &&
           inverse_mass_diagonal(model_, q_) == dyn_.ws_.free.A_diag;
  }

  // The chart at q (selected from Eᵀ, then from F: the independent components that move
  // most), factorised, and F in it. False when the position is singular.
  bool start_chart() {
    dyn_.state_.q = q_;
    dyn_.state_.u.setZero();
    dyn_.free_system();
    compute_constraint_jacobian(model_, q_, dyn_.ws_.constraints.Et);
    if (reuse_mobility_chart()) {
      dyn_.cs_.set_chart(mobility_chart_);
    } else if (!dyn_.cs_.select(dyn_.ws_.constraints.Et, dyn_.ws_.free.A_diag)) {
      return false;
    }
    if (!dyn_.factor_chart(dyn_.ws_.constraints.Et)) return false;
    dyn_.compute_F();
    dyn_.cs_.select_from_tangent(dyn_.F_, dyn_.M_sqrt());  // independent components that move most
    if (!dyn_.factor_chart(dyn_.ws_.constraints.Et)) return false;
    dyn_.compute_F();
    return true;
  }

  // v: the chart coordinates of u = α u₀ (eq. (70)), changed by the requested initial rates.
  VecX consistent_velocities() {
    dyn_.compute_H();
    const VecX u0 = initial_.u.size() == n_ ? initial_.u : VecX::Zero(n_);
    VecX v = project_velocity(dyn_.MF_, dyn_.H_llt_, u0);
    {
      const VecX du = u0 - dyn_.F_ * v;
      result_.kinetic_removed = 0.5 * du.dot(dyn_.mass_times(du));
    }
    if (!options_.initial_rates.empty()) apply_initial_rates(v);
    return v;
  }

  // The requested rates of measures: the least-squares change of v (minimum-norm).
  void apply_initial_rates(VecX& v) const {
    const int m = static_cast<int>(options_.initial_rates.size());
    MatX D(m, n_);
    VecX s(m);
    for (int i = 0; i < m; ++i) {
      const InitialRate& ir = options_.initial_rates[static_cast<size_t>(i)];
      if (ir.measure < 0 || ir.measure >= static_cast<int>(model_.measures.size()))
        throw std::invalid_argument("simulate: initial rate of an unknown measure");
      VecX d(n_);
      (void)compute_scalar(model_, model_.measures[static_cast<size_t>(ir.measure)].kind, q_,
                           nullptr, d);
      D.row(i) = d.transpose();
      s(i) = ir.rate;
    }
    const MatX DF = D * dyn_.F_;
    const Eigen::CompleteOrthogonalDecomposition<MatX> cod(DF);
    v += cod.solve(s - DF * v);  // least-squares change of v (minimum-norm)
  }

  // ---- 3. The ODE, the monitor, the energy balance ------------------------------------------

  // 3. ODE state: dual (q, v, W) or primal (q, p, W); W = work of non-conservative loads.
  void initial_ode_state(const VecX& v) {
    x_.head(nq_) = q_;
    if (primal_)
      x_.segment(nq_, n_) = dyn_.mass_times(dyn_.F_ * v);  // p = M u, eq. (5)
    else
      x_.segment(nq_, na_) = v;
    x_(nx_ - 1) = 0.0;
  }

  // Change-point monitor (both forms): σ̂ = σ_min(E_RDᵀ S_D)/σ_ref at every accepted, corrected
  // state (ChartEngine::estimate_sigma_min; S = diag(1/√M_kk), σ_ref the largest mass-scaled
  // column norm of Eᵀ at the start). Near a change point σ̂ ≈ a |t − t*| (C1), so two states
  // give the estimate t* = t_k + σ̂_k (t_k − t_{k−1}) / (σ̂_{k−1} − σ̂_k).
  void start_monitor() {
    const SparseEt& Et = dyn_.ws_.constraints.Et;
    for (int k = 0; k < n_; ++k) {
      double norm2 = 0.0;
      for (const SparseEt::Entry& e : Et.column(k))
        norm2 += Et.values()[e.index] * Et.values()[e.index];
      sigma_ref_ = std::max(sigma_ref_, std::sqrt(norm2) * dyn_.ws_.free.A_sqrt(k));
    }
    if (!(sigma_ref_ > 0.0)) sigma_ref_ = 1.0;
  }

  // The integrator's problem (right-hand side, step acceptance, outputs, step limit) and
  // options; the rows of f that are angles.
  void set_up_problem() {
    problem_.rhs = [this](const VecX& y, VecX& dy, double t) { rhs(y, dy, t); };
    problem_.autonomous = orthomech::free_system(model_).forces_time_invariant();
    if (dyn_.project_stages_)
      problem_.jacobian_columns = [this](std::vector<Eigen::Index>& columns) {
        jacobian_columns(columns);
      };
    problem_.output = [this](double t, const VecX& y) { emit(t, y); };
    problem_.step_limit = [this] { return next_step_limit_; };
    problem_.accept = [this](double t, VecX& y) { return accept(t, y); };
    // Rows of f that are angles (joint components "angle", "ratio"): the residual by kind.
    for (const Joint& j : model_.joints) {
      const auto names = j.component_names();
      for (int k = 0; k < j.rows(); ++k)
        angular_row_[static_cast<size_t>(j.row_offset + k)] =
            is_angular_row(names[static_cast<size_t>(k)]) ? 1 : 0;
    }
    base_.stepper = ode_stepper(options_.integrator);
    base_.rtol = options_.rtol;
    base_.atol = options_.atol;
    base_.max_dt = options_.max_step;
    base_.max_steps = options_.max_steps;
  }

  // Initial energy (at the consistent initial state), and σ̂ with its rate at the start
  // ((C2'') checks the first step too).
  void start_energy(const VecX& v) {
    dyn_.state_.q = q_;
    dyn_.state_.u = dyn_.F_ * v;
    energy0_ = kinetic_energy(model_, dyn_.state_) + potential_energy(model_, q_);
    have_energy0_ = true;
    result_.energy_scale =
        std::abs(kinetic_energy(model_, dyn_.state_)) + std::abs(potential_energy(model_, q_));
    saved_prev_.valid = true;
    saved_prev_.t = T0_;
    saved_prev_.sigma = primal_ ? primal_quality_rate(T0_, dyn_.state_.u, saved_prev_.rate)
                                : chart_quality_rate(q_, dyn_.state_.u, saved_prev_.rate);
    saved_prev_.spread = primal_ ? 0.0 : dyn_.chart_spread();
    saved_prev_.chart = dyn_.cs_.chart();
    events_.start(model_, q_, dyn_.state_.u, dyn_.state_.load_on);
    dyn_.pin_sign_ = events_.pin_signs();
    for (size_t j = 0; j < dyn_.pin_sign_.size(); ++j)  // a pin at rest: stuck if it can be
      if (dyn_.pin_sign_[j] == 0.0) (void)stick_pin(T0_, x_, pin_hold(j));
    saved_prev_.x = x_;
    saved_prev_.load_on = dyn_.state_.load_on;
    saved_prev_.held = events_.held();
    saved_prev_.pin_sign = events_.pin_signs();
  }

  // ---- The integrator's callbacks -------------------------------------------------------------

  void rhs(const VecX& y, VecX& dy, double t) {
    ++evaluations_;
    dy.resize(nx_);
    if (primal_) {
      dyn_.evaluate_primal(t, y.head(nq_), y.segment(nq_, n_));
      compute_coordinate_rates(model_, y.head(nq_), dyn_.state_.u, dy.head(nq_));  // eq. (100)
      dy.segment(nq_, n_) = dyn_.pdot_;
    } else {
      dyn_.evaluate_dual(t, y.head(nq_), y.segment(nq_, na_));
      compute_coordinate_rates(model_, y.head(nq_), dyn_.state_.u, dy.head(nq_));  // q̇ = B̃ u
      dy.segment(nq_, na_) = dyn_.vdot_;
    }
    dy(nx_ - 1) = dyn_.nonconservative_power();
    if (events_.holding()) {  // resting contacts (dynamics/stop_contacts.hpp): no work
      if (primal_)
        contacts_.apply(dyn_, true, events_.held(), dy.segment(nq_, n_), contact_mu_);
      else
        contacts_.apply(dyn_, false, events_.held(), dy.segment(nq_, na_), contact_mu_);
    }
  }

  // The held stops' contact forces at the state (t, y) (an evaluation there): their switching
  // values (dynamics/events.hpp).
  // A stop's value is its contact force; a stuck pin's the margin of its static friction,
  // μ r |F| − |μ| (F from the multipliers with the holding moments).
  void contact_forces_at(double t, const VecX& y) {
    rhs(y, contact_dy_, t);
    const std::vector<StopHit>& held = events_.held();
    contact_value_ = contact_mu_;
    bool pins = false;
    for (const StopHit& h : held) pins = pins || h.pin >= 0;
    if (pins) {
      if (!primal_) dyn_.dual_multipliers();  // (Q̂ and u̇ include the holding moments)
      for (size_t k = 0; k < held.size(); ++k) {
        if (held[k].pin < 0) continue;
        const FrictionPin& p = dyn_.pins_[static_cast<size_t>(held[k].pin)];
        contact_value_[k] = p.coefficient * p.radius * dyn_.lambda_.segment<2>(p.row).norm() -
                            std::abs(contact_mu_[k]);
      }
    }
    events_.set_contact_forces(contact_value_);
  }

  // With projected stages the right-hand side depends on q through the chart's independent
  // coordinates only (the dependent ones are solved for): the Jacobian's other position
  // columns, and the work column, are zero. A planar body's velocity component k is its
  // coordinate k; a spatial body's rotation moves all four quaternion components.
  void jacobian_columns(std::vector<Eigen::Index>& columns) const {
    columns.clear();
    const Chart& c = dyn_.cs_.chart();
    for (const int k : c.independent) {
      if (model_.nq == model_.n) {
        columns.push_back(k);
        continue;
      }
      for (const Body& b : model_.bodies) {
        if (k < b.u_offset || k >= b.u_offset + b.nu()) continue;
        if (b.nq() == b.nu()) {
          columns.push_back(b.q_offset + (k - b.u_offset));
        } else {
          for (int i = 0; i < b.nq(); ++i) columns.push_back(b.q_offset + i);
        }
      }
    }
    std::sort(columns.begin(), columns.end());
    columns.erase(std::unique(columns.begin(), columns.end()), columns.end());
    if (!primal_) {
      for (int k = 0; k < na_; ++k) columns.push_back(nq_ + k);
      return;
    }
    // Primal: the stage's u = F (A p)_I. With a diagonal M, (A p)_I are the momenta's
    // independent components; otherwise every momentum column is differenced.
    if (dyn_.ws_.free.diagonal_mass) {
      for (const int k : c.independent) columns.push_back(nq_ + k);
    } else {
      for (int k = 0; k < n_; ++k) columns.push_back(nq_ + k);
    }
  }

  // ---- Output grid and samples ----------------------------------------------------------------

  // Output grid T0 + k·dt_out ≤ T1. The integration runs in segments (between change-point
  // passages and approaches): every output time is emitted once, whatever segment reaches it.
  [[nodiscard]] double grid_time(long k) const { return T0_ + static_cast<double>(k) * dt_out_; }
  [[nodiscard]] bool grid_pending() const { return grid_time(next_out_) <= T1_ + grid_slack_; }

  void sample_at(double t, const VecX& y, SimulationSample& smp) {
    if (primal_) {
      dyn_.evaluate_primal(t, y.head(nq_), y.segment(nq_, n_));
      // u̇ = A (ṗ − Ṁ u)
      dyn_.tmp_ = dyn_.pdot_;
      if (!dyn_.ws_.free.constant_mass) dyn_.tmp_.noalias() -= dyn_.ws_.free.Mdot * dyn_.state_.u;
      if (dyn_.ws_.free.diagonal_mass)
        dyn_.udot_ = dyn_.ws_.free.A_diag.cwiseProduct(dyn_.tmp_);
      else
        dyn_.udot_.noalias() = dyn_.ws_.free.A * dyn_.tmp_;
    } else {
      dyn_.evaluate_dual(t, y.head(nq_), y.segment(nq_, na_));
    }
    dyn_.fill_sample(y(nx_ - 1), smp, primal_);
  }

  // An output at t (a grid time within the slack, not yet emitted); other times (a segment's
  // start) are ignored.
  void emit(double t, const VecX& y) {
    if (!grid_pending() || std::abs(t - grid_time(next_out_)) > grid_slack_) return;
    if (options_.record_samples || options_.on_sample) {
      result_.samples.emplace_back();
      try {
        sample_at(t, y, result_.samples.back());
      } catch (...) {  // no equation there (a singular G or chart): no half-filled sample
        result_.samples.pop_back();
        throw;
      }
      if (!limited_.empty()) note_limits(t, result_.samples.back().q);
      deliver(false);
    }
    ++next_out_;
  }

  // The outputs that no rewind can undo any more (at or before the oldest state saved for a
  // rewind; `all`: every one, the run is over) go to options_.on_sample, in time order. Without
  // record_samples only the last of them is kept (finish_stopped's fallback), none at the end.
  void deliver(bool all) {
    if (!options_.on_sample) return;
    constexpr double kInf = std::numeric_limits<double>::infinity();
    const double t_safe = all                  ? kInf
                          : saved_older_.valid ? saved_older_.t
                          : saved_prev_.valid  ? saved_prev_.t
                                               : -kInf;
    std::vector<SimulationSample>& s = result_.samples;
    for (; delivered_ < s.size() && s[delivered_].t <= t_safe + grid_slack_; ++delivered_) {
      options_.on_sample(s[delivered_]);
      if (!primal_)  // as finish() does over the kept samples
        result_.max_velocity_residual =
            std::max(result_.max_velocity_residual, s[delivered_].velocity_residual);
    }
    if (options_.record_samples || delivered_ == 0) return;
    const size_t drop = all ? delivered_ : delivered_ - 1;
    s.erase(s.begin(), s.begin() + static_cast<std::ptrdiff_t>(drop));
    delivered_ -= drop;
  }

  void note_residual(const VecX& res) {
    for (Eigen::Index r = 0; r < res.size(); ++r) {
      double& to = angular_row_[static_cast<size_t>(r)] ? result_.max_residual_angle
                                                        : result_.max_residual_length;
      to = std::max(to, std::abs(res(r)));
    }
  }

  // ---- Chart quality σ̂ ----------------------------------------------------------------------

  double chart_quality() {
    if (model_.nc == 0 || rank_ == 0) return std::numeric_limits<double>::infinity();
    return dyn_.cs_.estimate_sigma_min(sigma_w_) / sigma_ref_;
  }

  // The two constraint rates of the polarisation H(u, x) = (D(u + x)ᵀ(u + x) − D(u − x)ᵀ(u − x))/4
  // with x = α rate_x_, α = |u|/|rate_x_| (x scaled to |u| against cancellation): rate_plus_ and
  // rate_minus_ at (qq, uu ± x). Returns α. Allocation-free after the first call.
  double polarised_rates(const VecX& qq, const VecX& uu) {
    const double alpha = uu.norm() / rate_x_.norm();
    rate_state_.q = qq;
    rate_rotations_.update(model_, qq);
    rate_state_.u = uu + alpha * rate_x_;
    compute_constraint_rate(model_, rate_state_, rate_rotations_, rate_plus_);
    rate_state_.u = uu - alpha * rate_x_;
    compute_constraint_rate(model_, rate_state_, rate_rotations_, rate_minus_);
    return alpha;
  }

  // (C1) σ̂ and its rate dσ̂/dt at (q, u) in the current chart (factorised at q): the rate of a
  // simple singular value is ŷᵀ (dB̃/dt) ŵ with its unit singular vectors [Stewart & Sun 1990,
  // §IV.2], and (dEᵀ/dt) x = H(u, x) is the constraints' second derivative, bilinear in (u, x);
  // H(y, y) = Dᵀy is the constraint rate (compute_constraint_rate), so by polarisation
  // H(u, x) = (D(u + x)ᵀ(u + x) − D(u − x)ᵀ(u − x))/4 (x scaled to |u| against cancellation).
  // Allocation-free after the first call.
  double chart_quality_rate(const VecX& qq, const VecX& uu, double& rate) {
    rate = 0.0;
    if (model_.nc == 0 || rank_ == 0) return std::numeric_limits<double>::infinity();
    const double sigma = dyn_.cs_.estimate_sigma_min(sigma_w_, &sigma_left_) / sigma_ref_;
    const double wn = sigma_w_.norm(), un = uu.norm();
    if (!(sigma > 0.0) || !(wn > 0.0) || !std::isfinite(wn) || !(un > 0.0)) return sigma;
    const Chart& c = dyn_.cs_.chart();
    rate_x_.setZero();
    for (int k = 0; k < rank_; ++k) {
      const int d = c.dependent[static_cast<size_t>(k)];
      rate_x_(d) = dyn_.ws_.free.A_sqrt(d) * sigma_w_(k) / wn;  // x = S_D ŵ
    }
    const double alpha = polarised_rates(qq, uu);
    double d = 0.0;
    for (int i = 0; i < rank_; ++i) {
      const int row = c.rows[static_cast<size_t>(i)];
      d += sigma_left_(i) * (rate_plus_(row) - rate_minus_(row));
    }
    rate = 0.25 * d / (alpha * sigma_ref_);
    return sigma;
  }

  // Primal form: σ̂ free of the chart, σ_min(Eᵀ A^½)/σ_ref = √λ_min(G)/σ_ref with G = Eᵀ A E
  // (eq. (42)) at the corrected q, and its rate. The primal form stops where G is singular,
  // which is where E loses rank: every chart's block is singular there, but a chart's block is
  // also singular where E is regular (the chart's own singularity), and the chart-free σ̂, which
  // bounds every chart's from above, falls to 0 only at a change point (the RSSR of
  // mechanisms/rssr.yaml: its charts' σ̂ fall to 1e-4 three times in 0.4 s, E stays regular).
  // λ_min by inverse iteration on G's factor, warm-started from the last step's vector; the
  // rate as in chart_quality_rate, with y the unit eigenvector and x = A E y/σ_abs
  // (the right singular vector of Eᵀ A^½ mapped back by A^½). Allocation-free after the first call.
  double primal_quality_rate(double t, const VecX& uu, double& rate) {
    rate = 0.0;
    if (model_.nc == 0 || rank_ == 0) return std::numeric_limits<double>::infinity();
    try {
      dyn_.state_.t = t;  // (for factor_G's message)
      dyn_.factor_G();    // at the corrected q: ws_.constraints.Et and the mass there
    } catch (const detail::SingularEvaluation&) {
      return 0.0;  // G singular: at the point (the monitor stops there)
    }
    const SparseEt::Matrix& E = dyn_.ws_.constraints.Et.matrix();  // Eᵀ
    if (g_y_.size() != model_.nc) g_y_ = VecX::Ones(model_.nc);
    g_y_.normalize();
    for (int k = 0; k < kPrimalQualityIterations; ++k) {
      dyn_.solve_G(g_y_, g_z_);
      const double zn = g_z_.norm();
      if (!(zn > 0.0) || !std::isfinite(zn)) return 0.0;
      g_y_ = g_z_ / zn;
    }
    g_Ety_.noalias() = E.transpose() * g_y_;  // E y
    if (dyn_.ws_.free.diagonal_mass)
      rate_x_ = dyn_.ws_.free.A_diag.cwiseProduct(g_Ety_);
    else
      rate_x_.noalias() = dyn_.ws_.free.A * g_Ety_;
    const double lambda = g_Ety_.dot(rate_x_);  // yᵀ G y
    if (!(lambda > 0.0)) return 0.0;
    const double sigma_abs = std::sqrt(lambda);
    const double sigma = sigma_abs / sigma_ref_;
    const double un = uu.norm();
    if (!(un > 0.0)) return sigma;
    rate_x_ /= sigma_abs;  // x = A E y / σ_abs
    const double alpha = polarised_rates(q_, uu);
    rate = 0.25 * g_y_.dot(rate_plus_ - rate_minus_) / (alpha * sigma_ref_);
    return sigma;
  }

  // (C2'') A change point inside the step just taken (from saved_prev, in the same chart): σ̂
  // fell at the start and rises at the end, and the two tangents σ̂₀ + σ̂'₀ τ and
  // σ̂₁ + σ̂'₁ (τ − h) meet at or near 0 (below kCrossingVertex of the smaller end value; a
  // regular minimum that the steps resolve has its tangents meet near the minimum). Whatever
  // the step's length and whatever the chart did before: the step is undone and the point
  // approached from the step's start, with t* at the tangents' vertex. Returns true when the
  // step must be undone (request set) or the run stopped (stop_message set).
  //
  // A long step (Bulirsch–Stoer's) can also start where σ̂ still rises, pass a maximum and the
  // point, and end rising again, low: then σ̂ at the end is below its start value, within
  // kWatchQuality, and the end's tangent reaches 0 inside the step, at t* = t − σ̂₁/σ̂'₁.
  bool crossed_within_step(double t, double s1, double d1) {
    if (!monitor_armed_ || !saved_prev_.valid || !(d1 > 0.0)) return false;
    const Chart& c = dyn_.cs_.chart();
    if (!primal_ &&
        (saved_prev_.chart.independent != c.independent || saved_prev_.chart.rows != c.rows))
      return false;
    const double h = t - saved_prev_.t, s0 = saved_prev_.sigma, d0 = saved_prev_.rate;
    if (!(h > 0.0)) return false;
    double tau = 0.0;
    if (d0 < 0.0) {
      tau = tangents_meet(s0, d0, s1, d1, h);
      const double vertex = std::max(s0 + d0 * tau, s1 + d1 * (tau - h));
      if (!(vertex < kCrossingVertex * std::min(s0, s1))) return false;
    } else {
      if (!(s1 < s0 && s1 < kWatchQuality && s1 < d1 * h)) return false;
      tau = h - s1 / d1;
    }
    last_crossing_t_star_ = saved_prev_.t + tau;
    if (++crossing_rewinds_ > kMaxCrossingRewinds) {
      char buf[160];
      std::snprintf(buf, sizeof buf,
                    "the steps keep crossing the change point at t ≈ %.9g s (undone %d times)",
                    last_crossing_t_star_, kMaxCrossingRewinds);
      stop_message_ = buf;
      return true;
    }
    undo_step_towards(last_crossing_t_star_);
    return true;
  }

  // The step just taken is undone (back to saved_prev) and the point at t_star approached from
  // there (C2'').
  void undo_step_towards(double t_star) {
    rewind_to_ = 1;
    request_ = {true, t_star, saved_prev_.sigma};
    last_rewind_t_star_ = t_star;
  }

  // ---- Step acceptance ------------------------------------------------------------------------

  // After every accepted step: the step's end corrected (positions, velocities, chart), its
  // residuals and energy booked, and the change-point monitor run. False stops the integrator
  // (a change point ahead, or a failed check: stop_message set).
  bool accept(double t, VecX& y) {
    dyn_.chart_ready_ = false;  // Eᵀ, the chart's factors and F change below
    bool chart_changed = false;
    book_step_residual(y);
    if (!correct_step(t, y, chart_changed)) return false;
    // (C2'') σ̂ and its rate at the step's end in the step's chart (the block is factorised at
    // the corrected q): a change point inside the step, whatever the step's length, is undone
    // before anything else looks at the step's end (its velocity check included).
    double rate_end = 0.0;
    const double sigma_end = primal_ ? primal_quality_rate(t, dyn_.state_.u, rate_end)
                                     : chart_quality_rate(q_, u_step_, rate_end);
    if ((primal_ || !chart_changed) && crossed_within_step(t, sigma_end, rate_end)) return false;
    if (primal_) {
      project_momenta(y, chart_changed);
    } else {
      if (!project_step_velocity(t, y)) return false;
      const double spread = monitor_chart(t, y, chart_changed);
      dyn_.state_.u.noalias() = dyn_.F_ * y.segment(nq_, na_);
      dyn_.chart_q_ = q_;  // Eᵀ, the factors and F are those at the corrected q
      dyn_.chart_ready_ = true;
      limit_next_step(t, spread, chart_changed);
    }
    // The switched loads: a step across which one of their switching values changed sign is
    // undone and the crossing located, unless it is within the tolerance already.
    if (events_.holding()) contact_forces_at(t, y);
    const Events::StepEnd event = events_.step_end(model_, t_last_accept_, t, q_, dyn_.state_.u);
    // (The step's start must be the saved step end to go back to; it is, but for a step after
    // an undone crossing of a change point: there the step is kept and the loads switched.)
    const bool undoable = saved_prev_.valid && saved_prev_.t == t_last_accept_;
    if (event == Events::StepEnd::locate && undoable) {
      events_.open_bracket(t_last_accept_, t);
      event_request_ = EventRequest::locate;
      return false;
    }
    book_energy(t, y);
    const bool request = monitor_change_points(t, y, sigma_end, rate_end, chart_changed);
    const bool switched = event != Events::StepEnd::smooth;
    if (switched && !apply_events(t, y)) return false;
    if (!switched) events_.keep_step_end();
    // The bounds count every accepted step; a step that raised a change-point request ends the
    // segment anyway, and a bound met there stops the first step after the request is served.
    const bool go_on = within_bounds(t);
    if (switched && !go_on) event_request_ = EventRequest::none;
    return go_on && !request && !switched;
  }

  // The events at the step's end t (kept: its state is saved as saved_prev): the loads switch,
  // the stops met give their impacts (y's velocity changes), and the integrator restarts there.
  // False when the events chatter (the run stops, status sliding or resting).
  bool apply_events(double t, VecX& y) {
    std::string why;
    const std::vector<std::uint8_t> modes_before = dyn_.state_.load_on;  // (an event: rare)
    const std::vector<double> signs_before = dyn_.pin_sign_;
    const std::vector<StopHit> held_before = events_.held();
    const std::vector<double> mu_before = contact_mu_;
    const Events::Chatter chatter = events_.switch_at(model_, t, dyn_.state_.load_on, hits_, why);
    dyn_.pin_sign_ = events_.pin_signs();
    if (chatter == Events::Chatter::loads ||
        (chatter == Events::Chatter::sticks && !stick_pin(t, y, events_.sticking_pin())) ||
        (chatter == Events::Chatter::stop && !rest_on_stop(t, y))) {
      failure_status_ =
          chatter == Events::Chatter::stop ? SimulateStatus::resting : SimulateStatus::sliding;
      stop_message_ = why;
      return false;
    }
    ++events_applied_;
    if (dyn_.state_.load_on != modes_before) ++result_.load_switches;
    if (dyn_.pin_sign_ != signs_before) ++result_.friction_switches;
    // A sliding pin whose rate passed through zero sticks there if its static friction can hold
    // it (not one that has just slipped, signs_before 0: its margin is spent).
    for (size_t j = 0; j < signs_before.size() && j < dyn_.pin_sign_.size(); ++j)
      if (signs_before[j] != 0.0 && dyn_.pin_sign_[j] != signs_before[j])
        (void)stick_pin(t, y, pin_hold(j));
    if (chatter == Events::Chatter::none)
      for (const StopHit& hit : hits_) {
        if (hit.release && hit.pin >= 0)
          slip_pin(t, hit, held_before, mu_before);
        else if (hit.release)
          end_contact(t, hit);
        else
          impact(t, hit, y);
      }
    if (saved_prev_.valid && saved_prev_.t == t) {
      saved_prev_.load_on = dyn_.state_.load_on;
      saved_prev_.held = events_.held();
      saved_prev_.pin_sign = events_.pin_signs();
      saved_prev_.x = y;
    }
    event_request_ = EventRequest::restart;
    return true;
  }

  // A joint come to rest on its stop (the impacts' chatter) is held there as a resting contact
  // (dynamics/stop_contacts.hpp): its speed towards or away from the stop taken away (a plastic
  // impact, e = 0, its loss booked), the switched loads' modes taken from their rates there, and
  // the contact force that holds it computed. False when that force would pull at once: the
  // contact cannot hold it (the run stops, status resting).
  bool rest_on_stop(double t, VecX& y) {
    const StopHit stop = events_.resting_stop();
    impact(t, stop, y, Approach::either_way);
    events_.hold(stop, 1.0);
    if (static_cast<int>(events_.held().size()) == na_) {  // locked: at rest exactly
      y.segment(nq_, primal_ ? n_ : na_).setZero();
      dyn_.state_.u.setZero();
      if (!result_.impacts.empty() && result_.impacts.back().t == t)
        result_.impacts.back().speed_after = 0.0;
    }
    contact_forces_at(t, y);
    events_.restored(model_, q_, dyn_.state_.u);
    events_.modes_from_values(dyn_.state_.load_on);
    contact_forces_at(t, y);  // with the loads' modes there
    if (!(contact_mu_.back() > 0.0)) {
      std::vector<StopHit> others = events_.held();
      others.pop_back();
      events_.set_held(others);
      return false;
    }
    events_.restored(model_, q_, dyn_.state_.u);
    result_.contacts.push_back(
        {t, std::numeric_limits<double>::quiet_NaN(), stop.joint, stop.side});
    return true;
  }

  // A pin whose friction reverses at ever shorter intervals (its rate comes back through zero at
  // once) is stuck: held at zero relative rate (its rate taken away, a plastic projection with
  // its loss booked) by a moment μ that its static friction bounds, |μ| ≤ μ r |F|. False when
  // the friction cannot hold it at all (the run stops, status sliding).
  bool stick_pin(double t, VecX& y, const StopHit& pin) {
    const VecX y_before = y, u_before = dyn_.state_.u;
    const std::vector<StopHit> held_before = events_.held();
    const std::vector<double> signs_before = events_.pin_signs();
    impact(t, pin, y, Approach::stick);
    events_.hold(pin, 1.0);
    dyn_.pin_sign_ = events_.pin_signs();
    if (static_cast<int>(events_.held().size()) == na_) {  // locked: at rest exactly
      y.segment(nq_, primal_ ? n_ : na_).setZero();
      dyn_.state_.u.setZero();
    }
    contact_forces_at(t, y);
    if (!(contact_value_.back() > 0.0)) {  // it cannot hold: as it was
      y = y_before;
      dyn_.state_.u = u_before;
      events_.set_held(held_before);
      events_.set_pin_signs(signs_before);
      dyn_.pin_sign_ = signs_before;
      if (events_.holding()) contact_forces_at(t, y);
      return false;
    }
    events_.restored(model_, q_, dyn_.state_.u);
    result_.contacts.push_back({t, std::numeric_limits<double>::quiet_NaN(), pin.joint, 0});
    return true;
  }

  // The hold of friction pin j (Events: a stuck pin, side +1).
  [[nodiscard]] StopHit pin_hold(size_t j) const {
    return {dyn_.pins_[j].joint, 1, false, static_cast<int>(j)};
  }

  // A stuck pin whose holding moment reached its static bound slips, away from that moment
  // (its kinetic friction then opposes the slip).
  void slip_pin(double t, const StopHit& hit, const std::vector<StopHit>& held_before,
                const std::vector<double>& mu_before) {
    std::vector<double> signs = events_.pin_signs();
    for (size_t k = 0; k < held_before.size() && k < mu_before.size(); ++k)
      if (held_before[k].pin == hit.pin)
        signs[static_cast<size_t>(hit.pin)] = mu_before[k] > 0.0 ? -1.0 : 1.0;
    events_.set_pin_signs(signs);
    dyn_.pin_sign_ = signs;
    end_contact(t, {hit.joint, 0});
  }

  // A held stop released at t (its contact force reached zero).
  void end_contact(double t, const StopHit& hit) {
    // (At most one contact of a stop is open: the first open one is the last.)
    for (SimulateResult::StopContact& c : result_.contacts)
      if (c.joint == hit.joint && c.side == hit.side && std::isnan(c.t_to)) c.t_to = t;
  }

  // An impact on an end stop, Newton's law with restitution e in the mass metric: the admissible
  // velocity v⁺ closest to v⁻ in H = FᵀMF with ġ⁺ = −e ġ⁻, where ġ = cᵀv, c = σ Fᵀdᵀ (d the
  // joint coordinate's gradient, σ = +1 at the lower stop, −1 at the upper):
  //   v⁺ = v⁻ − (1 + e) (cᵀv⁻)/(cᵀH⁻¹c) H⁻¹c,  ΔT = ½ (1 − e²) (cᵀv⁻)²/(cᵀH⁻¹c),
  // the loss booked as work of the non-conservative forces (W), so T + V − W stays level.
  // Nothing happens when the joint already moves away from the stop (ġ⁻ ≥ 0).
  // towards: an impact (recorded); either_way: the plastic one where a resting contact begins
  // (recorded); stick: a pin's relative rate taken away where it sticks (its loss booked only).
  enum class Approach { towards, either_way, stick };
  void impact(double t, const StopHit& hit, VecX& y, Approach when = Approach::towards) {
    const Joint& joint = model_.joints[static_cast<size_t>(hit.joint)];
    const double e = when == Approach::towards ? *joint.stop_restitution : 0.0;
    stop_d_.resize(n_);
    (void)compute_scalar(model_, JointCoordinate{hit.joint}, q_, nullptr, stop_d_);
    dyn_.compute_H();
    const VecX v = primal_ ? project_velocity(dyn_.MF_, dyn_.H_llt_, dyn_.state_.u)
                           : VecX(y.segment(nq_, na_));
    stop_c_.noalias() = dyn_.F_.transpose() * stop_d_;
    stop_c_ *= hit.side;
    const double approach = stop_c_.dot(v);
    if (!(approach < 0.0) && when == Approach::towards) return;
    stop_Hc_ = dyn_.H_llt_.solve(stop_c_);
    const double k = stop_c_.dot(stop_Hc_);
    if (!(k > 0.0)) return;
    const VecX v_after = v - ((1.0 + e) * approach / k) * stop_Hc_;
    const double loss = 0.5 * (1.0 - e * e) * approach * approach / k;
    y(nx_ - 1) -= loss;
    dyn_.state_.u.noalias() = dyn_.F_ * v_after;
    if (primal_)
      dyn_.momentum_from_velocity(y.segment(nq_, n_));
    else
      y.segment(nq_, na_) = v_after;
    if (when != Approach::stick)
      result_.impacts.push_back({t, hit.joint, hit.side, -approach, stop_c_.dot(v_after), loss});
  }

  // Joints outside their `limits:` at q (SimulateResult::limits_left): every corrected step end
  // and every output sample (an output inside a long step may be outside before its end).
  void note_limits(double t, const VecX& q) {
    for (size_t k = 0; k < limited_.size(); ++k) {
      const int j = limited_[k];
      if (!outside_limits(model_, j, q)) continue;
      const Vec2& lim = *model_.joints[static_cast<size_t>(j)].limits;
      const double x = limit_coordinate(model_, j, q);
      const double beyond = std::max(lim.x() - x, x - lim.y());
      LimitExit& e = limit_exits_[k];
      if (e.steps++ == 0 || t < e.t_first) {  // (an output inside a step precedes its end)
        e.joint = j;
        e.t_first = t, e.value_first = x;
      }
      if (e.steps == 1) {
        e.t_furthest = t, e.value_furthest = x;
      } else if (beyond > std::max(lim.x() - e.value_furthest, e.value_furthest - lim.y())) {
        e.t_furthest = t, e.value_furthest = x;
      }
    }
  }
  void collect_limits() {
    result_.limits_left.clear();
    for (const LimitExit& e : limit_exits_)
      if (e.steps > 0) result_.limits_left.push_back(e);
  }

  // The run's bounds after an accepted, corrected step (SimulateOptions::max_steps, control):
  // false stops the integrator there (status stopped, the reason in the message).
  bool within_bounds(double t) {
    note_limits(t, q_);
    const double fraction = (t - T0_) / (T1_ - T0_);
    const StopReason r = monitor_run_.tick(fraction);
    if (r == StopReason::none) return !beyond_budget(t, fraction);
    stop_message_ = monitor_run_.stop_message(r, fraction, "step", "--max-steps");
    failure_status_ = SimulateStatus::stopped;
    result_.stop = r;
    return false;
  }

  // A run that cannot fit its step budget stops when that is clear, not when the budget is
  // spent: every kBudgetWindow steps, the steps still needed at the window's mean step size are
  // compared with the budget; beyond kBudgetMargin times what is left, the run stops (a spatial
  // gravity of 1e12 m/s² needs about 6e7 steps for 1 s: stopped after 1e4 steps, not 1e7).
  bool beyond_budget(double t, double fraction) {
    constexpr long kBudgetWindow = 10000;
    constexpr double kBudgetMargin = 2.0;
    const long done = monitor_run_.units();
    if (done % kBudgetWindow != 0) return false;
    const double h = (t - window_t_) / static_cast<double>(kBudgetWindow);
    window_t_ = t;
    const double left = static_cast<double>(options_.max_steps - done);
    if (!(h > 0.0) || (T1_ - t) / h <= kBudgetMargin * left) return false;
    char text[200];
    std::snprintf(text, sizeof text,
                  "stopped at %.0f %% of the run: at its mean step of the last %ld steps (%.3g s) "
                  "the motion needs about %.3g more steps, beyond the step budget of %ld "
                  "(--max-steps)",
                  100.0 * fraction, kBudgetWindow, h, (T1_ - t) / h, options_.max_steps);
    stop_message_ = text;
    failure_status_ = SimulateStatus::stopped;
    result_.stop = StopReason::work_budget;
    return true;
  }

  // Residual left by the step (before correction), with Eᵀ at the same q. Quaternions are
  // renormalised first (|e| = 1 is a first integral of q̇ = B̃u; only the step's error moves
  // it; f and R do not depend on |e|, docs/spatial.md §6.3).
  void book_step_residual(VecX& y) {
    auto qy = y.head(nq_);
    SparseEt& Et = dyn_.ws_.constraints.Et;
    normalize_coordinates(model_, qy);
    q_ = qy;
    dyn_.mass_at(q_);
    compute_constraint_residual_and_jacobian(model_, q_, f_, Et);
    if (f_.size()) {
      result_.max_constraint_residual =
          std::max(result_.max_constraint_residual, f_.cwiseAbs().maxCoeff());
      note_residual(f_);
    }
    if (primal_) {
      // Invariant J = Eᵀ A p, eq. (105), before the projection.
      dyn_.state_.q = q_;
      dyn_.velocity_from_momentum(y.segment(nq_, n_));
      if (model_.nc) {
        const double J = (Et.matrix() * dyn_.state_.u).cwiseAbs().maxCoeff();
        result_.max_invariant_J = std::max(result_.max_invariant_J, J);
        result_.max_velocity_residual = std::max(result_.max_velocity_residual, J);
      }
    }
  }

  // The step's position corrected in the chart; (dual) its velocity before the correction in
  // u_step. False when the correction fails (stop_message set).
  bool correct_step(double t, VecX& y, bool& chart_changed) {
    auto qy = y.head(nq_);
    SparseEt& Et = dyn_.ws_.constraints.Et;
    // The chart's block at the step's q: the corrector's first Newton step uses it, and (dual)
    // the step's velocity u = F(q) v before the correction (re-projected below).
    const bool factored = dyn_.factor_chart(Et);
    if (!primal_) {
      if (factored) {
        dyn_.compute_F();
        u_step_.noalias() = dyn_.F_ * y.segment(nq_, na_);
      } else {
        u_step_.setZero();  // exactly singular: keep v as it is (below)
      }
    }
    // Position correction in the chart (Newton; independent coordinates fixed). It leaves Eᵀ
    // at the corrected q factorised in the chart.
    ChartCorrectionResult corr = dyn_.cs_.correct_positions(
        q_, Et, f_, dq_,
        {.tolerance = options_.position_tolerance,
         .max_gain = kMaxCorrectionGain,
         .start = factored ? ChartCorrection::Start::prepared : ChartCorrection::Start::evaluate});
    if (corr.near_singular) ++result_.uncorrected_steps;
    if (corr.status == SolveStatus::singular) {  // try a fresh chart once
      compute_constraint_jacobian(model_, q_, Et);
      if (dyn_.cs_.select(Et, dyn_.ws_.free.A_diag))
        corr =
            dyn_.cs_.correct_positions(q_, Et, f_, dq_, {.tolerance = options_.position_tolerance});
      chart_changed = true;
    }
    if (corr.status != SolveStatus::converged) {
      // A step that ended next to a change point (σ̂ falling below kWatchQuality at the step
      // before), where the block is too ill-conditioned for the corrector: undone and the point
      // approached from the step before, as a crossing within a step (C2'').
      if (!primal_ && monitor_armed_ && saved_prev_.valid && saved_prev_.t < t &&
          saved_prev_.sigma < kWatchQuality && saved_prev_.rate < 0.0 &&
          crossing_rewinds_ < kMaxCrossingRewinds) {
        ++crossing_rewinds_;
        last_crossing_t_star_ = t;
        undo_step_towards(t);
        return false;
      }
      stop_message_ =
          "position correction failed at t = " + time_text(model_, t) + ": " + corr.message;
      return false;
    }
    qy = q_;
    dyn_.compute_F();
    dyn_.mass_at(q_);
    dyn_.state_.q = q_;
    if (primal_) dyn_.velocity_from_momentum(y.segment(nq_, n_));
    return true;
  }

  // Primal form. Momenta: p ← M α u, the mass-orthogonal projection (eq. (44): α = I − A π).
  void project_momenta(VecX& y, bool& chart_changed) {
    dyn_.compute_H();
    const VecX vv = project_velocity(dyn_.MF_, dyn_.H_llt_, dyn_.state_.u);
    dyn_.state_.u.noalias() = dyn_.F_ * vv;
    dyn_.momentum_from_velocity(y.segment(nq_, n_));
    // A poor chart only slows the corrector: re-select it when the rule says it degraded (no
    // hysteresis on the choice: the primal form's results do not depend on the chart).
    if (chart_rule_.due(1.0 / dyn_.chart_spread())) {
      const Chart old = dyn_.cs_.chart();
      dyn_.cs_.select_from_tangent(dyn_.F_, dyn_.M_sqrt());
      chart_changed = true;
      if (!dyn_.factor_chart(dyn_.ws_.constraints.Et)) {
        dyn_.cs_.set_chart(old);
        (void)dyn_.factor_chart(dyn_.ws_.constraints.Et);
      }
    }
  }

  // Dual form. v ← H⁻¹ Fᵀ M u_step: the admissible velocity at the corrected position closest
  // to the step's velocity in the mass metric (eq. (70), u = α u_step), rather than keeping u_I.
  // False (stop_message set) when the step left the branch.
  bool project_step_velocity(double t, VecX& y) {
    if (!(u_step_.squaredNorm() > 0.0)) return true;
    dyn_.compute_H();
    y.segment(nq_, na_) = project_velocity(dyn_.MF_, dyn_.H_llt_, u_step_);
    // The velocity the projection removes is the step's own error; a step that left the
    // branch (a change point crossed within one step onto another branch) loses a finite
    // part of it: refused (C6).
    const VecX du = u_step_ - dyn_.F_ * y.segment(nq_, na_);
    const double uu = mnorm2(u_step_, u_step_);
    const double jump = uu > 0.0 ? std::sqrt(mnorm2(du, du) / uu) : 0.0;
    if (jump > kStepVelocityJump) {
      stop_message_ = "the step to t = " + time_text(model_, t) +
                      " s left the motion's branch (its velocity changes by " +
                      std::to_string(jump) +
                      " relative when made admissible): a change point was crossed within "
                      "one step";
      return false;
    }
    return true;
  }

  // Dual form. Chart monitor: the engines' one switching rule (ChartSwitchRule) on the quality
  // 1/spread, the candidate chosen from the tangent F; a switch re-expresses v from u = F v.
  // Returns the spread of the chart the step ended in.
  double monitor_chart(double t, VecX& y, bool& chart_changed) {
    const double spread = dyn_.chart_spread();
    if (!chart_rule_.due(1.0 / spread)) return spread;
    const Chart old = dyn_.cs_.chart();
    const VecX u = dyn_.F_ * y.segment(nq_, na_);
    dyn_.cs_.select_from_tangent(dyn_.F_, dyn_.M_sqrt());
    // Next to a change point F is inaccurate in every chart and switching would not help: the
    // rule takes the new chart only if it is clearly better.
    if (dyn_.factor_chart(dyn_.ws_.constraints.Et)) {
      dyn_.compute_F();
      if (chart_rule_.better(1.0 / dyn_.chart_spread(), 1.0 / spread)) {
        for (int k = 0; k < na_; ++k)
          y(nq_ + k) = u(dyn_.cs_.chart().independent[static_cast<size_t>(k)]);
        result_.chart_switches.push_back(
            {t, chart_name(model_, old), chart_name(model_, dyn_.cs_.chart())});
        chart_rule_.switched();
        chart_changed = true;
        return spread;
      }
    }
    chart_rule_.refused(1.0 / spread);  // keep the chart; try again when it degrades further
    dyn_.cs_.set_chart(old);
    (void)dyn_.factor_chart(dyn_.ws_.constraints.Et);
    dyn_.compute_F();
    return spread;
  }

  // Dual form. Ahead of the chart's own singularity (its block singular, F unbounded, E
  // regular: the spread ~ 1/(t_s − t)): 1/spread is linear in t there, so two values in this
  // chart give t_s, and the next step ends at most half-way to it (the monitor above switches
  // charts at a step end; a step that ran into the singularity would have integrated, and been
  // corrected, where F is ill-conditioned: on the N = 40 bar one Bulirsch–Stoer step at
  // rtol 1e-8 lost 5e-7 of the energy that way).
  void limit_next_step(double t, double spread, bool chart_changed) {
    spread_now_ = chart_changed ? dyn_.chart_spread() : spread;
    next_step_limit_ = std::numeric_limits<double>::infinity();
    if (!chart_changed && saved_prev_.valid && saved_prev_.spread > 0.0 && t > saved_prev_.t &&
        saved_prev_.chart.independent == dyn_.cs_.chart().independent) {
      const double slope = (1.0 / spread_now_ - 1.0 / saved_prev_.spread) / (t - saved_prev_.t);
      if (slope < 0.0) next_step_limit_ = kChartStepFraction * (1.0 / spread_now_) / -slope;
    }
  }

  // Energy balance T + V − W at the corrected state; the step counted.
  void book_energy(double t, const VecX& y) {
    const double T = kinetic_energy(model_, dyn_.state_);
    const double V = potential_energy(model_, q_);
    const double W = y(nx_ - 1);
    const double E = T + V - W;
    if (!have_energy0_) energy0_ = E, have_energy0_ = true;
    result_.energy_max_drift = std::max(result_.energy_max_drift, std::abs(E - energy0_));
    result_.energy_scale = std::max(result_.energy_scale, std::abs(T) + std::abs(V) + std::abs(W));
    ++result_.steps;
    h_last_ = t - t_last_accept_;
    t_last_accept_ = t;
  }

  // ---- Change-point monitor -------------------------------------------------------------------

  // Change-point monitor: stop the segment when a change point is within reach of the next
  // steps (C2) or close enough to be passed (C3); the driver approaches or passes it. True:
  // stop (request set). The corrected state is saved for a rewind.
  bool monitor_change_points(double t, const VecX& y, double sigma_end, double rate_end,
                             bool chart_changed) {
    // σ̂ and its rate in the chart the next step uses (another block after a switch).
    // (The primal form's σ̂ does not depend on the chart.)
    const bool other_block = chart_changed && !primal_;
    double rate = rate_end;
    const double sigma = other_block ? chart_quality_rate(q_, dyn_.state_.u, rate) : sigma_end;
    if (other_block) monitor_.valid = false;  // σ̂ of another chart block: no secant trend
    bool stop = false;
    const bool minimum_above_zero = bottoms_out_above_zero(t, sigma);
    if (monitor_quiet_ && (rate > 0.0 || (monitor_.valid && sigma > monitor_.sigma)))
      monitor_quiet_ = false;
    // (C1) t* from a falling σ̂: the secant through the last two values in this chart and the
    // tangent t − σ̂/σ̂'. Far from the point σ̂ is concave as it falls (~|sin θ| on the
    // N-four-bar) and both are late, the secant more: the earlier is taken. A rising σ̂ (σ̂' > 0)
    // has no point ahead, whatever the secant says.
    const bool secant_falling = monitor_.valid && sigma < monitor_.sigma;
    const bool falling = rate < 0.0 || (rate == 0.0 && secant_falling);
    if (monitor_armed_ && !monitor_quiet_ && !minimum_above_zero && falling &&
        sigma < kWatchQuality) {
      double t_star = std::numeric_limits<double>::infinity();
      if (secant_falling) t_star = t + sigma * (t - monitor_.t) / (monitor_.sigma - sigma);  // (C1)
      if (rate < 0.0) t_star = std::min(t_star, t - sigma / rate);
      // σ̂ concave (its rate falling since the last step end, in this chart): the parabola's
      // zero is earlier still. Bulirsch–Stoer's long steps otherwise step over the point from
      // where the tangent puts it out of reach (the triple-crank at rtol 1e-12: from σ̂ = 0.14).
      if (rate < 0.0 && monitor_.valid && t > monitor_.t) {
        const double c = (rate - monitor_.rate) / (t - monitor_.t);
        if (c < 0.0)
          t_star = std::min(t_star, t + (-rate - std::sqrt(rate * rate - 2.0 * c * sigma)) / c);
      }
      // (A point estimated beyond the run's end raises nothing: the run ends first, or a later,
      // closer estimate puts it before the end.)
      if ((sigma <= (primal_ ? kPrimalStopQuality : pass_quality_) ||
           t_star - t < kReachSteps * h_last_) &&
          t_star < T1_ - end_slack_) {
        request_ = {true, t_star, sigma};
        stop = true;
      }
    }
    // (C2') the steps are undone: the saved step ends stay those the rewind goes back to (the
    // step start saved_prev_ or the one before, saved_older_), not shifted to this step's end.
    if (!stop && crossed_across_two_steps(t, sigma)) return true;
    if (t > last_crossing_t_star_) crossing_rewinds_ = 0;
    saved_older_ = saved_prev_;
    saved_prev_.valid = true;
    saved_prev_.t = t;
    saved_prev_.sigma = sigma;
    saved_prev_.rate = rate;
    saved_prev_.spread = spread_now_;
    saved_prev_.x = y;
    saved_prev_.load_on = dyn_.state_.load_on;
    saved_prev_.held = events_.held();
    saved_prev_.pin_sign = events_.pin_signs();
    saved_prev_.chart = dyn_.cs_.chart();
    if (sigma >= kFarPassQuality && sigma <= kFarPassQualityMax) far_ = saved_prev_;
    monitor_ = {true, t, sigma, rate};
    limit_step_by_quality(sigma, rate);
    return stop;
  }

  // Within kWatchQuality the next step ends before σ̂ could reach 0 falling at the fastest
  // rate seen in the run: a step may not cross a change point between two step ends that both
  // look regular (σ̂ rising, then falling from above its start: nothing at the ends shows it;
  // Bulirsch–Stoer's long steps did so on the triple-crank).
  void limit_step_by_quality(double sigma, double rate) {
    if (primal_) return;
    max_quality_rate_ = std::max(max_quality_rate_, std::abs(rate));
    if (sigma < kWatchQuality && max_quality_rate_ > 0.0)
      next_step_limit_ =
          std::min(next_step_limit_, kQualityStepFraction * sigma / max_quality_rate_);
  }

  // A falling σ̂ that bottoms out above 0 (C1'): the parabola through the last three values.
  [[nodiscard]] bool bottoms_out_above_zero(double t, double sigma) const {
    if (!(saved_older_.valid && saved_prev_.valid && monitor_.valid && sigma < saved_prev_.sigma))
      return false;
    const double t0 = saved_older_.t, t1 = saved_prev_.t, s0 = saved_older_.sigma,
                 s1 = saved_prev_.sigma;
    const double d01 = (s1 - s0) / (t1 - t0), d12 = (sigma - s1) / (t - t1);
    const double curv = (d12 - d01) / (t - t0);  // p(τ) = σ + d (τ − t) + curv (τ − t)²
    if (!(curv > 0.0)) return false;
    const double d = d12 + curv * (t - t1);  // slope at t
    const double p_min = sigma - d * d / (4.0 * curv);
    return p_min > kMinimumAboveZero * sigma;
  }

  // (C2') σ̂ fell and rose again across the last two steps along a V through 0: a change point
  // was crossed within one of them without being approached (large steps at a loose rtol).
  // Both hypotheses: crossing in the last step (zero of the falling line before t) or in the
  // one before (zero of the rising line after t_{k−2}), each checked against the third σ̂.
  // True: the steps are to be undone (request and rewind_to set).
  bool crossed_across_two_steps(double t, double sigma) {
    if (!(monitor_armed_ && saved_older_.valid && saved_prev_.valid &&
          saved_older_.t > last_rewind_t_star_ && sigma > saved_prev_.sigma &&
          saved_prev_.sigma < saved_older_.sigma && saved_prev_.sigma < kWatchQuality))
      return false;
    const double t0 = saved_older_.t, s0 = saved_older_.sigma;
    const double t1 = saved_prev_.t, s1 = saved_prev_.sigma;
    const double a1 = (s0 - s1) / (t1 - t0), z1 = t1 + s1 / a1;
    const double a2 = (sigma - s1) / (t - t1), z2 = t1 - s1 / a2;
    if (z1 < t && std::abs(a1 * (t - z1) - sigma) <= kVShapeTolerance * sigma) {
      rewind_to_ = 1;
      request_ = {true, z1, s1};
      last_rewind_t_star_ = z1;
      return true;
    }
    if (z2 > t0 && std::abs(a2 * (z2 - t0) - s0) <= kVShapeTolerance * s0) {
      rewind_to_ = 0;
      request_ = {true, z2, s0};
      last_rewind_t_star_ = z2;
      return true;
    }
    return false;
  }

  // ---- Segments -------------------------------------------------------------------------------

  // The integrator from t to t_e in segments that start on the output grid or end on it, so
  // that the integrator's output clock (t0 + k·dt_out) hits the grid times. Stops early when
  // `accept` stops it (a change point ahead, or a failed check).
  detail::OdeStats run_to(double t_e, double max_dt) {
    detail::OdeStats st;
    st.completed = true;
    st.t = t_now_;
    while (t_now_ < t_e - end_slack_) {
      detail::OdeOptions oo = base_;
      oo.t0 = t_now_;
      if (max_dt > 0.0) oo.max_dt = oo.max_dt > 0.0 ? std::min(oo.max_dt, max_dt) : max_dt;
      oo.dt_init = h_last_ > 0.0 ? std::min(h_last_, next_step_limit_) : 0.0;
      const bool on_grid =
          std::abs(t_now_ - grid_time(next_out_)) <= grid_slack_ ||
          (next_out_ > 0 && std::abs(t_now_ - grid_time(next_out_ - 1)) <= grid_slack_);
      if (on_grid || !grid_pending()) {
        oo.t_end = t_e;
        oo.dt_out = on_grid ? dt_out_ : 2.0 * (t_e - t_now_);
      } else {  // off the grid: to the next output time first
        const double g = grid_time(next_out_);
        oo.t_end = std::min(t_e, g);
        oo.dt_out = g <= t_e ? g - t_now_ : 2.0 * (t_e - t_now_);
      }
      if (oo.dt_init > 0.0 && oo.dt_init > oo.t_end - t_now_) oo.dt_init = oo.t_end - t_now_;
      st = detail::integrate_ode(problem_, x_, oo);
      rejected_steps_ += st.rejected;
      jacobians_ += st.jacobians;
      if (st.completed) st.t = oo.t_end;
      t_now_ = st.t;
      // An output time at a stop (accept stopped the integrator before its output there).
      if (std::abs(t_now_ - grid_time(next_out_)) <= grid_slack_ && grid_pending())
        emit(t_now_, x_);
      if (!st.completed && event_request_ == EventRequest::restart) {
        event_request_ = EventRequest::none;  // the loads switched: the integrator restarts
        if (!request_.pending) continue;
      }
      if (!st.completed) return st;
    }
    st.completed = true;
    st.t = t_now_;
    return st;
  }

  // ---- Passage of a change point --------------------------------------------------------------

  // (C4) a state on the branch: positions, velocity, acceleration, power of the loads.
  struct BranchState {
    VecX q, v, u, a;
    double P = 0.0;
  };
  // The passage step from t_a to t_b = t_a + h: its Lobatto stages (A = stage[0], the landing
  // B = stage[3]), the work at both ends, the corrector's last change and the velocity jump.
  struct PassageStep {
    double t_a = 0.0, h = 0.0, t_b = 0.0;
    BranchState stage[4];
    double W_a = 0.0, W_b = 0.0;
    double change = std::numeric_limits<double>::infinity(), jump = 0.0;
    int iterations = 0;
    double sigma_b = 0.0, rate_b = 0.0;  // σ̂ and its rate at the landing
    // The step crossed the change point (check_passage): false when it landed short of it or
    // stepped over a regular minimum of σ̂; it is then an ordinary step, not a passage.
    bool crossed = true;
  };

  [[nodiscard]] double mnorm2(const VecX& a, const VecX& b) const {
    return dyn_.ws_.free.diagonal_mass ? a.dot(dyn_.ws_.free.M_diag.cwiseProduct(b))
                                       : a.dot(dyn_.ws_.free.M * b);
  }

  // (C4) a state on the branch at time tt from a guess (qq, uu): positions corrected in the
  // incoming chart (Newton, q_I fixed) and polished to rounding, the velocity made admissible
  // (u = α uu, eq. (70)); then the dual equations there.
  bool on_branch(double tt, const VecX& qq, const VecX& uu, BranchState& s, std::string& why) {
    s.q = qq;
    SparseEt& Et = dyn_.ws_.constraints.Et;
    const SolveResult corr =
        dyn_.cs_.correct_positions(s.q, Et, f_, dq_, {.tolerance = options_.position_tolerance});
    if (corr.status != SolveStatus::converged) {
      why = "a position of the passage does not close (" + corr.message + ")";
      return false;
    }
    // (f, Eᵀ and the block's factors at s.q: correct_positions converged there.)
    (void)dyn_.cs_.polish_positions(s.q, Et, f_, dq_, 3, ChartCorrection::Start::prepared);
    dyn_.mass_at(s.q);
    dyn_.compute_F();
    dyn_.compute_H();
    s.v = project_velocity(dyn_.MF_, dyn_.H_llt_, uu);  // eq. (70)
    dyn_.chart_q_ = s.q;
    dyn_.chart_ready_ = true;
    dyn_.evaluate_dual(tt, s.q, s.v);
    s.u = dyn_.state_.u;
    s.a = dyn_.udot_;
    s.P = dyn_.nonconservative_power();
    return true;
  }

  // Quintic Hermite through (q, u, u̇) at both ends of [t_a, t_a + h], at s ∈ [0, 1]: q and its
  // derivative u (orders 6 and 5).
  static void quintic(double s, double h, const BranchState& A, const BranchState& B, VecX& qs,
                      VecX& us) {
    const double s2 = s * s, s3 = s2 * s, s4 = s3 * s, s5 = s4 * s;
    const double H0 = 1 - 10 * s3 + 15 * s4 - 6 * s5, H1 = s - 6 * s3 + 8 * s4 - 3 * s5;
    const double H2 = 0.5 * s2 - 1.5 * s3 + 1.5 * s4 - 0.5 * s5, H3 = 0.5 * s3 - s4 + 0.5 * s5;
    const double H4 = -4 * s3 + 7 * s4 - 3 * s5, H5 = 10 * s3 - 15 * s4 + 6 * s5;
    const double D0 = -30 * s2 + 60 * s3 - 30 * s4, D1 = 1 - 18 * s2 + 32 * s3 - 15 * s4;
    const double D2 = s - 4.5 * s2 + 6 * s3 - 2.5 * s4, D3 = 1.5 * s2 - 4 * s3 + 2.5 * s4;
    const double D4 = -12 * s2 + 28 * s3 - 15 * s4, D5 = 30 * s2 - 60 * s3 + 30 * s4;
    qs = H0 * A.q + (H1 * h) * A.u + (H2 * h * h) * A.a + (H3 * h * h) * B.a + (H4 * h) * B.u +
         H5 * B.q;
    us = (D0 / h) * A.q + D1 * A.u + (D2 * h) * A.a + (D3 * h) * B.a + D4 * B.u + (D5 / h) * B.q;
  }

  // Spatial bodies (nq ≠ n): the passage works in local coordinates x about the incoming
  // position, q = q_a ⊕ x (the exponential map), whose rates are ẋ = u except for the rotation
  // of a spatial body, θ̇ = J_r(θ)⁻¹ ω (model/spatial.hpp: exp_right_jacobian). For planar bodies
  // x = q − q_a and ẋ = u, and the passage below keeps its planar arithmetic unchanged.
  [[nodiscard]] VecX local_rate(const VecX& xx, const VecX& uu, bool to_x) const {
    VecX out = uu;
    for (const Body& b : model_.bodies)
      if (b.kind == BodyKind::spatial) {
        const Mat3 Jr = exp_right_jacobian(xx.segment<3>(b.u_offset + 3));
        const Vec3 w = uu.segment<3>(b.u_offset + 3);
        out.segment<3>(b.u_offset + 3) = to_x ? Vec3(Jr.lu().solve(w)) : Vec3(Jr * w);
      }
    return out;
  }
  // A branch state in local coordinates about q_a: q ← x, u ← ẋ, a ← ẍ (to first order in θ:
  // ẍ ≈ J_r⁻¹ u̇, exact at x = 0).
  [[nodiscard]] BranchState to_local(const BranchState& S, const VecX& q_a) const {
    BranchState L = S;
    L.q.resize(n_);
    difference_positions(model_, S.q, q_a, L.q);
    L.u = local_rate(L.q, S.u, true);
    L.a = local_rate(L.q, S.a, true);
    return L;
  }

  // Outputs strictly inside a passage step (t_a, t_b): the quintic Hermite of the step in q and
  // u, u̇ linear (no equations are evaluated next to the point; no reactions: some multipliers
  // are indeterminate there).
  void passage_outputs(const PassageStep& p) {
    const BranchState &A = p.stage[0], &B = p.stage[3];
    const double t_a = p.t_a, t_b = p.t_b, h = t_b - t_a;
    VecX qs, us;
    while (grid_pending() && grid_time(next_out_) < t_b - grid_slack_) {
      const double to = grid_time(next_out_);
      if (to > t_a + grid_slack_ && (options_.record_samples || options_.on_sample)) {
        const double s = (to - t_a) / h;
        if (local_passage_) {  // the Hermite in x about q_a, mapped back: q = q_a ⊕ x, u = J ẋ
          VecX xs, xd;
          quintic(s, h, to_local(A, A.q), to_local(B, A.q), xs, xd);
          qs = A.q;
          integrate_positions(model_, qs, xs, 1.0);
          us = local_rate(xs, xd, false);
        } else {
          quintic(s, h, A, B, qs, us);
        }
        passage_sample(to, s, qs, us, p);
      }
      ++next_out_;
    }
  }

  // A sample at `to` (the fraction s of the passage step) at the interpolated (qs, us).
  void passage_sample(double to, double s, const VecX& qs, const VecX& us, const PassageStep& p) {
    const BranchState &A = p.stage[0], &B = p.stage[3];
    dyn_.state_.t = to;
    dyn_.state_.q = qs;
    dyn_.state_.u = us;
    dyn_.udot_ = (1 - s) * A.a + s * B.a;
    SimulationSample& smp = result_.samples.emplace_back();
    smp.t = to;
    smp.q = qs;
    smp.u = us;
    smp.udot = dyn_.udot_;
    smp.kinetic = kinetic_energy(model_, dyn_.state_);
    smp.potential = potential_energy(model_, qs);
    smp.work = (1 - s) * p.W_a + s * p.W_b;
    compute_constraint_residual(model_, qs, f_);
    smp.residual = model_.nc ? f_.cwiseAbs().maxCoeff() : 0.0;
    for (const Measure& m : model_.measures)
      smp.measures.push_back(evaluate_measure(model_, m, qs, &us, &dyn_.udot_));
  }

  // The passage step (dual form) from the approached state (t_a, x) over the change point at
  // t* to t_b = t_a + 2 (t* − t_a), landing at about the same distance beyond it (C3)–(C6).
  // False (why set) when a stage does not close or the checks fail.
  bool pass_change_point(double t_star, double sigma_a, std::string& why) {
    PassageStep p;
    p.t_a = t_now_;
    p.h = 2.0 * (t_star - p.t_a);
    if (p.t_a + p.h > T1_) p.h = T1_ - p.t_a;
    p.t_b = p.t_a + p.h;
    // The incoming state, polished (its equations are those the step integrated).
    if (!on_branch(p.t_a, x_.head(nq_), dyn_.F_ * x_.segment(nq_, na_), p.stage[0], why))
      return false;
    p.W_a = x_(nx_ - 1);
    p.W_b = p.W_a;
    const LobattoIIIA lobatto;
    if (!predict_stages(p, lobatto, why) || !correct_stages(p, lobatto, why)) return false;
    ChangePointPassage pass;
    if (!check_passage(p, t_star, sigma_a, pass, why)) return false;
    land(p, pass);
    // Landed short of the point (σ̂ still falling): passed from the landing, at the zero of σ̂'s
    // tangent there (σ̂ is linear in t this close to it).
    if (!p.crossed && p.rate_b < 0.0) request_ = {true, p.t_b - p.sigma_b / p.rate_b, p.sigma_b};
    return true;
  }

  // (C5) one step of the 4-stage Lobatto IIIA collocation method (order 6) [Hairer, Nørsett
  // & Wanner, Solving ODEs II, §IV.5] on q̇ = u, u̇ = a(q, u), Ẇ = P, whose stages are states
  // on the branch (C4): nodes t_a + c_i h, c = (0, (5 ∓ √5)/10, 1). The interior nodes are
  // 0.45 (t* − t_a) from the point, the last is the landing. Stage values by fixed-point
  // iteration from the Taylor predictor (C3), q_i = q_a + c_i h u_a + ½ (c_i h)² u̇_a,
  // u_i = u_a + c_i h u̇_a.
  bool predict_stages(PassageStep& p, const LobattoIIIA& lobatto, std::string& why) {
    const BranchState& A = p.stage[0];
    VecX q_p, u_p;
    for (int i = 1; i < 4; ++i) {
      const double ch = lobatto.c[i] * p.h;
      if (local_passage_) {
        q_p = A.q;
        integrate_positions(model_, q_p, VecX(ch * A.u + 0.5 * ch * ch * A.a), 1.0);
      } else {
        q_p = A.q + ch * A.u + 0.5 * ch * ch * A.a;
      }
      u_p = A.u + ch * A.a;
      if (i == 3 && options_.passage_hook) options_.passage_hook(p.t_b, q_p, u_p);
      if (!on_branch(p.t_a + ch, q_p, u_p, p.stage[i], why)) return false;
    }
    return true;
  }

  // The stage values' fixed-point iteration: iterated to a change of u below
  // kPassageConverged, or until it stalls at the rounding noise (a change not halving);
  // accepted below kPassageConvergence (C6).
  bool correct_stages(PassageStep& p, const LobattoIIIA& lobatto, std::string& why) {
    const BranchState& A = p.stage[0];
    BranchState& B = p.stage[3];
    const double h = p.h;
    const auto& L = lobatto.L;
    std::vector<VecX> Qn(4), Un(4), xdot(4);
    double previous_change = std::numeric_limits<double>::infinity();
    while (p.iterations < kPassageIterations && !(p.change <= kPassageConverged) &&
           !(p.change > 0.5 * previous_change)) {
      ++p.iterations;
      previous_change = p.change;
      if (local_passage_)  // the stages' rates ẋ_j in local coordinates about q_a
        for (int j = 0; j < 4; ++j) {
          VecX xj(n_);
          difference_positions(model_, p.stage[j].q, A.q, xj);
          xdot[static_cast<size_t>(j)] = local_rate(xj, p.stage[j].u, true);
        }
      for (int i = 1; i < 4; ++i) {  // q_i = q_a + h Σ L_ij u_j, u_i = u_a + h Σ L_ij u̇_j
        Qn[static_cast<size_t>(i)] = A.q;
        Un[static_cast<size_t>(i)] = A.u;
        VecX dx = VecX::Zero(local_passage_ ? n_ : 0);
        for (int j = 0; j < 4; ++j) {
          if (local_passage_)
            dx += (h * L[i][j]) * xdot[static_cast<size_t>(j)];  // q_i = q_a ⊕ h Σ L_ij ẋ_j
          else
            Qn[static_cast<size_t>(i)] += (h * L[i][j]) * p.stage[j].u;
          Un[static_cast<size_t>(i)] += (h * L[i][j]) * p.stage[j].a;
        }
        if (local_passage_) integrate_positions(model_, Qn[static_cast<size_t>(i)], dx, 1.0);
      }
      p.W_b = p.W_a;
      for (int j = 0; j < 4; ++j) p.W_b += h * L[3][j] * p.stage[j].P;
      if (options_.passage_hook) options_.passage_hook(p.t_b, Qn[3], Un[3]);
      const VecX u_old = B.u;
      for (int i = 1; i < 4; ++i)
        if (!on_branch(p.t_a + lobatto.c[i] * h, Qn[static_cast<size_t>(i)],
                       Un[static_cast<size_t>(i)], p.stage[i], why))
          return false;
      const VecX du = B.u - u_old, dj = Un[3] - B.u;
      const double ub2 = std::max(mnorm2(B.u, B.u), 1e-300);
      p.change = std::sqrt(mnorm2(du, du) / ub2);
      p.jump = std::sqrt(mnorm2(dj, dj) / ub2);
    }
    return true;
  }

  // (C6) the checks: velocity continuity (the quadrature velocity is admissible at the
  // landing up to the step's truncation error), no reversal, a regular landing beyond, and (v)
  // the energy balance across the step within the velocity jump's bound (the truncation error
  // along the energy: on n-four-bar-40 at rtol 1e-11 it grew as h⁷, to 2.4e-9 of T on the
  // longest passages, h = 0.037 s, and B0 ended up to 1.2e-6 off at 20 s; docs/theory.md, (C6)).
  // The passage's record and σ̂ with its rate at the landing are set either way.
  bool check_passage(PassageStep& p, double t_star, double sigma_a, ChangePointPassage& pass,
                     std::string& why) {
    const BranchState &A = p.stage[0], &B = p.stage[3];
    const double jump = p.jump, change = p.change;
    const double ub2 = mnorm2(B.u, B.u), ua2 = mnorm2(A.u, A.u);
    const double cosine = ua2 > 0.0 && ub2 > 0.0 ? mnorm2(A.u, B.u) / std::sqrt(ua2 * ub2) : 1.0;
    (void)chart_quality();  // one more inverse-iteration pair: σ̂ at the landing converged
    p.sigma_b = chart_quality_rate(B.q, B.u, p.rate_b);
    const double sigma_b = p.sigma_b;
    // The point's time where the tangents of σ̂ at the step's ends meet (σ̂ is ~linear in |t − t*|
    // next to it, with slopes that differ on the two sides): the estimate t_star that placed the
    // step can be off by a part of it (a passage from farther, from a coarser estimate).
    double t_point = t_star;
    const double rate_a = saved_prev_.valid && saved_prev_.t == p.t_a ? saved_prev_.rate : 0.0;
    if (rate_a < 0.0 && p.rate_b > 0.0)
      t_point = p.t_a + tangents_meet(sigma_a, rate_a, sigma_b, p.rate_b, p.h);
    p.crossed = crossed_in_passage(p, sigma_a, rate_a, t_point);
    pass = {t_point, p.t_a, p.t_b, sigma_a, sigma_b, jump, cosine, p.iterations};
    pass.energy_balance = passage_energy_balance(p);
    char buf[200];
    std::snprintf(buf, sizeof buf,
                  " (velocity jump %.3g relative, cosine %.9f, corrector change %.3g, chart "
                  "quality %.3g before, %.3g after)",
                  jump, cosine, change, sigma_a, sigma_b);
    // The bound, raised to 10× the passage's own rounding noise (the corrector's last change,
    // where it stalled) when that is larger, never above kPassageJumpCeiling.
    const double jump_bound = std::min(
        kPassageJumpCeiling, std::max(passage_velocity_jump_bound(options_.rtol), 10.0 * change));
    if (!(cosine > 0.0) || !(jump <= kBranchJump)) {
      why = "the passage would change the velocity discontinuously, leaving the motion's branch" +
            std::string(buf);
      return false;
    }
    if (!(jump <= jump_bound)) {  // on the branch, but not as accurate as the steps around it
      // The energy balance (the step's truncation) well below the jump: the jump is the
      // landing's rounding noise (~1/σ̂), which a passage from farther reduces (pass()).
      noise_failure_ = pass.energy_balance < 0.5 * jump;
      char bound[64];
      std::snprintf(bound, sizeof bound, "%.3g", jump_bound);
      why = "the passage is less accurate than the bound " + std::string(bound) +
            " on its velocity jump (rtol/10 within [1e-9, 1e-7], or 10× its corrector's noise)" +
            std::string(buf);
      return false;
    }
    if (!(change <= kPassageConvergence)) {
      why = "the passage step's corrector did not converge" + std::string(buf);
      return false;
    }
    if (!(pass.energy_balance <= jump_bound)) {  // (v): retried from closer (pass())
      truncation_failure_ = true;
      char eb[112];
      std::snprintf(eb, sizeof eb, "; its energy balance is off by %.3g of the kinetic energy",
                    pass.energy_balance);
      why = "the passage step's truncation error is above the bound" + std::string(buf) + eb;
      return false;
    }
    if (!(sigma_b >= kLandingQualityRatio * sigma_a)) {
      why = "the landing is not beyond the change point at a regular position" + std::string(buf);
      return false;
    }
    return true;
  }

  // Did the passage step cross the change point? σ̂ still falling at the landing, below its
  // start value: the point lies beyond it (t* was estimated early: σ̂ is concave as it falls).
  // σ̂ falling at the start and rising at the landing with the tangents meeting well above 0
  // (the (C2'') criterion): the step went over a regular minimum of σ̂, not through 0. Either
  // way the step is an ordinary one (its accuracy checked as a passage's) and is not recorded.
  [[nodiscard]] static bool crossed_in_passage(const PassageStep& p, double sigma_a, double rate_a,
                                               double t_point) {
    if (p.rate_b < 0.0 && p.sigma_b < sigma_a) return false;  // short of the point
    if (rate_a < 0.0 && p.rate_b > 0.0) {
      const double tau = t_point - p.t_a;
      const double vertex = std::max(sigma_a + rate_a * tau, p.sigma_b + p.rate_b * (tau - p.h));
      if (!(vertex < kCrossingVertex * std::min(sigma_a, p.sigma_b))) return false;  // minimum
    }
    return true;
  }

  // |Δ(T + V − W)| across the passage step relative to the larger kinetic energy at its ends: 0
  // for the exact motion (dE/dt = P); the step's truncation error along the energy. Less the
  // rounding of the energies' terms (1024 ε of their magnitudes), so that a slow passage
  // (T ≪ |V|) is not refused for the rounding of V.
  double passage_energy_balance(const PassageStep& p) {
    const BranchState &A = p.stage[0], &B = p.stage[3];
    dyn_.state_.q = A.q;
    dyn_.state_.u = A.u;
    const double T_a = kinetic_energy(model_, dyn_.state_), V_a = potential_energy(model_, A.q);
    dyn_.state_.q = B.q;
    dyn_.state_.u = B.u;
    const double T_b = kinetic_energy(model_, dyn_.state_), V_b = potential_energy(model_, B.q);
    const double rounding = 1024.0 * std::numeric_limits<double>::epsilon() *
                            (std::abs(T_a) + std::abs(V_a) + std::abs(p.W_a) + std::abs(T_b) +
                             std::abs(V_b) + std::abs(p.W_b));
    const double imbalance = std::abs((T_b + V_b - p.W_b) - (T_a + V_a - p.W_a));
    const double T = std::max(T_a, T_b);
    return T > 0.0 ? std::max(0.0, imbalance - rounding) / T : 0.0;
  }

  // The run continues from the landing B: outputs inside the step, the ODE state, the monitor's
  // saved state, the energy balance (as after every step), an output at t_b.
  void land(const PassageStep& p, const ChangePointPassage& pass) {
    const BranchState& B = p.stage[3];
    passage_outputs(p);
    x_.head(nq_) = B.q;
    x_.segment(nq_, na_) = B.v;
    x_(nx_ - 1) = p.W_b;
    t_now_ = p.t_b;
    t_last_accept_ = p.t_b;
    if (p.crossed) result_.passages.push_back(pass);
    saved_older_.valid = false;  // the next step starts from the landing ((C2''))
    saved_prev_.valid = true;
    saved_prev_.t = p.t_b;
    saved_prev_.sigma = p.sigma_b;
    saved_prev_.rate = p.rate_b;
    saved_prev_.spread = 0.0;  // no trend across the passage
    next_step_limit_ = std::numeric_limits<double>::infinity();
    saved_prev_.x = x_;
    saved_prev_.chart = dyn_.cs_.chart();
    crossing_rewinds_ = 0;
    // Energy balance at the landing, as after every step.
    dyn_.state_.q = B.q;
    dyn_.state_.u = B.u;
    const double E = kinetic_energy(model_, dyn_.state_) + potential_energy(model_, B.q) - p.W_b;
    result_.energy_max_drift = std::max(result_.energy_max_drift, std::abs(E - energy0_));
    // An event across the passage: applied at the landing (q_, F and u there first).
    if (events_.step_end(model_, p.t_a, p.t_b, B.q, B.u) != Events::StepEnd::smooth) {
      q_ = B.q;
      dyn_.evaluate_dual(p.t_b, x_.head(nq_), x_.segment(nq_, na_));
      if (apply_events(p.t_b, x_)) event_request_ = EventRequest::none;
    } else {
      events_.keep_step_end();
    }
    if (std::abs(t_now_ - grid_time(next_out_)) <= grid_slack_ && grid_pending()) emit(t_now_, x_);
  }

  // ---- The driver -----------------------------------------------------------------------------

  // Integrates to T1 in segments: after a stop by the monitor, undoes the steps that crossed a
  // change point unannounced (C2'), passes the point (C3)–(C6) or approaches it (C2). Sets
  // failure_ (and failure_status_) when the run stops early.
  void drive() {
    try {
      while (true) {
        if (event_request_ == EventRequest::locate) {
          if (!locate_event()) break;
          continue;
        }
        if (!request_.pending) {
          const detail::OdeStats st = run_to(T1_, 0.0);
          if (st.completed && !request_.pending) break;
          if (event_request_ == EventRequest::locate) continue;
          if (!request_.pending) {
            failure_ = !stop_message_.empty() ? stop_message_ : st.message;
            if (stop_message_.empty() && result_.uncorrected_steps > 0)
              failure_ +=
                  "; steps were left uncorrected next to a change point (E nearly loses rank "
                  "there)";
            break;
          }
        }
        const Request rq = request_;
        request_.pending = false;
        if (rewind_to_ >= 0) rewind();
        if (rq.t_star >= T1_ - end_slack_) {  // the change point lies beyond the end: finish
          monitor_armed_ = false;
          continue;
        }
        if (rq.sigma <= pass_quality_) {
          if (!pass(rq)) break;
          continue;
        }
        if (!approach(rq)) break;
      }
    } catch (const SingularEvaluation& e) {
      failure_status_ = SimulateStatus::singular;
      failure_ = e.message;
    }
  }

  // A switching value changed sign inside the step just undone (dynamics/events.hpp):
  // from the bracket's lower end (the saved step end before it), integrations to the regula
  // falsi point until the bracket is within the tolerance; the step that then crosses switches
  // the loads or gives the impact (accept) and the run goes on from there. False: the run stops
  // (failure_ set).
  bool locate_event() {
    const long applied = events_applied_;
    while (true) {
      event_request_ = EventRequest::none;
      if (t_now_ != saved_prev_.t) restore(saved_prev_);  // back to the bracket's lower end
      const double target = events_.next_time();
      const detail::OdeStats st = run_to(target, 0.0);
      if (events_applied_ > applied || request_.pending) {
        events_.abandon();  // (switch_at has reset it when it switched)
        return true;
      }
      if (event_request_ == EventRequest::locate) continue;  // crossed before the target
      if (!st.completed) {
        failure_ = !stop_message_.empty() ? stop_message_ : st.message;
        return false;
      }
      // Reached the target without a change of sign: the lower end moves up (or, at the
      // bracket's upper end, the crossing is not there any more: the run goes on).
      if (target >= events_.bracket_high()) {
        events_.abandon();
        return true;
      }
      if (!events_.reached(target)) {
        failure_ = "cannot locate the switch of a load switched by active_while between t = " +
                   time_text(model_, events_.bracket_low()) + " and " +
                   time_text(model_, events_.bracket_high());
        return false;
      }
    }
  }

  // (C2') undo the steps that crossed the point unannounced: back to the saved state, its
  // outputs after it removed.
  void rewind() {
    const bool older = rewind_to_ == 0;
    rewind_to_ = -1;
    restore(older ? saved_older_ : saved_prev_);  // (restore copies it before it changes them)
    ++result_.rewinds;
  }

  // The run continues from a saved step end: its state, chart and monitor; the outputs after it
  // removed.
  void restore(const SavedState& back) {
    x_ = back.x;
    t_now_ = back.t;
    t_last_accept_ = back.t;
    dyn_.cs_.set_chart(back.chart);
    dyn_.chart_ready_ = false;
    dyn_.state_.load_on = back.load_on;
    events_.set_held(back.held);
    events_.set_pin_signs(back.pin_sign);
    dyn_.pin_sign_ = back.pin_sign;
    while (!result_.contacts.empty() && result_.contacts.back().t_from > t_now_)
      result_.contacts.pop_back();
    for (SimulateResult::StopContact& c : result_.contacts)
      if (c.t_to > t_now_) c.t_to = std::numeric_limits<double>::quiet_NaN();
    while (!result_.samples.empty() && result_.samples.back().t > t_now_ + grid_slack_)
      result_.samples.pop_back();
    while (!result_.chart_switches.empty() && result_.chart_switches.back().t > t_now_)
      result_.chart_switches.pop_back();
    while (next_out_ > 0 && grid_time(next_out_ - 1) > t_now_ + grid_slack_) --next_out_;
    monitor_ = {true, back.t, back.sigma, back.rate};
    const SavedState start = back;  // the state the next step starts from ((C2''))
    saved_older_.valid = false;
    saved_prev_ = start;
    next_step_limit_ = std::numeric_limits<double>::infinity();
    // F at the restored position: a passage from here starts from u = F v, and F_ is still
    // that of the undone steps' last evaluation.
    if (!primal_) dyn_.evaluate_dual(t_now_, x_.head(nq_), x_.segment(nq_, na_));
    if (!events_.empty()) {  // the switching values there
      if (primal_) {
        dyn_.state_.q = x_.head(nq_);
        dyn_.mass_at(dyn_.state_.q);
        dyn_.velocity_from_momentum(x_.segment(nq_, n_));
      }
      if (events_.holding()) contact_forces_at(t_now_, x_);
      events_.restored(model_, x_.head(nq_), dyn_.state_.u);
    }
  }

  [[nodiscard]] std::string change_point_name(double t_star) const {
    return "the change point at t ≈ " + time_text(model_, t_star);
  }

  // σ̂ ≤ pass_quality: the passage (dual form), tried again from closer when it fails; the
  // primal form stops. False: the run stops (failure_ set).
  bool pass(const Request& rq) {
    if (primal_) {  // G = EᵀAE is singular at the change point: no equation there
      failure_status_ = SimulateStatus::singular;
      failure_ = change_point_name(rq.t_star) +
                 " is ahead (E loses rank there, G = EᵀAE is singular): the primal form stops "
                 "at t = " +
                 time_text(model_, t_now_) + "; the dual form passes it";
      return false;
    }
    std::string why;
    const double t_from = t_now_;
    if (!pass_change_point(rq.t_star, rq.sigma, why)) {
      dyn_.chart_ready_ = false;  // the attempt moved the chart's factors elsewhere
      // The first attempt's reason is kept for the message: the later ones, closer to the
      // point, are dominated by rounding noise (ε/σ̂²) rather than the step's truncation.
      if (first_passage_why_.empty()) first_passage_why_ = why;
      const bool noise = noise_failure_;
      noise_failure_ = false;
      if (noise && far_.valid && far_.t < t_from && far_.sigma > 2.0 * rq.sigma &&
          far_retries_ < kMaxFartherRetries) {  // from the saved state farther from the point
        ++far_retries_;
        const SavedState from = far_;
        far_.valid = false;
        restore(from);
        pass_quality_ = from.sigma;
        request_ = {true, rq.t_star, from.sigma};
        approaches_ = 0;
        return true;
      }
      const double closer = truncation_failure_ ? kTruncationRetry : kRetry;
      truncation_failure_ = false;
      if (rq.sigma * closer >= kPassQualityFloor) {  // try again from closer
        pass_quality_ = rq.sigma * closer;
        request_ = {true, rq.t_star, rq.sigma};
        approaches_ = 0;
        return true;
      }
      failure_ = "cannot pass " + change_point_name(rq.t_star) +
                 " from t = " + time_text(model_, t_from) + ": " + why +
                 (first_passage_why_ != why ? "; first attempt: " + first_passage_why_ : "");
      return false;
    }
    first_passage_why_.clear();
    far_.valid = false;
    far_retries_ = 0;
    monitor_.valid = false;
    saved_older_.valid = false;  // saved_prev: the landing
    approaches_ = 0;
    pass_quality_ = std::min(kPassQuality, 2.0 * pass_quality_);
    return true;
  }

  // (C2) approach: a segment that ends short of the change point (its estimate improves as
  // σ̂ falls), until σ̂ ≤ pass_quality. False: the run stops (failure_ set).
  bool approach(const Request& rq) {
    if (++approaches_ > kMaxApproaches) {  // σ̂ does not go to 0 here: not a change point
      monitor_quiet_ = true;
      approaches_ = 0;
      return true;
    }
    const double fraction =
        std::min(kApproachFraction, 1.0 - kApproachTarget * pass_quality_ / rq.sigma);
    const double dist = rq.t_star - t_now_;
    const detail::OdeStats sa = run_to(t_now_ + fraction * dist, kApproachStep * dist);
    if (!sa.completed && !request_.pending && event_request_ != EventRequest::locate) {
      failure_ = !stop_message_.empty() ? stop_message_ : sa.message;
      return false;
    }
    // Completed (its last step raises a new request when the point is near) or stopped by a
    // newer request: the loop goes on from there.
    return true;
  }

  // ---- Final sample and status ----------------------------------------------------------------

  void finish() {
    collect_limits();
    result_.evaluations = evaluations_;
    result_.rejected_steps = rejected_steps_;
    result_.jacobians = jacobians_;
    if (!failure_.empty()) {
      finish_stopped();
      return;
    }
    // Final sample at the corrected final state.
    try {
      sample_at(t_now_, x_, result_.final);
    } catch (const SingularEvaluation& e) {
      result_.status = SimulateStatus::singular;
      result_.message = e.message;
      return;
    }
    result_.energy_initial = energy0_;
    result_.energy_final = result_.final.kinetic + result_.final.potential - result_.final.work;
    result_.max_constraint_residual =
        std::max(result_.max_constraint_residual, result_.final.residual);
    if (model_.nc) {
      VecX f_final(model_.nc);
      compute_constraint_residual(model_, result_.final.q, f_final);
      note_residual(f_final);
    }
    if (!primal_)
      for (const auto& smp : result_.samples)
        result_.max_velocity_residual =
            std::max(result_.max_velocity_residual, smp.velocity_residual);
    result_.status = SimulateStatus::completed;
    check_energy_balance();
  }

  // The energy balance T + V − W against what the tolerance allows (energy_drift_limit): a run
  // whose balance drifted beyond it is not `completed` (its motion cannot be vouched for).
  void check_energy_balance() {
    result_.energy_drift_limit = energy_drift_limit(options_.rtol);
    const double drift =
        result_.energy_scale > 0.0 ? result_.energy_max_drift / result_.energy_scale : 0.0;
    if (!(drift > result_.energy_drift_limit)) return;
    char text[160];
    std::snprintf(text, sizeof text,
                  "the energy balance T + V - W drifted by %.3g relative, beyond the %.3g that "
                  "rtol %.3g allows",
                  drift, result_.energy_drift_limit, options_.rtol);
    result_.status = SimulateStatus::energy_drift;
    result_.message =
        std::string(text) +
        ": the motion does not meet its tolerance (a discontinuity of the forces that "
        "is not an event defeats the step-size control)";
  }

  // A run stopped early: its status and message, and the final sample at the stop time (the
  // last accepted, corrected state).
  void finish_stopped() {
    result_.status = failure_status_;
    result_.message = failure_;
    try {
      sample_at(t_last_accept_ > t_now_ ? t_last_accept_ : t_now_, x_, result_.final);
    } catch (const SingularEvaluation&) {
      // No equation at the stop (G or the chart singular there): the last output, or, when the
      // run stopped before its first one, the stop's position and velocity alone (no
      // accelerations, multipliers or measures: they cannot be vouched for there).
      if (!result_.samples.empty()) {
        result_.final = result_.samples.back();
      } else {
        result_.final = SimulationSample{};
        result_.final.q = x_.head(nq_);
        result_.final.u = dyn_.state_.u.size() == n_ ? dyn_.state_.u : VecX::Zero(n_);
      }
      result_.final.t = std::max(t_now_, t_last_accept_);
    }
    result_.energy_initial = energy0_;
    result_.energy_final = result_.final.kinetic + result_.final.potential - result_.final.work;
    result_.energy_drift_limit = energy_drift_limit(options_.rtol);
  }

  // ---- State ----------------------------------------------------------------------------------

  const Model& model_;
  Chart mobility_chart_;  // the start's chart from compute_mobility (reuse_mobility_chart)
  const State& initial_;
  const SimulateOptions& options_;
  SimulateResult result_;
  bool primal_;
  int n_, nq_, na_, rank_, nx_;
  Dynamics dyn_;
  VecX q_;  // the last corrected position
  VecX x_;  // the ODE state
  VecX f_, dq_, u_step_;
  // Output grid.
  double T0_, T1_, dt_out_, grid_slack_, end_slack_;
  long next_out_ = 0;
  // Energy balance and counters.
  double energy0_ = 0.0;
  bool have_energy0_ = false;
  long evaluations_ = 0;
  // The chart monitor's switching rule: quality 1/spread, threshold 1/kSpreadLimit.
  ChartSwitchRule chart_rule_{1.0 / kSpreadLimit, 2.0, ChartSwitchRule::Retry::after_further_fall};
  // Change-point monitor.
  VecX sigma_w_;
  double sigma_ref_ = 0.0;
  MonitorPoint monitor_;
  Request request_;
  SavedState saved_older_, saved_prev_;
  int rewind_to_ = -1;    // 0: saved_older, 1: saved_prev (with request)
  size_t delivered_ = 0;  // result_.samples[0, delivered_) went to options_.on_sample
  double last_rewind_t_star_ = -std::numeric_limits<double>::infinity();
  bool monitor_armed_ = true;
  // Set when an approach does not reach σ̂ ≤ pass_quality in kMaxApproaches segments (σ̂ has a
  // minimum above 0 there, not a change point): no request until σ̂ rises again.
  bool monitor_quiet_ = false;
  double pass_quality_ = kPassQuality;  // σ̂ at which the next passage is tried
  bool noise_failure_ = false;       // the last passage failed its velocity jump by rounding noise
  SavedState far_;                   // the latest step end with σ̂ in [kFarPassQuality, …Max]
  int far_retries_ = 0;              // passages tried from far_ for the point ahead
  bool truncation_failure_ = false;  // the last passage failed its energy balance
  double t_last_accept_, h_last_ = 0.0;
  Events events_;
  std::vector<StopHit> hits_;
  StopContacts contacts_;
  std::vector<double> contact_mu_;     // the held stops' contact forces at the last evaluation
  std::vector<double> contact_value_;  // their switching values (contact_forces_at)
  VecX contact_dy_;                    // contact_forces_at's evaluation
  long events_applied_ = 0;            // the stops met at an event
  VecX stop_d_, stop_c_, stop_Hc_;     // an impact's gradient d, c = σ Fᵀ dᵀ, H⁻¹ c
  EventRequest event_request_ = EventRequest::none;
  // chart_quality_rate's work space.
  VecX sigma_left_, rate_x_, rate_plus_, rate_minus_;
  VecX g_y_, g_z_, g_Ety_;  // primal_quality_rate's eigenvector, G⁻¹ y, E y
  State rate_state_;
  BodyPoses rate_rotations_;
  std::string stop_message_;  // why accept stopped the integrator
  int crossing_rewinds_ = 0;
  double last_crossing_t_star_ = -std::numeric_limits<double>::infinity();
  detail::OdeProblem problem_;
  double spread_now_ = 0.0;  // the chart's spread after the last acceptance (dual form)
  double next_step_limit_ = std::numeric_limits<double>::infinity();
  double max_quality_rate_ = 0.0;       // the largest |dσ̂/dt| of the run (limit_step_by_quality)
  std::vector<char> angular_row_;       // rows of f that are angles
  bool local_passage_;                  // passages in local coordinates (spatial bodies)
  RunMonitor monitor_run_;              // the step budget, time limit, interrupt and progress
  double window_t_;                     // t at the start of beyond_budget's window
  std::vector<int> limited_;            // joints with limits
  std::vector<LimitExit> limit_exits_;  // per limited_ joint
  // Segments and the driver.
  detail::OdeOptions base_;
  double t_now_;
  long rejected_steps_ = 0, jacobians_ = 0;  // summed over the segments
  std::string failure_, first_passage_why_;
  SimulateStatus failure_status_ = SimulateStatus::failed_step;
  int approaches_ = 0;
};

}  // namespace

SimulateResult simulate(const Model& model, const SimulateOptions& options) {
  State s(model);
  s.q = model.design_q();
  if (options.initial_u.size() == model.n) s.u = options.initial_u;
  if (options.initial_rates.empty() && options.use_file_rates && !model.initial.rates.empty()) {
    SimulateOptions with_file_rates = options;  // the file's initial rates (Model::initial)
    for (const InitialRateSpec& r : model.initial.rates)
      with_file_rates.initial_rates.push_back({r.measure, r.rate});
    return simulate(model, s, with_file_rates);
  }
  return simulate(model, s, options);
}

SimulateResult simulate(const Model& model, const State& initial, const SimulateOptions& options) {
  SimulateResult result;
  result.form = options.form;
  if (!(options.t_end > 0.0)) throw std::invalid_argument("simulate: t_end must be positive");
  if (const std::string problem = request_problem(options); !problem.empty()) {
    result.status = SimulateStatus::stopped;
    result.stop = StopReason::work_budget;
    result.message = problem;
    return result;
  }
  VecX q;
  int rank = 0;
  Chart chart;
  if (!consistent_start(model, initial, options, q, rank, chart, result)) return result;
  Simulation simulation(model, initial, options, q, rank, std::move(chart), std::move(result));
  return simulation.run();
}

}  // namespace orthomech
