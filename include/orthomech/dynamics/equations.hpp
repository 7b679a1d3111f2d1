#pragma once
// Equations of motion of the constrained system at one state, in both forms (paper §7; design
// §4), with the dense matrices of the projection workspace. Used by `crosscheck` and by the
// tests as the reference for the lean integrators of simulate.
//
// Both give ṗ = M u̇ + Ṁ u = Q̂ + R with R = E λ the constraint reaction (non-working: Fᵀ R = 0,
// eq. (64)); sign convention of λ as in docs/notation.md.
#include "orthomech/model/state.hpp"
#include "orthomech/projection/workspace.hpp"

namespace orthomech {

struct DynamicsPoint {
  VecX udot;    // n: u̇
  VecX pdot;    // n: ṗ = M u̇ + Ṁ u
  VecX R;       // n: constraint reaction R = ṗ − Q̂ = E λ
  VecX lambda;  // nc: multipliers, E λ = R (minimum-norm when E is rank-deficient)
  VecX J;       // nc: J = Eᵀ A p, eq. (105) (primal; Eᵀ u for the dual)
  explicit DynamicsPoint(const Model& model)
      : udot(VecX::Zero(model.n)),
        pdot(VecX::Zero(model.n)),
        R(VecX::Zero(model.n)),
        lambda(VecX::Zero(model.nc)),
        J(VecX::Zero(model.nc)) {}
};

// Dual form at a state whose u is admissible (Eᵀ u = 0): with v = u_I (the chart's independent
// components, so u = F v), H v̇ = Fᵀ (Q̂ − Ṁ u − M Ḟ v) and u̇ = F v̇ + Ḟ v; then R = ṗ − Q̂.
// Evaluates the free system, the constraints and the dual projections (eq. (68), eq. (69),
// eq. (70), eq. (83), eq. (84)) into ws first. λ by a minimum-norm least-squares solve of E λ = R.
ProjectionStatus compute_dual_dynamics(const Model& model, const State& state, Workspace& ws,
                                       DynamicsPoint& out);

// Primal form, Theorem 7: ṗ = αᵀ Q̂ − Ω u + βᵀ Ṁ u (eq. (99)), u = A p (eq. (100)); the
// reaction from Theorem 5, R = −βᵀ Q̂ − ω u + Ṁ_βα u (eq. (91)); λ = G⁻¹ Eᵀ A R; J, eq. (105).
// Returns singular_G (and leaves out untouched) when G is singular.
ProjectionStatus compute_primal_dynamics(const Model& model, const State& state, Workspace& ws,
                                         DynamicsPoint& out);

// Minimum-norm solution of E λ = R (complete orthogonal decomposition of E). Allocates.
void compute_multipliers(const MatX& Et, const VecX& R, VecX& lambda);

}  // namespace orthomech
