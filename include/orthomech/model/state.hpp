#pragma once
// State: small values only (house style). t, q (size nq), u (size n).
#include <Eigen/Core>

#include "orthomech/model/model.hpp"

namespace orthomech {

struct State {
  double t = 0.0;
  VecX q;  // coordinates, eq. (3)
  VecX u;  // velocity parameters, eq. (19)
  State() = default;
  explicit State(const Model& model) : q(VecX::Zero(model.nq)), u(VecX::Zero(model.n)) {}
};

}  // namespace orthomech
