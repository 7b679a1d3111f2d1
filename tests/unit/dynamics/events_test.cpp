// The events of simulate (dynamics/events.hpp, issue 49 item 3): loads switched by
// `active_while` and impacts on end stops. Oracles written in the test:
//   - a block on a spring with a one-sided force −F0 while it moves right: its motion is a cosine
//     about x = L0 (force off) or L0 − F0/k (force on) in each half period π/ω, so every
//     position and the force's work −F0 Σ(distance moved right) have a closed form;
//   - a pendulum with a Coulomb pin torque ∓T written as two switched torques: between two
//     turning points the energy falls by T times the angle swept, V(φ_{k+1}) + T|φ_{k+1} − φ_k| =
//     V(φ_k), which gives every turning angle without integrating; it sticks (a sliding mode the
//     run refuses to go on through) where the gravity torque at a turning point is below T;
//   - a pendulum falling onto an end stop: it meets the stop first at the speed the energy gives,
//     ½ J_O ω₀² = m g l_c (sin φ₀ − sin φ_s), rebounds at e times its speed, and (no loss in
//     flight) comes back at the speed it left; the energy lost in all its impacts when it comes to
//     rest is the whole drop m g l_c (sin φ₀ − sin φ_s);
//   - a pendulum with Coulomb friction in its pin against its 1-DOF equation written here (the pin
//     force depends on the acceleration: a fixed point per evaluation, RK4), and where it sticks.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "orthomech/dynamics/simulate.hpp"
#include "orthomech/io/mechanism_file.hpp"

namespace orthomech {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A run to t_end with outputs every dt_out at rtol 1e-10, atol 1e-12.
SimulateOptions tight(double t_end, double dt_out, DynamicsForm form = DynamicsForm::dual) {
  SimulateOptions o;
  o.form = form;
  o.t_end = t_end;
  o.dt_out = dt_out;
  o.rtol = 1e-10;
  o.atol = 1e-12;
  return o;
}

// Block 1 kg on a horizontal guide, spring k = 100 N/m of free length 1 m to the ground point O,
// released at rest at x = 1.5 m; the press force −10 N acts while x grows.
const char* const kPressBlock = R"(orthomech: 1
name: one-sided-block
units: {length: m, angle: rad, mass: kg, time: s, force: N}
ground:
  points: {O: [0, 0]}
bodies:
  - {name: block, mass: 1, inertia: 0.1, pose: [1.5, 0, 0], points: {P: [0, 0]}}
joints:
  - {name: guide, type: prismatic, connects: [ground.O, block.P], axis: [1, 0]}
loads:
  - {name: spring, type: spring-damper, connects: [ground.O, block.P], stiffness: 100, free_length: 1, damping: 0}
  - {name: press, type: force, point: block.P, force: [-10, 0], active_while: {measure: x, velocity: positive}}
measures:
  - {name: x, type: point, point: block.P, component: x}
)";

// The block's x(t): from each turning point x_a, a cosine about the centre of its half period.
double block_x(double t) {
  const double k = 100.0, m = 1.0, F0 = 10.0, L0 = 1.0, w = std::sqrt(k / m);
  const double half = kPi / w;
  double xa = 1.5;
  for (int i = 0;; ++i) {
    const double centre = i % 2 == 1 ? L0 - F0 / k : L0;  // odd halves move right (force on)
    if (t <= (i + 1) * half) return centre + (xa - centre) * std::cos(w * (t - i * half));
    xa = 2.0 * centre - xa;
  }
}

TEST(SimulateEvents, OneSidedForceOnASpringBlockMeetsItsClosedForm) {
  const Model model = parse_mechanism(kPressBlock, "one-sided-block");
  for (DynamicsForm form : {DynamicsForm::dual, DynamicsForm::primal}) {
    SCOPED_TRACE(form == DynamicsForm::dual ? "dual" : "primal");
    SimulateOptions o = tight(1.5, 0.01, form);  // four switches, at π/10, 2π/10, 3π/10, 4π/10 s
    const SimulateResult r = simulate(model, o);
    ASSERT_EQ(r.status, SimulateStatus::completed) << r.message;
    EXPECT_EQ(r.load_switches, 4);
    double worst = 0.0;
    for (const SimulationSample& s : r.samples)
      worst = std::max(worst, std::abs(s.measures[0] - block_x(s.t)));
    EXPECT_LT(worst, 1e-7);
    // The force's work: −F0 times the distance moved right, (1.3 − 0.5) + (1.1 − 0.7) m.
    EXPECT_NEAR(r.final.work, -10.0 * 1.2, 1e-6);
    EXPECT_LT(r.energy_max_drift, 1e-8 * r.energy_scale);
  }
}

// Pendulum: link of 1 m, 1 kg, centre of mass 0.5 m from the pin, released at rest horizontal,
// under gravity; its pin joint's extra keys and extra loads as given (angles in rad).
std::string pendulum(const std::string& pin_keys, const std::string& loads) {
  return R"(orthomech: 1
name: pendulum-test
units: {length: m, angle: rad, mass: kg, time: s, force: N}
ground:
  points: {O: [0, 0]}
bodies:
  - {name: bob, mass: 1, inertia: 0.0833333333333333, com: [0.5, 0], pose: [0, 0, 0], points: {O: [0, 0]}}
joints:
  - {name: O, type: revolute, connects: [ground.O, bob.O])" +
         pin_keys + R"(}
loads:
  - {name: weight, type: gravity, g: [0, -9.81]}
)" + loads +
         R"(measures:
  - {name: swing, type: joint, joint: O}
)";
}

// The Coulomb pin torque T as two torques switched by the swing's rate.
std::string coulomb_pendulum(double torque) {
  const std::string T = std::to_string(torque);
  return pendulum("", "  - {name: friction_up, type: torque, body: bob, torque: -" + T +
                          ", active_while: {measure: swing, velocity: positive}}\n"
                          "  - {name: friction_down, type: torque, body: bob, torque: " +
                          T + ", active_while: {measure: swing, velocity: negative}}\n");
}

// V(φ) = m g l_c sin φ; the next turning angle after φ_k (where the gravity torque exceeds T, so
// the swing starts towards the bottom −π/2): the first root of V(φ) + T|φ − φ_k| − V(φ_k) in
// the swing's direction (it falls from 0 first), found by a scan and bisection.
double next_turning_angle(double phi_k, double T) {
  const double mgl = 1.0 * 9.81 * 0.5;
  const double dir = phi_k > -kPi / 2.0 ? -1.0 : 1.0;
  auto residual = [&](double phi) {
    return mgl * std::sin(phi) + T * std::abs(phi - phi_k) - mgl * std::sin(phi_k);
  };
  double a = phi_k + dir * 1e-6, b = a;
  while (residual(b) < 0.0 && std::abs(b - phi_k) < 2.0 * kPi) {
    a = b;
    b += dir * 1e-3;
  }
  for (int i = 0; i < 200; ++i) {
    const double m = 0.5 * (a + b);
    (residual(m) < 0.0 ? a : b) = m;
  }
  return 0.5 * (a + b);
}

// The turning angles of the run: the extreme samples between sign changes of the rate.
std::vector<double> turning_angles(const SimulateResult& r) {
  std::vector<double> out;
  for (size_t i = 1; i + 1 < r.samples.size(); ++i) {
    const double a = r.samples[i - 1].measures[0], b = r.samples[i].measures[0],
                 c = r.samples[i + 1].measures[0];
    if ((b - a) * (c - b) < 0.0) out.push_back(b);
  }
  return out;
}

TEST(SimulateEvents, CoulombPendulumTurnsWhereTheEnergyLostToFrictionSays) {
  const Model model = parse_mechanism(coulomb_pendulum(1.0), "pendulum-test");
  // Two turns (at about 0.94 s and 1.80 s; it sticks at about 2.63 s); a sample within 5e-5 s of
  // each turn: |Δφ| ≤ ½ φ̈ (5e-5)² < 2e-8 rad.
  const SimulateOptions o = tight(2.5, 1e-4);
  const SimulateResult r = simulate(model, o);
  ASSERT_EQ(r.status, SimulateStatus::completed) << r.message;
  const std::vector<double> turns = turning_angles(r);
  ASSERT_GE(turns.size(), 2u);
  // One switch at the start (the rate leaves 0: friction_down on) and one per turn (both loads).
  EXPECT_EQ(r.load_switches, static_cast<long>(turns.size()) + 1);
  double phi = 0.0;
  for (const double turn : turns) {
    phi = next_turning_angle(phi, 1.0);
    EXPECT_NEAR(turn, phi, 1e-6);
  }
  // T + V − W held although the pin torque flips at every turn.
  EXPECT_LT(r.energy_max_drift, 1e-8 * r.energy_scale);
}

TEST(SimulateEvents, CoulombPendulumThatSticksStopsAsSlidingWhereGravityIsBelowTheFriction) {
  // T = 2 N*m: the turning angles shrink until the gravity torque there, m g l_c |cos φ|, is
  // below T; the switched torques then chatter and the run stops (status sliding) at the
  // sticking angle instead of stepping for ever (or drifting, as before events).
  const Model model = parse_mechanism(coulomb_pendulum(2.0), "pendulum-test");
  SimulateOptions o;
  o.t_end = 20.0;
  o.dt_out = 1e-3;
  const SimulateResult r = simulate(model, o);
  ASSERT_EQ(r.status, SimulateStatus::sliding) << r.message;
  EXPECT_NE(r.message.find("chatter"), std::string::npos) << r.message;
  EXPECT_LT(r.final.t, o.t_end);
  // The oracle's sequence of turning angles up to the first whose gravity torque is below T.
  double phi = 0.0;
  int turns = 0;
  while (turns < 100) {
    phi = next_turning_angle(phi, 2.0);
    ++turns;
    if (9.81 * 0.5 * std::abs(std::cos(phi)) <= 2.0) break;
  }
  EXPECT_NEAR(r.final.measures[0], phi, 1e-5);
  EXPECT_EQ(static_cast<int>(turning_angles(r).size()), turns - 1);
}

// Without friction, with end stops at [−60°, 60°] of its pin and restitution e.
std::string pendulum_on_stops(double e) {
  return pendulum(", limits: [-1.0471975511965976, 1.0471975511965976], end_stops: {restitution: " +
                      std::to_string(e) + "}",
                  "");
}

constexpr double kStop = -kPi / 3.0;
// J_O = 1/12 + 1/4 kg m²; the fall from 0 to −60°: m g l_c sin 60°.
constexpr double kJO = 0.0833333333333333 + 0.25;
const double kDrop = 9.81 * 0.5 * std::sin(kPi / 3.0);

TEST(SimulateEvents, PendulumOnAnEndStopReboundsAtRestitutionAndComesToRest) {
  const Model model = parse_mechanism(pendulum_on_stops(0.5), "pendulum-test");
  const double omega0 = std::sqrt(2.0 * kDrop / kJO);
  for (DynamicsForm form : {DynamicsForm::dual, DynamicsForm::primal}) {
    SCOPED_TRACE(form == DynamicsForm::dual ? "dual" : "primal");
    const SimulateOptions o = tight(10.0, 1e-3, form);
    const SimulateResult r = simulate(model, o);
    // The bounces shrink by e each: it comes to rest against the stop and is held there (a
    // resting contact) to the end; the last impact, where the hold begins, takes what speed is
    // left (e = 0).
    ASSERT_EQ(r.status, SimulateStatus::completed) << r.message;
    ASSERT_EQ(r.contacts.size(), 1u);
    EXPECT_EQ(r.contacts[0].side, 1);
    EXPECT_TRUE(std::isnan(r.contacts[0].t_to));
    ASSERT_GE(r.impacts.size(), 12u);
    EXPECT_EQ(r.impacts.back().t, r.contacts[0].t_from);
    EXPECT_EQ(r.impacts.back().speed_after, 0.0);
    EXPECT_NEAR(r.impacts[0].speed_before, omega0, 1e-7 * omega0);
    double lost = 0.0;
    for (size_t k = 0; k < r.impacts.size(); ++k) {
      const auto& i = r.impacts[k];
      EXPECT_EQ(i.side, 1);  // the lower stop
      const double e = k + 1 < r.impacts.size() ? 0.5 : 0.0;
      EXPECT_NEAR(i.speed_after, e * i.speed_before, 1e-12 * omega0);
      // The loss is the kinetic energy the speed change takes: ½ J_O (ω⁻² − ω⁺²).
      EXPECT_NEAR(i.energy_loss,
                  0.5 * kJO * (i.speed_before * i.speed_before - i.speed_after * i.speed_after),
                  1e-9 * kDrop);
      // Conservative flight: it comes back at the speed it left.
      if (k + 1 < r.impacts.size() && i.speed_after > 1e-4 * omega0) {
        EXPECT_NEAR(r.impacts[k + 1].speed_before, i.speed_after, 1e-7 * omega0) << k;
      }
      lost += i.energy_loss;
    }
    EXPECT_NEAR(lost, kDrop, 1e-6 * kDrop);
    // Held on the stop from there to the end (10 s), at rest.
    EXPECT_NEAR(r.final.t, o.t_end, 1e-9);
    EXPECT_NEAR(r.final.measures[0], kStop, 1e-9);
    EXPECT_EQ(r.final.u.norm(), 0.0);
    for (const SimulationSample& smp : r.samples) {
      ASSERT_GE(smp.measures[0], kStop - 1e-8) << smp.t;
    }
    // T + V − W level through the impacts (their losses are in W).
    EXPECT_LT(r.energy_max_drift, 1e-7 * r.energy_scale);
  }
}

TEST(SimulateEvents, ElasticEndStopKeepsTheEnergyAndTheSwingWithinTheLimits) {
  const Model model = parse_mechanism(pendulum_on_stops(1.0), "pendulum-test");
  const double omega0 = std::sqrt(2.0 * kDrop / kJO);
  const SimulateOptions o = tight(3.0, 1e-3);
  const SimulateResult r = simulate(model, o);
  ASSERT_EQ(r.status, SimulateStatus::completed) << r.message;
  ASSERT_GE(r.impacts.size(), 3u);
  for (const auto& i : r.impacts) {
    EXPECT_NEAR(i.speed_before, omega0, 1e-7 * omega0);
    EXPECT_NEAR(i.speed_after, omega0, 1e-7 * omega0);
    EXPECT_NEAR(i.energy_loss, 0.0, 1e-12);
  }
  // Back to the start's height (φ = 0) after the first impact, and never beyond the stop.
  double top = -10.0, bottom = 10.0;
  for (const SimulationSample& smp : r.samples) {
    if (smp.t > r.impacts[0].t) top = std::max(top, smp.measures[0]);
    bottom = std::min(bottom, smp.measures[0]);
  }
  EXPECT_NEAR(top, 0.0, 1e-5);  // (a sample within 5e-4 s of the top: ½ φ̈ (5e-4)² < 2e-6)
  EXPECT_GE(bottom, kStop - 1e-8);
  EXPECT_LT(r.energy_max_drift, 1e-8 * r.energy_scale);
}

}  // namespace
}  // namespace orthomech

namespace orthomech {
namespace {

// The pendulum of the tests above with Coulomb friction in its pin (`friction:`, μ r): the
// oracle is its 1-DOF equation written here, J_O φ̈ = −m g l_c cos φ − μ r |F| sgn φ̇, with the
// pin force F = m (a_G − g) that depends on φ̈ itself (a_G = l_c (−sin φ φ̈ − cos φ φ̇²,
// cos φ φ̈ − sin φ φ̇²)), solved by fixed point at each evaluation and integrated by RK4.
struct FrictionPendulum {
  double mu_r = 0.0;
  double phi = 0.0, w = 0.0;
  [[nodiscard]] double accel(double p, double v) const {
    const double m = 1.0, l = 0.5, J = 1.0 / 3.0, g = 9.81;
    double a = -m * g * l * std::cos(p) / J;
    if (v == 0.0) return a;
    for (int it = 0; it < 200; ++it) {
      const double ax = l * (-std::sin(p) * a - std::cos(p) * v * v);
      const double ay = l * (std::cos(p) * a - std::sin(p) * v * v);
      const double F = m * std::hypot(ax, ay + g);
      const double next = (-m * g * l * std::cos(p) - mu_r * F * (v > 0.0 ? 1.0 : -1.0)) / J;
      const bool done = std::abs(next - a) <= 1e-15 * std::abs(next);
      a = next;
      if (done) break;
    }
    return a;
  }
  void step(double h) {
    const double k1p = w, k1w = accel(phi, w);
    const double k2p = w + 0.5 * h * k1w, k2w = accel(phi + 0.5 * h * k1p, w + 0.5 * h * k1w);
    const double k3p = w + 0.5 * h * k2w, k3w = accel(phi + 0.5 * h * k2p, w + 0.5 * h * k2w);
    const double k4p = w + h * k3w, k4w = accel(phi + h * k3p, w + h * k3w);
    phi += h / 6.0 * (k1p + 2 * k2p + 2 * k3p + k4p);
    w += h / 6.0 * (k1w + 2 * k2w + 2 * k3w + k4w);
  }
};

std::string friction_pendulum(double mu, double radius) {
  return pendulum(", friction: {coefficient: " + std::to_string(mu) +
                      ", radius: " + std::to_string(radius) + "}",
                  "");
}

TEST(SimulateEvents, PinFrictionPendulumFollowsItsOneDofEquation) {
  const Model model = parse_mechanism(friction_pendulum(0.2, 0.05), "pendulum-test");
  for (DynamicsForm form : {DynamicsForm::dual, DynamicsForm::primal}) {
    SCOPED_TRACE(form == DynamicsForm::dual ? "dual" : "primal");
    const SimulateOptions o = tight(2.0, 0.01, form);
    const SimulateResult r = simulate(model, o);
    ASSERT_EQ(r.status, SimulateStatus::completed) << r.message;
    FrictionPendulum oracle{0.2 * 0.05};
    const double h = 1e-5;
    long taken = 0;  // (steps counted, not times summed: a step too many is ω h)
    double worst = 0.0;
    for (const SimulationSample& smp : r.samples) {
      for (const long due = std::lround(smp.t / h); taken < due; ++taken) oracle.step(h);
      worst = std::max(worst, std::abs(smp.measures[0] - oracle.phi));
    }
    EXPECT_LT(worst, 1e-6);
    // The moment reverses at every turning point (and once at the start, from rest).
    EXPECT_GE(r.friction_switches, 3);
    // The pin dissipates: W < 0, and T + V − W stays level.
    EXPECT_LT(r.final.work, -1e-3);
    EXPECT_LT(r.energy_max_drift, 1e-8 * r.energy_scale);
  }
}

TEST(SimulateEvents, PinFrictionPendulumSticksWhereGravityIsBelowTheStaticMoment) {
  // μ r = 0.15 m: at rest the pin carries m g, so the friction can hold the pendulum wherever
  // m g l_c |cos φ| ≤ μ r m g, |cos φ| ≤ 0.3: the first turning point there is where it sticks,
  // and it stays stuck (held at rest by its static friction) to the end.
  const Model model = parse_mechanism(friction_pendulum(0.5, 0.3), "pendulum-test");
  FrictionPendulum oracle{0.15};
  double turning = 0.0;
  for (int steps = 0; steps < 1000000; ++steps) {
    const double w0 = oracle.w;
    oracle.step(1e-5);
    if (steps > 0 && (w0 > 0.0) != (oracle.w > 0.0) && std::abs(std::cos(oracle.phi)) <= 0.3) {
      turning = oracle.phi;
      break;
    }
  }
  ASSERT_NE(turning, 0.0);
  for (DynamicsForm form : {DynamicsForm::dual, DynamicsForm::primal}) {
    SCOPED_TRACE(form == DynamicsForm::dual ? "dual" : "primal");
    const SimulateOptions o = tight(10.0, 0.01, form);
    const SimulateResult r = simulate(model, o);
    ASSERT_EQ(r.status, SimulateStatus::completed) << r.message;
    ASSERT_EQ(r.contacts.size(), 1u);
    EXPECT_EQ(r.contacts[0].side, 0) << "stuck by friction";
    EXPECT_TRUE(std::isnan(r.contacts[0].t_to));
    EXPECT_NEAR(r.final.t, o.t_end, 1e-9);
    EXPECT_NEAR(r.final.measures[0], turning, 1e-6);
    EXPECT_EQ(r.final.u.norm(), 0.0);
    EXPECT_LT(r.energy_max_drift, 1e-8 * r.energy_scale);
  }
}

}  // namespace
}  // namespace orthomech
