// Initial velocities in the mechanism file (`initial: {rates: {…}}`, docs/file-format.md): read
// in the file's units, used by simulate unless the caller gives its own rates (issue 10, item 7).
// Oracle: the IFToMM A02 initial state in closed form (every link turns at −1 rad/s, every
// coupler translates at 1 m/s: T0 = (N + 1)/6 + N/2) and unit conversions by hand.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>

#include "orthomech/dynamics/simulate.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/model/free_system.hpp"
#include "support/cli_runner.hpp"
#include "support/fixtures.hpp"

namespace orthomech {
namespace {

// Rounding of a few arithmetic operations on O(1) numbers.
constexpr double kTight = 1e-12;

std::string crank_file(const std::string& units, const std::string& rates) {
  return "orthomech: 1\nunits: " + units +
         "\nground:\n  points: {O: [0, 0]}\nbodies:\n"
         "  - {name: crank, mass: 1, inertia: 0.1, pose: [0, 0, 0], points: {A: [0, 0], B: [100, "
         "0]}}\njoints:\n  - {name: A, type: revolute, connects: [ground.O, crank.A]}\n"
         "measures:\n  - {name: angle, type: joint, joint: A}\n"
         "  - {name: Bx, type: point, point: crank.B, component: x}\n"
         "  - {name: Bvy, type: point, point: crank.B, component: y, derivative: 1}\n"
         "initial:\n  rates: " +
         rates + "\n";
}

TEST(InitialRates, ReadInTheFilesUnits) {
  // deg and mm per s: 30 deg/s = π/6 rad/s; 250 mm/s = 0.25 m/s; a velocity measure names the
  // rate of its position quantity (the value it has at t = 0).
  const Model m = parse_mechanism(
      crank_file("{length: mm, angle: deg, time: s}", "{angle: 30, Bx: 250, Bvy: -40}"), "t.yaml");
  ASSERT_EQ(m.initial.rates.size(), 3u);
  EXPECT_EQ(m.initial.rates[0].measure, m.find_measure("angle"));
  EXPECT_NEAR(m.initial.rates[0].rate, std::numbers::pi / 6.0, kTight);
  EXPECT_NEAR(m.initial.rates[1].rate, 0.25, kTight);
  EXPECT_NEAR(m.initial.rates[2].rate, -0.04, kTight);
  EXPECT_EQ(m.initial.rates[0].where.line, 14);  // the line of `rates:`
  // A string with its own unit: 60 rpm = 2π rad/s; 1 m/s whatever the file's length unit.
  const Model s = parse_mechanism(
      crank_file("{length: mm, angle: deg}", "{angle: '60 rpm', Bx: 1 m/s}"), "s.yaml");
  EXPECT_NEAR(s.initial.rates[0].rate, 2.0 * std::numbers::pi, kTight);
  EXPECT_NEAR(s.initial.rates[1].rate, 1.0, kTight);
}

// A02 N = 2 from the file alone: the benchmark's initial state.
TEST(InitialRates, NFourBarFileGivesTheBenchmarkVelocity) {
  const Model model = test::load_bundled("n-four-bar-2");
  ASSERT_EQ(model.initial.rates.size(), 1u);
  SimulateOptions o;
  o.t_end = 0.01;
  o.dt_out = 0.01;
  o.reactions = false;
  const SimulateResult r = simulate(model, o);
  ASSERT_EQ(r.status, SimulateStatus::completed) << r.message;
  const SimulationSample& s0 = r.samples.front();
  const int N = 2;
  EXPECT_NEAR(s0.kinetic, (N + 1) / 6.0 + N / 2.0, kTight);
  EXPECT_NEAR(s0.measures[static_cast<size_t>(model.find_measure("B0_vx"))], 1.0, kTight);
  EXPECT_NEAR(s0.measures[static_cast<size_t>(model.find_measure("B0_vy"))], 0.0, kTight);
  for (int k = 0; k <= N; ++k)
    EXPECT_NEAR(body_angular_velocity(model, model.find_body("link" + std::to_string(k)), s0.u),
                -1.0, kTight);

  // The caller's rates replace the file's: B0 at 2 m/s is 4 T0.
  o.initial_rates = {{model.find_measure("B0_x"), 2.0}};
  EXPECT_NEAR(simulate(model, o).samples.front().kinetic, 4.0 * ((N + 1) / 6.0 + N / 2.0), kTight);
  // Or are switched off: at rest.
  o.initial_rates.clear();
  o.use_file_rates = false;
  EXPECT_NEAR(simulate(model, o).samples.front().kinetic, 0.0, kTight);
}

// A zero rate is an input like any other (at rest in that coordinate). A double pendulum of two
// rods (1 kg, 0.1 kg m² about the centre, 1 m, hinged at O and at their common end): with the
// first hinge at 1 rad/s and the second at 0 the pair turns as one rigid body about O, so
// T = ½ ω² Σ (m r_c² + J) = ½ (0.25 + 0.1 + 2.25 + 0.1) = 1.35 J; with the first rate alone the
// least-squares velocity is another one (the zero is not the same as no rate).
TEST(InitialRates, AZeroRateHoldsItsCoordinateAtRest) {
  auto pendulum = [](const std::string& rates) {
    return "orthomech: 1\nground:\n  points: {O: [0, 0]}\nbodies:\n"
           "  - {name: a, mass: 1, inertia: 0.1, pose: [0.5, 0, 0], points: {O: [-0.5, 0], B: "
           "[0.5, 0]}}\n"
           "  - {name: b, mass: 1, inertia: 0.1, pose: [1.5, 0, 0], points: {B: [-0.5, 0]}}\n"
           "joints:\n  - {name: J1, type: revolute, connects: [ground.O, a.O]}\n"
           "  - {name: J2, type: revolute, connects: [a.B, b.B]}\n"
           "measures:\n  - {name: t1, type: joint, joint: J1}\n"
           "  - {name: t2, type: joint, joint: J2}\n"
           "  - {name: w2, type: joint, joint: J2, derivative: 1}\n"
           "initial:\n  rates: " +
           rates + "\n";
  };
  const Model m = parse_mechanism(pendulum("{t1: 1, t2: 0}"), "zero.yaml");
  ASSERT_EQ(m.initial.rates.size(), 2u);
  EXPECT_EQ(m.initial.rates[1].rate, 0.0);
  SimulateOptions o;
  o.t_end = 1e-3;
  o.dt_out = 1e-3;
  o.reactions = false;
  const SimulateResult r = simulate(m, o);
  ASSERT_EQ(r.status, SimulateStatus::completed) << r.message;
  EXPECT_NEAR(r.samples.front().kinetic, 1.35, kTight);
  EXPECT_NEAR(r.samples.front().measures[static_cast<size_t>(m.find_measure("w2"))], 0.0, kTight);
  // '0 rpm' with its unit too; without the zero the start differs.
  const Model with_unit = parse_mechanism(pendulum("{t1: 1, t2: '0 rpm'}"), "zero.yaml");
  EXPECT_EQ(with_unit.initial.rates[1].rate, 0.0);
  const SimulateResult one = simulate(parse_mechanism(pendulum("{t1: 1}"), "one.yaml"), o);
  ASSERT_EQ(one.status, SimulateStatus::completed) << one.message;
  EXPECT_GT(std::abs(one.samples.front().kinetic - 1.35), 1e-3);
}

TEST(InitialRates, CliUsesTheFileAndRateOverridesIt) {
  const std::string file = test::source_path("mechanisms/n-four-bar-2.yaml");
  const auto a = test::run_cli({"simulate", file, "--t-end", "0.01", "--json"});
  ASSERT_EQ(a.status, 0) << a.err;
  EXPECT_NEAR(nlohmann::json::parse(a.out)["samples"]["kinetic"][0].get<double>(), 1.5, kTight);
  const auto b = test::run_cli({"simulate", file, "--t-end", "0.01", "--rate", "B0_x=2", "--json"});
  ASSERT_EQ(b.status, 0) << b.err;
  EXPECT_NEAR(nlohmann::json::parse(b.out)["samples"]["kinetic"][0].get<double>(), 6.0, kTight);
}

}  // namespace
}  // namespace orthomech
