// Loads (src/model/loads.cpp) against central finite differences (issue 2 §2):
//  - conservative loads: Q = −∂V/∂q (gravity, springs with the damping switched off);
//  - point forces and torques: Qᵀ δq = virtual work F·δr_P (eq. (8)) with δr_P by differences;
//  - dampers: Q = −c L̇ ∂L/∂q.
#include "orthomech/model/loads.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/model/measures.hpp"
#include "support/zoo.hpp"
#include "support/zoo_differences.hpp"

namespace orthomech {
namespace {

using test::find_load;
using test::gradient;
using test::kFdStep;
using test::kFdTol;
using test::zoo_state;

TEST(Loads, ConservativeLoadsAreMinusGradientOfPotential) {
  Model model = parse_mechanism(test::kZooYaml, "zoo");
  // Keep gravity and the springs, without damping.
  std::vector<Load> kept;
  for (Load l : model.loads) {
    if (auto* s = std::get_if<SpringDamper>(&l.kind)) s->damping = 0.0;
    if (auto* r = std::get_if<RotarySpringDamper>(&l.kind)) r->damping = 0.0;
    if (std::holds_alternative<Gravity>(l.kind) || std::holds_alternative<SpringDamper>(l.kind) ||
        std::holds_alternative<RotarySpringDamper>(l.kind))
      kept.push_back(l);
  }
  model.loads = kept;
  ASSERT_EQ(model.loads.size(), 4u);
  const State s = zoo_state(model);
  VecX Q(model.n);
  compute_applied_forces(model, s, Q);
  const VecX g = gradient([&](const VecX& q) { return potential_energy(model, q); }, s.q);
  for (int k = 0; k < model.n; ++k) EXPECT_NEAR(Q(k), -g(k), kFdTol) << "coordinate " << k;
}

TEST(Loads, Eq8_PointForceAndTorqueDoTheirVirtualWork) {
  const Model model = parse_mechanism(test::kZooYaml, "zoo");
  const State s = zoo_state(model);
  for (const std::string name : {"push", "pull", "twist"}) {
    const Load& load = find_load(model, name);
    VecX Q = VecX::Zero(model.n);
    add_load(model, load, s, Q);
    // Virtual work of the load along each coordinate, by differences of the point (or angle).
    VecX W(model.n);
    if (const auto* f = std::get_if<PointForce>(&load.kind)) {
      const Vec2 F_world =
          f->body_fixed ? Vec2(rotation(body_angle(model, f->at.body, s.q)) * f->force) : f->force;
      const double factor = table_factor(model, f->table, s.q);
      const VecX* none = nullptr;
      for (int axis = 0; axis < 2; ++axis) {
        const VecX g = gradient(
            [&](const VecX& q) { return point_kinematics(model, f->at, q, none).r(axis); }, s.q);
        if (axis == 0)
          W = factor * F_world.x() * g;
        else
          W += factor * F_world.y() * g;
      }
    } else {
      const auto& t = std::get<Torque>(load.kind);
      W = t.torque * gradient([&](const VecX& q) { return body_angle(model, t.body, q); }, s.q);
    }
    for (int k = 0; k < model.n; ++k)
      EXPECT_NEAR(Q(k), W(k), kFdTol) << name << ", coordinate " << k;
  }
}

TEST(Loads, DampersOpposeTheRateOfTheirStretch) {
  Model model = parse_mechanism(test::kZooYaml, "zoo");
  std::vector<Load> kept;
  for (Load l : model.loads) {
    if (auto* s = std::get_if<SpringDamper>(&l.kind)) {
      s->stiffness = 0.0;
      kept.push_back(l);
    }
    if (auto* r = std::get_if<RotarySpringDamper>(&l.kind)) {
      r->stiffness = 0.0;
      kept.push_back(l);
    }
  }
  model.loads = kept;
  const State s = zoo_state(model);
  VecX Q(model.n);
  compute_applied_forces(model, s, Q);
  // Oracle: Q = −Σ c (∇ℓ·u) ∇ℓ for each damper stretch ℓ(q) (length or relative angle).
  VecX expected = VecX::Zero(model.n);
  double power = 0.0;
  const VecX* none = nullptr;
  for (const Load& l : model.loads) {
    std::function<double(const VecX&)> stretch;
    double c = 0.0;
    if (const auto* sd = std::get_if<SpringDamper>(&l.kind)) {
      c = sd->damping;
      stretch = [&, sd](const VecX& q) {
        return (point_kinematics(model, sd->pj, q, none).r -
                point_kinematics(model, sd->pi, q, none).r)
            .norm();
      };
    } else {
      const auto* rd = std::get_if<RotarySpringDamper>(&l.kind);
      c = rd->damping;
      stretch = [&, rd](const VecX& q) {
        return body_angle(model, rd->bj, q) - body_angle(model, rd->bi, q);
      };
    }
    const VecX g = gradient(stretch, s.q);
    expected -= c * g.dot(s.u) * g;
    power += c * g.dot(s.u) * g.dot(s.u);
  }
  for (int k = 0; k < model.n; ++k) EXPECT_NEAR(Q(k), expected(k), kFdTol) << "coordinate " << k;
  EXPECT_NEAR(dissipated_power(model, s), power, 1e-6 * (1.0 + power));
  EXPECT_NEAR(dissipated_power(model, s), -Q.dot(s.u), 1e-9 * (1.0 + power));
}

}  // namespace
}  // namespace orthomech
