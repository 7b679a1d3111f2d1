#include "orthomech/dynamics/simulate.hpp"

#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <vector>

#include "integrator.hpp"
#include "orthomech/analysis/assembly.hpp"
#include "orthomech/analysis/mobility.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/dynamics/equations.hpp"
#include "orthomech/io/units.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/model/general_system.hpp"
#include "orthomech/model/loads.hpp"
#include "orthomech/model/measures.hpp"
#include "orthomech/model/spatial.hpp"
#include "orthomech/projection/free_system_stage.hpp"
#include "orthomech/projection/primal.hpp"

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
  }
  return "?";
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

// A time for a message, in the file's declared time unit (a model built in code: s).
std::string time_text(const Model& model, double t) {
  return format_quantity(t, Dimension::time, unit_system(model.units), 9);
}

}  // namespace

namespace {

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
// The chart's block is singular for the integrator below this quality (min/max pivot of its LU).
constexpr double kSingularBlock = 1e-14;
// A step ends at most this fraction of the way to the chart's singularity extrapolated from the
// spread (1/spread linear in t next to it).
constexpr double kChartStepFraction = 0.5;

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
// Approach: each approach segment covers at most this fraction of the way to t* and aims at
// kApproachTarget · pass_quality.
constexpr double kApproachFraction = 0.75;
constexpr double kApproachTarget = 0.8;
// Steps of an approach segment at most this fraction of the estimated distance to t*: far from
// the point σ̂ is not yet linear and t* is rough; every step re-estimates it (C2).
constexpr double kApproachStep = 0.25;
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

// Thrown inside a right-hand side when the equations cannot be evaluated (singular chart block
// or singular G); caught in simulate() and returned as a status (never escapes the library).
struct SingularEvaluation {
  std::string message;
};

// "K1.phi": the user's name of a velocity component.
std::string velocity_name(const Model& model, int k) {
  if (model.general) return model.general->coordinates[static_cast<size_t>(k)];
  for (const Body& b : model.bodies) {
    if (k >= b.u_offset && k < b.u_offset + b.nu()) {
      static const char* const kPlanar[] = {"x", "y", "phi"};
      static const char* const kSpatial[] = {"vx", "vy", "vz", "wx", "wy", "wz"};
      const char* const* kNames = b.kind == BodyKind::spatial ? kSpatial : kPlanar;
      std::string name = b.name;
      name.push_back('.');
      name.append(kNames[k - b.u_offset]);
      return name;
    }
  }
  return "?";
}

std::string chart_name(const Model& model, const Chart& c) {
  std::string s;
  for (size_t k = 0; k < c.independent.size(); ++k) {
    if (k) s.push_back(',');
    s.append(velocity_name(model, c.independent[k]));
  }
  return s;
}

// Whether the dual form evaluates every stage at its position projected onto f(q) = 0 in the
// chart (independent coordinates fixed): on request, and always for rosenbrock4. Its Jacobian
// is then that of the ODE on the constraint manifold in chart coordinates (the columns of the
// dependent coordinates are zero). Without the projection the right-hand side off the manifold
// is that of F extended through Eᵀ(q), which stiffens as the chart degrades: rosenbrock4 needed
// 14 812 steps (2·10⁻⁶ s next to the change points) on n-four-bar-2 over 10 s at rtol 1e-6,
// 1057 with it (issue 10; docs/theory.md, "Rosenbrock on the chart's ODE").
bool projects_stages(const SimulateOptions& options) {
  return options.project_stages ||
         (options.form == DynamicsForm::dual && options.integrator == Integrator::rosenbrock4);
}

// Everything the two forms share: the free system, constraints, the chart solver for F and for
// position correction, the power of the non-conservative loads, and the samples.
class Dynamics {
 public:
  Dynamics(const Model& model, int rank, const SimulateOptions& options)
      : model_(model),
        options_(options),
        n_(model.n),
        nq_(model.nq),
        nc_(model.nc),
        r_(rank),
        na_(model.n - rank),
        project_stages_(projects_stages(options)),
        ws_(model, rank),
        cs_(model, rank, ChartFactorisation::sparse_when_large),
        state_(model),
        F_(MatX::Zero(model.n, model.n - rank)),
        MF_(model.n, model.n - rank),
        H_(model.n - rank, model.n - rank),
        H_llt_(model.n - rank),
        Fdv_(VecX::Zero(model.n)),
        b_(VecX::Zero(model.nc)),
        col_(VecX::Zero(model.n)),
        rhs_(VecX::Zero(model.n - rank)),
        vdot_(VecX::Zero(model.n - rank)),
        udot_(VecX::Zero(model.n)),
        tmp_(VecX::Zero(model.n)),
        Qnc_(VecX::Zero(model.n)),
        lambda_(VecX::Zero(model.nc)),
        AEt_(model.n, model.nc),
        G_(model.nc, model.nc),
        G_llt_(model.nc),
        dq_(VecX::Zero(model.n)),
        chart_q_(VecX::Zero(model.nq)),
        rotations_(model) {
    for (const Load& l : model.loads)
      if (std::holds_alternative<PointForce>(l.kind) || std::holds_alternative<Torque>(l.kind) ||
          std::holds_alternative<SpatialPointForce>(l.kind) ||
          std::holds_alternative<SpatialTorque>(l.kind))
        nonconservative_.push_back(&l);
  }

  // ---- Shared pieces ----------------------------------------------------------------------

  // Free system at state_ (M once if constant; Q̂; Ṁ).
  void free_system() { compute_free_system(model_, state_, ws_); }
  // M, A at q when M depends on q (before products with M or A at a corrected position).
  void mass_at(const VecX& q) {
    if (ws_.free.constant_mass) return;
    state_.q = q;
    free_system();
  }

  // Power of the non-conservative loads at state_: Q_ncᵀ u − dissipated power.
  double nonconservative_power() {
    // General system (general_system.hpp): Q̂ = Q + ∂T/∂q and ∂T/∂q · u = ½ uᵀṀu, so the
    // power of the applied forces is Q̂ᵀu − ½ uᵀṀu (dT/dt = uᵀṗ − ½ uᵀṀu, uᵀR = 0).
    if (model_.general)
      return ws_.free.Q.dot(state_.u) - 0.5 * state_.u.dot(ws_.free.Mdot * state_.u);
    if (nonconservative_.empty() && !has_dampers()) return 0.0;
    Qnc_.setZero();
    for (const Load* l : nonconservative_) add_load(model_, *l, state_, Qnc_);
    return Qnc_.dot(state_.u) - dissipated_power(model_, state_);
  }
  bool has_dampers() const {
    for (const Load& l : model_.loads) {
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

  // λ (size nc): λ_R = (E_RD)⁻¹ c_D on the chart's rows, 0 on the others: the unique λ of
  // E λ = c when E has full column rank and c ∈ range(E).
  void solve_transposed(const VecX& c, VecX& lambda) {
    lambda.setZero();
    auto lambda_r = col_.head(r_);  // scratch
    cs_.solve_transposed(c, lambda_r);
    for (int i = 0; i < r_; ++i) lambda(cs_.chart().rows[static_cast<size_t>(i)]) = lambda_r(i);
  }

  // The chart's block at Eᵀ (scaled to the free system's metric). False when it is singular.
  bool factor_chart(const MatX& Et) { return cs_.factor(Et, ws_.free.A_sqrt) > kSingularBlock; }

  // F in the current chart at Eᵀ = ws_.constraints.Et (factorised): F = P [I; −(E_RDᵀ)⁻¹ E_RIᵀ].
  void compute_F() {
    const Chart& c = cs_.chart();
    const MatX& Et = ws_.constraints.Et;
    for (int k = 0; k < na_; ++k) {
      const int ik = c.independent[static_cast<size_t>(k)];
      b_ = -Et.col(ik);
      cs_.solve(b_, col_);
      col_(ik) = 1.0;
      F_.col(k) = col_;
    }
  }

  // Largest entry of F in the mass metric, |F_dk| √M_dd / √M_ii (i = independent k): it grows
  // without bound as the chart's dependent block degrades (design §4: the chart monitor).
  double chart_spread() const {
    const VecX& s = ws_.free.A_sqrt;  // 1/√M_kk
    double m = 0.0;
    const Chart& c = cs_.chart();
    for (int k = 0; k < na_; ++k) {
      const int ik = c.independent[static_cast<size_t>(k)];
      for (int d : c.dependent) m = std::max(m, std::abs(F_(d, k)) * s(ik) / s(d));
    }
    return m;
  }

  VecX M_sqrt() const { return ws_.free.M_diag.cwiseSqrt(); }

  // H = Fᵀ M F (eq. (68)) and its Cholesky factor.
  void compute_H() {
    if (ws_.free.diagonal_mass)
      MF_ = ws_.free.M_diag.asDiagonal() * F_;
    else
      MF_.noalias() = ws_.free.M * F_;
    H_.noalias() = F_.transpose() * MF_;  // eq. (68)
    H_llt_.compute(H_);
  }

  // Dual form at (t, q, v): u = F v, Ḟ v from Eᵀ (Ḟ v) = −Dᵀ u, H v̇ = Fᵀ (Q̂ − Ṁ u − M Ḟ v).
  void evaluate_dual(double t, const Eigen::Ref<const VecX>& q, const Eigen::Ref<const VecX>& v) {
    state_.t = t;
    state_.q = q;
    // 0. The stage's position projected onto f(q) = 0 with its independent coordinates fixed
    //    (L4): the right-hand side is then the ODE on the constraint manifold in the chart
    //    coordinates, smooth even next to a change point, where F off the manifold is very
    //    sensitive to the stage's constraint error (IFToMM A02).
    if (project_stages_) {
      // Leaves Eᵀ at the projected q factorised in the chart.
      const SolveResult pr = cs_.correct_positions(state_.q, ws_.constraints.Et, ws_.constraints.f,
                                                   dq_, {.tolerance = options_.position_tolerance});
      if (pr.status != SolveStatus::converged) {  // factorise at the q it stopped at
        compute_constraint_jacobian(model_, state_.q, ws_.constraints.Et);
        if (pr.status == SolveStatus::singular || !factor_chart(ws_.constraints.Et))
          throw SingularEvaluation{"the chart's dependent block is singular at t = " +
                                   time_text(model_, t) + " (a change point: E loses rank)"};
      }
      compute_F();
      chart_ready_ = false;
      rotations_.update(model_, state_.q);
    } else if (!(chart_ready_ && state_.q == chart_q_)) {
      // 1. Eᵀ(q), the chart's dependent block, F, unless they are already those at q (the
      //    stepper restarts at the accepted state, where the acceptance has just computed them).
      //    The bodies' rotations at q come along for the constraint rate below.
      rotations_.update(model_, state_.q);
      compute_constraint_residual_and_jacobian(model_, state_.q, rotations_, ws_.constraints.f,
                                               ws_.constraints.Et);
      if (!factor_chart(ws_.constraints.Et))
        throw SingularEvaluation{"the chart's dependent block is singular at t = " +
                                 time_text(model_, t) + " (a change point: E loses rank)"};
      compute_F();
      chart_q_ = state_.q;
      chart_ready_ = true;
    } else {
      rotations_.update(model_, state_.q);
    }
    // 2. u = F v; then Dᵀ u and Ḟ v (design §4: Eᵀ Ḟ v = −Dᵀ u, independent rows of Ḟ zero).
    state_.u.noalias() = F_ * v;
    compute_constraint_rate(model_, state_, rotations_, ws_.constraints);  // Dᵀ u
    b_ = -ws_.constraints.Dtu;
    cs_.solve(b_, Fdv_);
    // 3. Free system, H (eq. (68)) and v̇.
    free_system();
    compute_H();
    tmp_ = ws_.free.Q;
    if (!ws_.free.constant_mass) tmp_.noalias() -= ws_.free.Mdot * state_.u;
    if (ws_.free.diagonal_mass)
      tmp_ -= ws_.free.M_diag.cwiseProduct(Fdv_);
    else
      tmp_.noalias() -= ws_.free.M * Fdv_;
    rhs_.noalias() = F_.transpose() * tmp_;
    vdot_ = H_llt_.solve(rhs_);  // H v̇ = Fᵀ (Q̂ − Ṁ u − M Ḟ v)
    udot_ = Fdv_;
    udot_.noalias() += F_ * vdot_;
  }

  // Primal form at (t, q, p), Theorem 7. Expanding αᵀ = I − π A, Ω = E G⁻¹ Dᵀ and
  // βᵀ = π A (eq. (43), eq. (44), eq. (78)) in eq. (99):
  //   (L3) ṗ = Q̂ + E λ,  λ = −G⁻¹ (Eᵀ A (Q̂ − Ṁ u) + Dᵀ u),  u = A p (eq. (100)),
  // which avoids the n × n matrices; crosscheck compares it with the matrices of eq. (99).
  void evaluate_primal(double t, const Eigen::Ref<const VecX>& q, const Eigen::Ref<const VecX>& p) {
    state_.t = t;
    state_.q = q;
    if (!ws_.free.mass_ready || !ws_.free.constant_mass) {
      state_.u.setZero();
      free_system();
    }
    state_.u.noalias() = ws_.free.A * p;  // eq. (100)
    compute_constraints(model_, state_, ws_.constraints);
    free_system();
    tmp_ = ws_.free.Q;
    if (!ws_.free.constant_mass) tmp_.noalias() -= ws_.free.Mdot * state_.u;
    factor_G();
    b_.noalias() = ws_.constraints.Et * (ws_.free.A * tmp_);
    b_ += ws_.constraints.Dtu;
    solve_G(b_, lambda_);
    lambda_ = -lambda_;  // (L3)
    pdot_ = ws_.free.Q;
    pdot_.noalias() += ws_.constraints.Et.transpose() * lambda_;  // eq. (99) as (L3)
  }

  // G = Eᵀ A E (eq. (42)) at ws_.constraints.Et: dense Cholesky, or sparse for large diagonal-
  // mass systems.
  void factor_G() {
    const MatX& Et = ws_.constraints.Et;
    if (nc_ > 48 && ws_.free.diagonal_mass) {
      Es_ = Et.sparseView();
      Gs_ = Es_ * ws_.free.A_diag.asDiagonal() * Es_.transpose();  // eq. (42)
      Gs_ldlt_.compute(Gs_);
      if (Gs_ldlt_.info() != Eigen::Success || Gs_ldlt_.vectorD().minCoeff() <= 0.0)
        throw SingularEvaluation{"G = EᵀAE is singular at t = " + time_text(model_, state_.t)};
      sparse_G_ = true;
      return;
    }
    sparse_G_ = false;
    AEt_.noalias() = ws_.free.A * Et.transpose();
    G_.noalias() = Et * AEt_;  // eq. (42)
    G_llt_.compute(G_);
    const auto Ld = G_llt_.matrixLLT().diagonal();
    constexpr double kSingularG = 1e-12;  // as in projection/primal.cpp
    if (G_llt_.info() != Eigen::Success ||
        !(Ld.minCoeff() * Ld.minCoeff() > kSingularG * Ld.maxCoeff() * Ld.maxCoeff()))
      throw SingularEvaluation{"G = EᵀAE is singular at t = " + time_text(model_, state_.t) +
                               " (redundant constraints or a change point)"};
  }
  void solve_G(const VecX& b, VecX& x) {
    if (sparse_G_)
      x = Gs_ldlt_.solve(b);
    else
      x = G_llt_.solve(b);
  }

  // ---- Samples ----------------------------------------------------------------------------

  // Fills a sample from state_ and udot_ (the equations were just evaluated there).
  void fill_sample(double work, SimulationSample& s, bool primal) {
    s.t = state_.t;
    s.q = state_.q;
    s.u = state_.u;
    s.udot = udot_;
    s.kinetic = kinetic_energy(model_, state_);
    s.potential = potential_energy(model_, state_.q);
    s.work = work;
    compute_constraint_residual(model_, state_.q, ws_.constraints.f);
    s.residual = nc_ ? ws_.constraints.f.cwiseAbs().maxCoeff() : 0.0;
    s.velocity_residual = nc_ ? (ws_.constraints.Et * state_.u).cwiseAbs().maxCoeff() : 0.0;
    s.measures.clear();
    for (const Measure& m : model_.measures)
      s.measures.push_back(evaluate_measure(model_, m, state_.q, &state_.u, &udot_));
    s.reactions.clear();
    s.lambda.resize(0);
    if (!options_.reactions || nc_ == 0) return;
    if (primal) {
      s.lambda = lambda_;
    } else {
      // R = M u̇ + Ṁ u − Q̂ = E λ.
      tmp_ = ws_.free.M * udot_ - ws_.free.Q;
      if (!ws_.free.constant_mass) tmp_ += ws_.free.Mdot * state_.u;
      if (r_ == nc_)
        solve_transposed(tmp_, lambda_);
      else
        compute_multipliers(ws_.constraints.Et, tmp_, lambda_);  // minimum-norm (redundant)
      s.lambda = lambda_;
    }
    compute_reactions(model_, state_.q, s.lambda, s.reactions);
  }

  const Model& model_;
  const SimulateOptions& options_;
  int n_, nq_, nc_, r_, na_;
  bool project_stages_;
  Workspace ws_;
  ChartEngine cs_;
  State state_;
  MatX F_, MF_, H_;
  Eigen::LLT<MatX> H_llt_;
  VecX Fdv_, b_, col_, rhs_, vdot_, udot_, tmp_, Qnc_, lambda_;
  VecX pdot_;
  MatX AEt_, G_;
  Eigen::LLT<MatX> G_llt_;
  Eigen::SparseMatrix<double> Es_, Gs_;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> Gs_ldlt_;
  bool sparse_G_ = false;
  VecX dq_;
  // Eᵀ (ws_.constraints.Et), the chart's factors and F_ are those at chart_q_ in the current
  // chart: an evaluation at chart_q_ need not compute them again. Whoever changes one of them
  // (the step's acceptance, the stage projection) clears it or sets it anew.
  bool chart_ready_ = false;
  VecX chart_q_;
  BodyRotations rotations_;  // R(φ_b) of every body at state_.q (evaluate_dual)
  std::vector<const Load*> nonconservative_;
};

// Mass-orthogonal projection of u₀ onto the admissible velocities, u = α u₀ = ψ M u₀ with
// ψ = F H⁻¹ Fᵀ (eq. (69), eq. (70)); v = H⁻¹ Fᵀ M u₀ are its chart coordinates.
VecX project_velocity(Dynamics& d, const VecX& u0) {
  return d.H_llt_.solve(d.MF_.transpose() * u0);  // eq. (70): α u₀ = F (H⁻¹ Fᵀ M u₀)
}

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
  const bool primal = options.form == DynamicsForm::primal;

  // 1. Consistent positions: mass-metric Gauss–Newton projection of the given position.
  VecX q = initial.q;
  PositionOptions popt;
  popt.tolerance = options.position_tolerance;
  result.assembly = project_positions(model, q, popt);
  if (result.assembly.status != SolveStatus::converged) {
    result.status = SimulateStatus::failed_assembly;
    result.message = "the initial position does not assemble: " + result.assembly.message;
    return result;
  }
  const Mobility mob = compute_mobility(model, q);
  const int rank = mob.rank;
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
        return result;
      }
    }
  }
  const int n = model.n, nq = model.nq, na = n - rank;
  Dynamics dyn(model, rank, options);
  result.components = reaction_components(model);

  // 2. Chart and F at q; velocities u = α u₀ (eq. (70)), then the requested rates.
  dyn.state_.q = q;
  dyn.state_.u.setZero();
  dyn.free_system();
  compute_constraint_jacobian(model, q, dyn.ws_.constraints.Et);
  if (!dyn.cs_.select(dyn.ws_.constraints.Et, dyn.ws_.free.A_diag) ||
      !dyn.factor_chart(dyn.ws_.constraints.Et)) {
    result.status = SimulateStatus::singular;
    result.message = "the initial position is singular (E loses rank there)";
    return result;
  }
  dyn.compute_F();
  dyn.cs_.select_from_tangent(dyn.F_, dyn.M_sqrt());  // independent components that move most
  if (!dyn.factor_chart(dyn.ws_.constraints.Et)) {
    result.status = SimulateStatus::singular;
    result.message = "the initial position is singular (E loses rank there)";
    return result;
  }
  dyn.compute_F();
  dyn.compute_H();
  const VecX u0 = initial.u.size() == n ? initial.u : VecX::Zero(n);
  VecX v = project_velocity(dyn, u0);
  {
    const VecX du = u0 - dyn.F_ * v;
    result.kinetic_removed = 0.5 * du.dot(dyn.ws_.free.M * du);
  }
  if (!options.initial_rates.empty()) {
    const int m = static_cast<int>(options.initial_rates.size());
    MatX D(m, n);
    VecX s(m);
    for (int i = 0; i < m; ++i) {
      const InitialRate& ir = options.initial_rates[static_cast<size_t>(i)];
      if (ir.measure < 0 || ir.measure >= static_cast<int>(model.measures.size()))
        throw std::invalid_argument("simulate: initial rate of an unknown measure");
      VecX d(n);
      (void)compute_scalar(model, model.measures[static_cast<size_t>(ir.measure)].kind, q, nullptr,
                           d);
      D.row(i) = d.transpose();
      s(i) = ir.rate;
    }
    const MatX DF = D * dyn.F_;
    const Eigen::CompleteOrthogonalDecomposition<MatX> cod(DF);
    v += cod.solve(s - DF * v);  // least-squares change of v (minimum-norm)
  }

  // 3. ODE state: dual (q, v, W) or primal (q, p, W); W = work of non-conservative loads.
  const int nx = primal ? nq + n + 1 : nq + na + 1;
  VecX x(nx);
  x.head(nq) = q;
  if (primal)
    x.segment(nq, n) = dyn.ws_.free.M * (dyn.F_ * v);  // p = M u, eq. (5)
  else
    x.segment(nq, na) = v;
  x(nx - 1) = 0.0;

  double energy0 = 0.0;
  bool have_energy0 = false;
  long evaluations = 0;
  VecX f(model.nc), dq(n), u_step(VecX::Zero(n));
  double spread_limit = kSpreadLimit;  // chart monitor threshold (raised while no chart helps)

  // Output grid T0 + k·dt_out ≤ T1. The integration runs in segments (between change-point
  // passages and approaches): every output time is emitted once, whatever segment reaches it.
  const double T0 = initial.t, T1 = initial.t + options.t_end;
  const double dt_out = options.dt_out > 0.0 ? options.dt_out : options.t_end / 100.0;
  const double grid_slack = 1e-12 * std::max(1.0, std::abs(T1));
  const double end_slack = 1e-14 * std::max(1.0, std::abs(T1));
  long next_out = 0;
  const auto grid_time = [&](long k) { return T0 + static_cast<double>(k) * dt_out; };
  const auto grid_pending = [&] { return grid_time(next_out) <= T1 + grid_slack; };

  // Change-point monitor (both forms): σ̂ = σ_min(E_RDᵀ S_D)/σ_ref at every accepted, corrected
  // state (ChartEngine::estimate_sigma_min; S = diag(1/√M_kk), σ_ref the largest mass-scaled
  // column norm of Eᵀ at the start). Near a change point σ̂ ≈ a |t − t*| (C1), so two states
  // give the estimate t* = t_k + σ̂_k (t_k − t_{k−1}) / (σ̂_{k−1} − σ̂_k).
  VecX sigma_w;
  double sigma_ref = 0.0;
  for (int k = 0; k < n; ++k)
    sigma_ref = std::max(sigma_ref, dyn.ws_.constraints.Et.col(k).norm() * dyn.ws_.free.A_sqrt(k));
  if (!(sigma_ref > 0.0)) sigma_ref = 1.0;
  struct MonitorPoint {
    bool valid = false;
    double t = 0.0, sigma = 0.0;
  } monitor;
  struct Request {
    bool pending = false;
    double t_star = 0.0, sigma = 0.0;
  } request;
  // The last two accepted states (with their charts): a step that crossed a change point
  // unannounced (C2') is undone back to the last state before it.
  struct SavedState {
    bool valid = false;
    double t = 0.0, sigma = 0.0, rate = 0.0;  // σ̂ and dσ̂/dt in `chart`
    double spread = 0.0;                      // the chart's spread (dual form; 0: unknown)
    VecX x;
    Chart chart;
  } saved_older, saved_prev;
  int rewind_to = -1;  // 0: saved_older, 1: saved_prev (with request)
  double last_rewind_t_star = -std::numeric_limits<double>::infinity();
  bool monitor_armed = true;
  // Set when an approach does not reach σ̂ ≤ pass_quality in kMaxApproaches segments (σ̂ has a
  // minimum above 0 there, not a change point): no request until σ̂ rises again.
  bool monitor_quiet = false;
  double pass_quality = kPassQuality;  // σ̂ at which the next passage is tried
  double t_last_accept = T0, h_last = 0.0;
  const auto chart_quality = [&]() {
    if (model.nc == 0 || rank == 0) return std::numeric_limits<double>::infinity();
    return dyn.cs_.estimate_sigma_min(sigma_w) / sigma_ref;
  };
  // (C1) σ̂ and its rate dσ̂/dt at (q, u) in the current chart (factorised at q): the rate of a
  // simple singular value is ŷᵀ (dB̃/dt) ŵ with its unit singular vectors [Stewart & Sun 1990,
  // §IV.2], and (dEᵀ/dt) x = H(u, x) is the constraints' second derivative, bilinear in (u, x);
  // H(y, y) = Dᵀy is the constraint rate (compute_constraint_rate), so by polarisation
  // H(u, x) = (D(u + x)ᵀ(u + x) − D(u − x)ᵀ(u − x))/4 (x scaled to |u| against cancellation).
  // Allocation-free after the first call.
  VecX sigma_left, rate_x = VecX::Zero(n), rate_plus;
  State rate_state(model);
  ConstraintWorkspace rate_ws(model);
  const auto chart_quality_rate = [&](const VecX& qq, const VecX& uu, double& rate) {
    rate = 0.0;
    if (model.nc == 0 || rank == 0) return std::numeric_limits<double>::infinity();
    const double sigma = dyn.cs_.estimate_sigma_min(sigma_w, &sigma_left) / sigma_ref;
    const double wn = sigma_w.norm(), un = uu.norm();
    if (!(sigma > 0.0) || !(wn > 0.0) || !std::isfinite(wn) || !(un > 0.0)) return sigma;
    const Chart& c = dyn.cs_.chart();
    rate_x.setZero();
    for (int k = 0; k < rank; ++k) {
      const int d = c.dependent[static_cast<size_t>(k)];
      rate_x(d) = dyn.ws_.free.A_sqrt(d) * sigma_w(k) / wn;  // x = S_D ŵ
    }
    const double alpha = un / rate_x.norm();
    rate_state.q = qq;
    rate_state.u = uu + alpha * rate_x;
    compute_constraint_rate(model, rate_state, rate_ws);
    rate_plus = rate_ws.Dtu;
    rate_state.u = uu - alpha * rate_x;
    compute_constraint_rate(model, rate_state, rate_ws);
    double d = 0.0;
    for (int i = 0; i < rank; ++i) {
      const int row = c.rows[static_cast<size_t>(i)];
      d += sigma_left(i) * (rate_plus(row) - rate_ws.Dtu(row));
    }
    rate = 0.25 * d / (alpha * sigma_ref);
    return sigma;
  };

  // (C2'') A change point inside the step just taken (from saved_prev, in the same chart): σ̂
  // fell at the start and rises at the end, and the two tangents σ̂₀ + σ̂'₀ τ and
  // σ̂₁ + σ̂'₁ (τ − h) meet at or near 0 (below kCrossingVertex of the smaller end value; a
  // regular minimum that the steps resolve has its tangents meet near the minimum). Whatever
  // the step's length and whatever the chart did before: the step is undone and the point
  // approached from the step's start, with t* at the tangents' vertex. Returns true when the
  // step must be undone (request set) or the run stopped (stop_message set).
  std::string stop_message;
  int crossing_rewinds = 0;
  double last_crossing_t_star = -std::numeric_limits<double>::infinity();
  const auto crossed_within_step = [&](double t, double s1, double d1) {
    if (!monitor_armed || !saved_prev.valid || !(saved_prev.rate < 0.0) || !(d1 > 0.0))
      return false;
    const Chart& c = dyn.cs_.chart();
    if (saved_prev.chart.independent != c.independent || saved_prev.chart.rows != c.rows)
      return false;
    const double h = t - saved_prev.t, s0 = saved_prev.sigma, d0 = saved_prev.rate;
    if (!(h > 0.0)) return false;
    const double tau = std::clamp((s0 - s1 + d1 * h) / (d1 - d0), 0.0, h);
    const double vertex = std::max(s0 + d0 * tau, s1 + d1 * (tau - h));
    if (!(vertex < kCrossingVertex * std::min(s0, s1))) return false;
    last_crossing_t_star = saved_prev.t + tau;
    if (++crossing_rewinds > kMaxCrossingRewinds) {
      char buf[160];
      std::snprintf(buf, sizeof buf,
                    "the steps keep crossing the change point at t ≈ %.9g s (undone %d times)",
                    last_crossing_t_star, kMaxCrossingRewinds);
      stop_message = buf;
      return true;
    }
    rewind_to = 1;
    request = {true, last_crossing_t_star, s0};
    last_rewind_t_star = last_crossing_t_star;
    return true;
  };

  detail::OdeProblem problem;
  problem.rhs = [&](const VecX& y, VecX& dy, double t) {
    ++evaluations;
    dy.resize(nx);
    if (primal) {
      dyn.evaluate_primal(t, y.head(nq), y.segment(nq, n));
      compute_coordinate_rates(model, y.head(nq), dyn.state_.u, dy.head(nq));  // eq. (100)
      dy.segment(nq, n) = dyn.pdot_;
    } else {
      dyn.evaluate_dual(t, y.head(nq), y.segment(nq, na));
      compute_coordinate_rates(model, y.head(nq), dyn.state_.u, dy.head(nq));  // q̇ = B̃ u
      dy.segment(nq, na) = dyn.vdot_;
    }
    dy(nx - 1) = dyn.nonconservative_power();
  };

  problem.autonomous = !model.general;  // only a general system's forces may depend on t
  // With projected stages the right-hand side depends on q through the chart's independent
  // coordinates only (the dependent ones are solved for): the Jacobian's other position
  // columns, and the work column, are zero. A planar body's velocity component k is its
  // coordinate k; a spatial body's rotation moves all four quaternion components.
  if (!primal && dyn.project_stages_)
    problem.jacobian_columns = [&](std::vector<Eigen::Index>& columns) {
      columns.clear();
      const Chart& c = dyn.cs_.chart();
      for (const int k : c.independent) {
        if (model.nq == model.n) {
          columns.push_back(k);
          continue;
        }
        for (const Body& b : model.bodies) {
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
      for (int k = 0; k < na; ++k) columns.push_back(nq + k);
    };

  auto sample_at = [&](double t, const VecX& y, SimulationSample& smp) {
    if (primal) {
      dyn.evaluate_primal(t, y.head(nq), y.segment(nq, n));
      dyn.udot_ = dyn.ws_.free.A * (dyn.pdot_ - (dyn.ws_.free.constant_mass
                                                     ? VecX::Zero(n)
                                                     : VecX(dyn.ws_.free.Mdot * dyn.state_.u)));
    } else {
      dyn.evaluate_dual(t, y.head(nq), y.segment(nq, na));
    }
    dyn.fill_sample(y(nx - 1), smp, primal);
  };

  // An output at t (a grid time within the slack, not yet emitted); other times (a segment's
  // start) are ignored.
  const auto emit = [&](double t, const VecX& y) {
    if (!grid_pending() || std::abs(t - grid_time(next_out)) > grid_slack) return;
    if (options.record_samples) {
      result.samples.emplace_back();
      sample_at(t, y, result.samples.back());
    }
    ++next_out;
  };
  problem.output = [&](double t, const VecX& y) { emit(t, y); };

  double spread_now = 0.0;  // the chart's spread after the last acceptance (dual form)
  double next_step_limit = std::numeric_limits<double>::infinity();
  problem.step_limit = [&] { return next_step_limit; };
  // Rows of f that are angles (joint components "angle", "ratio"): the residual by kind.
  std::vector<char> angular_row(static_cast<size_t>(model.nc), 0);
  for (const Joint& j : model.joints) {
    const auto names = j.component_names();
    for (int k = 0; k < j.rows(); ++k)
      angular_row[static_cast<size_t>(j.row_offset + k)] =
          is_angular_row(names[static_cast<size_t>(k)]) ? 1 : 0;
  }
  const auto note_residual = [&](const VecX& res) {
    for (Eigen::Index r = 0; r < res.size(); ++r) {
      double& to = angular_row[static_cast<size_t>(r)] ? result.max_residual_angle
                                                       : result.max_residual_length;
      to = std::max(to, std::abs(res(r)));
    }
  };
  problem.accept = [&](double t, VecX& y) {
    auto qy = y.head(nq);
    MatX& Et = dyn.ws_.constraints.Et;
    dyn.chart_ready_ = false;  // Eᵀ, the chart's factors and F change below
    bool chart_changed = false;
    // Residual left by the step (before correction), with Eᵀ at the same q. Quaternions are
    // renormalised first (|e| = 1 is a first integral of q̇ = B̃u; only the step's error moves
    // it; f and R do not depend on |e|, spatial.md §6.3).
    normalize_coordinates(model, qy);
    q = qy;
    dyn.mass_at(q);
    compute_constraint_residual_and_jacobian(model, q, f, Et);
    if (f.size()) {
      result.max_constraint_residual =
          std::max(result.max_constraint_residual, f.cwiseAbs().maxCoeff());
      note_residual(f);
    }
    if (primal) {
      // Invariant J = Eᵀ A p, eq. (105), before the projection.
      dyn.state_.q = q;
      dyn.state_.u.noalias() = dyn.ws_.free.A * y.segment(nq, n);
      if (model.nc) {
        const double J = (Et * dyn.state_.u).cwiseAbs().maxCoeff();
        result.max_invariant_J = std::max(result.max_invariant_J, J);
        result.max_velocity_residual = std::max(result.max_velocity_residual, J);
      }
    }
    // The chart's block at the step's q: the corrector's first Newton step uses it, and (dual)
    // the step's velocity u = F(q) v before the correction (re-projected below).
    const bool factored = dyn.factor_chart(Et);
    if (!primal) {
      if (factored) {
        dyn.compute_F();
        u_step.noalias() = dyn.F_ * y.segment(nq, na);
      } else {
        u_step.setZero();  // exactly singular: keep v as it is (below)
      }
    }
    // Position correction in the chart (Newton; independent coordinates fixed). It leaves Eᵀ
    // at the corrected q factorised in the chart.
    ChartCorrectionResult corr = dyn.cs_.correct_positions(
        q, Et, f, dq,
        {.tolerance = options.position_tolerance,
         .max_gain = kMaxCorrectionGain,
         .start = factored ? ChartCorrection::Start::prepared : ChartCorrection::Start::evaluate});
    if (corr.near_singular) ++result.uncorrected_steps;
    if (corr.status == SolveStatus::singular) {  // try a fresh chart once
      compute_constraint_jacobian(model, q, Et);
      if (dyn.cs_.select(Et, dyn.ws_.free.A_diag))
        corr = dyn.cs_.correct_positions(q, Et, f, dq, {.tolerance = options.position_tolerance});
      chart_changed = true;
    }
    if (corr.status != SolveStatus::converged) {
      stop_message =
          "position correction failed at t = " + time_text(model, t) + ": " + corr.message;
      return false;
    }
    qy = q;
    dyn.compute_F();
    dyn.mass_at(q);
    dyn.state_.q = q;
    if (primal) dyn.state_.u.noalias() = dyn.ws_.free.A * y.segment(nq, n);
    // (C2'') σ̂ and its rate at the step's end in the step's chart (the block is factorised at
    // the corrected q): a change point inside the step, whatever the step's length, is undone
    // before anything else looks at the step's end (its velocity check included).
    double rate_end = 0.0;
    const double sigma_end = chart_quality_rate(q, primal ? dyn.state_.u : u_step, rate_end);
    if (!chart_changed && crossed_within_step(t, sigma_end, rate_end)) return false;
    if (primal) {
      // Momenta: p ← M α u, the mass-orthogonal projection (eq. (44): α = I − A π).
      dyn.compute_H();
      const VecX vv = project_velocity(dyn, dyn.state_.u);
      dyn.state_.u.noalias() = dyn.F_ * vv;
      y.segment(nq, n) = dyn.ws_.free.M * dyn.state_.u;
      // A poor chart only slows the corrector: re-select it when it degrades.
      if (dyn.chart_spread() > kSpreadLimit) {
        const Chart old = dyn.cs_.chart();
        dyn.cs_.select_from_tangent(dyn.F_, dyn.M_sqrt());
        chart_changed = true;
        if (!dyn.factor_chart(dyn.ws_.constraints.Et)) {
          dyn.cs_.set_chart(old);
          (void)dyn.factor_chart(dyn.ws_.constraints.Et);
        }
      }
    } else {
      // v ← H⁻¹ Fᵀ M u_step: the admissible velocity at the corrected position closest to the
      // step's velocity in the mass metric (eq. (70), u = α u_step), rather than keeping u_I.
      if (u_step.squaredNorm() > 0.0) {
        dyn.compute_H();
        y.segment(nq, na) = project_velocity(dyn, u_step);
        // The velocity the projection removes is the step's own error; a step that left the
        // branch (a change point crossed within one step onto another branch) loses a finite
        // part of it: refused (C6).
        const VecX du = u_step - dyn.F_ * y.segment(nq, na);
        const double uu = u_step.dot(dyn.ws_.free.M * u_step);
        const double jump = uu > 0.0 ? std::sqrt(du.dot(dyn.ws_.free.M * du) / uu) : 0.0;
        if (jump > kStepVelocityJump) {
          stop_message = "the step to t = " + time_text(model, t) +
                         " s left the motion's branch (its velocity changes by " +
                         std::to_string(jump) +
                         " relative when made admissible): a change point was crossed within "
                         "one step";
          return false;
        }
      }
      // Chart monitor: re-select when F's mass-scaled entries grow; switch if the new chart is
      // clearly better (hysteresis 2), re-expressing v from u = F v.
      const double spread = dyn.chart_spread();

      if (spread > spread_limit) {
        const Chart old = dyn.cs_.chart();
        const VecX u = dyn.F_ * y.segment(nq, na);
        dyn.cs_.select_from_tangent(dyn.F_, dyn.M_sqrt());
        bool switched = false;
        if (dyn.factor_chart(dyn.ws_.constraints.Et)) {
          dyn.compute_F();
          // Take the new chart only if it is clearly better (hysteresis 2): next to a change
          // point F is inaccurate in every chart and switching would not help.
          if (dyn.chart_spread() < 0.5 * spread) {
            for (int k = 0; k < na; ++k)
              y(nq + k) = u(dyn.cs_.chart().independent[static_cast<size_t>(k)]);
            result.chart_switches.push_back(
                {t, chart_name(model, old), chart_name(model, dyn.cs_.chart())});
            spread_limit = kSpreadLimit;
            switched = true;
            chart_changed = true;
          }
        }
        if (!switched) {  // keep the chart; try again only when it degrades further
          dyn.cs_.set_chart(old);
          (void)dyn.factor_chart(dyn.ws_.constraints.Et);
          dyn.compute_F();
          spread_limit = 2.0 * spread;
        }
      } else if (spread < 0.5 * spread_limit) {
        spread_limit = std::max(kSpreadLimit, 2.0 * spread);
      }
      dyn.state_.u.noalias() = dyn.F_ * y.segment(nq, na);
      dyn.chart_q_ = q;  // Eᵀ, the factors and F are those at the corrected q
      dyn.chart_ready_ = true;
      // Ahead of the chart's own singularity (its block singular, F unbounded, E regular: the
      // spread ~ 1/(t_s − t)): 1/spread is linear in t there, so two values in this chart give
      // t_s, and the next step ends at most half-way to it (the monitor above switches charts
      // at a step end; a step that ran into the singularity would have integrated, and been
      // corrected, where F is ill-conditioned: on the N = 40 bar one Bulirsch–Stoer step at
      // rtol 1e-8 lost 5e-7 of the energy that way).
      spread_now = chart_changed ? dyn.chart_spread() : spread;
      next_step_limit = std::numeric_limits<double>::infinity();
      if (!chart_changed && saved_prev.valid && saved_prev.spread > 0.0 && t > saved_prev.t &&
          saved_prev.chart.independent == dyn.cs_.chart().independent) {
        const double slope = (1.0 / spread_now - 1.0 / saved_prev.spread) / (t - saved_prev.t);
        if (slope < 0.0) next_step_limit = kChartStepFraction * (1.0 / spread_now) / -slope;
      }
    }
    // Energy balance T + V − W at the corrected state.
    const double T = kinetic_energy(model, dyn.state_);
    const double V = potential_energy(model, q);
    const double W = y(nx - 1);
    const double E = T + V - W;
    if (!have_energy0) energy0 = E, have_energy0 = true;
    result.energy_max_drift = std::max(result.energy_max_drift, std::abs(E - energy0));
    result.energy_scale = std::max(result.energy_scale, std::abs(T) + std::abs(V) + std::abs(W));
    ++result.steps;
    h_last = t - t_last_accept;
    t_last_accept = t;
    // Change-point monitor: stop the segment when a change point is within reach of the next
    // steps (C2) or close enough to be passed (C3); the driver below approaches or passes it.
    // σ̂ and its rate in the chart the next step uses (another block after a switch).
    double rate = rate_end;
    const double sigma = chart_changed ? chart_quality_rate(q, dyn.state_.u, rate) : sigma_end;
    if (chart_changed) monitor.valid = false;  // σ̂ of another chart block: no secant trend
    bool stop = false;
    // A falling σ̂ that bottoms out above 0 (C1'): the parabola through the last three values.
    bool minimum_above_zero = false;
    if (saved_older.valid && saved_prev.valid && monitor.valid && sigma < saved_prev.sigma) {
      const double t0 = saved_older.t, t1 = saved_prev.t, s0 = saved_older.sigma,
                   s1 = saved_prev.sigma;
      const double d01 = (s1 - s0) / (t1 - t0), d12 = (sigma - s1) / (t - t1);
      const double curv = (d12 - d01) / (t - t0);  // p(τ) = σ + d (τ − t) + curv (τ − t)²
      if (curv > 0.0) {
        const double d = d12 + curv * (t - t1);  // slope at t
        const double p_min = sigma - d * d / (4.0 * curv);
        minimum_above_zero = p_min > kMinimumAboveZero * sigma;
      }
    }
    if (monitor_quiet && (rate > 0.0 || (monitor.valid && sigma > monitor.sigma)))
      monitor_quiet = false;
    // (C1) t* from a falling σ̂: the secant through the last two values in this chart and the
    // tangent t − σ̂/σ̂'. Far from the point σ̂ is concave as it falls (~|sin θ| on the
    // N-four-bar) and both are late, the secant more: the earlier is taken. A rising σ̂ (σ̂' > 0)
    // has no point ahead, whatever the secant says.
    const bool secant_falling = monitor.valid && sigma < monitor.sigma;
    const bool falling = rate < 0.0 || (rate == 0.0 && secant_falling);
    if (monitor_armed && !monitor_quiet && !minimum_above_zero && falling &&
        sigma < kWatchQuality) {
      double t_star = std::numeric_limits<double>::infinity();
      if (secant_falling) t_star = t + sigma * (t - monitor.t) / (monitor.sigma - sigma);  // (C1)
      if (rate < 0.0) t_star = std::min(t_star, t - sigma / rate);
      if (sigma <= pass_quality || t_star - t < kReachSteps * h_last) {
        request = {true, t_star, sigma};
        stop = true;
      }
    }
    // (C2') σ̂ fell and rose again across the last two steps along a V through 0: a change point
    // was crossed within one of them without being approached (large steps at a loose rtol).
    // Both hypotheses: crossing in the last step (zero of the falling line before t) or in the
    // one before (zero of the rising line after t_{k−2}), each checked against the third σ̂.
    if (!stop && monitor_armed && saved_older.valid && saved_prev.valid &&
        saved_older.t > last_rewind_t_star && sigma > saved_prev.sigma &&
        saved_prev.sigma < saved_older.sigma && saved_prev.sigma < kWatchQuality) {
      const double t0 = saved_older.t, s0 = saved_older.sigma;
      const double t1 = saved_prev.t, s1 = saved_prev.sigma;
      const double a1 = (s0 - s1) / (t1 - t0), z1 = t1 + s1 / a1;
      const double a2 = (sigma - s1) / (t - t1), z2 = t1 - s1 / a2;
      if (z1 < t && std::abs(a1 * (t - z1) - sigma) <= kVShapeTolerance * sigma) {
        rewind_to = 1;
        request = {true, z1, s1};
        last_rewind_t_star = z1;
        stop = true;
      } else if (z2 > t0 && std::abs(a2 * (z2 - t0) - s0) <= kVShapeTolerance * s0) {
        rewind_to = 0;
        request = {true, z2, s0};
        last_rewind_t_star = z2;
        stop = true;
      }
    }
    if (t > last_crossing_t_star) crossing_rewinds = 0;
    saved_older = saved_prev;
    saved_prev.valid = true;
    saved_prev.t = t;
    saved_prev.sigma = sigma;
    saved_prev.rate = rate;
    saved_prev.spread = spread_now;
    saved_prev.x = y;
    saved_prev.chart = dyn.cs_.chart();
    monitor = {true, t, sigma};
    return !stop;
  };

  // Initial energy (at the consistent initial state).
  {
    dyn.state_.q = q;
    dyn.state_.u = dyn.F_ * v;
    energy0 = kinetic_energy(model, dyn.state_) + potential_energy(model, q);
    have_energy0 = true;
    result.energy_scale =
        std::abs(kinetic_energy(model, dyn.state_)) + std::abs(potential_energy(model, q));
    // σ̂ and its rate at the start ((C2'') checks the first step too).
    saved_prev.valid = true;
    saved_prev.t = T0;
    saved_prev.sigma = chart_quality_rate(q, dyn.state_.u, saved_prev.rate);
    saved_prev.spread = primal ? 0.0 : dyn.chart_spread();
    saved_prev.x = x;
    saved_prev.chart = dyn.cs_.chart();
  }

  detail::OdeOptions base;
  base.stepper = ode_stepper(options.integrator);
  base.rtol = options.rtol;
  base.atol = options.atol;
  base.max_dt = options.max_step;
  base.max_steps = options.max_steps;

  // The integrator from t to t_e in segments that start on the output grid or end on it, so
  // that the integrator's output clock (t0 + k·dt_out) hits the grid times. Stops early when
  // `accept` stops it (a change point ahead, or a failed check).
  double t_now = T0;
  long rejected_steps = 0, jacobians = 0;  // summed over the segments
  const auto run_to = [&](double t_e, double max_dt) {
    detail::OdeStats st;
    st.completed = true;
    st.t = t_now;
    while (t_now < t_e - end_slack) {
      detail::OdeOptions oo = base;
      oo.t0 = t_now;
      if (max_dt > 0.0) oo.max_dt = oo.max_dt > 0.0 ? std::min(oo.max_dt, max_dt) : max_dt;
      oo.dt_init = h_last > 0.0 ? std::min(h_last, next_step_limit) : 0.0;
      const bool on_grid =
          std::abs(t_now - grid_time(next_out)) <= grid_slack ||
          (next_out > 0 && std::abs(t_now - grid_time(next_out - 1)) <= grid_slack);
      if (on_grid || !grid_pending()) {
        oo.t_end = t_e;
        oo.dt_out = on_grid ? dt_out : 2.0 * (t_e - t_now);
      } else {  // off the grid: to the next output time first
        const double g = grid_time(next_out);
        oo.t_end = std::min(t_e, g);
        oo.dt_out = g <= t_e ? g - t_now : 2.0 * (t_e - t_now);
      }
      if (oo.dt_init > 0.0 && oo.dt_init > oo.t_end - t_now) oo.dt_init = oo.t_end - t_now;
      st = detail::integrate_ode(problem, x, oo);
      rejected_steps += st.rejected;
      jacobians += st.jacobians;
      if (st.completed) st.t = oo.t_end;
      t_now = st.t;
      // An output time at a stop (accept stopped the integrator before its output there).
      if (std::abs(t_now - grid_time(next_out)) <= grid_slack && grid_pending()) emit(t_now, x);
      if (!st.completed) return st;
    }
    st.completed = true;
    st.t = t_now;
    return st;
  };

  // The passage step (dual form) from the approached state (t_a, x) over the change point at
  // t* to t_b = t_a + 2 (t* − t_a), landing at about the same distance beyond it (C3)–(C6).
  const auto mnorm2 = [&](const VecX& a, const VecX& b) {
    return dyn.ws_.free.diagonal_mass ? a.dot(dyn.ws_.free.M_diag.cwiseProduct(b))
                                      : a.dot(dyn.ws_.free.M * b);
  };
  // (C4) a state on the branch at time tt from a guess (qq, uu): positions corrected in the
  // incoming chart (Newton, q_I fixed) and polished to rounding, the velocity made admissible
  // (u = α uu, eq. (70)); then the dual equations there.
  struct BranchState {
    VecX q, v, u, a;
    double P = 0.0;
  };
  const auto on_branch = [&](double tt, const VecX& qq, const VecX& uu, BranchState& s,
                             std::string& why) {
    s.q = qq;
    MatX& Et = dyn.ws_.constraints.Et;
    const SolveResult corr =
        dyn.cs_.correct_positions(s.q, Et, f, dq, {.tolerance = options.position_tolerance});
    if (corr.status != SolveStatus::converged) {
      why = "a position of the passage does not close (" + corr.message + ")";
      return false;
    }
    (void)dyn.cs_.polish_positions(s.q, Et, f, dq, 3);
    dyn.mass_at(s.q);
    dyn.compute_F();
    dyn.compute_H();
    s.v = project_velocity(dyn, uu);  // eq. (70)
    dyn.chart_q_ = s.q;
    dyn.chart_ready_ = true;
    dyn.evaluate_dual(tt, s.q, s.v);
    s.u = dyn.state_.u;
    s.a = dyn.udot_;
    s.P = dyn.nonconservative_power();
    return true;
  };
  // Quintic Hermite through (q, u, u̇) at both ends of [t_a, t_a + h], at s ∈ [0, 1]: q and its
  // derivative u (orders 6 and 5).
  const auto quintic = [](double s, double h, const BranchState& A, const BranchState& B, VecX& qs,
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
  };

  // Spatial bodies (nq ≠ n): the passage works in local coordinates x about the incoming
  // position, q = q_a ⊕ x (the exponential map), whose rates are ẋ = u except for the rotation
  // of a spatial body, θ̇ = J_r(θ)⁻¹ ω (model/spatial.hpp: exp_right_jacobian). For planar bodies
  // x = q − q_a and ẋ = u, and the passage below keeps its planar arithmetic unchanged.
  const bool local_passage = nq != n;
  const auto local_rate = [&](const VecX& xx, const VecX& uu, bool to_x) {
    VecX out = uu;
    for (const Body& b : model.bodies)
      if (b.kind == BodyKind::spatial) {
        const Mat3 Jr = exp_right_jacobian(xx.segment<3>(b.u_offset + 3));
        const Vec3 w = uu.segment<3>(b.u_offset + 3);
        out.segment<3>(b.u_offset + 3) = to_x ? Vec3(Jr.lu().solve(w)) : Vec3(Jr * w);
      }
    return out;
  };
  // A branch state in local coordinates about q_a: q ← x, u ← ẋ, a ← ẍ (to first order in θ:
  // ẍ ≈ J_r⁻¹ u̇, exact at x = 0).
  const auto to_local = [&](const BranchState& S, const VecX& q_a) {
    BranchState L = S;
    L.q.resize(n);
    difference_positions(model, S.q, q_a, L.q);
    L.u = local_rate(L.q, S.u, true);
    L.a = local_rate(L.q, S.a, true);
    return L;
  };

  // Outputs strictly inside a passage step (t_a, t_b): the quintic Hermite of the step in q and
  // u, u̇ linear (no equations are evaluated next to the point; no reactions: some multipliers
  // are indeterminate there).
  const auto passage_outputs = [&](double t_a, double t_b, const BranchState& A,
                                   const BranchState& B, double W_a, double W_b) {
    const double h = t_b - t_a;
    VecX qs, us;
    while (grid_pending() && grid_time(next_out) < t_b - grid_slack) {
      const double to = grid_time(next_out);
      if (to > t_a + grid_slack && options.record_samples) {
        const double s = (to - t_a) / h;
        if (local_passage) {  // the Hermite in x about q_a, mapped back: q = q_a ⊕ x, u = J ẋ
          VecX xs, xd;
          quintic(s, h, to_local(A, A.q), to_local(B, A.q), xs, xd);
          qs = A.q;
          integrate_positions(model, qs, xs, 1.0);
          us = local_rate(xs, xd, false);
        } else {
          quintic(s, h, A, B, qs, us);
        }
        dyn.state_.t = to;
        dyn.state_.q = qs;
        dyn.state_.u = us;
        dyn.udot_ = (1 - s) * A.a + s * B.a;
        SimulationSample& smp = result.samples.emplace_back();
        smp.t = to;
        smp.q = qs;
        smp.u = us;
        smp.udot = dyn.udot_;
        smp.kinetic = kinetic_energy(model, dyn.state_);
        smp.potential = potential_energy(model, qs);
        smp.work = (1 - s) * W_a + s * W_b;
        compute_constraint_residual(model, qs, f);
        smp.residual = model.nc ? f.cwiseAbs().maxCoeff() : 0.0;
        for (const Measure& m : model.measures)
          smp.measures.push_back(evaluate_measure(model, m, qs, &us, &dyn.udot_));
      }
      ++next_out;
    }
  };

  const auto pass_change_point = [&](double t_star, double sigma_a, std::string& why) -> bool {
    const double t_a = t_now;
    double h = 2.0 * (t_star - t_a);
    if (t_a + h > T1) h = T1 - t_a;
    const double t_b = t_a + h;
    BranchState A, B, S1, S2;
    // The incoming state, polished (its equations are those the step integrated).
    if (!on_branch(t_a, x.head(nq), dyn.F_ * x.segment(nq, na), A, why)) return false;
    const double W_a = x(nx - 1);
    // (C5) one step of the 4-stage Lobatto IIIA collocation method (order 6) [Hairer, Nørsett
    // & Wanner, Solving ODEs II, §IV.5] on q̇ = u, u̇ = a(q, u), Ẇ = P, whose stages are states
    // on the branch (C4): nodes t_a + c_i h, c = (0, (5 ∓ √5)/10, 1). The interior nodes are
    // 0.45 (t* − t_a) from the point, the last is the landing. Stage values by fixed-point
    // iteration from the Taylor predictor (C3), q_i = q_a + c_i h u_a + ½ (c_i h)² u̇_a,
    // u_i = u_a + c_i h u̇_a.
    const double r5 = std::sqrt(5.0);
    const double c[4] = {0.0, (5.0 - r5) / 10.0, (5.0 + r5) / 10.0, 1.0};
    const double L[4][4] = {
        {0.0, 0.0, 0.0, 0.0},
        {(11 + r5) / 120, (25 - r5) / 120, (25 - 13 * r5) / 120, (-1 + r5) / 120},
        {(11 - r5) / 120, (25 + 13 * r5) / 120, (25 + r5) / 120, (-1 - r5) / 120},
        {1.0 / 12, 5.0 / 12, 5.0 / 12, 1.0 / 12}};
    BranchState* st[4] = {&A, &S1, &S2, &B};
    VecX q_p, u_p;
    for (int i = 1; i < 4; ++i) {
      const double ch = c[i] * h;
      if (local_passage) {
        q_p = A.q;
        integrate_positions(model, q_p, VecX(ch * A.u + 0.5 * ch * ch * A.a), 1.0);
      } else {
        q_p = A.q + ch * A.u + 0.5 * ch * ch * A.a;
      }
      u_p = A.u + ch * A.a;
      if (i == 3 && options.passage_hook) options.passage_hook(t_b, q_p, u_p);
      if (!on_branch(t_a + ch, q_p, u_p, *st[i], why)) return false;
    }
    double change = std::numeric_limits<double>::infinity(), W_b = W_a, jump = 0.0;
    int it = 0;
    std::vector<VecX> Qn(4), Un(4), xdot(4);
    // Iterated to a change of u below kPassageConverged, or until it stalls at the rounding
    // noise (a change not halving); accepted below kPassageConvergence (C6).
    double previous_change = std::numeric_limits<double>::infinity();
    while (it < kPassageIterations && !(change <= kPassageConverged) &&
           !(change > 0.5 * previous_change)) {
      ++it;
      previous_change = change;
      if (local_passage)  // the stages' rates ẋ_j in local coordinates about q_a
        for (int j = 0; j < 4; ++j) {
          VecX xj(n);
          difference_positions(model, st[j]->q, A.q, xj);
          xdot[static_cast<size_t>(j)] = local_rate(xj, st[j]->u, true);
        }
      for (int i = 1; i < 4; ++i) {  // q_i = q_a + h Σ L_ij u_j, u_i = u_a + h Σ L_ij u̇_j
        Qn[static_cast<size_t>(i)] = A.q;
        Un[static_cast<size_t>(i)] = A.u;
        VecX dx = VecX::Zero(local_passage ? n : 0);
        for (int j = 0; j < 4; ++j) {
          if (local_passage)
            dx += (h * L[i][j]) * xdot[static_cast<size_t>(j)];  // q_i = q_a ⊕ h Σ L_ij ẋ_j
          else
            Qn[static_cast<size_t>(i)] += (h * L[i][j]) * st[j]->u;
          Un[static_cast<size_t>(i)] += (h * L[i][j]) * st[j]->a;
        }
        if (local_passage) integrate_positions(model, Qn[static_cast<size_t>(i)], dx, 1.0);
      }
      W_b = W_a;
      for (int j = 0; j < 4; ++j) W_b += h * L[3][j] * st[j]->P;
      if (options.passage_hook) options.passage_hook(t_b, Qn[3], Un[3]);
      const VecX u_old = B.u;
      for (int i = 1; i < 4; ++i)
        if (!on_branch(t_a + c[i] * h, Qn[static_cast<size_t>(i)], Un[static_cast<size_t>(i)],
                       *st[i], why))
          return false;
      const VecX du = B.u - u_old, dj = Un[3] - B.u;
      const double ub2 = std::max(mnorm2(B.u, B.u), 1e-300);
      change = std::sqrt(mnorm2(du, du) / ub2);
      jump = std::sqrt(mnorm2(dj, dj) / ub2);
    }
    // (C6) the checks: velocity continuity (the quadrature velocity is admissible at the
    // landing up to the step's truncation error), no reversal, and a regular landing beyond.
    const double ub2 = mnorm2(B.u, B.u), ua2 = mnorm2(A.u, A.u);
    const double cosine = ua2 > 0.0 && ub2 > 0.0 ? mnorm2(A.u, B.u) / std::sqrt(ua2 * ub2) : 1.0;
    (void)chart_quality();  // one more inverse-iteration pair: σ̂ at the landing converged
    double rate_b = 0.0;
    const double sigma_b = chart_quality_rate(B.q, B.u, rate_b);
    const ChangePointPassage pass{t_star, t_a, t_b, sigma_a, sigma_b, jump, cosine, it};
    char buf[200];
    std::snprintf(buf, sizeof buf,
                  " (velocity jump %.3g relative, cosine %.9f, corrector change %.3g, chart "
                  "quality %.3g before, %.3g after)",
                  jump, cosine, change, sigma_a, sigma_b);
    // The bound, raised to 10× the passage's own rounding noise (the corrector's last change,
    // where it stalled) when that is larger, never above kPassageJumpCeiling.
    const double jump_bound = std::min(
        kPassageJumpCeiling, std::max(passage_velocity_jump_bound(options.rtol), 10.0 * change));
    if (!(cosine > 0.0) || !(jump <= kBranchJump)) {
      why = "the passage would change the velocity discontinuously, leaving the motion's branch" +
            std::string(buf);
      return false;
    }
    if (!(jump <= jump_bound)) {  // on the branch, but not as accurate as the steps around it
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
    if (!(sigma_b >= kLandingQualityRatio * sigma_a)) {
      why = "the landing is not beyond the change point at a regular position" + std::string(buf);
      return false;
    }
    passage_outputs(t_a, t_b, A, B, W_a, W_b);
    x.head(nq) = B.q;
    x.segment(nq, na) = B.v;
    x(nx - 1) = W_b;
    t_now = t_b;
    t_last_accept = t_b;
    result.passages.push_back(pass);
    saved_older.valid = false;  // the next step starts from the landing ((C2''))
    saved_prev.valid = true;
    saved_prev.t = t_b;
    saved_prev.sigma = sigma_b;
    saved_prev.rate = rate_b;
    saved_prev.spread = 0.0;  // no trend across the passage
    next_step_limit = std::numeric_limits<double>::infinity();
    saved_prev.x = x;
    saved_prev.chart = dyn.cs_.chart();
    crossing_rewinds = 0;
    // Energy balance at the landing, as after every step.
    dyn.state_.q = B.q;
    dyn.state_.u = B.u;
    const double E = kinetic_energy(model, dyn.state_) + potential_energy(model, B.q) - W_b;
    result.energy_max_drift = std::max(result.energy_max_drift, std::abs(E - energy0));
    if (std::abs(t_now - grid_time(next_out)) <= grid_slack && grid_pending()) emit(t_now, x);
    return true;
  };

  const auto change_point_name = [&](double t_star) {
    return "the change point at t ≈ " + time_text(model, t_star);
  };

  std::string failure, first_passage_why;
  SimulateStatus failure_status = SimulateStatus::failed_step;
  int approaches = 0;
  try {
    while (true) {
      if (!request.pending) {
        const detail::OdeStats st = run_to(T1, 0.0);
        if (st.completed && !request.pending) break;
        if (!request.pending) {
          failure = !stop_message.empty() ? stop_message : st.message;
          if (stop_message.empty() && result.uncorrected_steps > 0)
            failure +=
                "; steps were left uncorrected next to a change point (E nearly loses rank there)";
          break;
        }
      }
      const Request rq = request;
      request.pending = false;
      if (rewind_to >= 0) {  // (C2') undo the steps that crossed the point unannounced
        const SavedState& back = rewind_to == 0 ? saved_older : saved_prev;
        rewind_to = -1;
        x = back.x;
        t_now = back.t;
        t_last_accept = back.t;
        dyn.cs_.set_chart(back.chart);
        dyn.chart_ready_ = false;
        while (!result.samples.empty() && result.samples.back().t > t_now + grid_slack)
          result.samples.pop_back();
        while (next_out > 0 && grid_time(next_out - 1) > t_now + grid_slack) --next_out;
        monitor = {true, back.t, back.sigma};
        const SavedState start = back;  // the state the next step starts from ((C2''))
        saved_older.valid = false;
        saved_prev = start;
        next_step_limit = std::numeric_limits<double>::infinity();
        ++result.rewinds;
      }
      if (rq.t_star >= T1 - end_slack) {  // the change point lies beyond the end: finish
        monitor_armed = false;
        continue;
      }
      if (rq.sigma <= pass_quality) {
        if (primal) {  // G = EᵀAE is singular at the change point: no equation there
          failure_status = SimulateStatus::singular;
          failure = change_point_name(rq.t_star) +
                    " is ahead (E loses rank there, G = EᵀAE is singular): the primal form stops "
                    "at t = " +
                    time_text(model, t_now) + "; the dual form passes it";
          break;
        }
        std::string why;
        const double t_from = t_now;
        if (!pass_change_point(rq.t_star, rq.sigma, why)) {
          dyn.chart_ready_ = false;  // the attempt moved the chart's factors elsewhere
          // The first attempt's reason is kept for the message: the later ones, closer to the
          // point, are dominated by rounding noise (ε/σ̂²) rather than the step's truncation.
          if (first_passage_why.empty()) first_passage_why = why;
          if (rq.sigma / 4.0 >= kPassQualityFloor) {  // try again from closer
            pass_quality = rq.sigma / 4.0;
            request = {true, rq.t_star, rq.sigma};
            approaches = 0;
            continue;
          }
          failure = "cannot pass " + change_point_name(rq.t_star) +
                    " from t = " + time_text(model, t_from) + ": " + why +
                    (first_passage_why != why ? "; first attempt: " + first_passage_why : "");
          break;
        }
        first_passage_why.clear();
        monitor.valid = false;
        saved_older.valid = false;  // saved_prev: the landing
        approaches = 0;
        pass_quality = std::min(kPassQuality, 2.0 * pass_quality);
        continue;
      }
      // (C2) approach: a segment that ends short of the change point (its estimate improves as
      // σ̂ falls), until σ̂ ≤ pass_quality.
      if (++approaches > kMaxApproaches) {  // σ̂ does not go to 0 here: not a change point
        monitor_quiet = true;
        approaches = 0;
        continue;
      }
      const double fraction =
          std::min(kApproachFraction, 1.0 - kApproachTarget * pass_quality / rq.sigma);
      const double dist = rq.t_star - t_now;
      const detail::OdeStats sa = run_to(t_now + fraction * dist, kApproachStep * dist);
      if (!sa.completed && !request.pending) {
        failure = !stop_message.empty() ? stop_message : sa.message;
        break;
      }
      // Completed (its last step raises a new request when the point is near) or stopped by a
      // newer request: the loop goes on from there.
    }
  } catch (const SingularEvaluation& e) {
    failure_status = SimulateStatus::singular;
    failure = e.message;
  }
  result.evaluations = evaluations;
  result.rejected_steps = rejected_steps;
  result.jacobians = jacobians;
  if (!failure.empty()) {
    result.status = failure_status;
    result.message = failure;
    // The final sample at the stop time (the last accepted, corrected state).
    try {
      sample_at(t_last_accept > t_now ? t_last_accept : t_now, x, result.final);
    } catch (const SingularEvaluation&) {
      if (!result.samples.empty()) result.final = result.samples.back();
      result.final.t = std::max(t_now, t_last_accept);
    }
    result.energy_initial = energy0;
    return result;
  }
  // Final sample at the corrected final state.
  try {
    sample_at(t_now, x, result.final);
  } catch (const SingularEvaluation& e) {
    result.status = SimulateStatus::singular;
    result.message = e.message;
    return result;
  }
  result.energy_initial = energy0;
  result.energy_final = result.final.kinetic + result.final.potential - result.final.work;
  result.max_constraint_residual = std::max(result.max_constraint_residual, result.final.residual);
  if (model.nc) {
    VecX f_final(model.nc);
    compute_constraint_residual(model, result.final.q, f_final);
    note_residual(f_final);
  }
  if (!primal)
    for (const auto& smp : result.samples)
      result.max_velocity_residual = std::max(result.max_velocity_residual, smp.velocity_residual);
  result.status = SimulateStatus::completed;
  return result;
}

}  // namespace orthomech
