#pragma once
// Forward dynamics of the constrained system (issue 5; paper §7; docs/design.md §4–5).
//
// Initial conditions: the design position is projected onto f(q) = 0 (mass-metric Gauss–Newton,
// analysis/positions.hpp; it can switch to Ipopt's `assemble` once that exists), then the
// velocity guess u₀ is made admissible by the mass-orthogonal projection u = α u₀ (closed form,
// the closest admissible velocity in the kinetic-energy norm; the energy removed, ½ (βu₀)ᵀ M
// (βu₀), is reported). Requested input rates (e.g. "B0_vx = 1 m/s") then fix the admissible
// velocity by least squares in the chart coordinates.
//
// Dual form (default): ODE state (q, v) in the current chart, u = F v; H v̇ = Fᵀ (Q̂ − Ṁ u − M Ḟ v)
// (eq. (68)). After every accepted step: Newton position correction in the chart (the
// independent coordinates stay, the dependent ones move), then a chart check; on a switch v is
// re-expressed in the new chart from u. Velocities are admissible by construction (u = F v).
// Primal form: Theorem 7, ṗ = αᵀ Q̂ − Ω u + βᵀ Ṁ u, u = A p (eq. (99), eq. (100)); after every
// accepted step the invariant J = Eᵀ A p (eq. (105)) is recorded, then positions are corrected
// and the momenta projected (p ← M α u).
// Energy: T + V − W, with W the work of the non-conservative loads (torques, point forces,
// dampers), integrated with the motion; it is constant for every model.
#include <functional>
#include <string>
#include <vector>

#include "orthomech/analysis/positions.hpp"
#include "orthomech/analysis/reactions.hpp"
#include "orthomech/model/model.hpp"
#include "orthomech/model/state.hpp"
#include "orthomech/run_control.hpp"

namespace orthomech {

enum class DynamicsForm { dual, primal };
// The integrators behind `simulate --integrator` (docs/theory.md, "Integrators"):
//   dopri5          Dormand–Prince 5(4), dense output of order 4 (default; moderate tolerances)
//   rkf78           Runge–Kutta–Fehlberg 7(8); steps land on the output times
//   bulirsch_stoer  Bulirsch–Stoer extrapolation (orders up to 16), dense output: long runs at
//                   tight tolerances
//   rosenbrock4     Rosenbrock 4(3), L-stable, Jacobian by central differences of the right-hand
//                   side: stiff mechanisms (stiff spring-dampers); steps land on the output times
enum class Integrator { dopri5, rkf78, bulirsch_stoer, rosenbrock4 };
[[nodiscard]] const char* to_string(Integrator i);  // "dopri5", "rkf78", "bulirsch-stoer", …
// The integrator named `name` (as to_string gives it); false when there is none.
[[nodiscard]] bool parse_integrator(const std::string& name, Integrator& out);

// A prescribed initial rate: the rate of a measure's underlying position quantity (a joint
// coordinate, a point coordinate, a distance, a body angle).
struct InitialRate {
  int measure = -1;
  double rate = 0.0;  // SI: m/s or rad/s
};

struct SimulationSample;

// The default step budget of a motion: about 3 to 60 minutes of stepping at 2 to 20 µs a step,
// far beyond every bundled motion (the longest, the 2000 s pendulum, takes about 1e5 steps).
inline constexpr long kDefaultMaxSteps = 10'000'000;
inline constexpr long kMaxMaxSteps = 1'000'000'000;

struct SimulateOptions {
  DynamicsForm form = DynamicsForm::dual;
  Integrator integrator = Integrator::dopri5;
  double t_end = 1.0;     // s
  double rtol = 1e-8;     // relative tolerance of the step-size control
  double atol = 1e-10;    // absolute tolerance (SI units of q, v or p)
  double dt_out = 0.0;    // s; 0: t_end / 100
  double max_step = 0.0;  // s; 0: unlimited
  VecX initial_u;         // guess u₀ (size n) or empty (zero)
  // Prescribed initial rates. When empty, those of the mechanism file (Model::initial.rates)
  // are used unless use_file_rates is false; when given, they replace the file's (all of them).
  std::vector<InitialRate> initial_rates;
  bool use_file_rates = true;
  bool record_samples = true;         // keep every output sample (else only the final one)
  bool reactions = true;              // compute λ and joint reactions at the samples
  double position_tolerance = 1e-12;  // max |f| after the per-step correction (m, rad)
  // Evaluate every stage at its position projected onto f(q) = 0 in the chart (independent
  // coordinates fixed; primal form: and its velocity onto the admissible ones, independent
  // components kept). Needed to pass change points (IFToMM A02) at a sane step size; costs
  // about one Newton iteration per evaluation. Always on for rosenbrock4.
  bool project_stages = false;
  // The budget of accepted steps over the whole run (every segment and passage), the wall-clock
  // limit, the interrupt flag and the progress callback (run_control.hpp). A run that meets one
  // stops with status `stopped` and what it computed so far. A request that cannot fit the
  // budget (t_end / max_step steps at least) is refused before it starts (request_problem).
  long max_steps = kDefaultMaxSteps;
  RunControl control;
  // For tests only: called with the predicted landing state (t, q, u) of every change-point
  // passage before it is corrected, so that a test can force a passage onto a wrong branch and
  // see it refused. Empty in every normal run.
  std::function<void(double t, VecX& q, VecX& u)> passage_hook;
  // Called once per output sample, in time order (the outputs inside a change-point passage
  // included), as soon as no rewind can undo it (a few steps behind the integrator). With
  // record_samples false the result then keeps no samples (only `final` and the summary): the
  // memory does not grow with the number of outputs (`simulate --json`, `--out`).
  std::function<void(const SimulationSample&)> on_sample;
};

// completed: the run reached t_end and its energy balance held within its limit;
// energy_drift: it reached t_end but T + V − W drifted beyond what the tolerance allows
//   (energy_drift_limit): the motion cannot be vouched for (e.g. a force that jumps with the
//   state other than by `active_while`, whose switches are events);
// stopped: a bound of SimulateOptions (max_steps, control) stopped it before t_end (stop says
//   which); the samples up to the stop are kept;
// sliding: loads switched by `active_while` chatter (each switch turns their measure's rate back,
//   holding it at 0: a Coulomb torque written with active_while that sticks), so the motion from
//   there is not determined; the samples up to it are kept.
// resting: a joint with end stops came to rest against one (impacts at ever shorter intervals)
//   where its contact could not hold it (the stop would have to pull at once): the motion from
//   there is not determined; the samples up to it are kept. (A joint that comes to rest pressed
//   against its stop is held there, SimulateResult::contacts, and the run goes on.)
enum class SimulateStatus {
  completed,
  failed_assembly,
  failed_step,
  singular,
  energy_drift,
  stopped,
  sliding,
  resting
};
[[nodiscard]] const char* to_string(SimulateStatus s);

struct SimulationSample {
  double t = 0.0;
  VecX q, u, udot, lambda;
  std::vector<double> measures;   // per Model::measures
  std::vector<double> reactions;  // per reaction component (analysis/reactions.hpp)
  double kinetic = 0.0, potential = 0.0;
  double work = 0.0;               // work of the non-conservative loads since t = 0
  double residual = 0.0;           // max |f(q)| (m, rad)
  double velocity_residual = 0.0;  // max |Eᵀ u|
};

struct ChartSwitch {
  double t = 0.0;
  std::string from, to;  // independent velocity components, e.g. "link0.phi"
};

// A change point passed by the dual form (docs/theory.md, "Change points"): the passage step
// from t_from (approach, chart quality sigma_from) to t_to (landing beyond the point), and its
// checks: the velocity removed when the landed velocity is made admissible (relative, in the
// mass metric) and the cosine of the incoming and outgoing velocities in the mass metric.
struct ChangePointPassage {
  double t = 0.0;                           // estimated time of the change point (s)
  double t_from = 0.0, t_to = 0.0;          // the passage step (s)
  double sigma_from = 0.0, sigma_to = 0.0;  // chart quality σ̂ before and after
  double velocity_jump = 0.0;               // ‖u_pred − u_to‖_M / ‖u_to‖_M
  double tangent_cosine = 0.0;              // ⟨u_from, u_to⟩_M / (‖u_from‖_M ‖u_to‖_M)
  int iterations = 0;                       // corrector iterations of the passage step
  double energy_balance = 0.0;              // |Δ(T + V − W)| / max(T_from, T_to) over the step
};

// A joint that left its `limits:` during the motion (simulate does not enforce limits: no end
// stops yet). Checked after every accepted step and at every output sample; values are the joint
// coordinate (rad or m), a revolute's angle taken within a turn of the limits' middle
// (analysis/cycle_metrics.hpp).
struct LimitExit {
  int joint = -1;
  double t_first = 0.0, value_first = 0.0;        // where it first left them
  double t_furthest = 0.0, value_furthest = 0.0;  // furthest beyond them
  long steps = 0;                                 // accepted steps and output samples outside them
};

struct SimulateResult {
  SimulateStatus status = SimulateStatus::failed_step;
  std::string message;
  DynamicsForm form = DynamicsForm::dual;
  SolveResult assembly;          // initial position projection
  double kinetic_removed = 0.0;  // by the velocity projection u = α u₀
  std::vector<ReactionComponent> components;
  std::vector<SimulationSample> samples;  // at t = 0, dt_out, 2 dt_out, …, t_end
  SimulationSample final;
  std::vector<ChartSwitch> chart_switches;
  std::vector<ChangePointPassage> passages;  // change points passed (dual form), in order
  double energy_initial = 0.0, energy_final = 0.0;
  double energy_max_drift = 0.0;  // max |E(t) − E(0)| over the accepted steps (J)
  double energy_scale = 0.0;      // max (|T| + |V| + |W|) (J): for relative drifts
  // The largest relative drift energy_max_drift / energy_scale the run's tolerance allows
  // (energy_drift_limit(rtol)); beyond it the status is energy_drift.
  double energy_drift_limit = 0.0;
  StopReason stop = StopReason::none;    // status stopped: which bound
  std::vector<LimitExit> limits_left;    // joints that left their limits, in joint order
  double max_constraint_residual = 0.0;  // max |f| over the accepted steps before correction
  // The same split by kind of row: length rows (m) and angular rows, "angle"/"ratio" (rad).
  double max_residual_length = 0.0, max_residual_angle = 0.0;
  double max_velocity_residual = 0.0;  // max |Eᵀ u| (dual: after the step; primal: |J|)
  double max_invariant_J = 0.0;        // primal: max |J|, eq. (105), before projection
  long steps = 0;
  long uncorrected_steps = 0;  // steps left uncorrected next to a change point
  long rewinds = 0;            // steps undone because they crossed a change point unannounced
  long load_switches = 0;      // events: loads switched on or off by `active_while`
  // Events: a pin with friction whose relative rate changed sign (its moment reversed).
  long friction_switches = 0;
  // Events: impacts on end stops (`end_stops`), in time order: the joint, +1 at its lower stop
  // or −1 at its upper one, the speed of its coordinate towards the stop before (> 0) and away
  // from it after (e times it), the kinetic energy lost (J).
  struct StopImpact {
    double t = 0.0;
    int joint = -1, side = 0;
    double speed_before = 0.0, speed_after = 0.0, energy_loss = 0.0;
  };
  std::vector<StopImpact> impacts;
  // Resting contacts: a joint that came to rest against its end stop (impacts at ever shorter
  // intervals) held there as a constraint, from `t_from` until its contact force would pull
  // (`t_to`; NaN when it still rests at the run's end); the stop's side as in StopImpact, or 0
  // for a pin stuck by its friction (held at zero relative rate until the moment it needs
  // reaches μ r |F|).
  struct StopContact {
    double t_from = 0.0, t_to = 0.0;
    int joint = -1, side = 0;
  };
  std::vector<StopContact> contacts;
  long evaluations = 0;     // right-hand side evaluations
  long rejected_steps = 0;  // rejected step attempts (rkf78, rosenbrock4)
  long jacobians = 0;       // Jacobians by finite differences (rosenbrock4)
};

// The relative energy drift a run at relative tolerance `rtol` may show: kEnergyDriftFactor ·
// rtol, at least kEnergyDriftFloor (docs/theory.md "The energy balance").
inline constexpr double kEnergyDriftFactor = 1e4;
inline constexpr double kEnergyDriftFloor = 1e-6;
[[nodiscard]] double energy_drift_limit(double rtol);

// A switch of a load by `active_while` (an event, SimulateResult::load_switches) is located
// within kEventTimeTolerance · max(t_end, 1 s) after the first time its measure's rate has the
// new sign (docs/theory.md "Switched loads as events").
inline constexpr double kEventTimeTolerance = 1e-10;

// "" when the request fits its bounds; else why not, naming the options (t_end / max_step needs
// more steps than max_steps allows). simulate() returns status `stopped` for such a request
// without starting.
[[nodiscard]] std::string request_problem(const SimulateOptions& options);

// Simulates from the design position (projected) with the velocity given by the options.
[[nodiscard]] SimulateResult simulate(const Model& model, const SimulateOptions& options);
// Same from a given state (positions and velocities are still made consistent first).
[[nodiscard]] SimulateResult simulate(const Model& model, const State& initial,
                                      const SimulateOptions& options);

}  // namespace orthomech
