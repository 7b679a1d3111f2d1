#include "orthomech/dynamics/crosscheck.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include "orthomech/analysis/mobility.hpp"
#include "orthomech/dynamics/equations.hpp"
#include "orthomech/dynamics/simulate.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/projection/dual.hpp"
#include "orthomech/projection/primal.hpp"
#include "orthomech/projection/workspace.hpp"

namespace orthomech {

namespace {

// ‖a − b‖∞ / max(‖a‖∞, ‖b‖∞, floor): relative difference with a floor for quantities that
// vanish (e.g. accelerations at rest); floor = 1e-300 gives the pure relative value.
// The scale is at least 1e-300, so that two zeros (a mechanism at rest without loads) compare
// as 0, not 0/0.
double relative(const MatX& a, const MatX& b, double floor) {
  if (a.size() == 0) return 0.0;
  const double scale = std::max({a.cwiseAbs().maxCoeff(), b.cwiseAbs().maxCoeff(), floor, 1e-300});
  return (a - b).cwiseAbs().maxCoeff() / scale;
}
// ‖x‖∞ / scale for an identity x = 0 whose terms are of size `scale`.
double residual(const MatX& x, double scale) {
  return x.size() ? x.cwiseAbs().maxCoeff() / std::max(scale, 1e-300) : 0.0;
}

class Recorder {
 public:
  explicit Recorder(double tol) : tol_(tol) {}
  void add(const std::string& name, const std::string& kind, double value, double t) {
    for (auto& it : items_) {
      if (it.name == name) {
        if (!(value <= it.max_relative)) it.max_relative = value, it.at_t = t;  // NaN counts
        it.pass = it.max_relative <= tol_;
        return;
      }
    }
    items_.push_back({name, kind, value, t, value <= tol_});
  }
  std::vector<CrosscheckItem> items_;

 private:
  double tol_;
};

}  // namespace

CrosscheckResult run_crosscheck(const Model& model, const CrosscheckOptions& options) {
  CrosscheckResult result;
  result.tolerance = options.tolerance;
  result.nc = model.nc;
  const int n = model.n;
  // Its two dense Workspaces: a model too large for them is refused before the motion is
  // simulated, not after.
  check_dense_workspace_size(model);

  // 1. The motion: dual form from the design position, seeded initial velocity guess.
  SimulateOptions so;
  so.t_end = options.t_end;
  so.rtol = 1e-9;
  so.atol = 1e-11;
  so.dt_out = options.t_end / std::max(1, options.samples - 1);
  so.reactions = false;
  so.use_file_rates = false;  // the seeded guess below, not the file's initial rates
  std::mt19937 rng(options.seed);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  so.initial_u = VecX(n);
  for (int k = 0; k < n; ++k) so.initial_u(k) = uni(rng);
  const SimulateResult motion = simulate(model, so);
  if (motion.samples.empty()) {
    result.message = "the motion could not be simulated: " + motion.message;
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
  Workspace wd(model, mob.rank), wp(model, mob.rank);
  DynamicsPoint dd(model), dp(model);
  Recorder rec(options.tolerance);
  const bool redundant = mob.rank < model.nc;
  if (redundant) {
    result.primal_skipped_reason = "E has rank " + std::to_string(mob.rank) +
                                   " < n_c = " + std::to_string(model.nc) + " (redundant: ";
    for (size_t k = 0; k < mob.redundant.size(); ++k)
      result.primal_skipped_reason += (k ? "; " : "") + mob.redundant[k];
    result.primal_skipped_reason +=
        "), so G = EᵀAE (eq. (42)) is singular and the primal form is undefined; the reactions "
        "are not unique (minimum-norm λ)";
  }
  const MatX I = MatX::Identity(n, n);

  for (const SimulationSample& s : motion.samples) {
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
      rec.add("primal form evaluable (G regular)", "dual-vs-primal", 1.0, s.t);
      continue;
    }
    result.primal_checked = true;
    const auto& p = wp.primal;
    rec.add("alpha dual vs primal (eq. (70) vs (44))", "dual-vs-primal",
            relative(d.alpha, p.alpha, 1e-300), s.t);
    rec.add("beta dual vs primal (eq. (70) vs (44))", "dual-vs-primal",
            relative(d.beta, p.beta, 1e-300), s.t);
    const double qscale =
        std::max(wd.free.Q.cwiseAbs().maxCoeff(), (M * dd.udot).cwiseAbs().maxCoeff());
    rec.add("acceleration dual vs primal (eq. (99))", "dual-vs-primal",
            relative(M * dd.udot, M * dp.udot, qscale), s.t);
    rec.add("reaction dual vs Theorem 5 (eq. (91))", "dual-vs-primal", relative(dd.R, dp.R, qscale),
            s.t);
    rec.add("reaction eq. (91) vs eq. (99): R = pdot - Q", "identity",
            relative(dp.R, dp.pdot - wp.free.Q, qscale), s.t);
    rec.add(
        "multipliers dual vs primal", "dual-vs-primal",
        relative(dd.lambda, dp.lambda, std::max(1e-300, 1e-12 * dp.lambda.cwiseAbs().maxCoeff())),
        s.t);
    const double uS = std::max(st.u.cwiseAbs().maxCoeff(), 1e-300);
    rec.add("omega u = Omega u (eq. (102))", "identity",
            relative(p.omega * st.u, p.Omega * st.u, p.Omega.cwiseAbs().maxCoeff() * uS), s.t);
    rec.add("Omega^T alpha = 0 (eq. (103))", "identity",
            residual(p.Omega.transpose() * p.alpha, p.Omega.cwiseAbs().maxCoeff() * aS), s.t);
    rec.add("J = E^T A p = 0 (eq. (105))", "identity",
            residual(dp.J, Et.cwiseAbs().maxCoeff() * uS), s.t);
    // α̇ = −β̇ from eq. (85) and from eq. (82): θ M = −A ω, also when Ṁ ≠ 0 (their Ṁ terms,
    // −Ȧ_αβ M and A Ṁ_αβ, are both A αᵀ Ṁ β since ψ = A αᵀ).
    rec.add("theta M = -A omega (eqs. (82), (85))", "dual-vs-primal",
            relative(d.theta * M, -(A * p.omega), 1e-300), s.t);
    rec.add("alpha + beta = I (eq. (29))", "identity", residual(p.alpha + p.beta - I, 1.0), s.t);
  }
  (void)I;
  result.items = rec.items_;
  result.pass = !result.items.empty();
  for (const auto& it : result.items) result.pass = result.pass && it.pass;
  if (!result.pass && result.message.empty()) result.message = "a difference exceeds the tolerance";
  return result;
}

}  // namespace orthomech
