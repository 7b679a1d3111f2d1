// Measures (src/model/measures.cpp) against central finite differences (issue 2 §2):
// d = ∂s/∂q, ṡ = d u, and ḋu = d²s/dt² along q + t u; table factors against linear interpolation.
#include "orthomech/model/measures.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/model/loads.hpp"
#include "support/zoo.hpp"
#include "support/zoo_differences.hpp"

namespace orthomech {
namespace {

using test::find_load;
using test::gradient;
using test::kFdStep;
using test::kFdTol;
using test::zoo_state;

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
// differences): s, ṡ = d u and s̈ = d u̇ + ḋu, with and without a rotation table (BodyPoses
// against rotation(φ) of each body's angle).
TEST(Measures, EvaluateMeasureAtEveryOrderWithAndWithoutRotationTable) {
  const Model model = parse_mechanism(test::kZooYaml, "zoo");
  const State s = zoo_state(model);
  VecX udot(model.n);
  for (int k = 0; k < model.n; ++k) udot(k) = 0.7 * std::sin(1.1 * k + 0.2);
  BodyPoses rotations(model);
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
