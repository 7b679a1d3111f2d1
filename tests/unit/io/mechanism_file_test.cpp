#include "orthomech/io/mechanism_file.hpp"

#include <gtest/gtest.h>

namespace orthomech {
namespace {
TEST(MechanismFile, MinimalPendulumParses) {
  const Model m = parse_mechanism(R"(
orthomech: 1
bodies:
  - {name: bar, mass: 2, inertia: 0.5, com: [0.5, 0], pose: [0, 0, 0], points: {O: [0, 0]}}
joints:
  - {name: O, type: revolute, connects: [ground.O, bar.O]}
ground:
  points: {O: [0, 0]}
)",
                                  "inline");
  EXPECT_EQ(m.n, 3);
  EXPECT_EQ(m.nc, 2);
}
}  // namespace
}  // namespace orthomech
