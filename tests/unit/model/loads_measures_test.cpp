// Loads and measures against central finite differences (issue 2 §2):
//  - conservative loads: Q = −∂V/∂q (gravity, springs with the damping switched off);
//  - point forces and torques: Qᵀ δq = virtual work F·δr_P (eq. (8)) with δr_P by differences;
//  - dampers: Q = −c L̇ ∂L/∂q;
//  - measures: d = ∂s/∂q, ṡ = d u, and ḋu = d²s/dt² along q + t u.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/model/loads.hpp"
#include "orthomech/model/measures.hpp"
#include "support/zoo.hpp"

namespace orthomech {
namespace {

constexpr double kFdStep = 1e-6;
constexpr double kFdTol = 1e-6;  // forces up to ~100 N: rounding ~1e-10·100/1e-6 ≈ 1e-8

State zoo_state(const Model& model) {
  State s(model);
  s.q = model.design_q();
  for (int k = 0; k < model.n; ++k) s.u(k) = 1.5 * std::cos(0.9 * k + 0.3);
  return s;
}

VecX gradient(const std::function<double(const VecX&)>& fn, const VecX& q) {
  VecX g(q.size());
  for (Eigen::Index k = 0; k < q.size(); ++k) {
    VecX qp = q, qm = q;
    qp(k) += kFdStep;
    qm(k) -= kFdStep;
    g(k) = (fn(qp) - fn(qm)) / (2.0 * kFdStep);
  }
  return g;
}

const Load& find_load(const Model& m, const std::string& name) {
  for (const Load& l : m.loads)
    if (l.name == name) return l;
  throw std::runtime_error("no load " + name);
}

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

TEST(Measures, JacobianRateAndConvectiveTermAgainstDifferences) {
  const Model model = parse_mechanism(test::kZooYaml, "zoo");
  const State s = zoo_state(model);
  for (const Measure& m : model.measures) {
    VecX d(model.n);
    const ScalarKinematics k = compute_scalar(model, m.kind, s.q, &s.u, d);
    const auto value = [&](const VecX& q) {
      return compute_scalar(model, m.kind, q, nullptr).value;
    };
    EXPECT_NEAR(k.value, value(s.q), 1e-15) << m.name;
    const VecX g = gradient(value, s.q);
    for (int c = 0; c < model.n; ++c) EXPECT_NEAR(d(c), g(c), 1e-8) << m.name << ", column " << c;
    EXPECT_NEAR(k.rate, d.dot(s.u), 1e-12) << m.name;
    const double h = 1e-4;  // second difference along q + t u (u̇ = 0 there, so s̈ = ḋu)
    const double second =
        (value(s.q + h * s.u) - 2.0 * value(s.q) + value(s.q - h * s.u)) / (h * h);
    EXPECT_NEAR(k.ddot_u, second, 1e-5 * (1.0 + s.u.squaredNorm())) << m.name;
  }
}

// evaluate_measure at every derivative order against compute_scalar (checked above against
// differences): s, ṡ = d u and s̈ = d u̇ + ḋu, with and without a rotation table (BodyRotations
// against rotation(φ) of each body's angle).
TEST(Measures, EvaluateMeasureAtEveryOrderWithAndWithoutRotationTable) {
  const Model model = parse_mechanism(test::kZooYaml, "zoo");
  const State s = zoo_state(model);
  VecX udot(model.n);
  for (int k = 0; k < model.n; ++k) udot(k) = 0.7 * std::sin(1.1 * k + 0.2);
  BodyRotations rotations(model);
  rotations.update(model, s.q);
  for (size_t b = 0; b < model.bodies.size(); ++b)
    EXPECT_LT(
        (rotations[static_cast<int>(b)] - rotation(body_angle(model, static_cast<int>(b), s.q)))
            .cwiseAbs()
            .maxCoeff(),
        1e-15);
  for (Measure m : model.measures) {
    VecX d(model.n);
    const ScalarKinematics k = compute_scalar(model, m.kind, s.q, &s.u, d);
    const double expected[3] = {k.value, d.dot(s.u), d.dot(udot) + k.ddot_u};
    for (int order = 0; order < 3; ++order) {
      m.derivative = order;
      const double tol = 1e-13 * (1.0 + std::abs(expected[order]));
      EXPECT_NEAR(evaluate_measure(model, m, s.q, &s.u, &udot), expected[order], tol)
          << m.name << " derivative " << order;
      EXPECT_NEAR(evaluate_measure(model, m, s.q, &s.u, &udot, rotations), expected[order], tol)
          << m.name << " derivative " << order << " (rotation table)";
    }
  }
}

TEST(Measures, TableFactorInterpolatesLinearlyAndClamps) {
  const Model model = parse_mechanism(test::kZooYaml, "zoo");
  const auto& push = std::get<PointForce>(find_load(model, "push").kind);
  VecX q = model.design_q();
  // m_rev = φ_a − 0 = q(2); table [(-1, 0.5), (2, 1.5)]: factor = 0.5 + (φ + 1)/3. The table is
  // over an angle, so it wraps with the turn by default: φ is first taken into [−1, −1 + 2π).
  ASSERT_TRUE(push.table.wrap);
  constexpr double kTurn = 2.0 * std::numbers::pi;
  Table unwrapped = push.table;
  unwrapped.wrap = false;
  for (const double phi : {-3.0, -1.0, 0.0, 0.4, 2.0, 5.0, 5.0 + kTurn, 0.4 - 3.0 * kTurn}) {
    q(2) = phi;
    const double turned = phi + kTurn * std::ceil(-(phi + 1.0) / kTurn - 1e-15);  // into [−1, …)
    const double clamped = std::clamp(turned, -1.0, 2.0);
    // 4 ulp of a few turns: the wrap subtracts multiples of 2π.
    EXPECT_NEAR(table_factor(model, push.table, q), 0.5 + (clamped + 1.0) / 3.0, 1e-14) << phi;
    const double plain = std::clamp(phi, -1.0, 2.0);
    EXPECT_NEAR(table_factor(model, unwrapped, q), 0.5 + (plain + 1.0) / 3.0, 1e-15) << phi;
  }
}

}  // namespace
}  // namespace orthomech
