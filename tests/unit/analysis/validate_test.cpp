// Validation of design positions (issue 4) against independent oracles:
//  - Grashof type: the rotatability of each joint from the triangle inequality (a joint angle
//    turns fully iff the diagonal it spans can take every value its two links allow);
//  - transmission angle: the law of cosines cos μ = (b² + c² − |AB0|²)/(2bc);
//  - dead points of the non-Grashof double-rocker: cos θ = (a² + d² − (b + c)²)/(2ad);
//  - defects on files whose targets are closed-form circle intersections (tests/data/validate).
#include "orthomech/analysis/validate.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <set>
#include <sstream>
#include <string>

#include "orthomech/io/mechanism_file.hpp"
#include "support/fixtures.hpp"
#include "unit/analysis/large_mechanisms.hpp"

namespace orthomech {
namespace {

constexpr double kPi = std::numbers::pi;

// a joint angle between links p and q turns fully iff the diagonal opposite can take every
// value in [|p − q|, p + q], i.e. that interval lies inside the one allowed by the other two.
bool turns(double p, double q, double r, double s) {
  return std::abs(r - s) <= std::abs(p - q) && p + q <= r + s;
}

TEST(Grashof, RandomFourBarsAgainstRotatabilityOracle) {
  std::mt19937 gen(2024);
  std::uniform_real_distribution<double> len(0.1, 10.0);
  int counted[6] = {0, 0, 0, 0, 0, 0};
  for (int trial = 0; trial < 20000; ++trial) {
    const double d = len(gen), a = len(gen), b = len(gen), c = len(gen);
    const double sum = a + b + c + d;
    const double s = std::min({a, b, c, d}), l = std::max({a, b, c, d});
    if (std::abs((s + l) - (sum - s - l)) < 1e-6 * sum) continue;  // folding case: no oracle
    const GrashofType t = classify_grashof(d, a, b, c);
    const bool input = turns(d, a, b, c);   // angle at A0 (ground–crank)
    const bool output = turns(d, c, a, b);  // angle at B0 (ground–follower)
    const bool at_A = turns(a, b, d, c);    // crank–coupler
    const bool at_B = turns(b, c, d, a);    // coupler–follower
    GrashofType expected;
    if (input && output)
      expected = GrashofType::double_crank;
    else if (input)
      expected = GrashofType::crank_rocker;
    else if (output)
      expected = GrashofType::rocker_crank;
    else if (at_A || at_B)
      expected = GrashofType::grashof_double_rocker;
    else
      expected = GrashofType::triple_rocker;
    ASSERT_EQ(t, expected) << "d " << d << " a " << a << " b " << b << " c " << c;
    ++counted[static_cast<int>(t)];
  }
  for (int k = 0; k < 5; ++k) EXPECT_GT(counted[k], 100) << "type " << k;  // all types seen
}

TEST(Grashof, FoldingCaseIsAChangePoint) {
  EXPECT_EQ(classify_grashof(3, 1, 3, 1), GrashofType::change_point);  // parallelogram
  EXPECT_EQ(classify_grashof(4, 1, 2, 3), GrashofType::change_point);  // 1 + 4 = 2 + 3
}

std::string four_bar(double a, double b, double c, double d) {
  std::ostringstream s;
  s.precision(17);
  s << "orthomech: 1\nground:\n  points: {A0: [0, 0], B0: [" << d << ", 0]}\nbodies:\n"
    << "  - {name: crank, mass: 1, inertia: 0.1, pose: [0, 0, 0], points: {A0: [0, 0], A: [" << a
    << ", 0]}}\n"
    << "  - {name: coupler, mass: 1, inertia: 0.1, pose: [" << a
    << ", 0, 0], points: {A: [0, 0], B: [" << b << ", 0]}}\n"
    << "  - {name: rocker, mass: 1, inertia: 0.1, pose: [" << d
    << ", 0, 1.5], points: {B0: [0, 0], B: [" << c << ", 0]}}\n"
    << "joints:\n"
    << "  - {name: J1, type: revolute, connects: [coupler.B, rocker.B]}\n"
    << "  - {name: B0, type: revolute, connects: [ground.B0, rocker.B0]}\n"
    << "  - {name: A0, type: revolute, connects: [ground.A0, crank.A0]}\n"
    << "  - {name: A, type: revolute, connects: [crank.A, coupler.A]}\n";
  return s.str();
}

// A large model (issue 18): the N-four-bar with N = 100 has exactly N four-bar loops, cell k
// being ground –O_k– link k –L_k– coupler k –R_k– link k+1 –O_{k+1}– ground, every one a
// parallelogram of 1 m sides (s + l = p + q: a change point); the one with the input O0 starts
// there. (Before, the search scanned every body for every pin: 7.4 s for `validate` at N = 400.)
TEST(FourBarLoops, EveryCellOfTheNFourBarOnce) {
  constexpr int N = 100;
  const Model m = parse_mechanism(test::n_four_bar_yaml(N, 1.1), "n-four-bar-100.yaml");
  const int O0 = m.find_joint("O0");
  const auto loops = find_four_bar_loops(m, O0);
  ASSERT_EQ(loops.size(), static_cast<size_t>(N));
  // Names built by append: g++ 12 reports a false -Wrestrict on `"O" + std::to_string(c)` here.
  const auto joint = [](char letter, int c) {
    std::string name(1, letter);
    name += std::to_string(c);
    return name;
  };
  std::set<int> cells;
  for (const FourBarLoop& l : loops) {
    std::set<std::string> names;
    for (const int j : l.joints) names.insert(m.joints[static_cast<size_t>(j)].name);
    int k = -1;
    for (int c = 0; c < N && k < 0; ++c)
      if (names ==
          std::set<std::string>{joint('O', c), joint('L', c), joint('R', c), joint('O', c + 1)})
        k = c;
    ASSERT_GE(k, 0) << "a loop that is not a cell";
    cells.insert(k);
    EXPECT_EQ(l.frame, kGround);
    for (const double len : {l.ground, l.crank, l.coupler, l.follower})
      EXPECT_NEAR(len, 1.0, 1e-12);
    EXPECT_EQ(l.type, GrashofType::change_point);
    if (k == 0) {
      EXPECT_EQ(l.joints[0], O0);
    }
  }
  EXPECT_EQ(cells.size(), static_cast<size_t>(N));
}

TEST(FourBarLoops, FoundWithLengthsAndInputFirst_TransmissionAgainstLawOfCosines) {
  std::mt19937 gen(5);
  std::uniform_real_distribution<double> len(0.5, 5.0), ang(-kPi, kPi);
  int checked = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const double a = len(gen), b = len(gen), c = len(gen), d = len(gen);
    const Model m = parse_mechanism(four_bar(a, b, c, d), "fb");
    const int A0 = m.find_joint("A0");
    const auto loops = find_four_bar_loops(m, A0);
    ASSERT_EQ(loops.size(), 1u);
    const FourBarLoop& l = loops[0];
    EXPECT_EQ(l.joints[0], A0);  // oriented from the input pivot
    EXPECT_EQ(l.joints[3], m.find_joint("B0"));
    EXPECT_NEAR(l.ground, d, 1e-14);
    EXPECT_NEAR(l.crank, a, 1e-14);
    EXPECT_NEAR(l.coupler, b, 1e-14);
    EXPECT_NEAR(l.follower, c, 1e-14);
    EXPECT_EQ(l.type, classify_grashof(d, a, b, c));
    // A reachable crank angle: |AB0| within [|b − c|, b + c].
    const double theta = ang(gen);
    const double AB0 = std::sqrt(a * a + d * d - 2 * a * d * std::cos(theta));
    if (AB0 < std::abs(b - c) + 1e-3 || AB0 > b + c - 1e-3) continue;
    AssemblyOptions o;
    o.locks.push_back({A0, theta});
    VecX q = m.design_q();
    if (!project_with_locks(m, q, o.locks)) continue;  // from this drawing it may not converge
    const double mu = transmission_angle(m, l, q);
    const double expected = std::acos((b * b + c * c - AB0 * AB0) / (2 * b * c));
    EXPECT_NEAR(mu, expected, 1e-9) << a << " " << b << " " << c << " " << d << " " << theta;
    ++checked;
  }
  EXPECT_GT(checked, 10);
}

TEST(Validate, BundledCrankRocker_AllPositionsPass_TwoModesEach) {
  const Model m = test::load_bundled("crank-rocker");
  const ValidationReport r = validate_design_positions(m);
  EXPECT_TRUE(r.pass());
  ASSERT_EQ(r.positions.size(), 3u);
  for (const PositionReport& p : r.positions) {
    EXPECT_TRUE(p.pass()) << p.name << ": " << (p.failures.empty() ? "" : p.failures[0]);
    EXPECT_EQ(p.dof, 1);
    EXPECT_EQ(p.modes, 2) << p.name;  // a circle pair meets twice
    EXPECT_EQ(p.mode_signature, r.positions[0].mode_signature);
    EXPECT_EQ(p.circuit, 1);
    EXPECT_FALSE(p.singular_distance.has_value());  // no dead point driven from the crank
    ASSERT_EQ(p.four_bars.size(), 1u);
    EXPECT_EQ(p.four_bars[0].type, GrashofType::crank_rocker);
  }
  EXPECT_EQ(r.circuits, 1);
}

Model load_data(const std::string& name) {
  return load_mechanism(test::source_path("tests/data/validate/" + name + ".yaml"));
}

TEST(Validate, CircuitDefect_CrossedCircuitPosition) {
  const ValidationReport r = validate_design_positions(load_data("crank-rocker-circuit-defect"));
  EXPECT_FALSE(r.pass());
  EXPECT_TRUE(r.circuit_defect);
  EXPECT_FALSE(r.branch_defect);
  EXPECT_FALSE(r.order_defect);
  ASSERT_EQ(r.positions.size(), 3u);
  EXPECT_EQ(r.positions[0].circuit, 1);
  EXPECT_EQ(r.positions[1].circuit, 2);
  EXPECT_EQ(r.positions[2].circuit, 1);
  EXPECT_NE(r.positions[1].mode_signature, r.positions[0].mode_signature);
  for (const PositionReport& p : r.positions) EXPECT_TRUE(p.target_met) << p.name;
}

TEST(Validate, BranchDefect_DeadPointsAtClosedFormInput) {
  const ValidationReport r = validate_design_positions(load_data("double-rocker-branch-defect"));
  EXPECT_FALSE(r.pass());
  EXPECT_TRUE(r.branch_defect);
  EXPECT_FALSE(r.circuit_defect);
  EXPECT_FALSE(r.order_defect);
  ASSERT_EQ(r.positions.size(), 2u);
  EXPECT_EQ(r.positions[0].circuit, r.positions[1].circuit);
  EXPECT_NE(r.positions[0].branch, r.positions[1].branch);
  // cos θ* = (a² + d² − (b + c)²)/(2ad), a 60, b 40, c 65, d 100 (mm).
  const double theta = std::acos((60.0 * 60 + 100.0 * 100 - 105.0 * 105) / (2 * 60.0 * 100));
  ASSERT_TRUE(r.positions[0].singular_distance.has_value());
  EXPECT_NEAR(*r.positions[0].singular_distance, theta, 1e-9);  // p1 at input 0
  EXPECT_EQ(r.positions[0].singular_kind, "dead point");
  ASSERT_TRUE(r.positions[1].singular_distance.has_value());
  EXPECT_NEAR(*r.positions[1].singular_distance, theta - 40.0 * kPi / 180.0, 1e-9);
  EXPECT_NEAR(std::abs(*r.positions[1].singular_input), theta, 1e-9);
  EXPECT_EQ(r.positions[0].four_bars.at(0).type, GrashofType::triple_rocker);
}

TEST(Validate, OrderDefect_InputNotMonotone) {
  const ValidationReport r = validate_design_positions(load_data("crank-rocker-order-defect"));
  EXPECT_TRUE(r.order_defect);
  EXPECT_FALSE(r.circuit_defect);
  EXPECT_FALSE(r.branch_defect);
  EXPECT_FALSE(r.pass());
  EXPECT_TRUE(r.positions[0].pass());
  EXPECT_TRUE(r.positions[1].pass());
  EXPECT_FALSE(r.positions[2].pass());  // p3 goes back
}

TEST(Validate, TransmissionIndexVanishesAtTheDeadPoint) {
  // Double-rocker driven from its input: η → 0 at θ* (closed form), σ_min of Eᵀ does not (a dead
  // point of the input, not a change point).
  const Model m = test::load_bundled("double-rocker");
  const int A0 = m.find_joint("A0");
  const double theta = std::acos((60.0 * 60 + 100.0 * 100 - 105.0 * 105) / (2 * 60.0 * 100));
  VecX q0 = m.design_q(), q1 = m.design_q();
  ASSERT_TRUE(project_with_locks(m, q0, {{A0, 0.0}}));
  ASSERT_TRUE(project_with_locks(m, q1, {{A0, theta - 1e-8}}));
  const auto s0 = singularity_measures(m, q0, {A0}, 8);
  const auto s1 = singularity_measures(m, q1, {A0}, 8);
  ASSERT_TRUE(s0.eta && s1.eta);
  EXPECT_GT(*s0.eta, 1e-2);
  EXPECT_LT(*s1.eta, 1e-3);  // ~√(θ* − θ) near a fold
  EXPECT_GT(s1.sigma_min, 1e-2);
}

// Parallelogram (crank 1, coupler 3 on a 3 m ground, follower 1): s + l = p + q, change points
// where all links are collinear, at crank 0° and 180° (closed form).
std::string parallelogram(const std::string& positions) {
  return R"(orthomech: 1
units: {length: m, angle: deg}
ground:
  points: {A0: [0, 0], B0: [3, 0]}
bodies:
  - {name: crank, mass: 1, inertia: 0.1, com: [0.5, 0], pose: [0, 0, 30], points: {A0: [0, 0], A: [1, 0]}}
  - {name: coupler, mass: 1, inertia: 0.1, com: [1.5, 0], pose: [0.8660254037844387, 0.5, 0], points: {A: [0, 0], B: [3, 0]}}
  - {name: rocker, mass: 1, inertia: 0.1, com: [0.5, 0], pose: [3, 0, 30], points: {B0: [0, 0], B: [1, 0]}}
joints:
  - {name: A0, type: revolute, connects: [ground.A0, crank.A0]}
  - {name: A, type: revolute, connects: [crank.A, coupler.A]}
  - {name: B, type: revolute, connects: [coupler.B, rocker.B]}
  - {name: B0, type: revolute, connects: [rocker.B0, ground.B0]}
design_positions:
)" + positions;
}

TEST(Validate, ParallelogramChangePoints_DistanceAndBranchDefect) {
  constexpr double kChangePointTol = 1e-7;  // σ_min is V-shaped there: NLopt locates it to ~1e-9
  {
    const ValidationReport r = validate_design_positions(parse_mechanism(
        parallelogram("  - {name: p1, inputs: {A0: 30}}\n  - {name: p2, inputs: {A0: 120}}\n"),
        "para"));
    ASSERT_EQ(r.positions.size(), 2u);
    EXPECT_TRUE(r.pass());
    EXPECT_EQ(r.positions[0].four_bars.at(0).type, GrashofType::change_point);
    ASSERT_TRUE(r.positions[0].singular_distance && r.positions[1].singular_distance);
    EXPECT_NEAR(*r.positions[0].singular_distance, 30.0 * kPi / 180.0, kChangePointTol);
    EXPECT_NEAR(*r.positions[1].singular_distance, 60.0 * kPi / 180.0, kChangePointTol);
    EXPECT_EQ(r.positions[0].singular_kind, "change point");
  }
  {
    const ValidationReport r = validate_design_positions(parse_mechanism(
        parallelogram("  - {name: p1, inputs: {A0: 150}}\n  - {name: p2, inputs: {A0: 200}}\n"),
        "para"));
    EXPECT_TRUE(r.branch_defect);  // the change point at 180° lies between them
    EXPECT_FALSE(r.circuit_defect);
    EXPECT_FALSE(r.pass());
  }
}

TEST(Validate, PositionWithoutInputs_IsNotFixed) {
  // DOF 1 and no input: the position is not determined; a failure that says so (not a dead point).
  Model m = test::load_bundled("crank-rocker");
  m.design_positions.clear();
  DesignPosition p;
  p.name = "loose";
  m.design_positions.push_back(p);
  const ValidationReport r = validate_design_positions(m);
  ASSERT_EQ(r.positions.size(), 1u);
  EXPECT_TRUE(r.positions[0].assembles);
  EXPECT_FALSE(r.positions[0].singular.eta.has_value());
  ASSERT_EQ(r.positions[0].failures.size(), 1u);
  EXPECT_NE(r.positions[0].failures[0].find("do not fix"), std::string::npos);
}

TEST(Validate, PositionThatCannotAssemble_Fails) {
  // Input 90° is beyond the double-rocker's dead point (77.6°).
  Model m = test::load_bundled("double-rocker");
  m.design_positions.clear();
  DesignPosition p;
  p.name = "far";
  p.inputs.push_back({m.find_joint("A0"), 90.0 * kPi / 180.0});
  m.design_positions.push_back(p);
  const ValidationReport r = validate_design_positions(m);
  ASSERT_EQ(r.positions.size(), 1u);
  EXPECT_FALSE(r.positions[0].assembles);
  EXPECT_FALSE(r.pass());
  EXPECT_NE(r.positions[0].failures.at(0).find("cannot close"), std::string::npos);
}

}  // namespace
}  // namespace orthomech
