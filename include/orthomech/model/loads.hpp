#pragma once
// Loads: generalized forces Q(q, u, t) of the free system, eq. (8): δW = Qᵀ δq̃.
// For planar bodies Q̂ = Q (no nonholonomic term, eq. (16), and ∂T/∂q = 0, eq. (11)); spatial
// bodies add the velocity term of eq. (16), −ω × Jω in their rotation rows (docs/spatial.md (S5)),
// which does no work (ωᵀ(ω × Jω) = 0), kept apart from the loads (add_velocity_terms).
#include "orthomech/model/model.hpp"
#include "orthomech/model/state.hpp"

namespace orthomech {

// Q̂ (size n), eq. (15), eq. (16), eq. (17): the sum of every load in the model. Allocation-free.
void compute_applied_forces(const Model& model, const State& state, VecX& Q);
// The velocity term of eq. (16) of every spatial body, −C p u = (0, −ω × Jω) (accumulated).
void add_velocity_terms(const Model& model, const State& state, VecX& Q);
// Q of one load (accumulated into Q).
void add_load(const Model& model, const Load& load, const State& state, VecX& Q);
// Potential energy of the conservative loads (gravity, springs); 0 for the others.
[[nodiscard]] double potential_energy(const Model& model, const VecX& q);
// Power dissipated by dampers (≥ 0).
[[nodiscard]] double dissipated_power(const Model& model, const State& state);
// Whether a load acts at this state: its `active_while` condition on a measure's velocity, or,
// when the state holds load_on (simulate's events), what that says (load must then be an element
// of model.loads).
[[nodiscard]] bool load_active(const Model& model, const Load& load, const State& state);
// Factor of a table at the current position (1 when empty).
[[nodiscard]] double table_factor(const Model& model, const Table& table, const VecX& q);

}  // namespace orthomech
