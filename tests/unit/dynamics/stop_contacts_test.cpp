// Resting contacts on end stops (src/dynamics/stop_contacts.cpp): a joint that comes to rest
// pressed against its stop is held there while its contact force pushes, and released when it
// would pull. The oracle is written in the test: an arm (1 m, 1 kg) pinned at O rests on its
// lower stop at 0 rad, pressed by its weight and by a link (1 m, 1 kg) pinned at its tip A that
// whirls from hanging at 12 rad/s. While the arm rests, the link is a pendulum about the fixed
// point A: J_A θ̈ = −m g (l/2) cos θ (J_A = m l²/3), integrated here by RK4; the arm is static,
// so the moments on it about O balance: the contact moment is
//   μ = m₁ g l₁/2 + l₁ (m₂ g + m₂ a_Gy),   a_Gy = (l/2)(cos θ θ̈ − sin θ θ̇²),
// (the weight of the arm and the vertical force of the link at A), and the arm is released where
// μ reaches 0: where the link's centre of mass accelerates downwards faster than g (1 + m₁/2m₂).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "orthomech/dynamics/simulate.hpp"
#include "orthomech/io/mechanism_file.hpp"

namespace orthomech {
namespace {

constexpr double kPi = 3.14159265358979323846;

const char* const kArmOnAStop = R"(orthomech: 1
name: arm-on-a-stop
units: {length: m, angle: rad, mass: kg, time: s, force: N}
ground:
  points: {O: [0, 0]}
bodies:
  - {name: arm, mass: 1, inertia: 0.0833333333333333, com: [0.5, 0], pose: [0, 0, 1e-12], points: {O: [0, 0], A: [1, 0]}}
  - {name: link, mass: 1, inertia: 0.0833333333333333, com: [0.5, 0], pose: [1, 1e-12, -1.5707963267948966], points: {A: [0, 0]}}
joints:
  - {name: O, type: revolute, connects: [ground.O, arm.O], limits: [0, 1.5], end_stops: {restitution: 0}}
  - {name: A, type: revolute, connects: [arm.A, link.A]}
loads:
  - {name: weight, type: gravity, g: [0, -9.81]}
measures:
  - {name: arm_angle, type: joint, joint: O}
  - {name: link_angle, type: angle, body: link}
initial:
  rates: {arm_angle: 0, link_angle: 12}
)";

constexpr double kG = 9.81;

// The link about the fixed point A: state (θ, θ̇).
struct Link {
  double theta = -kPi / 2.0, omega = 12.0;
  [[nodiscard]] static double accel(double theta) { return -kG * 0.5 * std::cos(theta) * 3.0; }
  void step(double h) {  // RK4
    const double k1t = omega, k1w = accel(theta);
    const double k2t = omega + 0.5 * h * k1w, k2w = accel(theta + 0.5 * h * k1t);
    const double k3t = omega + 0.5 * h * k2w, k3w = accel(theta + 0.5 * h * k2t);
    const double k4t = omega + h * k3w, k4w = accel(theta + h * k3t);
    theta += h / 6.0 * (k1t + 2 * k2t + 2 * k3t + k4t);
    omega += h / 6.0 * (k1w + 2 * k2w + 2 * k3w + k4w);
  }
  // The arm's contact moment about O (N·m).
  [[nodiscard]] double contact() const {
    const double a_gy = 0.5 * (std::cos(theta) * accel(theta) - std::sin(theta) * omega * omega);
    return 1.0 * kG * 0.5 + (kG + a_gy);
  }
};

// The first time a margin of the link's state reaches zero: RK4 steps of 1e-5 s to the step
// where it changes sign, then bisection on that step's length.
template <class Margin>
double first_zero(Margin margin) {
  Link s;
  const double h = 1e-5;
  double t = 0.0;
  while (true) {
    Link next = s;
    next.step(h);
    if (margin(next) <= 0.0) break;
    s = next;
    t += h;
  }
  double lo = 0.0, hi = h;
  for (int it = 0; it < 60; ++it) {
    const double mid = 0.5 * (lo + hi);
    Link m = s;
    m.step(mid);
    (margin(m) > 0.0 ? lo : hi) = mid;
  }
  return t + 0.5 * (lo + hi);
}

// The oracle's release time: where the contact moment μ reaches zero.
double release_time() {
  return first_zero([](const Link& s) { return s.contact(); });
}

TEST(StopContacts, AnArmRestsOnItsStopUntilTheWhirlingLinkLiftsIt) {
  const Model model = parse_mechanism(kArmOnAStop, "arm-on-a-stop");
  const double t_release = release_time();
  ASSERT_GT(t_release, 0.05);
  ASSERT_LT(t_release, 0.5);
  for (DynamicsForm form : {DynamicsForm::dual, DynamicsForm::primal}) {
    SCOPED_TRACE(form == DynamicsForm::dual ? "dual" : "primal");
    SimulateOptions o;
    o.form = form;
    o.t_end = 0.6;
    o.dt_out = 1e-3;
    o.rtol = 1e-10;
    o.atol = 1e-12;
    const SimulateResult r = simulate(model, o);
    ASSERT_EQ(r.status, SimulateStatus::completed) << r.message;
    ASSERT_GE(r.contacts.size(), 1u);
    const SimulateResult::StopContact& c = r.contacts[0];
    EXPECT_EQ(c.side, 1);
    EXPECT_LT(c.t_from, 1e-5) << "it comes to rest at once";
    EXPECT_NEAR(c.t_to, t_release, 1e-7) << "released where the contact force reaches 0";
    // While held, the arm stays on its stop and the link swings as the pendulum about A.
    Link oracle;
    double t = 0.0, worst = 0.0;
    int held_samples = 0;
    for (const SimulationSample& smp : r.samples) {
      if (smp.t <= c.t_from || smp.t >= c.t_to) continue;
      while (t + 1e-5 <= smp.t + 1e-12) {
        oracle.step(1e-5);
        t += 1e-5;
      }
      Link at = oracle;
      at.step(smp.t - t);
      EXPECT_NEAR(smp.measures[0], 0.0, 1e-11) << smp.t;
      worst = std::max(worst, std::abs(smp.measures[1] - at.theta));
      ++held_samples;
    }
    EXPECT_GT(held_samples, 50);
    EXPECT_LT(worst, 1e-7);
    // After the release the arm leaves the stop.
    double highest = 0.0;
    for (const SimulationSample& smp : r.samples)
      if (smp.t > c.t_to) highest = std::max(highest, smp.measures[0]);
    EXPECT_GT(highest, 1e-3);
    // The contact force does no work: T + V − W stays level.
    EXPECT_LT(r.energy_max_drift, 1e-8 * r.energy_scale);
  }
}

// The same arm, shorter (0.1 m), without stops but with Coulomb friction in its pin O
// (μ r = 0.1 m): released at rest, it sticks at once (its friction can hold it) and stays stuck
// while the moment that holds it stays within μ r |F_O|. The arm static, the moments about O
// balance as above, μ = m₁ g l₁/2 + l₁ m₂ (g + a_Gy), and the pin carries
// F_O = (m₂ a_Gx, (m₁ + m₂) g + m₂ a_Gy): it slips where |μ| reaches μ r |F_O|.
const char* const kArmOnItsFriction = R"(orthomech: 1
name: arm-on-its-friction
units: {length: m, angle: rad, mass: kg, time: s, force: N}
ground:
  points: {O: [0, 0]}
bodies:
  - {name: arm, mass: 1, inertia: 0.000833333333333333, com: [0.05, 0], pose: [0, 0, 0], points: {O: [0, 0], A: [0.1, 0]}}
  - {name: link, mass: 1, inertia: 0.0833333333333333, com: [0.5, 0], pose: [0.1, 0, -1.5707963267948966], points: {A: [0, 0]}}
joints:
  - {name: O, type: revolute, connects: [ground.O, arm.O], friction: {coefficient: 0.5, radius: 0.2}}
  - {name: A, type: revolute, connects: [arm.A, link.A]}
loads:
  - {name: weight, type: gravity, g: [0, -9.81]}
measures:
  - {name: arm_angle, type: joint, joint: O}
  - {name: link_angle, type: angle, body: link}
initial:
  rates: {arm_angle: 0, link_angle: 12}
)";

// μ r |F_O| − |μ| while the arm is stuck.
double friction_margin(const Link& s) {
  const double a = Link::accel(s.theta);
  const double a_gx = 0.5 * (-std::sin(s.theta) * a - std::cos(s.theta) * s.omega * s.omega);
  const double a_gy = 0.5 * (std::cos(s.theta) * a - std::sin(s.theta) * s.omega * s.omega);
  const double mu = kG * 0.1 / 2.0 + 0.1 * (kG + a_gy);
  return 0.1 * std::hypot(a_gx, 2.0 * kG + a_gy) - std::abs(mu);
}

double slip_time() { return first_zero(friction_margin); }

TEST(StopContacts, AnArmStuckByItsPinFrictionSlipsWhereTheMomentReachesTheStaticBound) {
  const Model model = parse_mechanism(kArmOnItsFriction, "arm-on-its-friction");
  const double t_slip = slip_time();
  ASSERT_GT(t_slip, 0.1);
  ASSERT_LT(t_slip, 0.5);
  for (DynamicsForm form : {DynamicsForm::dual, DynamicsForm::primal}) {
    SCOPED_TRACE(form == DynamicsForm::dual ? "dual" : "primal");
    SimulateOptions o;
    o.form = form;
    o.t_end = 0.4;
    o.dt_out = 1e-3;
    o.rtol = 1e-10;
    o.atol = 1e-12;
    const SimulateResult r = simulate(model, o);
    ASSERT_EQ(r.status, SimulateStatus::completed) << r.message;
    ASSERT_GE(r.contacts.size(), 1u);
    const SimulateResult::StopContact& c = r.contacts[0];
    EXPECT_EQ(c.side, 0) << "stuck by its friction";
    EXPECT_LT(c.t_from, 1e-5) << "it sticks at once";
    EXPECT_NEAR(c.t_to, t_slip, 1e-7) << "it slips where the moment reaches the bound";
    for (const SimulationSample& smp : r.samples)
      if (smp.t > c.t_from && smp.t < c.t_to) {
        EXPECT_NEAR(smp.measures[0], 0.0, 1e-9) << smp.t;
      }
    EXPECT_LT(r.energy_max_drift, 1e-8 * r.energy_scale);
  }
}

}  // namespace
}  // namespace orthomech
