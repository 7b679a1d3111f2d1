// The model (src/model/model.cpp): sizes and offsets from the bodies, the design position from
// the poses (q holds the centre of mass: pose + R(φ) com), names found and constraint rows
// named, on the crank-rocker (3 rigid bodies, 4 revolutes).
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>

#include "orthomech/model/free_system.hpp"
#include "support/fixtures.hpp"

namespace orthomech {
namespace {

TEST(Model, SizesOffsetsAndDesignPosition) {
  const Model model = test::load_bundled("crank-rocker");
  ASSERT_EQ(model.bodies.size(), 3u);
  EXPECT_EQ(model.n, 9);
  EXPECT_EQ(model.nq, 9);
  EXPECT_EQ(model.nc, 8);  // 4 revolutes × 2
  const VecX q = model.design_q();
  int offset = 0;
  for (const Body& b : model.bodies) {
    EXPECT_EQ(b.q_offset, offset) << b.name;
    EXPECT_EQ(b.u_offset, offset) << b.name;
    offset += 3;
    const Vec2 pose(b.design_pose.x(), b.design_pose.y());
    const Vec2 com = pose + rotation(b.design_pose.z()) * b.com_local;
    EXPECT_NEAR(q(b.q_offset), com.x(), 1e-15) << b.name;
    EXPECT_NEAR(q(b.q_offset + 1), com.y(), 1e-15) << b.name;
    EXPECT_EQ(q(b.q_offset + 2), b.design_pose.z()) << b.name;
  }
  // SI inside: the crank's centre of mass 15 mm along the crank at 60°.
  const Body& crank = model.bodies[static_cast<size_t>(model.find_body("crank"))];
  EXPECT_NEAR(crank.com_local.x(), 0.015, 1e-15);
  EXPECT_NEAR(crank.design_pose.z(), M_PI / 3.0, 1e-15);
}

TEST(Model, NamesAreFoundAndRowsNamed) {
  const Model model = test::load_bundled("crank-rocker");
  EXPECT_EQ(model.find_body("ground"), kGround);
  EXPECT_EQ(model.find_body("no-such-body"), -2);
  EXPECT_EQ(model.find_body("rocker"), 2);
  EXPECT_EQ(model.find_joint("B"), 2);
  EXPECT_EQ(model.find_joint("no-such-joint"), -1);
  EXPECT_EQ(model.find_measure("P_y"), 5);
  EXPECT_EQ(model.body_name(0), "crank");
  // Rows in joint order, x then y of each revolute.
  EXPECT_EQ(model.constraint_row_name(0), "joint 'A0', x");
  EXPECT_EQ(model.constraint_row_name(3), "joint 'A', y");
  EXPECT_EQ(model.constraint_row_name(7), "joint 'B0', y");
  EXPECT_THROW((void)model.constraint_row_name(8), std::invalid_argument);
}

}  // namespace
}  // namespace orthomech
