#pragma once
// State: small values only (house style). t, q (size nq), u (size n), and the discrete state of
// the switched loads.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "orthomech/model/model.hpp"

namespace orthomech {

struct State {
  double t = 0.0;
  VecX q;  // coordinates, eq. (3)
  VecX u;  // velocity parameters, eq. (19)
  // Per Model::loads: whether a load switched by `active_while` acts (1) or not (0), held between
  // the events that switch it (simulate, dynamics/events.hpp). Empty (the default, and every
  // analysis but simulate): it acts while its measure's velocity has its sign at the evaluation.
  std::vector<std::uint8_t> load_on;
  State() = default;
  explicit State(const Model& model) : q(VecX::Zero(model.nq)), u(VecX::Zero(model.n)) {}
};

}  // namespace orthomech
