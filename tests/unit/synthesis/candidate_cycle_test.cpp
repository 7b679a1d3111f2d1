// Step 4 of run_synthesis (src/synthesis/candidate_cycle.cpp): an accepted candidate's file
// through `cycle`; its peak drive torque against the rate of the closed form's kinetic energy.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "orthomech/synthesis/synthesize.hpp"

namespace orthomech::synthesis {
namespace {

std::string example(const std::string& name) {
  return std::string(ORTHOMECH_SOURCE_DIR) + "/examples/" + name;
}

// The kinetic energy of the four-bar's three uniform rods at crank angle θ and unit crank rate,
// from closed-form positions (calc_position) and central differences of them: T/ω².
double kinetic_per_rate(const FourBar& fb, double theta, double mass_per_length) {
  constexpr double h = 1e-5;
  const FourBarPosition m = calc_position(fb, theta - h), p = calc_position(fb, theta + h);
  const auto rod = [&](const Vec2& a0, const Vec2& a1, const Vec2& b0, const Vec2& b1,
                       double length) {  // ends at θ − h (a) and θ + h (b)
    const double mass = mass_per_length * length;
    const Vec2 vc = ((b0 + b1) - (a0 + a1)) / (4 * h);
    const double w = std::remainder(std::atan2((b1 - b0).y(), (b1 - b0).x()) -
                                        std::atan2((a1 - a0).y(), (a1 - a0).x()),
                                    2 * std::numbers::pi) /
                     (2 * h);
    return 0.5 * (mass * vc.squaredNorm() + mass * length * length / 12 * w * w);
  };
  return rod(fb.A0, m.A, fb.A0, p.A, fb.a) + rod(m.A, m.B, p.A, p.B, fb.b) +
         rod(fb.B0, m.B, fb.B0, p.B, fb.c);
}

// The peak drive torque that ranks candidates is `cycle`'s on the candidate's file. Its oracle:
// without gravity and at constant crank rate ω the drive's power is the kinetic energy's rate,
// τ ω = dT/dt, so τ(θ) = ω² d(T/ω²)/dθ, by central differences of kinetic_per_rate on the cycle's
// grid (the first target's crank angle and 359 steps of 1°).
TEST(Synthesize, PeakDriveTorqueIsTheRateOfTheKineticEnergy) {
  const SynthesisTask task = load_synthesis_task(example("synthesis-motion.yaml"));
  const SynthesisResult r = run_synthesis(task);
  ASSERT_FALSE(r.accepted.empty()) << r.message;
  for (const SynthesisCandidate& c : r.accepted) {
    ASSERT_TRUE(c.cycle.has_value()) << c.name;
    EXPECT_EQ(c.cycle->positions, 360);
    EXPECT_NEAR(c.cycle->to - c.cycle->from, 2 * std::numbers::pi, 1e-12);
    const FourBar& fb = std::get<FourBar>(c.linkage);
    const double w2 = task.speed * task.speed, dt = 1e-4;
    double peak = 0.0;
    for (int k = 0; k < 360; ++k) {
      const double theta = c.crank_angles.front() + k * std::numbers::pi / 180;
      const double tau = w2 *
                         (kinetic_per_rate(fb, theta + dt, task.mass_per_length) -
                          kinetic_per_rate(fb, theta - dt, task.mass_per_length)) /
                         (2 * dt);
      peak = std::max(peak, std::abs(tau));
    }
    EXPECT_NEAR(c.cycle->peak_drive, peak, 1e-5 * peak) << c.name;
    EXPECT_GT(c.cycle->peak_pin_force, 0.0);
    EXPECT_FALSE(c.cycle->peak_pin.empty());
  }
}

}  // namespace
}  // namespace orthomech::synthesis
