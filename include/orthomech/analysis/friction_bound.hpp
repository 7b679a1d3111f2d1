#pragma once
/// @file
/// The least friction a redundant mechanism can have (issue 49 item 2): where a pin's force is
/// statically indeterminate, so is its friction, and the drive with it. Over every admissible
/// split of the redundant reactions this finds the least dissipated power, and the drive there.
///
/// At a position of `cycle` the equation of motion [E d] (λ; τ) = b − G s (b = M u̇ + Ṁu − Q̂, G s
/// the friction loads, column j pin j's unit moment against its relative rotation ω_j) has the
/// solutions (λ; τ) = x* − K (s − s*) + Z α: K the minimum-norm solution of [E d] K = G, Z an
/// orthonormal basis of null([E d]) (r self-stresses), x*, s* the split `cycle` reports
/// (minimum-norm multipliers). For a split α ∈ ℝ^r the pins' moments are their friction,
/// s = μ r ‖λ(α, s)‖ (a fixed point, as in `cycle`); its dissipated power is
/// D(α) = Σ_j |ω_j| s_j(α), and the drive's power τ ṡ = uᵀb + D(α) grows with it. To first order
/// in μ, D(α) = Σ_j |ω_j| μ_j r_j ‖λ*_j + Z_j α‖, a sum of norms of affine functions: convex, one
/// minimum. D is minimised over α by NLopt (BOBYQA, or COBYLA for r = 1; derivative-free: D has
/// kinks where a pin's force passes through zero) in the box |α_i| ≤ 10 max|λ*|, from α = 0.
/// docs/theory.md "Joint friction"; the test checks the minimum against a global search over α.
#include <vector>

#include "orthomech/analysis/friction.hpp"
#include "orthomech/model/model.hpp"

namespace orthomech {

/// The least dissipation at one position of a driven sweep.
struct DissipationBound {
  bool solved = false;    // NLopt converged inside the box, the moments' fixed point settled
  int self_stresses = 0;  // r (0: the split is unique and so is its friction)
  double power = 0.0;     // D at the optimum, W
  double drive = 0.0;     // τ there (N·m or N): the drive at the least dissipation
  int evaluations = 0;    // of D
  VecX alpha;             // the optimum's split (N; the self-stresses' amounts)
  VecX lambda;            // the multipliers there
  VecX moment;            // s, per pin (N·m)
};

/// The least dissipation over the admissible splits at a position of `cycle` with driver joint
/// `driver_joint`: q, u the position and velocities, lambda and drive the split and drive it
/// reports (they fix b). Throws std::invalid_argument on sizes that do not fit the model.
[[nodiscard]] DissipationBound least_dissipation(const Model& model,
                                                 const std::vector<FrictionPin>& pins,
                                                 int driver_joint, const VecX& q, const VecX& u,
                                                 const VecX& lambda, double drive);

}  // namespace orthomech
