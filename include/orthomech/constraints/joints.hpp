#pragma once
// Constraints (paper §3, docs/design.md §3): every joint supplies, analytically,
//   f(q)            the geometric residual, eq. (20)  (holonomic joints),
//   Eᵀ(q)           the constraint matrix acting on u, eq. (23): Eᵀ u = 0,
//   Dᵀ(q, u)        its time derivative along the motion, Dᵀ = d/dt Eᵀ, eq. (76),
// so that Dᵀu is the convective term of the acceleration constraint Eᵀu̇ + Dᵀu = 0.
// Rows are stacked joint by joint in file order (Joint::row_offset).
#include "orthomech/model/free_system.hpp"
#include "orthomech/model/model.hpp"
#include "orthomech/model/state.hpp"

namespace orthomech {

struct ConstraintWorkspace {
  VecX f;    // nc:      geometric residual, eq. (20)
  MatX Et;   // nc × n:  Eᵀ, eq. (23) (0 × 0 without the matrices)
  MatX Dt;   // nc × n:  Dᵀ = Ėᵀ, eq. (76) (0 × 0 without the matrices)
  VecX Dtu;  // nc:      Dᵀ u
  // The kinematics stage at the q of the last compute_constraints / compute_constraint_rate
  // (the bodies' rotations, computed once for every row).
  BodyPoses poses;
  // matrices: false leaves Et and Dt 0 × 0, for an owner that holds Eᵀ on its pattern (SparseEt)
  // and never forms Dᵀ (the cycle of a large model, issue 18); compute_constraints then throws
  // std::logic_error.
  explicit ConstraintWorkspace(const Model& model, bool matrices = true);
};

// f(q) only (cheap: used by position solvers).
void compute_constraint_residual(const Model& model, const VecX& q, VecX& f);
// The same with the bodies' rotations at q already computed (rotations.update(model, q)).
void compute_constraint_residual(const Model& model, const VecX& q, const BodyPoses& rotations,
                                 VecX& f);
// Eᵀ(q) only.
void compute_constraint_jacobian(const Model& model, const VecX& q, MatX& Et);
// f(q) and Eᵀ(q) in one pass (the point kinematics shared).
void compute_constraint_residual_and_jacobian(const Model& model, const VecX& q, VecX& f, MatX& Et);
// The same with the bodies' rotations at q already computed (rotations.update(model, q)).
void compute_constraint_residual_and_jacobian(const Model& model, const VecX& q,
                                              const BodyPoses& rotations, VecX& f, MatX& Et);
// Dᵀu only (when Eᵀ at the same q is already there), each row's product with u formed directly:
// ws.Dt is neither formed nor changed. Allocation-free.
void compute_constraint_rate(const Model& model, const State& state, ConstraintWorkspace& ws);
// The same with the bodies' rotations at state.q already computed.
void compute_constraint_rate(const Model& model, const State& state, const BodyPoses& rotations,
                             ConstraintWorkspace& ws);
// f, Eᵀ, Dᵀ and Dᵀu at a state. Allocation-free.
void compute_constraints(const Model& model, const State& state, ConstraintWorkspace& ws);

// The coordinate a joint has (its `joint` measure, drivers, limits, design inputs): an angle
// (planar revolute; spatial revolute, cylindrical, screw), a slide (planar and spatial
// prismatic) or none.
enum class CoordinateKind { none, angle, slide };
[[nodiscard]] CoordinateKind joint_coordinate_kind(const Joint& joint);
// True when the joint's angle is read modulo 2π (a spatial twist angle in (−π, π]): callers
// that follow it over a motion unwrap it by continuity. A planar revolute's angle is continuous.
[[nodiscard]] bool joint_coordinate_wraps(const Joint& joint);

}  // namespace orthomech
