#pragma once
// The equations of motion on a model's sparse stages, shared by `simulate` (its right-hand sides,
// both forms) and `crosscheck` (its probe comparison of large models): the free system, Eᵀ on
// its structural pattern, the chart engine for F and position correction, G = EᵀAE for the
// primal form. Internal to the library (src/dynamics), like integrator.hpp.
#include <Eigen/Cholesky>
#include <string>

#include "orthomech/analysis/friction.hpp"
#include "orthomech/analysis/reactions.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/constraints/sparse_et.hpp"
#include "orthomech/dynamics/equations.hpp"
#include "orthomech/dynamics/simulate.hpp"
#include "orthomech/io/units.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/model/loads.hpp"
#include "orthomech/model/measures.hpp"
#include "orthomech/model/spatial.hpp"
#include "orthomech/numerics/weighted_gram.hpp"
#include "orthomech/projection/chart_engine.hpp"
#include "orthomech/projection/dual.hpp"
#include "orthomech/projection/free_system_stage.hpp"

namespace orthomech::detail {

// A time for a message, in the file's declared time unit (a model built in code: s).
inline std::string time_text(const Model& model, double t) {
  return format_quantity(t, Dimension::time, unit_system(model.units), 9);
}

// The chart's block is singular for the integrator below this quality (min/max pivot of its LU).
constexpr double kSingularBlock = 1e-14;

// Thrown inside a right-hand side when the equations cannot be evaluated (singular chart block
// or singular G); caught in simulate() and returned as a status (never escapes the library).
struct SingularEvaluation {
  std::string message;
};

// Whether the dual form evaluates every stage at its position projected onto f(q) = 0 in the
// chart (independent coordinates fixed): on request, and always for rosenbrock4. Its Jacobian
// is then that of the ODE on the constraint manifold in chart coordinates (the columns of the
// dependent coordinates are zero). Without the projection the right-hand side off the manifold
// is that of F extended through Eᵀ(q), which stiffens as the chart degrades: rosenbrock4 needed
// 14 812 steps (2·10⁻⁶ s next to the change points) on n-four-bar-2 over 10 s at rtol 1e-6,
// 1057 with it (issue 10; docs/theory.md, "Rosenbrock on the chart's ODE").
inline bool projects_stages(const SimulateOptions& options) {
  return options.project_stages || options.integrator == Integrator::rosenbrock4;
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
        ws_(model),
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
        dq_(VecX::Zero(model.n)),
        chart_q_(VecX::Zero(model.nq)),
        pins_(friction_pins(model)) {
    v_stage_.resize(na_);
  }

  // ---- Shared pieces ----------------------------------------------------------------------

  // Free system at state_ (M once if constant; Q̂; Ṁ).
  void free_system() { compute_free_system(model_, state_, ws_.free); }
  // M, A at q when M depends on q (before products with M or A at a corrected position).
  void mass_at(const VecX& q) {
    if (ws_.free.constant_mass) return;
    state_.q = q;
    free_system();
  }

  // Power of the non-conservative forces at state_ (Q̂, Ṁ there: ws_.free), as the free system
  // defines it (free_system.hpp): Q_ncᵀ u − dissipated power for bodies.
  double nonconservative_power() {
    return orthomech::free_system(model_).nonconservative_power(model_, state_, ws_.free.Q,
                                                                ws_.free.Mdot, Qnc_) +
           friction_power_;
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
  bool factor_chart(const SparseEt& Et) { return cs_.factor(Et, ws_.free.A_sqrt) > kSingularBlock; }

  // F in the current chart at Eᵀ = ws_.constraints.Et (factorised): F = P [I; −(E_RDᵀ)⁻¹ E_RIᵀ].
  void compute_F() { cs_.basis(ws_.constraints.Et, b_, col_, F_); }

  // Largest entry of F in the mass metric, |F_dk| √M_dd / √M_ii (i = independent k): it grows
  // without bound as the chart's dependent block degrades (docs/design.md §4: the chart monitor).
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

  // M x, whichever way the stage stores M (set-up only: allocates).
  [[nodiscard]] VecX mass_times(const VecX& x) const {
    if (ws_.free.diagonal_mass) return ws_.free.M_diag.cwiseProduct(x);
    return ws_.free.M * x;
  }

  // u = A p (eq. (100)) into state_.u.
  void velocity_from_momentum(const Eigen::Ref<const VecX>& p) {
    if (ws_.free.diagonal_mass)
      state_.u = ws_.free.A_diag.cwiseProduct(p);
    else
      state_.u.noalias() = ws_.free.A * p;  // eq. (100)
  }

  // p ← M u (eq. (5)) from state_.u.
  void momentum_from_velocity(Eigen::Ref<VecX> p) const {
    if (ws_.free.diagonal_mass)
      p = ws_.free.M_diag.cwiseProduct(state_.u);
    else
      p.noalias() = ws_.free.M * state_.u;
  }

  // H = Fᵀ M F (eq. (68)) and its Cholesky factor.
  void compute_H() {
    if (ws_.free.diagonal_mass)
      MF_ = ws_.free.M_diag.asDiagonal() * F_;
    else
      MF_.noalias() = ws_.free.M * F_;
    H_.noalias() = F_.transpose() * MF_;  // eq. (68)
    H_llt_.compute(H_);
  }

  // A stage's position projected onto f(q) = 0 in the chart, its independent coordinates fixed
  // (L4), with Eᵀ factorised in the chart and F at the projected q: the right-hand side is then
  // the ODE on the constraint manifold in chart coordinates, smooth even next to a change point,
  // where F off the manifold is very sensitive to the stage's constraint error (IFToMM A02).
  void project_stage_position(double t) {
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
  }

  // Dual form at (t, q, v): u = F v, Ḟ v from Eᵀ (Ḟ v) = −Dᵀ u, H v̇ = Fᵀ (Q̂ − Ṁ u − M Ḟ v).
  void evaluate_dual(double t, const Eigen::Ref<const VecX>& q, const Eigen::Ref<const VecX>& v) {
    state_.t = t;
    state_.q = q;
    // 0. The stage's position projected onto f(q) = 0 in the chart (project_stage_position).
    if (project_stages_) {
      project_stage_position(t);
      ws_.constraints.poses.update(model_, state_.q);
    } else if (!(chart_ready_ && state_.q == chart_q_)) {
      // 1. Eᵀ(q), the chart's dependent block, F, unless they are already those at q (the
      //    stepper restarts at the accepted state, where the acceptance has just computed them).
      //    The bodies' rotations at q come along for the constraint rate below.
      ws_.constraints.poses.update(model_, state_.q);
      compute_constraint_residual_and_jacobian(model_, state_.q, ws_.constraints.poses,
                                               ws_.constraints.f, ws_.constraints.Et);
      if (!factor_chart(ws_.constraints.Et))
        throw SingularEvaluation{"the chart's dependent block is singular at t = " +
                                 time_text(model_, t) + " (a change point: E loses rank)"};
      compute_F();
      chart_q_ = state_.q;
      chart_ready_ = true;
    } else {
      ws_.constraints.poses.update(model_, state_.q);
    }
    // 2. u = F v; then Dᵀ u and Ḟ v (docs/design.md §4: Eᵀ Ḟ v = −Dᵀ u, independent rows of
    // Ḟ zero).
    state_.u.noalias() = F_ * v;
    compute_constraint_rate(model_, state_, ws_.constraints.poses, ws_.constraints.Dtu);  // Dᵀ u
    b_ = -ws_.constraints.Dtu;
    cs_.solve(b_, Fdv_);
    // 3. Free system, H (eq. (68)) and v̇.
    free_system();
    compute_H();
    dual_accelerations();
    if (friction_on()) friction_dual();
  }

  // v̇ from H v̇ = Fᵀ (Q̂ − Ṁ u − M Ḟ v) and u̇ = F v̇ + Ḟ v, with H, F, Ḟ v and Q̂ at hand.
  void dual_accelerations() {
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
    if (project_stages_) project_stage_position(t);
    if (!ws_.free.mass_ready || !ws_.free.constant_mass) {
      state_.u.setZero();
      free_system();
    }
    velocity_from_momentum(p);
    if (project_stages_) {
      // The stage's velocity admissible at the projected q with its independent components
      // kept, u = F u_I (the momenta p = M u implied): the right-hand side then depends on p
      // through A p's independent components only.
      for (int k = 0; k < na_; ++k)
        v_stage_(k) = state_.u(cs_.chart().independent[static_cast<size_t>(k)]);
      state_.u.noalias() = F_ * v_stage_;
      // Eᵀ is that of the projected q: only Dᵀ u.
      ws_.constraints.poses.update(model_, state_.q);
      compute_constraint_rate(model_, state_, ws_.constraints.poses, ws_.constraints.Dtu);
    } else {
      ws_.constraints.poses.update(model_, state_.q);
      compute_constraint_residual_and_jacobian(model_, state_.q, ws_.constraints.poses,
                                               ws_.constraints.f, ws_.constraints.Et);
      compute_constraint_rate(model_, state_, ws_.constraints.poses, ws_.constraints.Dtu);
    }
    free_system();
    factor_G();
    primal_multipliers();
    if (friction_on()) friction_primal();
    pdot_ = ws_.free.Q;
    pdot_.noalias() += ws_.constraints.Et.matrix().transpose() * lambda_;  // eq. (99) as (L3)
  }

  // (L3)'s λ = −G⁻¹ (Eᵀ A (Q̂ − Ṁ u) + Dᵀ u), with G factorised and Q̂, Dᵀu at hand.
  void primal_multipliers() {
    const SparseEt::Matrix& E = ws_.constraints.Et.matrix();  // Eᵀ
    tmp_ = ws_.free.Q;
    if (!ws_.free.constant_mass) tmp_.noalias() -= ws_.free.Mdot * state_.u;
    if (ws_.free.diagonal_mass) {  // A = diag(A_diag)
      tmp_.array() *= ws_.free.A_diag.array();
      b_.noalias() = E * tmp_;
    } else {
      col_.noalias() = ws_.free.A * tmp_;
      b_.noalias() = E * col_;
    }
    b_ += ws_.constraints.Dtu;
    solve_G(b_, lambda_);
    lambda_ = -lambda_;  // (L3)
  }

  // ---- Pin friction (analysis/friction.hpp; issue 49 item 3) --------------------------------
  // With pin_sign_ set (per friction pin, the sign of its relative rate, held between the
  // events where it changes), each evaluation adds the pins' Coulomb moments μ r |F| against
  // their relative rotation, F from the multipliers the moments change: a fixed point from the
  // frictionless multipliers, as cycle's (at most kFrictionIterations passes, until λ moves by
  // less than kFrictionTolerance of its size). Q̂ then includes the moments (the samples'
  // reactions do too) and friction_power_ is their power (≤ 0), part of nonconservative_power.
  [[nodiscard]] bool friction_on() {
    friction_power_ = 0.0;
    return !pins_.empty() && pin_sign_.size() == pins_.size();
  }
  // Q_f(λ) into Qf_.
  void friction_loads(const VecX& lambda) {
    Qf_.setZero(n_);
    for (size_t j = 0; j < pins_.size(); ++j) {
      const FrictionPin& p = pins_[j];
      const double t = p.coefficient * p.radius * lambda.segment<2>(p.row).norm() * pin_sign_[j];
      if (p.u_second >= 0) Qf_(p.u_second) -= t;
      if (p.u_first >= 0) Qf_(p.u_first) += t;
    }
  }
  [[nodiscard]] bool friction_settled() const {
    const double size = lambda_.cwiseAbs().maxCoeff();
    return (lambda_ - lambda_prev_).cwiseAbs().maxCoeff() <= kFrictionTolerance * size;
  }
  // The dual form's multipliers from u̇: E λ = M u̇ + Ṁ u − Q̂ (minimum norm when redundant).
  void dual_multipliers() {
    if (ws_.free.diagonal_mass)
      R_ = ws_.free.M_diag.cwiseProduct(udot_) - ws_.free.Q;
    else
      R_ = ws_.free.M * udot_ - ws_.free.Q;
    if (!ws_.free.constant_mass) R_.noalias() += ws_.free.Mdot * state_.u;
    if (r_ == nc_) {
      solve_transposed(R_, lambda_);
    } else {  // minimum-norm (redundant): on the dense Eᵀ (a small mechanism's)
      ws_.constraints.Et.to_dense(Et_dense_);
      compute_multipliers(Et_dense_, R_, lambda_);
    }
  }
  void friction_dual() {
    Q0_ = ws_.free.Q;
    dual_multipliers();
    for (int it = 0; it < kFrictionIterations; ++it) {
      friction_loads(lambda_);
      ws_.free.Q = Q0_ + Qf_;
      dual_accelerations();
      lambda_prev_ = lambda_;
      dual_multipliers();
      if (friction_settled()) break;
    }
    friction_power_ = Qf_.dot(state_.u);
  }
  void friction_primal() {
    Q0_ = ws_.free.Q;
    for (int it = 0; it < kFrictionIterations; ++it) {
      friction_loads(lambda_);
      ws_.free.Q = Q0_ + Qf_;
      lambda_prev_ = lambda_;
      primal_multipliers();
      if (friction_settled()) break;
    }
    friction_power_ = Qf_.dot(state_.u);
  }

  // G = Eᵀ A E at ws_.constraints.Et: dense Cholesky, or for large diagonal-mass systems formed
  // on its fixed sparse pattern and factorised by a sparse LDLᵀ (numerics/weighted_gram.hpp).
  void factor_G() {
    const SparseEt::Matrix& E = ws_.constraints.Et.matrix();  // Eᵀ
    if (nc_ == 0) {  // no constraint: G is 0 × 0, λ empty and (L3) is ṗ = Q̂
      sparse_G_ = false;
      G_.resize(0, 0);
      return;
    }
    if (nc_ > 48 && ws_.free.diagonal_mass) {
      if (!G_analyzed_) {  // Eᵀ's structural pattern, hence G's, is fixed: one analysis
        G_sparse_.analyze(E);
        G_analyzed_ = true;
      }
      if (!G_sparse_.factorize(E, ws_.free.A_diag))
        throw SingularEvaluation{"G = EᵀAE is singular at t = " + time_text(model_, state_.t)};
      sparse_G_ = true;
      return;
    }
    sparse_G_ = false;
    if (G_.rows() != nc_) {  // the dense G's matrices, at the first primal evaluation only
      AEt_.resize(n_, nc_);
      G_.resize(nc_, nc_);
      G_llt_ = Eigen::LLT<MatX>(nc_);
    }
    if (ws_.free.diagonal_mass) {
      AEt_ = E.transpose();
      AEt_.array().colwise() *= ws_.free.A_diag.array();  // A Eᵀ with A = diag(A_diag)
    } else {
      AEt_.noalias() = ws_.free.A * E.transpose();
    }
    G_.noalias() = E * AEt_;  // eq. (42)
    G_llt_.compute(G_);
    const auto Ld = G_llt_.matrixLLT().diagonal();
    constexpr double kSingularG = 1e-12;  // as in projection/primal.cpp
    if (G_llt_.info() != Eigen::Success ||
        !(Ld.minCoeff() * Ld.minCoeff() > kSingularG * Ld.maxCoeff() * Ld.maxCoeff()))
      throw SingularEvaluation{"G = EᵀAE is singular at t = " + time_text(model_, state_.t) +
                               " (redundant constraints or a change point)"};
  }
  void solve_G(const VecX& b, VecX& x) {
    if (nc_ == 0)
      x.resize(0);
    else if (sparse_G_)
      G_sparse_.solve(b, x);
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
    s.velocity_residual =
        nc_ ? (ws_.constraints.Et.matrix() * state_.u).cwiseAbs().maxCoeff() : 0.0;
    s.measures.clear();
    for (const Measure& m : model_.measures)
      s.measures.push_back(evaluate_measure(model_, m, state_.q, &state_.u, &udot_));
    s.reactions.clear();
    s.lambda.resize(0);
    if (!options_.reactions || nc_ == 0) return;
    if (primal) {
      s.lambda = lambda_;
    } else {
      dual_multipliers();  // R = M u̇ + Ṁ u − Q̂ = E λ
      s.lambda = lambda_;
    }
    compute_reactions(model_, state_.q, s.lambda, s.reactions);
  }

  const Model& model_;
  const SimulateOptions& options_;
  int n_, nq_, nc_, r_, na_;
  bool project_stages_;
  // The stages simulate uses (the projections' n × n matrices are not allocated: heap peak
  // 400 MB → 178 MB on the N = 200 four-bar, valgrind massif).
  struct Constraints {
    VecX f;           // nc: geometric residual, eq. (20)
    SparseEt Et;      // nc × n on its structural pattern: Eᵀ, eq. (23)
    VecX Dtu;         // nc: Dᵀu, eq. (76)
    BodyPoses poses;  // the kinematics stage at state_.q (the bodies' rotations)
    explicit Constraints(const Model& model)
        : f(VecX::Zero(model.nc)), Et(model), Dtu(VecX::Zero(model.nc)), poses(model) {}
  };
  struct Stages {
    FreeSystemWorkspace free;
    Constraints constraints;
    explicit Stages(const Model& model)
        : free(model, MassStorage::diagonal_if_possible), constraints(model) {}
  } ws_;
  ChartEngine cs_;
  State state_;
  MatX F_, MF_, H_;
  Eigen::LLT<MatX> H_llt_;
  VecX Fdv_, b_, col_, rhs_, vdot_, udot_, tmp_, Qnc_, lambda_;
  VecX pdot_;
  VecX v_stage_;  // a projected primal stage's independent velocities (evaluate_primal)
  // The primal form's dense G = EᵀAE and A Eᵀ (small or non-diagonal-mass systems): sized at
  // the first factor_G that uses them, so that the dual form holds no n × n_c matrix.
  MatX AEt_, G_;
  Eigen::LLT<MatX> G_llt_;
  MatX Et_dense_;  // dual_multipliers' minimum-norm multipliers (redundant constraints) only
  WeightedGram G_sparse_;  // G = Eᵀ A E on its pattern (large diagonal-mass systems)
  bool sparse_G_ = false;
  bool G_analyzed_ = false;  // G_sparse_ has G's (fixed) pattern
  VecX dq_;
  // Eᵀ (ws_.constraints.Et), the chart's factors and F_ are those at chart_q_ in the current
  // chart: an evaluation at chart_q_ need not compute them again. Whoever changes one of them
  // (the step's acceptance, the stage projection) clears it or sets it anew.
  bool chart_ready_ = false;
  VecX chart_q_;
  // Pin friction: the model's friction pins, their held signs (empty: no friction applied, as
  // in crosscheck's probes), the last evaluation's friction power and scratch.
  std::vector<FrictionPin> pins_;
  std::vector<double> pin_sign_;
  double friction_power_ = 0.0;
  VecX Q0_, Qf_, R_, lambda_prev_;
};

}  // namespace orthomech::detail
