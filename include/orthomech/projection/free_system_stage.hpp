#pragma once
// Stage 1 of the Workspace (paper §2): the free system at a state, shared by both forms (the
// primal projections, the dual basis and the chart scaling) and by every command.
#include "orthomech/model/state.hpp"
#include "orthomech/projection/workspace.hpp"

namespace orthomech {

// Free-system quantities into ws.free: M (eq. (4)) and A = M⁻¹ (eq. (6)) (once, if constant), their
// diagonals, Ṁ along u, and the applied forces Q̂ (eq. (17)). Allocation-free.
void compute_free_system(const Model& model, const State& state, Workspace& ws);
// The same into a free-system stage alone (a command that needs no projection matrices:
// simulate).
void compute_free_system(const Model& model, const State& state, FreeSystemWorkspace& fs);

}  // namespace orthomech
