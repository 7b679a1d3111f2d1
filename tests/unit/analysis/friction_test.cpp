// Pin friction in the driven kinetostatics (src/analysis/friction.cpp, compute_driven's fixed
// point) against two oracles:
//   - a crank turning at constant ω about a ground pin with friction (written here): the pin
//     force is the Newton–Euler one, R = m (a_G − g) with a_G = −ω² r_G, and the drive is the
//     frictionless m g x_G plus μ r |R|;
//   - the power balance of the crank-rocker with friction in all four pins: with the same
//     motion, the drive's extra power is what the pins dissipate, (τ − τ₀) ṡ = Σ μ r |F| |ω_rel|
//     at every position, |F| from the reported multipliers (it holds only at the fixed point:
//     one pass from the frictionless forces misses it by the change of |F|).
#include "orthomech/analysis/friction.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "orthomech/analysis/cycle.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "support/fixtures.hpp"

namespace orthomech {
namespace {

constexpr double m = 2.0, c = 0.1, mu = 0.2, r = 0.01, omega = 10.0, g = 9.81;

const char* kCrank = R"(orthomech: 1
name: crank-with-pin-friction
units: {length: m, angle: rad, mass: kg, time: s, force: N}
ground:
  points: {O: [0, 0]}
bodies:
  - name: crank
    mass: 2
    inertia: 0.01
    com: [0.1, 0]
    pose: [0, 0, 0.3]
    points: {O: [0, 0]}
joints:
  - {name: O, type: revolute, connects: [ground.O, crank.O], friction: {coefficient: 0.2, radius: 0.01}}
loads:
  - {name: weight, type: gravity, g: [0, -9.81]}
drivers:
  - {name: motor, joint: O, speed: 10 rad/s}
analysis: {driver: motor, steps: 36}
)";

TEST(Friction, DrivenCrankAgainstNewtonEuler) {
  const Model model = parse_mechanism(kCrank, "crank (test)");
  ASSERT_EQ(friction_pins(model).size(), 1u);
  const CycleResult res = test::full_cycle(model, 36);
  ASSERT_EQ(res.status, CycleStatus::completed) << res.message;
  for (const DrivenPointView p : res.points) {
    const double th = p.q(2);
    const Vec2 aG = -omega * omega * c * Vec2(std::cos(th), std::sin(th));
    const double R = m * (aG - Vec2(0.0, -g)).norm();
    EXPECT_NEAR(p.drive_frictionless, m * g * c * std::cos(th), 1e-12) << th;
    EXPECT_NEAR(p.drive - p.drive_frictionless, mu * r * R, 1e-12) << th;
    EXPECT_NEAR(std::hypot(p.lambda(0), p.lambda(1)), R, 1e-10) << th;
    EXPECT_GT(p.friction_iterations, 0);
  }
}

TEST(Friction, CrankRockerPinsDissipateTheDrivesExtraPower) {
  std::vector<FileChange> changes;
  for (const char* j : {"A0", "A", "B", "B0"})
    changes.push_back(
        parse_file_change(std::string("joints.") + j + ".friction={coefficient: 0.15, radius: 4}"));
  const Model model = load_mechanism(test::source_path("mechanisms/crank-rocker.yaml"), changes);
  const std::vector<FrictionPin> pins = friction_pins(model);
  ASSERT_EQ(pins.size(), 4u);
  const CycleResult res = test::full_cycle(model, 90);
  ASSERT_EQ(res.status, CycleStatus::completed) << res.message;
  std::vector<double> moments;
  double largest = 0.0;
  for (const DrivenPointView p : res.points) {
    const double power = friction_moments(pins, p.u, p.lambda, moments);
    const double extra = (p.drive - p.drive_frictionless) * p.input_rate;
    EXPECT_NEAR(extra, power, 1e-9 * std::abs(p.drive * p.input_rate)) << p.input;
    EXPECT_GT(power, 0.0);
    EXPECT_GT(p.friction_iterations, 1);  // the forces moved: more than one pass
    EXPECT_LE(p.friction_iterations, 30);
    largest = std::max(largest, std::abs(p.drive - p.drive_frictionless));
  }
  EXPECT_GT(largest, 1e-3);  // N·m: friction changes the drive visibly (μ r ≈ 0.6 mm)
}

TEST(Friction, TheFileRefusesBadFriction) {
  const std::string base = kCrank;
  auto with = [&](const std::string& friction) {
    std::string text = base;
    text.replace(text.find("{coefficient: 0.2, radius: 0.01}"),
                 std::string("{coefficient: 0.2, radius: 0.01}").size(), friction);
    return text;
  };
  EXPECT_THROW((void)parse_mechanism(with("{coefficient: -0.1, radius: 0.01}"), "t"), InputError);
  EXPECT_THROW((void)parse_mechanism(with("{coefficient: 0.1, radius: 0}"), "t"), InputError);
  EXPECT_THROW((void)parse_mechanism(with("{coefficient: 0.1}"), "t"), InputError);
  EXPECT_THROW((void)parse_mechanism(with("{coefficient: 0.1, radius: 1, stribeck: 2}"), "t"),
               InputError);
}

}  // namespace
}  // namespace orthomech
