// A prismatic joint's moment M (issue 10 item 8): the moment on the joint's first body (the
// guide) from its second (the slider), about the joint's point pi on the first body — the
// convention of docs/cli.md and docs/notation.md.
//
// Oracle: the slider's own equation of motion, written here. The piston of the slider-crank
// translates (α = 0). Every force on it — its weight m g at its centre of mass C, the connecting
// rod's pin force at B (minus joint B's reaction, which is the rod's from the piston), an extra
// point force F_p at a point P off the axis (so that the moment is not zero about the piston's
// own point), and the guide's reaction (minus the joint's: force −N n and moment −M about P_i) —
// balances m a_C. The moment balance about the fixed point P_i (L1):
//   −M + (r_B − r_Pi) × (−F_B) + (r_C − r_Pi) × m g + (r_P − r_Pi) × F_p = (r_C − r_Pi) × m a_C
// gives M. The force balance gives N n (L2):
//   −N n − F_B + m g + F_p = m a_C.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "orthomech/analysis/cycle.hpp"
#include "support/fixtures.hpp"

namespace orthomech {
namespace {

double cross(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

// World position of a point given relative to its body's centre of mass (the ground's: absolute).
Vec2 world(const Model& model, const VecX& q, const PointRef& p) {
  if (p.body == kGround) return p.s;
  const Body& b = model.bodies[static_cast<size_t>(p.body)];
  const double phi = q(b.q_offset + 2);
  return q.segment<2>(b.q_offset) + Vec2(std::cos(phi) * p.s.x() - std::sin(phi) * p.s.y(),
                                         std::sin(phi) * p.s.x() + std::cos(phi) * p.s.y());
}

TEST(PrismaticMoment, AboutTheJointsFirstPointFromTheSlidersMomentBalance) {
  Model model = test::load_bundled("slider-crank");
  // The gas force's table is keyed on a measure; a constant force off the axis instead.
  std::erase_if(model.loads, [](const Load& l) { return l.name == "gas"; });
  const int piston = model.find_body("piston");
  const Body& body = model.bodies[static_cast<size_t>(piston)];
  const Vec2 P_local(0.0, 0.02);  // 20 mm above the piston's centre of mass (B), body frame
  const Vec2 F_p(-300.0, 50.0);   // N, world frame
  model.loads.push_back(
      {"push", PointForce{PointRef{piston, P_local, "piston.P"}, F_p, false, {}}, {}});
  CycleOptions o;
  o.driver = model.drivers.at(0);
  o.steps = 24;
  const CycleResult r = run_cycle(model, o);
  ASSERT_EQ(r.status, CycleStatus::completed) << r.message;

  const int slide = model.find_joint("slide"), pin = model.find_joint("B");
  const auto& prismatic = std::get<Prismatic>(model.joints[static_cast<size_t>(slide)].kind);
  auto index = [&](const std::string& name) {
    for (size_t i = 0; i < r.components.size(); ++i)
      if (r.components[i].name == name) return i;
    ADD_FAILURE() << name;
    return size_t{0};
  };
  const size_t M = index("slide.M"), N = index("slide.N");
  const size_t Fx = index("slide.Fx"), Fy = index("slide.Fy");
  const size_t Bx = index("B.Fx"), By = index("B.Fy");
  ASSERT_EQ(r.components[Bx].joint, pin);
  const Vec2 g(0.0, -9.81);
  double peak = 0.0;
  for (const DrivenPointView& p : r.points) {
    const VecX q = p.q;
    const Vec2 r_Pi = world(model, q, prismatic.pi);  // ground point X
    const Vec2 r_C = q.segment<2>(body.q_offset);
    const Vec2 r_B = world(model, q, prismatic.pj);  // the piston's B
    const Vec2 r_P = world(model, q, PointRef{piston, P_local, ""});
    const Vec2 a_C = p.udot.segment<2>(body.u_offset);
    const Vec2 F_B(p.reactions[Bx], p.reactions[By]);  // on the rod from the piston
    const double m = body.mass;
    const double expected = cross(r_B - r_Pi, -F_B) + cross(r_C - r_Pi, m * g) +
                            cross(r_P - r_Pi, F_p) - cross(r_C - r_Pi, m * a_C);  // (L1)
    // 1e-9 of the largest term (forces ~300 N at lever arms ~0.25 m): rounding of the solve.
    const double scale = 300.0 * 0.25;
    EXPECT_NEAR(p.reactions[M], expected, 1e-9 * scale) << "input " << p.input;
    const Vec2 force = -F_B + m * g + F_p - m * a_C;  // (L2): N n
    EXPECT_NEAR(p.reactions[Fx], force.x(), 1e-9 * 300.0);
    EXPECT_NEAR(p.reactions[Fy], force.y(), 1e-9 * 300.0);
    EXPECT_NEAR(p.reactions[N], force.y(), 1e-9 * 300.0);  // n = +y for the axis [1, 0]
    peak = std::max(peak, std::abs(expected));
  }
  // Not zero by construction: the moment about P_i includes N times the slider's distance.
  EXPECT_GT(peak, 1.0);
}

}  // namespace
}  // namespace orthomech
