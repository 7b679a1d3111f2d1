#pragma once
// The constraints of a Model as one of two alternatives, chosen with the free system
// (free_system.hpp: FreeSystem::constraints()): the joints, knife edges and rolling discs of a
// model of bodies (constraints/joints.cpp), or the functions of a general system
// (model/general_system.hpp, constraints/general_constraints.cpp). Every model-level constraint
// function (joints.hpp, sparse_et.hpp, Model::constraint_row_name) goes through it, so no caller
// asks which alternative it has.
#include <string>

#include "orthomech/model/model.hpp"

namespace orthomech {

class BodyPoses;   // model/free_system.hpp
class SparseEt;    // constraints/sparse_et.hpp
class EtRecorder;  // constraints/sparse_et.hpp

class ConstraintSystem {
 public:
  virtual ~ConstraintSystem() = default;
  // f(q) (eq. (20)), Eᵀ(q) (eq. (23)), Dᵀ(q, u) (eq. (76)) and Dᵀu at q (u for the last two);
  // a null pointer is not computed. poses: the bodies' rotations at q, when the caller has them.
  virtual void evaluate(const Model& model, const VecX& q, const VecX* u, VecX* f, MatX* Et,
                        MatX* Dt, VecX* Dtu, const BodyPoses* poses) const = 0;
  // The same with Eᵀ on its structural pattern (SparseEt(model)).
  virtual void evaluate(const Model& model, const VecX& q, const VecX* u, VecX* f, SparseEt* Et,
                        MatX* Dt, VecX* Dtu, const BodyPoses* poses) const = 0;
  // Every entry of Eᵀ an evaluation can write, whatever q.
  virtual void record_pattern(const Model& model, EtRecorder& recorder) const = 0;
  // True when Eᵀ has the bodies' structure (a few entries per row, whatever n): the sparse chart
  // factorisation and the sparse rank pay off on large models. False for a general system, whose
  // Eᵀ is a dense function.
  [[nodiscard]] virtual bool structurally_sparse() const = 0;
  // "joint 'A', x" or "constraint 'loop x'": the name of constraint row `row` (messages,
  // redundant equations, reactions).
  [[nodiscard]] virtual std::string row_name(const Model& model, int row) const = 0;
};

// The model's constraints (free_system(model).constraints()).
[[nodiscard]] const ConstraintSystem& constraint_system(const Model& model);

// The two alternatives (one instance each, stateless).
[[nodiscard]] const ConstraintSystem& joint_constraints();
[[nodiscard]] const ConstraintSystem& general_constraints();

}  // namespace orthomech
