#pragma once
// Helpers of the central-difference tests on the zoo mechanism (support/zoo.hpp): a state with a
// non-trivial velocity, a central-difference gradient, a load by name.
#include <cmath>
#include <functional>
#include <stdexcept>
#include <string>

#include "orthomech/model/model.hpp"
#include "orthomech/model/state.hpp"

namespace orthomech::test {

inline constexpr double kFdStep = 1e-6;
inline constexpr double kFdTol = 1e-6;  // forces up to ~100 N: rounding ~1e-10·100/1e-6 ≈ 1e-8

inline State zoo_state(const Model& model) {
  State s(model);
  s.q = model.design_q();
  for (int k = 0; k < model.n; ++k) s.u(k) = 1.5 * std::cos(0.9 * k + 0.3);
  return s;
}

inline VecX gradient(const std::function<double(const VecX&)>& fn, const VecX& q) {
  VecX g(q.size());
  for (Eigen::Index k = 0; k < q.size(); ++k) {
    VecX qp = q, qm = q;
    qp(k) += kFdStep;
    qm(k) -= kFdStep;
    g(k) = (fn(qp) - fn(qm)) / (2.0 * kFdStep);
  }
  return g;
}

inline const Load& find_load(const Model& m, const std::string& name) {
  for (const Load& l : m.loads)
    if (l.name == name) return l;
  throw std::runtime_error("no load " + name);
}

}  // namespace orthomech::test
