#pragma once
// Primal (E-based) form, the cross-check (paper §3–4, §6; docs/design.md §4).
#include "orthomech/model/state.hpp"
#include "orthomech/projection/workspace.hpp"

namespace orthomech {

// G, π, α, β, Ω, ω at the state (eq. (42), eq. (43), eq. (44), eq. (78), eq. (79)). Needs
// compute_free_system and compute_constraints first. With redundant constraints G is singular:
// ws.primal.status says so and the matrices are left untouched. Allocation-free.
ProjectionStatus compute_primal(const Model& model, const State& state, Workspace& ws);

// Everything in order: free system (free_system_stage.hpp), constraints, primal.
ProjectionStatus evaluate_primal(const Model& model, const State& state, Workspace& ws);

}  // namespace orthomech
