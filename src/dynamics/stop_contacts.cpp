#include "stop_contacts.hpp"

#include <Eigen/LU>

namespace orthomech::detail {

StopContacts::StopContacts(const Model& model) : model_(model), d_(VecX::Zero(model.n)) {}

void StopContacts::apply(Dynamics& dyn, bool primal_form, const std::vector<StopHit>& held,
                         Eigen::Ref<VecX> rate, std::vector<double>& mu) {
  const auto h = static_cast<Eigen::Index>(held.size());
  mu.assign(held.size(), 0.0);
  if (h == 0) return;
  gradients(dyn, held);
  if (primal_form)
    primal(dyn, rate);
  else
    dual(dyn, rate);
  // The contact forces as applied loads: the samples' reactions are those with them.
  for (Eigen::Index i = 0; i < h; ++i) {
    dyn.ws_.free.Q.noalias() += (sigma_(i) * mu_(i)) * D_.col(i);
    mu[static_cast<size_t>(i)] = mu_(i);
  }
}

// Step 1: each held coordinate's gradient d_i and rate term ḋ_i u at the evaluated state.
void StopContacts::gradients(Dynamics& dyn, const std::vector<StopHit>& held) {
  const auto h = static_cast<Eigen::Index>(held.size());
  d_.resize(model_.n);
  D_.resize(model_.n, h);
  ddot_u_.resize(h);
  sigma_.resize(h);
  for (Eigen::Index i = 0; i < h; ++i) {
    const StopHit& s = held[static_cast<size_t>(i)];
    const ScalarKinematics sk =
        compute_scalar(model_, JointCoordinate{s.joint}, dyn.state_.q, &dyn.state_.u, d_);
    D_.col(i) = d_;
    ddot_u_(i) = sk.ddot_u;
    sigma_(i) = s.side;
  }
}

// Dual form: (Cᵀ H⁻¹ C) μ = −(Cᵀ v̇₀ + a), v̇ = v̇₀ + H⁻¹ C μ.
void StopContacts::dual(Dynamics& dyn, Eigen::Ref<VecX> rate) {
  const Eigen::Index h = D_.cols();
  C_.noalias() = dyn.F_.transpose() * D_;
  a_.noalias() = D_.transpose() * dyn.Fdv_;
  a_ += ddot_u_;
  for (Eigen::Index i = 0; i < h; ++i) {
    C_.col(i) *= sigma_(i);
    a_(i) *= sigma_(i);
  }
  W_ = dyn.H_llt_.solve(C_);
  S_.noalias() = C_.transpose() * W_;
  g_.noalias() = C_.transpose() * dyn.vdot_;
  g_ += a_;
  S_ldlt_.compute(S_);
  mu_ = S_ldlt_.solve(-g_);
  if (h == dyn.na_) {  // locked: v̇ = −C⁻ᵀ a (exactly 0 at rest)
    lu_.compute(C_.transpose());
    dyn.vdot_ = lu_.solve(-a_);
  } else {
    dyn.vdot_.noalias() += W_ * mu_;
  }
  dyn.udot_ = dyn.Fdv_;
  dyn.udot_.noalias() += dyn.F_ * dyn.vdot_;
  rate = dyn.vdot_;
}

// Primal form: ṗ = ṗ₀ + Σ Δṗ_i μ_i with Δṗ_i = σ_i (d_iᵀ − E G⁻¹ Eᵀ A d_iᵀ).
void StopContacts::primal(Dynamics& dyn, Eigen::Ref<VecX> rate) {
  const Eigen::Index h = D_.cols(), n = model_.n;
  const auto& fs = dyn.ws_.free;
  const SparseEt::Matrix& Et = dyn.ws_.constraints.Et.matrix();
  auto times_A = [&](const VecX& x, VecX& out) {
    if (fs.diagonal_mass)
      out = fs.A_diag.cwiseProduct(x);
    else
      out.noalias() = fs.A * x;
  };
  // The held accelerations without the forces: u̇₀ = A (ṗ₀ − Ṁ u).
  z_ = dyn.pdot_;  // ṗ₀ − Ṁ u
  if (!fs.constant_mass) z_.noalias() -= fs.Mdot * dyn.state_.u;
  times_A(z_, w_);
  g_.noalias() = D_.transpose() * w_;
  g_ += ddot_u_;
  g_.array() *= sigma_.array();
  // Each unit force's change of ṗ (C_) and of λ (W_), and S.
  C_.resize(n, h);
  W_.resize(model_.nc, h);
  S_.resize(h, h);
  for (Eigen::Index i = 0; i < h; ++i) {
    times_A(D_.col(i), w_);
    d_.noalias() = Et * w_;  // (d_: scratch here)
    dyn.solve_G(d_, z_);
    C_.col(i) = sigma_(i) * (D_.col(i) - Et.transpose() * z_);
    W_.col(i) = -sigma_(i) * z_;
  }
  for (Eigen::Index i = 0; i < h; ++i) {
    times_A(C_.col(i), w_);
    for (Eigen::Index k = 0; k < h; ++k) S_(k, i) = sigma_(k) * D_.col(k).dot(w_);
  }
  lu_.compute(S_);
  mu_ = lu_.solve(-g_);
  const bool at_rest = dyn.state_.u.isZero(0.0);
  if (h == dyn.na_ && at_rest) {  // locked at rest: ṗ = M u̇ = 0 exactly
    dyn.pdot_.setZero();
  } else {
    dyn.pdot_.noalias() += C_ * mu_;
  }
  if (dyn.lambda_.size() == W_.rows()) dyn.lambda_.noalias() += W_ * mu_;
  rate = dyn.pdot_;
}

}  // namespace orthomech::detail
