#pragma once
// Dual (F-based) form, the centre of the tool (paper §5–6; docs/design.md §4).
#include "orthomech/model/state.hpp"
#include "orthomech/projection/workspace.hpp"

namespace orthomech {

// F in the current chart (switching charts when it degrades), H, ψ, α, β, Ḟ, Θ, θ
// (eq. (68), eq. (69), eq. (70), eq. (83), eq. (84)). Needs compute_free_system and
// compute_constraints first. Allocation-free while no chart switch happens.
ProjectionStatus compute_dual(const Model& model, const State& state, Workspace& ws);
// Only the first steps of compute_dual: the chart (switching when it degrades) and F. Needs
// ws.constraints.Et at state.q and the free system's scaling A (ws.free.A_diag, A_sqrt).
ProjectionStatus compute_basis(const Model& model, const State& state, Workspace& ws);
// The same at Eᵀ on its structural pattern (Et at state.q, a SparseEt of the model): what a
// Workspace without the constraint matrices (WorkspaceStages::constraint_matrices) uses.
ProjectionStatus compute_basis(const Model& model, const State& state, Workspace& ws,
                               const SparseEt& Et);

// Everything in order: free system, constraints, dual.
ProjectionStatus evaluate_dual(const Model& model, const State& state, Workspace& ws);

// LU of the current chart's dependent block at ws.constraints.Et (selecting a chart first if
// none); returns its quality. Used by the position corrector.
double refactor_chart(Workspace& ws);
// x = the solution of E_RDᵀ x_D = b_R with x_I = 0 (current chart, after refactor_chart).
// Sizes: b nc, x n. Allocation-free.
void solve_chart(Workspace& ws, const VecX& b, VecX& x);

// x (size r, chart row order) solving (E_RDᵀ)ᵀ x = b_D, the dependent components of b (size n):
// E λ = b on the dependent coordinates with λ on the chart's rows. Allocation-free.
void solve_chart_transposed(Workspace& ws, const VecX& b, Eigen::Ref<VecX> x);
// Newton in the current chart of ws (a chart chosen at q first if none): the independent
// coordinates stay fixed, the dependent ones move, Δq_D = −(E_RDᵀ)⁻¹ f_R
// (ChartEngine::correct_positions, the one chart corrector). Allocation-free once the free
// system is computed.
ChartCorrectionResult correct_positions_in_chart(const Model& model, VecX& q, Workspace& ws,
                                                 const ChartCorrection& options = {});
// Forces a fresh chart choice at the current Eᵀ (e.g. at the start of an analysis).
void reset_chart(Workspace& ws);

// The one velocity projection: the admissible velocity closest to u₀ in the mass metric,
// u = α u₀ = F H⁻¹ Fᵀ M u₀ (eq. (70)), returned as its coefficients v (u = F v) from M F and the
// Cholesky factor of H = Fᵀ M F. Used by simulate (initial state, every step) and assemble.
[[nodiscard]] VecX project_velocity(const MatX& MF, const Eigen::LLT<MatX>& H_llt, const VecX& u0);

}  // namespace orthomech
