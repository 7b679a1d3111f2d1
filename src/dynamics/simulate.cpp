#include "orthomech/dynamics/simulate.hpp"

#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "chart_solver.hpp"
#include "integrator.hpp"
#include "orthomech/analysis/mobility.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/dynamics/equations.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/model/general_system.hpp"
#include "orthomech/model/loads.hpp"
#include "orthomech/model/measures.hpp"
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

using detail::ChartSolver;

// Chart monitor (dual form): re-select the chart when an entry of F in the mass metric exceeds
// this (a dependent velocity then moves 4 times faster, in energy terms, than the independent
// ones). The new chart is chosen from the current F (ChartSolver::select_from_tangent), whose
// entries are then ≤ 1 for n_a = 1: the hysteresis is the factor 4.
constexpr double kSpreadLimit = 4.0;
// Per-step position correction: a Newton step more than this many times the residual means the
// chart's dependent block is nearly singular (a change point, IFToMM A02): the step is then
// left uncorrected (its residual is the integrator's local error) rather than risk a jump to
// another branch; counted in SimulateResult::uncorrected_steps.
constexpr double kMaxCorrectionGain = 1e4;

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
      static const char* const kNames[] = {"x", "y", "phi"};
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
        ws_(model, rank),
        cs_(model, rank),
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
        rotations_(model.bodies.size()) {
    for (const Load& l : model.loads)
      if (std::holds_alternative<PointForce>(l.kind) || std::holds_alternative<Torque>(l.kind))
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
    }
    return false;
  }

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
    if (options_.project_stages) {
      // Leaves Eᵀ at the projected q factorised in the chart.
      const SolveResult pr = cs_.correct_positions(state_.q, ws_.constraints.Et, ws_.constraints.f,
                                                   dq_, options_.position_tolerance);
      if (pr.status != SolveStatus::converged) {  // factorise at the q it stopped at
        compute_constraint_jacobian(model_, state_.q, ws_.constraints.Et);
        if (pr.status == SolveStatus::singular || !cs_.factor(ws_.constraints.Et))
          throw SingularEvaluation{"the chart's dependent block is singular at t = " +
                                   std::to_string(t) + " (a change point: E loses rank)"};
      }
      compute_F();
      chart_ready_ = false;
      body_rotations(model_, state_.q, rotations_.data());
    } else if (!(chart_ready_ && state_.q == chart_q_)) {
      // 1. Eᵀ(q), the chart's dependent block, F, unless they are already those at q (the
      //    stepper restarts at the accepted state, where the acceptance has just computed them).
      //    The bodies' rotations at q come along for the constraint rate below.
      compute_constraint_residual_and_jacobian(model_, state_.q, ws_.constraints.f,
                                               ws_.constraints.Et, rotations_.data());
      if (!cs_.factor(ws_.constraints.Et))
        throw SingularEvaluation{"the chart's dependent block is singular at t = " +
                                 std::to_string(t) + " (a change point: E loses rank)"};
      compute_F();
      chart_q_ = state_.q;
      chart_ready_ = true;
    } else {
      body_rotations(model_, state_.q, rotations_.data());
    }
    // 2. u = F v; then Dᵀ u and Ḟ v (design §4: Eᵀ Ḟ v = −Dᵀ u, independent rows of Ḟ zero).
    state_.u.noalias() = F_ * v;
    compute_constraint_rate(model_, state_, ws_.constraints, rotations_.data());  // Dᵀ u
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
  // βᵀ = π A (eqs. (43)–(44), (78)) in eq. (99):
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
        throw SingularEvaluation{"G = EᵀAE is singular at t = " + std::to_string(state_.t)};
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
      throw SingularEvaluation{"G = EᵀAE is singular at t = " + std::to_string(state_.t) +
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
        cs_.solve_transposed(ws_.constraints.Et, tmp_, lambda_);
      else
        compute_multipliers(ws_.constraints.Et, tmp_, lambda_);  // minimum-norm (redundant)
      s.lambda = lambda_;
    }
    compute_reactions(model_, state_.q, s.lambda, s.reactions);
  }

  const Model& model_;
  const SimulateOptions& options_;
  int n_, nq_, nc_, r_, na_;
  Workspace ws_;
  ChartSolver cs_;
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
  std::vector<Eigen::Matrix2d> rotations_;  // R(φ_b) of every body at state_.q (evaluate_dual)
  std::vector<const Load*> nonconservative_;
};

// Mass-orthogonal projection of u₀ onto the admissible velocities, u = α u₀ = ψ M u₀ with
// ψ = F H⁻¹ Fᵀ (eqs. (69)–(70)); v = H⁻¹ Fᵀ M u₀ are its chart coordinates.
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
  if (model.nq != model.n)
    throw std::invalid_argument("simulate: only planar free systems (q̇ = u) are supported");
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
  const int n = model.n, nq = model.nq, na = n - rank;
  Dynamics dyn(model, rank, options);
  result.components = reaction_components(model);

  // 2. Chart and F at q; velocities u = α u₀ (eq. (70)), then the requested rates.
  dyn.state_.q = q;
  dyn.state_.u.setZero();
  dyn.free_system();
  compute_constraint_jacobian(model, q, dyn.ws_.constraints.Et);
  if (!dyn.cs_.select(dyn.ws_.constraints.Et, dyn.ws_.free.A_diag) ||
      !dyn.cs_.factor(dyn.ws_.constraints.Et)) {
    result.status = SimulateStatus::singular;
    result.message = "the initial position is singular (E loses rank there)";
    return result;
  }
  dyn.compute_F();
  dyn.cs_.select_from_tangent(dyn.F_, dyn.M_sqrt());  // independent components that move most
  if (!dyn.cs_.factor(dyn.ws_.constraints.Et)) {
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

  detail::OdeProblem problem;
  problem.rhs = [&](const VecX& y, VecX& dy, double t) {
    ++evaluations;
    dy.resize(nx);
    if (primal) {
      dyn.evaluate_primal(t, y.head(nq), y.segment(nq, n));
      dy.head(nq) = dyn.state_.u;  // eq. (100): q̇ = B̃ u (B̃ = I here)
      dy.segment(nq, n) = dyn.pdot_;
    } else {
      dyn.evaluate_dual(t, y.head(nq), y.segment(nq, na));
      dy.head(nq) = dyn.state_.u;  // q̇ = B̃ u (B̃ = I here)
      dy.segment(nq, na) = dyn.vdot_;
    }
    dy(nx - 1) = dyn.nonconservative_power();
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

  problem.output = [&](double t, const VecX& y) {
    if (!options.record_samples) return;
    result.samples.emplace_back();
    sample_at(t, y, result.samples.back());
  };

  std::string stop_message;
  problem.accept = [&](double t, VecX& y) {
    auto qy = y.head(nq);
    MatX& Et = dyn.ws_.constraints.Et;
    dyn.chart_ready_ = false;  // Eᵀ, the chart's factors and F change below
    // Residual left by the step (before correction), with Eᵀ at the same q.
    q = qy;
    dyn.mass_at(q);
    compute_constraint_residual_and_jacobian(model, q, f, Et);
    if (f.size())
      result.max_constraint_residual =
          std::max(result.max_constraint_residual, f.cwiseAbs().maxCoeff());
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
    const bool factored = dyn.cs_.factor(Et);
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
    bool near_singular = false;
    SolveResult corr = dyn.cs_.correct_positions(q, Et, f, dq, options.position_tolerance,
                                                 kMaxCorrectionGain, &near_singular, factored);
    if (near_singular) ++result.uncorrected_steps;
    if (corr.status == SolveStatus::singular) {  // try a fresh chart once
      compute_constraint_jacobian(model, q, Et);
      if (dyn.cs_.select(Et, dyn.ws_.free.A_diag))
        corr = dyn.cs_.correct_positions(q, Et, f, dq, options.position_tolerance);
    }
    if (corr.status != SolveStatus::converged) {
      stop_message = "position correction failed at t = " + std::to_string(t) + ": " + corr.message;
      return false;
    }
    qy = q;
    dyn.compute_F();
    dyn.mass_at(q);
    dyn.state_.q = q;
    if (primal) {
      // Momenta: p ← M α u, the mass-orthogonal projection (eq. (44): α = I − A π).
      dyn.state_.u.noalias() = dyn.ws_.free.A * y.segment(nq, n);
      dyn.compute_H();
      const VecX vv = project_velocity(dyn, dyn.state_.u);
      dyn.state_.u.noalias() = dyn.F_ * vv;
      y.segment(nq, n) = dyn.ws_.free.M * dyn.state_.u;
      // A poor chart only slows the corrector: re-select it when it degrades.
      if (dyn.chart_spread() > kSpreadLimit) {
        const Chart old = dyn.cs_.chart();
        dyn.cs_.select_from_tangent(dyn.F_, dyn.M_sqrt());
        if (!dyn.cs_.factor(dyn.ws_.constraints.Et)) {
          dyn.cs_.set_chart(old);
          (void)dyn.cs_.factor(dyn.ws_.constraints.Et);
        }
      }
    } else {
      // Chart monitor: re-select when F's mass-scaled entries grow; switch if the new chart is
      // clearly better (hysteresis 2), re-expressing v from u = F v.
      // v ← H⁻¹ Fᵀ M u_step: the admissible velocity at the corrected position closest to the
      // step's velocity in the mass metric (eq. (70), u = α u_step), rather than keeping u_I.
      if (u_step.squaredNorm() > 0.0) {
        dyn.compute_H();
        y.segment(nq, na) = project_velocity(dyn, u_step);
      }
      const double spread = dyn.chart_spread();
      if (spread > spread_limit) {
        const Chart old = dyn.cs_.chart();
        const VecX u = dyn.F_ * y.segment(nq, na);
        dyn.cs_.select_from_tangent(dyn.F_, dyn.M_sqrt());
        bool switched = false;
        if (dyn.cs_.factor(dyn.ws_.constraints.Et)) {
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
          }
        }
        if (!switched) {  // keep the chart; try again only when it degrades further
          dyn.cs_.set_chart(old);
          (void)dyn.cs_.factor(dyn.ws_.constraints.Et);
          dyn.compute_F();
          spread_limit = 2.0 * spread;
        }
      } else if (spread < 0.5 * spread_limit) {
        spread_limit = std::max(kSpreadLimit, 2.0 * spread);
      }
      dyn.state_.u.noalias() = dyn.F_ * y.segment(nq, na);
      dyn.chart_q_ = q;  // Eᵀ, the factors and F are those at the corrected q
      dyn.chart_ready_ = true;
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
    return true;
  };

  // Initial energy (at the consistent initial state).
  {
    dyn.state_.q = q;
    dyn.state_.u = dyn.F_ * v;
    energy0 = kinetic_energy(model, dyn.state_) + potential_energy(model, q);
    have_energy0 = true;
    result.energy_scale =
        std::abs(kinetic_energy(model, dyn.state_)) + std::abs(potential_energy(model, q));
  }

  detail::OdeOptions oo;
  oo.stepper = ode_stepper(options.integrator);
  oo.rtol = options.rtol;
  oo.atol = options.atol;
  oo.t0 = initial.t;
  oo.t_end = initial.t + options.t_end;
  oo.dt_out = options.dt_out > 0.0 ? options.dt_out : options.t_end / 100.0;
  oo.max_dt = options.max_step;
  oo.max_steps = options.max_steps;

  detail::OdeStats stats;
  try {
    stats = detail::integrate_ode(problem, x, oo);
  } catch (const SingularEvaluation& e) {
    result.status = SimulateStatus::singular;
    result.message = e.message;
    result.evaluations = evaluations;
    if (!result.samples.empty()) result.final = result.samples.back();  // last good output
    return result;
  }
  result.evaluations = evaluations;
  result.rejected_steps = stats.rejected;
  result.jacobians = stats.jacobians;
  // Final sample at the corrected final state.
  try {
    sample_at(stats.t, x, result.final);
  } catch (const SingularEvaluation& e) {
    result.status = SimulateStatus::singular;
    result.message = e.message;
    return result;
  }
  result.energy_initial = energy0;
  result.energy_final = result.final.kinetic + result.final.potential - result.final.work;
  result.max_constraint_residual = std::max(result.max_constraint_residual, result.final.residual);
  if (!primal)
    for (const auto& smp : result.samples)
      result.max_velocity_residual = std::max(result.max_velocity_residual, smp.velocity_residual);
  if (!stats.completed) {
    result.status = SimulateStatus::failed_step;
    result.message = !stop_message.empty() ? stop_message : stats.message;
    if (stop_message.empty() && result.uncorrected_steps > 0)
      result.message +=
          "; steps were left uncorrected next to a change point (E nearly loses rank there), "
          "where a tight rtol can stall the step-size control: a looser one (e.g. 1e-8) passes "
          "it";
    return result;
  }
  result.status = SimulateStatus::completed;
  return result;
}

}  // namespace orthomech
