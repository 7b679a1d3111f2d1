#pragma once
// Measures and inputs: scalar functions s(q) of the position, with their Jacobian row
// d = ∂s/∂u (so ṡ = d u) and convective term ḋ u (so s̈ = d u̇ + ḋ u). Drivers use the same
// functions for the input (docs/design.md §6).
#include "orthomech/model/free_system.hpp"
#include "orthomech/model/model.hpp"

namespace orthomech {

struct ScalarKinematics {
  double value = 0.0;   // s(q)
  double rate = 0.0;    // ṡ = d u   (0 when u is null)
  double ddot_u = 0.0;  // ḋ u       (0 when u is null)
};

// s, ṡ and ḋu of the position measure underlying `kind`; if d is non-null it receives d (size n).
ScalarKinematics compute_scalar(const Model& model, const MeasureKind& kind, const VecX& q,
                                const VecX* u, Eigen::Ref<VecX> d);
ScalarKinematics compute_scalar(const Model& model, const MeasureKind& kind, const VecX& q,
                                const VecX* u);

// Value of a measure (its derivative order applied). udot may be null for derivative < 2.
// Allocation-free.
[[nodiscard]] double evaluate_measure(const Model& model, const Measure& m, const VecX& q,
                                      const VecX* u, const VecX* udot);
// The same with the bodies' rotations at q already computed (no sin/cos).
[[nodiscard]] double evaluate_measure(const Model& model, const Measure& m, const VecX& q,
                                      const VecX* u, const VecX* udot, const BodyPoses& rotations);

}  // namespace orthomech
