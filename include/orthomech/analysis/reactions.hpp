#pragma once
// Joint reactions from the constraint multipliers λ (docs/design.md §3): the force (and moment)
// that each joint applies to its first body from its second, in the world frame and in the joint's
// frame, with named components. Used by `cycle` (kinetostatics), `simulate` and `crosscheck`.
#include <string>
#include <vector>

#include "orthomech/model/free_system.hpp"
#include "orthomech/model/model.hpp"

namespace orthomech {

struct ReactionComponent {
  std::string name;    // "A.Fx", "A.Ft", …
  int joint = -1;      // index in Model::joints; knife edge e has joints.size() + e
  bool global = true;  // global frame (else the joint's frame = the first body's frame)
  std::string unit;    // "N" or "N*m"
};

// Reaction components of every joint (names, frames, units), in output order.
[[nodiscard]] std::vector<ReactionComponent> reaction_components(const Model& model);
// Their values at a position from the multipliers (any vector expression of size n_c, e.g. a
// column of the null space N, without a copy). Allocation-free once `out` has its capacity.
void compute_reactions(const Model& model, const VecX& q, const Eigen::Ref<const VecX>& lambda,
                       std::vector<double>& out);
// The same with the bodies' rotations at q already computed (e.g. DrivenWorkspace::rotations
// after compute_driven): no sin/cos.
void compute_reactions(const Model& model, const VecX& q, const BodyPoses& rotations,
                       const Eigen::Ref<const VecX>& lambda, std::vector<double>& out);

}  // namespace orthomech
