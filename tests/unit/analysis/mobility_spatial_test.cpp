// Mobility of spatial models (issue 12 item 4): rank DOF, the Grübler–Kutzbach count n − n_c,
// named redundant equations and idle degrees of freedom.
#include <gtest/gtest.h>

#include "orthomech/analysis/mobility.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "support/spatial_fixtures.hpp"

namespace orthomech {
namespace {

using testing::spatial::body;
using testing::spatial::inertia_b;
using testing::spatial::point_at;

Joint spherical(const std::string& name, const SpatialPointRef& a, const SpatialPointRef& b) {
  SpatialJoint s;
  s.type = SpatialJointType::spherical;
  s.pi = a;
  s.pj = b;
  Joint j;
  j.name = name;
  j.kind = s;
  return j;
}

// A rod held by spherical joints at both ends: it can only spin about the line through them.
// Closed form: n = 6, n_c = 6, rank 5 (the two point rows repeat the distance between the
// ends), DOF 1, one redundant row, Grübler 0, and that one DOF is idle.
TEST(SpatialMobility, RodBetweenTwoSphericalJointsHasOneIdleSpin) {
  Model m;
  m.name = "rod";
  m.dimension = 3;
  m.bodies.push_back(body("rod", 1.0, Vec3(0.2, 0.1, 0.3),
                          testing::spatial::unit_quaternion(0.9, 0.1, 0.2, -0.3), Vec3::Zero(),
                          inertia_b()));
  finalize_model(m);
  const Vec3 A(0.0, 0.0, 0.0), B(0.4, 0.3, 0.5);
  m.joints.push_back(spherical("A", point_at(m, kGround, A), point_at(m, 0, A)));
  m.joints.push_back(spherical("B", point_at(m, kGround, B), point_at(m, 0, B)));
  finalize_model(m);
  const Mobility mob = compute_mobility(m, m.design_q());
  EXPECT_EQ(mob.n, 6);
  EXPECT_EQ(mob.nc, 6);
  EXPECT_EQ(mob.rank, 5);
  EXPECT_EQ(mob.dof, 1);
  EXPECT_EQ(mob.grubler, 0);
  ASSERT_EQ(mob.redundant.size(), 1u);
  ASSERT_EQ(mob.idle.size(), 1u);
  EXPECT_EQ(mob.idle[0].body, "rod");
  EXPECT_EQ(mob.idle[0].count, 1);
  // Held at one end only, the rod is a spherical pendulum: 3 DOF, none idle (one joint only).
  m.joints.pop_back();
  finalize_model(m);
  const Mobility pendulum = compute_mobility(m, m.design_q());
  EXPECT_EQ(pendulum.dof, 3);
  EXPECT_TRUE(pendulum.idle.empty());
}

// Planar mechanisms have no idle motion: every link of the crank-rocker is bound by its joints.
TEST(SpatialMobility, PlanarCrankRockerHasNoIdleMotion) {
  const Model m =
      load_mechanism(std::string(ORTHOMECH_SOURCE_DIR) + "/mechanisms/crank-rocker.yaml");
  const Mobility mob = compute_mobility(m, m.design_q());
  EXPECT_EQ(mob.dof, 1);
  EXPECT_TRUE(mob.idle.empty());
}

}  // namespace
}  // namespace orthomech
