#pragma once
// Private: resting contacts on end stops (issue 49 item 3). A joint that comes to rest pressed
// against its end stop (impacts at ever shorter intervals, dynamics/events.hpp) is held there as
// a constraint: its coordinate x keeps ẍ = 0 while the contact force that this takes pushes,
// and is released (an event) when that force would have to pull.
//
// For held stops i (joint coordinate x_i with gradient d_i, side σ_i = +1 at the lower stop, −1
// at the upper) the contact forces μ_i ≥ 0 act along σ_i d_iᵀ (a generalised force: along the
// joint's coordinate, away from the stop) and make each held coordinate's acceleration zero,
//   σ_i (d_i u̇ + ḋ_i u) = 0.
// Dual form: u̇ = F v̇ + Ḟ v and H v̇ = ψ + C μ with C = [σ_i Fᵀ d_iᵀ]:
//   (Cᵀ H⁻¹ C) μ = −(Cᵀ v̇₀ + a),  a_i = σ_i (d_i Ḟ v + ḋ_i u),  v̇ = v̇₀ + H⁻¹ C μ.
// Primal form (ṗ = Q̂ + E λ, λ from G = EᵀAE): a unit μ_i changes ṗ by
// Δṗ_i = σ_i (d_iᵀ − E G⁻¹ Eᵀ A d_iᵀ), u̇ by A Δṗ_i, so S μ = −g̈₀ with S_ki = σ_k d_k A Δṗ_i and
// g̈₀ the held accelerations without the forces. Both add Σ σ_i μ_i d_iᵀ to Q̂ (so the reactions
// of the samples are those with the contact) and, in the primal form, its share to λ.
// The forces do no work while the stops are held (σ_i d_i u = 0): the energy balance is that of
// the frictionless motion. As many held stops as degrees of freedom lock the mechanism: at rest
// its rates' derivative is then set to exactly zero (rounding would otherwise switch loads held
// on the sign of a rate).
#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <vector>

#include "dynamics.hpp"
#include "events.hpp"

namespace orthomech::detail {

class StopContacts {
 public:
  explicit StopContacts(const Model& model);
  // After dyn.evaluate_dual / evaluate_primal at a state: the held stops' contact forces into
  // `mu` (in `held` order; N or N·m, along the coordinate away from the stop) and the state's
  // rate `rate` (dual: v̇, primal: ṗ) with them; dyn's Q̂, u̇ (dual) and λ (primal) updated.
  void apply(Dynamics& dyn, bool primal, const std::vector<StopHit>& held, Eigen::Ref<VecX> rate,
             std::vector<double>& mu);

 private:
  void gradients(Dynamics& dyn, const std::vector<StopHit>& held);
  void dual(Dynamics& dyn, Eigen::Ref<VecX> rate);
  void primal(Dynamics& dyn, Eigen::Ref<VecX> rate);

  const Model& model_;
  MatX D_;           // n × h: the held coordinates' gradients d_iᵀ
  VecX ddot_u_, a_;  // h: ḋ_i u, the held accelerations' rate terms
  VecX sigma_;       // h: the sides
  MatX C_, W_, S_;   // dual: na × h, H⁻¹C, CᵀH⁻¹C; primal: Δṗ (n × h), S
  VecX g_, mu_, d_, z_, w_;
  // S's and Cᵀ's factorisations (held on to: the right-hand side evaluates them at every stage
  // while a stop is held).
  Eigen::LDLT<MatX> S_ldlt_;
  Eigen::PartialPivLU<MatX> lu_;
};

}  // namespace orthomech::detail
