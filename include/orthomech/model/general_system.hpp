#pragma once
// A free system given by functions (docs/design.md §2: "a general free system with configuration-
// dependent M(q) … must fit the same interface"), e.g. a tree in joint coordinates such as
// Andrews' squeezer in the test set's relative coordinates. Holonomic, q̇ = u (B̃ = I).
//
// A Model built by make_general_model holds one of these instead of bodies and joints; the
// model-level functions (free_system.hpp, loads.hpp, constraints/joints.hpp) call it, so every
// algorithm (projections, mobility, positions, simulate, crosscheck) runs unchanged on it, with
// every Ṁ term live (eq. (81), eq. (82), eq. (91), eq. (97), eq. (98), eq. (99)).
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "orthomech/model/model.hpp"

namespace orthomech {

struct GeneralSystem {
  int n = 0;                             // coordinates = velocity parameters
  int nc = 0;                            // constraint rows
  VecX q0;                               // n: design position (need not satisfy f = 0)
  std::vector<std::string> coordinates;  // n: names of the coordinates (messages, outputs)
  std::vector<std::string> rows;         // nc: names of the constraint rows
  std::function<void(const VecX& q, MatX& M)> mass;                         // M(q), eq. (4)
  std::function<void(const VecX& q, const VecX& u, MatX& Mdot)> mass_rate;  // Ṁ along u
  // Q̂(q, u, t), eq. (17): the applied generalized forces Q plus the velocity term ∂T/∂q of the
  // free system (ṗ = Q̂ + R). simulate's energy balance counts all of Q as non-conservative
  // work, W = ∫ (Q̂ᵀu − ½ uᵀṀu) dt (∂T/∂q · u = ½ uᵀṀu); T − W is then the conserved
  // quantity and the potential energy is reported as 0.
  std::function<void(const VecX& q, const VecX& u, double t, VecX& Q)> forces;
  std::function<void(const VecX& q, VecX& f)> residual;                       // f, eq. (20)
  std::function<void(const VecX& q, MatX& Et)> jacobian;                      // Eᵀ, eq. (23)
  std::function<void(const VecX& q, const VecX& u, MatX& Dt)> jacobian_rate;  // Dᵀ = Ėᵀ, (76)
};

// A Model around a general system (no bodies, joints or loads; measures: none). Throws
// std::invalid_argument when a function is missing or the sizes disagree.
[[nodiscard]] Model make_general_model(std::string name, GeneralSystem system);

}  // namespace orthomech
