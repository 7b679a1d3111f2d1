// Measures of spatial bodies (src/model/measures.cpp; issue 12), on the two-body models of
// tests/support/spatial_fixtures.hpp.
#include <gtest/gtest.h>

#include <numbers>
#include <random>
#include <string>
#include <variant>

#include "orthomech/constraints/joints.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/model/loads.hpp"
#include "orthomech/model/measures.hpp"
#include "orthomech/model/spatial.hpp"
#include "support/spatial_fixtures.hpp"

namespace orthomech {
namespace {

using testing::spatial::random_state;
using testing::spatial::two_body_model;

// Spatial measures: rates and accelerations against differences of their values along
// q ⊕ t u, and values against direct formulas.
TEST(SpatialMeasures, RatesAndAccelerationsAgainstDifferences) {
  Model m = two_body_model(SpatialJointType::spherical, 0);
  const SpatialPointRef a = testing::spatial::point_at(m, 0, Vec3(0.2, 0.1, 0.6));
  const SpatialPointRef b = testing::spatial::point_at(m, 1, Vec3(0.7, 0.3, 0.0));
  const std::vector<MeasureKind> kinds = {SpatialPointCoordinate{a, 0},
                                          SpatialPointCoordinate{b, 2}, SpatialPointDistance{a, b},
                                          VectorAngle{0, 1, Vec3(1, 0, 0), Vec3(0, 0.6, 0.8)}};
  std::mt19937_64 rng(9);
  const State s = random_state(m, rng, 0.3);
  const VecX zero = VecX::Zero(m.n);
  for (size_t i = 0; i < kinds.size(); ++i) {
    const Measure pos{"m", kinds[i], 0, "", {}}, vel{"m", kinds[i], 1, "", {}},
        acc{"m", kinds[i], 2, "", {}};
    const auto value_at = [&](double dt) {
      VecX qt = s.q;
      integrate_positions(m, qt, s.u, dt);
      return evaluate_measure(m, pos, qt, nullptr, nullptr);
    };
    const double h = 1e-5, h2 = 1e-4;
    EXPECT_NEAR(evaluate_measure(m, vel, s.q, &s.u, nullptr),
                (value_at(h) - value_at(-h)) / (2 * h), 1e-8)
        << i;
    EXPECT_NEAR(evaluate_measure(m, acc, s.q, &s.u, &zero),
                (value_at(h2) - 2 * value_at(0) + value_at(-h2)) / (h2 * h2), 1e-5)
        << i;
  }
  // Values: the distance and the angle from their definitions.
  const Vec3 ra = spatial_point(spatial_frame(m, 0, s.q, nullptr), a.s).r;
  const Vec3 rb = spatial_point(spatial_frame(m, 1, s.q, nullptr), b.s).r;
  EXPECT_NEAR(evaluate_measure(m, Measure{"d", kinds[2], 0, "", {}}, s.q, nullptr, nullptr),
              (rb - ra).norm(), 1e-15);
  const Vec3 ai = spatial_frame(m, 0, s.q, nullptr).R * Vec3(1, 0, 0);
  const Vec3 aj = spatial_frame(m, 1, s.q, nullptr).R * Vec3(0, 0.6, 0.8);
  EXPECT_NEAR(evaluate_measure(m, Measure{"a", kinds[3], 0, "", {}}, s.q, nullptr, nullptr),
              std::acos(ai.dot(aj)), 1e-12);
}

}  // namespace
}  // namespace orthomech
