#include "orthomech/dynamics/crosscheck.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>

#include "dynamics.hpp"
#include "orthomech/analysis/mobility.hpp"
#include "orthomech/dynamics/equations.hpp"
#include "orthomech/dynamics/simulate.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/projection/dual.hpp"
#include "orthomech/projection/primal.hpp"
#include "orthomech/projection/workspace.hpp"

namespace orthomech {

namespace {

// One comparison at one state: the difference ‖a − b‖∞ (or the residual ‖x‖∞ of an identity
// x = 0) and the size of what is compared (the scale the difference is relative to).
struct Difference {
  double difference = 0.0;
  double scale = 1e-300;
};
// ‖a − b‖∞ against max(‖a‖∞, ‖b‖∞, floor): `floor` is the size of the terms the compared
// quantity is summed from, where it may vanish while they do not (accelerations at rest,
// reactions at a symmetric position); floor = 1e-300 gives the pure relative value.
// The scale is at least 1e-300, so that two zeros (a mechanism at rest without loads) compare
// as 0, not 0/0.
Difference relative(const MatX& a, const MatX& b, double floor) {
  if (a.size() == 0) return {};
  return {(a - b).cwiseAbs().maxCoeff(),
          std::max({a.cwiseAbs().maxCoeff(), b.cwiseAbs().maxCoeff(), floor, 1e-300})};
}
// ‖x‖∞ for an identity x = 0 whose terms are of size `scale`.
Difference residual(const MatX& x, double scale) {
  return {x.size() ? x.cwiseAbs().maxCoeff() : 0.0, std::max(scale, 1e-300)};
}

// The checks over the motion. A check's value is its largest difference over the states divided
// by the largest scale over the states: a quantity that vanishes at one state (a drive line's
// reactions at its symmetric position) is measured against its size along the motion, not
// against its own roundoff there (docs/cli.md, crosscheck).
class Recorder {
 public:
  explicit Recorder(double tol) : tol_(tol) {}
  void add(const std::string& name, const std::string& kind, Difference d, double t) {
    size_t k = 0;
    while (k < items_.size() && items_[k].name != name) ++k;
    if (k == items_.size()) {
      items_.push_back({name, kind, 0.0, t, true});
      worst_.push_back({-1.0, 1e-300});
    }
    Difference& w = worst_[k];
    CrosscheckItem& it = items_[k];
    if (!std::isnan(w.difference) && !(d.difference <= w.difference))  // a NaN stays
      w.difference = d.difference, it.at_t = t;
    w.scale = std::max(w.scale, d.scale);
    it.max_relative = w.difference / w.scale;
    it.pass = it.max_relative <= tol_;
  }
  std::vector<CrosscheckItem> items_;

 private:
  double tol_;
  std::vector<Difference> worst_;  // per item: the largest difference, the largest scale
};

// The states the forms are compared at: the motion (dual form) from the design position with the
// seeded initial velocity guess. Empty samples: the message says why.
SimulateResult simulate_motion(const Model& model, const CrosscheckOptions& options) {
  SimulateOptions so;
  so.t_end = options.t_end;
  so.rtol = 1e-9;
  so.atol = 1e-11;
  so.dt_out = options.t_end / std::max(1, options.samples - 1);
  so.reactions = false;
  so.use_file_rates = false;  // the seeded guess below, not the file's initial rates
  so.max_steps = options.max_steps;
  so.control = options.control;  // the motion is the first half of the run's progress
  if (options.control.progress)
    so.control.progress = [&options](double f) { options.control.progress(0.5 * f); };
  std::mt19937 rng(options.seed);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  so.initial_u = VecX(model.n);
  for (int k = 0; k < model.n; ++k) so.initial_u(k) = uni(rng);
  return simulate(model, so);
}

// Why the primal form is skipped; `lambda` says which of the non-unique multipliers the dual
// checks use (the dense comparison's minimum-norm one, or the probe comparison's on a chart's
// rows).
std::string redundancy_reason(const Mobility& mob, int nc, const char* lambda) {
  std::string reason =
      "E has rank " + std::to_string(mob.rank) + " < n_c = " + std::to_string(nc) + " (redundant: ";
  for (size_t k = 0; k < mob.redundant.size(); ++k) reason += (k ? "; " : "") + mob.redundant[k];
  return reason +
         "), so G = EᵀAE (eq. (42)) is singular and the primal form is undefined; the reactions "
         "are not unique (" +
         lambda + ")";
}

// The comparisons' side of the run's bounds: the second half of its progress, the wall-clock
// limit less what the motion took, the interrupt. True (result.stop and message set) when a
// bound is met before state k of `count`.
class StateMonitor {
 public:
  StateMonitor(const RunControl& control, double spent)
      : time_limit_(control.time_limit),
        control_(remaining(control, spent)),
        monitor_(control_, 0) {}
  bool stop_before(size_t k, size_t count, CrosscheckResult& result) {
    const double fraction = count ? static_cast<double>(k) / static_cast<double>(count) : 1.0;
    const StopReason r = monitor_.tick(fraction);
    if (r == StopReason::none) return false;
    result.stop = r;
    std::string why = monitor_.stop_message(r, 0.5 + 0.5 * fraction, "state", "--samples");
    if (r == StopReason::time_limit) {  // the whole run's limit, not what was left of it
      char limit[96];
      std::snprintf(limit, sizeof limit, "the time limit of %g s is reached (--time-limit)",
                    time_limit_);
      why = why.substr(0, why.find("the time limit")) + limit;
    }
    result.message =
        why + "; compared " + std::to_string(k) + " of " + std::to_string(count) + " states";
    return true;
  }

 private:
  static RunControl remaining(const RunControl& control, double spent) {
    RunControl c = control;
    if (control.time_limit > 0.0) c.time_limit = std::max(1e-9, control.time_limit - spent);
    if (control.progress) c.progress = [&control](double f) { control.progress(0.5 + 0.5 * f); };
    c.progress_after = std::max(0.0, control.progress_after - spent);
    return c;
  }
  double time_limit_;
  RunControl control_;
  RunMonitor monitor_;
};

// The dense comparison: α, β, ψ, Θ, θ formed as n × n matrices (projection/dual.hpp,
// projection/primal.hpp) at every state.
void compare_dense(const Model& model, const SimulateResult& motion, const Mobility& mob,
                   CrosscheckResult& result, Recorder& rec, StateMonitor& monitor) {
  const int n = model.n;
  const bool redundant = mob.rank < model.nc;
  Workspace wd(model, mob.rank), wp(model, mob.rank);
  DynamicsPoint dd(model), dp(model);
  const MatX I = MatX::Identity(n, n);
  for (const SimulationSample& s : motion.samples) {
    if (monitor.stop_before(static_cast<size_t>(result.samples), motion.samples.size(), result))
      return;
    State st(model);
    st.t = s.t;
    st.q = s.q;
    st.u = s.u;
    ++result.samples;
    // Dual form and its identities.
    if (compute_dual_dynamics(model, st, wd, dd) != ProjectionStatus::ok) {
      result.message = "the dual form is singular at t = " + std::to_string(s.t);
      continue;
    }
    const auto& d = wd.dual;
    const MatX& M = wd.free.M;
    const MatX& A = wd.free.A;
    const MatX& Et = wd.constraints.Et;
    const double aS = std::max(1.0, d.alpha.cwiseAbs().maxCoeff());
    rec.add("alpha^2 = alpha (eq. (65))", "identity", residual(d.alpha * d.alpha - d.alpha, aS),
            s.t);
    rec.add("E^T alpha = 0 (eq. (30))", "identity",
            residual(Et * d.alpha, Et.cwiseAbs().maxCoeff() * aS), s.t);
    const MatX Mb = M * d.beta;
    rec.add("M beta symmetric (eq. (35))", "identity",
            residual(Mb - Mb.transpose(), Mb.cwiseAbs().maxCoeff()), s.t);
    rec.add("alpha^T M beta = 0 (eq. (34))", "identity",
            residual(d.alpha.transpose() * Mb, M.cwiseAbs().maxCoeff() * aS * aS), s.t);
    rec.add("psi = alpha A (eq. (69))", "identity", relative(d.psi, d.alpha * A, 1e-300), s.t);
    rec.add("F^T R = 0 (eq. (64))", "identity",
            residual(d.F.transpose() * dd.R,
                     d.F.cwiseAbs().maxCoeff() *
                         std::max(dd.R.cwiseAbs().maxCoeff(), wd.free.Q.cwiseAbs().maxCoeff())),
            s.t);
    rec.add("E lambda = R (dual reactions)", "identity",
            relative(Et.transpose() * dd.lambda, dd.R, wd.free.Q.cwiseAbs().maxCoeff()), s.t);
    if (redundant) continue;

    // Primal form, compared with the dual.
    if (compute_primal_dynamics(model, st, wp, dp) != ProjectionStatus::ok) {
      rec.add("primal form evaluable (G regular)", "dual-vs-primal", {1.0, 1.0}, s.t);
      continue;
    }
    result.primal_checked = true;
    const auto& p = wp.primal;
    rec.add("alpha dual vs primal (eq. (70) vs (44))", "dual-vs-primal",
            relative(d.alpha, p.alpha, 1e-300), s.t);
    rec.add("beta dual vs primal (eq. (70) vs (44))", "dual-vs-primal",
            relative(d.beta, p.beta, 1e-300), s.t);
    // Scales (the sizes of the terms the compared quantities are summed from): the applied
    // forces, the inertia forces, and the velocity-product forces through Ω = E G⁻¹ Dᵀ (eq. (78)),
    // whose size ‖Ω‖ ‖u‖ does not vanish where Ω u does (a symmetric position).
    const double uS = std::max(st.u.cwiseAbs().maxCoeff(), 1e-300);
    const double OmegaS = p.Omega.cwiseAbs().maxCoeff();
    const double qscale = std::max(
        {wd.free.Q.cwiseAbs().maxCoeff(), (M * dd.udot).cwiseAbs().maxCoeff(), OmegaS * uS});
    rec.add("acceleration dual vs primal (eq. (99))", "dual-vs-primal",
            relative(M * dd.udot, M * dp.udot, qscale), s.t);
    rec.add("reaction dual vs Theorem 5 (eq. (91))", "dual-vs-primal", relative(dd.R, dp.R, qscale),
            s.t);
    rec.add("reaction eq. (91) vs eq. (99): R = pdot - Q", "identity",
            relative(dp.R, dp.pdot - wp.free.Q, qscale), s.t);
    // λ of the size the reactions E λ have: qscale over the largest entry of E.
    const double lambda_scale = qscale / std::max(Et.cwiseAbs().maxCoeff(), 1e-300);
    rec.add("multipliers dual vs primal", "dual-vs-primal",
            relative(dd.lambda, dp.lambda, lambda_scale), s.t);
    rec.add("omega u = Omega u (eq. (102))", "identity",
            relative(p.omega * st.u, p.Omega * st.u, OmegaS * uS), s.t);
    rec.add("Omega^T alpha = 0 (eq. (103))", "identity",
            residual(p.Omega.transpose() * p.alpha, OmegaS * aS), s.t);
    rec.add("J = E^T A p = 0 (eq. (105))", "identity",
            residual(dp.J, Et.cwiseAbs().maxCoeff() * uS), s.t);
    // α̇ = −β̇ from eq. (85) and from eq. (82): θ M = −A ω, also when Ṁ ≠ 0 (their Ṁ terms,
    // −Ȧ_αβ M and A Ṁ_αβ, are both A αᵀ Ṁ β since ψ = A αᵀ). Both sum two terms (ω = Ω α +
    // αᵀ Ωᵀ, eq. (79); θ = β Θ + Θᵀ βᵀ, eq. (84)) that cancel at a symmetric position.
    const double theta_scale = std::max((A * p.Omega * p.alpha).cwiseAbs().maxCoeff(),
                                        (d.beta * d.Theta * M).cwiseAbs().maxCoeff());
    rec.add("theta M = -A omega (eqs. (82), (85))", "dual-vs-primal",
            relative(d.theta * M, -(A * p.omega), theta_scale), s.t);
    rec.add("alpha + beta = I (eq. (29))", "identity", residual(p.alpha + p.beta - I, 1.0), s.t);
  }
}

// ---- The probe comparison (large models) -----------------------------------------------------
// No n × n matrix: the projections are applied to kProbes seeded vectors X (n × kProbes) instead
// of being formed, the dual form through the chart engine's sparse LU (F, n × n_a), the primal
// form through G = EᵀAE's sparse LDLᵀ; both are the right-hand sides simulate integrates
// (dynamics.hpp). Two matrices agree when they agree on random vectors, up to a null set of them.
constexpr int kProbes = 4;

// Largest Euclidean norm of X's columns.
double column_norm(const MatX& X) { return X.colwise().norm().maxCoeff(); }

// The operators of one state, applied to vectors.
class ProbeState {
 public:
  ProbeState(const Model& model, detail::Dynamics& dyn) : model_(model), dyn_(dyn) {}

  // The dual form at (t, q, u) in a chart chosen there (ChartEngine::select); false (message
  // set) when no chart of the branch's rank is regular there.
  bool evaluate_dual(double t, const VecX& q, const VecX& u, std::string& message) {
    dyn_.state_.t = t;
    dyn_.state_.q = q;
    dyn_.state_.u = u;
    dyn_.free_system();
    compute_constraint_jacobian(model_, q, dyn_.ws_.constraints.Et);
    if (!dyn_.cs_.select(dyn_.ws_.constraints.Et, dyn_.ws_.free.A_diag) ||
        !dyn_.factor_chart(dyn_.ws_.constraints.Et)) {
      message = "the dual form is singular at t = " + detail::time_text(model_, t);
      return false;
    }
    dyn_.chart_ready_ = false;
    VecX v(dyn_.na_);
    for (int k = 0; k < dyn_.na_; ++k)
      v(k) = u(dyn_.cs_.chart().independent[static_cast<size_t>(k)]);
    try {
      dyn_.evaluate_dual(t, q, v);  // u = F v, H, v̇, u̇ = F v̇ + Ḟ v
    } catch (const detail::SingularEvaluation& e) {
      message = e.message;
      return false;
    }
    u_ = dyn_.state_.u;
    udot_ = dyn_.udot_;
    Q_ = dyn_.ws_.free.Q;
    R_ = mass(udot_) - Q_;  // R = M u̇ + Ṁ u − Q̂ = E λ
    if (!dyn_.ws_.free.constant_mass) R_.noalias() += dyn_.ws_.free.Mdot * u_;
    lambda_ = VecX::Zero(model_.nc);  // on the chart's rows: E λ = R (unique when not redundant)
    dyn_.solve_transposed(R_, lambda_);
    return true;
  }

  // The primal form at the same state, p = M u: G = EᵀAE factorised (sparse LDLᵀ when large).
  bool evaluate_primal(std::string& message) {
    try {
      dyn_.evaluate_primal(dyn_.state_.t, dyn_.state_.q, mass(u_));  // (L3): λ, ṗ
    } catch (const detail::SingularEvaluation& e) {
      message = e.message;
      return false;
    }
    lambda_primal_ = dyn_.lambda_;
    pdot_primal_ = dyn_.pdot_;  // Q̂ + E λ
    return true;
  }

  // ---- Dual operators (F, H of the chart)
  MatX alpha_dual(const MatX& X) const {  // eq. (70): α X = F H⁻¹ Fᵀ M X
    return dyn_.F_ * dyn_.H_llt_.solve(dyn_.MF_.transpose() * X);
  }
  MatX psi_dual(const MatX& X) const {  // eq. (69): ψ X = F H⁻¹ Fᵀ X
    return dyn_.F_ * dyn_.H_llt_.solve(dyn_.F_.transpose() * X);
  }
  MatX alpha_dual_transposed(const MatX& Y) const {  // αᵀ Y = M F H⁻¹ Fᵀ Y
    return dyn_.MF_ * dyn_.H_llt_.solve(dyn_.F_.transpose() * Y);
  }
  // ---- Primal operators (G = EᵀAE factorised)
  MatX beta_primal(const MatX& X) {  // eq. (44): β X = A E G⁻¹ Eᵀ X
    MatX out(X.rows(), X.cols());
    for (Eigen::Index j = 0; j < X.cols(); ++j) out.col(j) = inverse_mass(E_G_inv_Et(X.col(j)));
    return out;
  }
  VecX beta_primal_transposed(const VecX& y) {  // eq. (43), (44): βᵀ y = E G⁻¹ Eᵀ A y
    return E_G_inv_Et(inverse_mass(y));
  }
  VecX Omega_u() {  // eq. (78): Ω u = E G⁻¹ Dᵀ u, at the state's own u (Dᵀ u from its stage)
    VecX g(model_.nc);
    dyn_.solve_G(dyn_.ws_.constraints.Dtu, g);
    return Et().transpose() * g;
  }

  [[nodiscard]] VecX mass(const VecX& x) const { return dyn_.mass_times(x); }
  [[nodiscard]] VecX inverse_mass(const VecX& x) const {
    if (dyn_.ws_.free.diagonal_mass) return dyn_.ws_.free.A_diag.cwiseProduct(x);
    return dyn_.ws_.free.A * x;
  }
  [[nodiscard]] const SparseEt::Matrix& Et() const { return dyn_.ws_.constraints.Et.matrix(); }
  [[nodiscard]] const MatX& F() const { return dyn_.F_; }

  VecX u_, udot_, Q_, R_, lambda_, lambda_primal_, pdot_primal_;

 private:
  VecX E_G_inv_Et(const VecX& x) {  // E G⁻¹ Eᵀ x (eq. (43): π x)
    const VecX b = Et() * x;
    VecX g(model_.nc);
    dyn_.solve_G(b, g);
    return Et().transpose() * g;
  }
  const Model& model_;
  detail::Dynamics& dyn_;
};

void compare_probes(const Model& model, const SimulateResult& motion, const Mobility& mob,
                    const CrosscheckOptions& options, CrosscheckResult& result, Recorder& rec,
                    StateMonitor& monitor) {
  const bool redundant = mob.rank < model.nc;
  SimulateOptions so;  // the right-hand sides as simulate evaluates them, reactions included
  detail::Dynamics dyn(model, mob.rank, so);
  ProbeState ps(model, dyn);
  std::mt19937 rng(options.seed + 1);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  MatX X(model.n, kProbes);
  for (Eigen::Index k = 0; k < X.size(); ++k) X.data()[k] = uni(rng);
  const double xS = X.cwiseAbs().maxCoeff();
  for (const SimulationSample& s : motion.samples) {
    if (monitor.stop_before(static_cast<size_t>(result.samples), motion.samples.size(), result))
      return;
    ++result.samples;
    std::string why;
    if (!ps.evaluate_dual(s.t, s.q, s.u, why)) {
      result.message = why;
      continue;
    }
    // Dual form and its identities, on the probes.
    const MatX aX = ps.alpha_dual(X);
    const MatX bX = X - aX;                                          // eq. (70): β = I − α
    const double aS = std::max(1.0, aX.cwiseAbs().maxCoeff() / xS);  // ~ max |α_ij|
    rec.add("alpha^2 = alpha (eq. (65))", "identity", residual(ps.alpha_dual(aX) - aX, aS * xS),
            s.t);
    const double eS = std::max(ps.Et().coeffs().cwiseAbs().maxCoeff(), 1e-300);
    rec.add("E^T alpha = 0 (eq. (30))", "identity", residual(ps.Et() * aX, eS * aS * xS), s.t);
    MatX MbX(model.n, kProbes);
    for (int k = 0; k < kProbes; ++k) MbX.col(k) = ps.mass(bX.col(k));
    const MatX S = X.transpose() * MbX;  // xᵢᵀ M β xⱼ
    rec.add("M beta symmetric (eq. (35))", "identity",
            residual(S - S.transpose(), column_norm(MbX) * column_norm(X)), s.t);
    rec.add("alpha^T M beta = 0 (eq. (34))", "identity",
            residual(aX.transpose() * MbX, column_norm(aX) * column_norm(MbX)), s.t);
    MatX AX(model.n, kProbes);
    for (int k = 0; k < kProbes; ++k) AX.col(k) = ps.inverse_mass(X.col(k));
    rec.add("psi = alpha A (eq. (69))", "identity",
            relative(ps.psi_dual(X), ps.alpha_dual(AX), 1e-300), s.t);
    const double Qs = ps.Q_.cwiseAbs().maxCoeff();
    rec.add("F^T R = 0 (eq. (64))", "identity",
            residual(ps.F().transpose() * ps.R_,
                     ps.F().cwiseAbs().maxCoeff() * std::max(ps.R_.cwiseAbs().maxCoeff(), Qs)),
            s.t);
    rec.add("E lambda = R (dual reactions)", "identity",
            relative(ps.Et().transpose() * ps.lambda_, ps.R_, Qs), s.t);
    if (redundant) continue;

    // Primal form, compared with the dual.
    if (!ps.evaluate_primal(why)) {
      rec.add("primal form evaluable (G regular)", "dual-vs-primal", {1.0, 1.0}, s.t);
      continue;
    }
    result.primal_checked = true;
    const MatX bXp = ps.beta_primal(X);
    rec.add("alpha dual vs primal (eq. (70) vs (44))", "dual-vs-primal",
            relative(aX, X - bXp, 1e-300), s.t);  // eq. (44): α = I − β
    rec.add("beta dual vs primal (eq. (70) vs (44))", "dual-vs-primal", relative(bX, bXp, 1e-300),
            s.t);
    // Eq. (99), ṗ = αᵀ Q̂ − Ω u + βᵀ Ṁ u, and eq. (91), R = −βᵀ Q̂ − ω u + βᵀ Ṁ α u, with ω u =
    // Ω α u: its other term αᵀ Ωᵀ u = αᵀ D G⁻¹ Eᵀ u vanishes with Eᵀ u (eq. (102); J below
    // checks Eᵀ u = 0). Ωᵀ itself would need D as an operator, which no stage forms.
    const VecX& u = ps.u_;
    const VecX Omega_u = ps.Omega_u();
    VecX Mdot_u = VecX::Zero(model.n);
    if (!dyn.ws_.free.constant_mass) Mdot_u = dyn.ws_.free.Mdot * u;
    const VecX bTQ = ps.beta_primal_transposed(ps.Q_);
    const VecX bTMdot_u = ps.beta_primal_transposed(Mdot_u);  // α u = u on the motion
    const VecX pdot = ps.Q_ - bTQ - Omega_u + bTMdot_u;       // eq. (99)
    const VecX R91 = -bTQ - Omega_u + bTMdot_u;               // eq. (91)
    const VecX Mudot = ps.mass(ps.udot_);
    const double qscale = std::max(Qs, Mudot.cwiseAbs().maxCoeff());
    rec.add("acceleration dual vs primal (eq. (99))", "dual-vs-primal",
            relative(Mudot, pdot - Mdot_u, qscale), s.t);
    rec.add("reaction dual vs Theorem 5 (eq. (91))", "dual-vs-primal", relative(ps.R_, R91, qscale),
            s.t);
    rec.add("reaction eq. (91) vs (L3): R = E lambda", "identity",
            relative(R91, ps.pdot_primal_ - ps.Q_, qscale), s.t);
    rec.add("multipliers dual vs primal", "dual-vs-primal",
            relative(ps.lambda_, ps.lambda_primal_, qscale / eS),  // λ of E λ's size
            s.t);
    const double uS = std::max(u.cwiseAbs().maxCoeff(), 1e-300);
    const VecX aT_Omega_u = ps.alpha_dual_transposed(Omega_u);
    rec.add("Omega^T alpha = 0 (eq. (103)), along u", "identity",
            residual(aT_Omega_u, std::max(Omega_u.cwiseAbs().maxCoeff(), 1e-300) * aS), s.t);
    rec.add("J = E^T A p = 0 (eq. (105))", "identity", residual(ps.Et() * u, eS * uS), s.t);
  }
}

}  // namespace

CrosscheckResult run_crosscheck(const Model& model, const CrosscheckOptions& options) {
  CrosscheckResult result;
  result.tolerance = options.tolerance;
  result.nc = model.nc;
  result.method =
      options.method == CrosscheckMethod::automatic
          ? (model.n >= kCrosscheckProbesFrom ? CrosscheckMethod::probes : CrosscheckMethod::dense)
          : options.method;
  // The dense comparison's two Workspaces: a model too large for them is refused before the
  // motion is simulated, not after.
  if (result.method == CrosscheckMethod::dense) {
    try {
      check_dense_workspace_size(model);
    } catch (const ModelTooLarge& e) {
      throw ModelTooLarge(
          std::string(e.what()) + "; the probe comparison (--method probes, the default from " +
          std::to_string(kCrosscheckProbesFrom) + " velocity components) needs no dense matrix");
    }
  }

  // 1. The motion: dual form from the design position, seeded initial velocity guess.
  const auto start = std::chrono::steady_clock::now();
  const SimulateResult motion = simulate_motion(model, options);
  if (motion.status == SimulateStatus::stopped) result.stop = motion.stop;
  if (motion.samples.empty()) {
    result.message = "the motion could not be simulated: " + motion.message;
    return result;
  }
  if (result.stop == StopReason::time_limit || result.stop == StopReason::interrupted) {
    result.message = "the motion " + motion.message + "; no state compared";
    return result;
  }
  if (motion.status != SimulateStatus::completed)
    result.message = "the motion stopped early (" + motion.message + "); checked the states before";

  // 2. Rank on the branch (at the first state). Without joints or without a degree of freedom
  //    there is no projection to compare (α = I, or no motion at all): said, not computed.
  const Mobility mob = compute_mobility(model, motion.samples.front().q);
  result.rank = mob.rank;
  if (model.nc == 0 || mob.dof == 0) {
    result.message = model.nc == 0 ? "the mechanism has no joints: the dual and the primal form "
                                     "are both the free system, there is nothing to cross-check"
                                   : "the mechanism has no degree of freedom (DOF 0): it cannot "
                                     "move, there is no motion to cross-check";
    return result;
  }
  if (mob.rank < model.nc)
    result.primal_skipped_reason = redundancy_reason(
        mob, model.nc,
        result.method == CrosscheckMethod::dense ? "minimum-norm λ" : "λ on the chart's rows");

  // 3. The two forms at every state.
  Recorder rec(options.tolerance);
  StateMonitor monitor(
      options.control,
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  if (result.method == CrosscheckMethod::dense)
    compare_dense(model, motion, mob, result, rec, monitor);
  else
    compare_probes(model, motion, mob, options, result, rec, monitor);
  result.items = rec.items_;
  result.pass = result.stop == StopReason::none && !result.items.empty();
  for (const auto& it : result.items) result.pass = result.pass && it.pass;
  if (!result.pass && result.message.empty()) result.message = "a difference exceeds the tolerance";
  return result;
}

const char* to_string(CrosscheckMethod m) {
  switch (m) {
    case CrosscheckMethod::automatic:
      return "auto";
    case CrosscheckMethod::dense:
      return "dense";
    case CrosscheckMethod::probes:
      return "probes";
  }
  return "?";
}

bool parse_crosscheck_method(const std::string& name, CrosscheckMethod& out) {
  for (const CrosscheckMethod m :
       {CrosscheckMethod::automatic, CrosscheckMethod::dense, CrosscheckMethod::probes})
    if (name == to_string(m)) {
      out = m;
      return true;
    }
  return false;
}

}  // namespace orthomech
