#pragma once
/// @file
/// Coulomb friction in the pins of a driven planar mechanism (issue 49 item 2, first part).
///
/// A revolute joint with `friction: {coefficient: μ, radius: r}` carries the friction moment
///
///     T = μ r |F| sgn(ω₂ − ω₁)   against the relative rotation: −T on the second body, +T on the
///     first,
///
/// F the force the joint transmits (its two multipliers), ω₁, ω₂ its bodies' angular rates
/// (0 for the ground). The moment changes the forces it depends on, so at every position of a
/// sweep `compute_driven` (analysis/cycle.hpp) solves
///
///     E λ + d τ = M u̇ + Ṁu − Q̂ − Q_f(λ, u)
///
/// by fixed-point iteration from the frictionless λ until λ changes by less than
/// kFrictionTolerance of its size (at most kFrictionIterations; DrivenPoint::friction_iterations
/// is −1 when it does not converge: μ r large against the linkage's lever arms). At zero relative
/// rate the moment is taken as 0 (the stick case of a driven joint at a turning point: any moment
/// up to μ r |F| balances, and the rate is zero there for an instant only). Where the joint's force
/// is not determined (redundant constraints) neither is its friction: the value under the
/// minimum-norm multipliers is reported and flagged. docs/theory.md "Joint friction".
#include <vector>

#include "orthomech/model/model.hpp"

namespace orthomech {

/// A revolute joint with friction: its multipliers' first row, its bodies' angle entries of u
/// (−1: the ground) and μ, r.
struct FrictionPin {
  int joint = -1;
  int row = 0;
  int u_first = -1, u_second = -1;
  double coefficient = 0.0, radius = 0.0;
};

inline constexpr int kFrictionIterations = 100;
inline constexpr double kFrictionTolerance = 1e-13;

/// The model's joints with friction (planar revolute joints).
[[nodiscard]] std::vector<FrictionPin> friction_pins(const Model& model);

/// Adds the friction loads Q_f(λ, u) of `pins` to Q (generalised forces, size n).
void add_friction_forces(const std::vector<FrictionPin>& pins, const VecX& u, const VecX& lambda,
                         VecX& Q);

/// Each pin's friction moment on its second body, −μ r |F| sgn(ω₂ − ω₁) (N·m), into `moments`
/// (one per pin); returns the power they dissipate, Σ μ r |F| |ω₂ − ω₁| (W).
double friction_moments(const std::vector<FrictionPin>& pins, const Eigen::Ref<const VecX>& u,
                        const Eigen::Ref<const VecX>& lambda, std::vector<double>& moments);

}  // namespace orthomech
