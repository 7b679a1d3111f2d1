// Nonholonomic constraint: the Chaplygin sled (a rigid body on a knife edge, no gravity).
// Oracles: the classical reduced equations [Neimark & Fufaev, Dynamics of Nonholonomic Systems,
// 1972, Ch. I] for the forward speed v of the contact point and the angular velocity ω, with the
// centre of mass a distance a ahead of the contact point along the blade:
//   v̇ = a ω²,  (J + m a²) ω̇ = −m a v ω,  φ̇ = ω,  ẋ_P = v cos φ,  ẏ_P = v sin φ,
// integrated by RK4 in the test; energy ½ m v² + ½ (J + m a²) ω² is conserved, ω → 0 and
// v → √(v0² + (J/m + a²) ω0²) (the classical behaviour).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <string>

#include "orthomech/constraints/joints.hpp"
#include "orthomech/dynamics/simulate.hpp"
#include "orthomech/error.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/model/free_system.hpp"

namespace orthomech {
namespace {

constexpr double kM = 1.0, kJ = 0.05, kA = 0.2, kV0 = 1.0, kW0 = 2.0;

const char* const kSled = R"(orthomech: 1
name: chaplygin-sled
units: {length: m, angle: rad, mass: kg}
bodies:
  - {name: sled, mass: 1, inertia: 0.05, com: [0.2, 0], pose: [0, 0, 0], points: {P: [0, 0]}}
nonholonomic:
  - {name: blade, type: knife-edge, point: sled.P, axis: [1, 0]}
measures:
  - {name: heading, type: angle, body: sled}
  - {name: P_x, type: point, point: sled.P, component: x}
  - {name: P_y, type: point, point: sled.P, component: y}
)";

// (v, ω, φ, x_P, y_P) at t by RK4.
std::array<double, 5> reduced(double t_end) {
  auto rhs = [](const std::array<double, 5>& s) {
    return std::array<double, 5>{kA * s[1] * s[1], -kM * kA * s[0] * s[1] / (kJ + kM * kA * kA),
                                 s[1], s[0] * std::cos(s[2]), s[0] * std::sin(s[2])};
  };
  std::array<double, 5> s{kV0, kW0, 0.0, 0.0, 0.0};
  const int steps = 100000;
  const double h = t_end / steps;
  auto axpy = [](const std::array<double, 5>& x, double a, const std::array<double, 5>& y) {
    std::array<double, 5> r{};
    for (size_t i = 0; i < 5; ++i) r[i] = x[i] + a * y[i];
    return r;
  };
  for (int i = 0; i < steps; ++i) {
    const auto k1 = rhs(s), k2 = rhs(axpy(s, h / 2, k1)), k3 = rhs(axpy(s, h / 2, k2)),
               k4 = rhs(axpy(s, h, k3));
    for (size_t j = 0; j < 5; ++j) s[j] += h / 6 * (k1[j] + 2 * k2[j] + 2 * k3[j] + k4[j]);
  }
  return s;
}

TEST(KnifeEdge, EtAndDtAgainstCentralDifferences) {
  const Model model = parse_mechanism(kSled, "chaplygin-sled");
  ASSERT_EQ(model.nc, 1);
  EXPECT_EQ(model.constraint_row_name(0), "knife edge 'blade', lateral");
  State s(model);
  s.q = Vec3(0.3, -0.1, 0.7);
  s.u = Vec3(0.4, -1.1, 2.3);
  ConstraintWorkspace ws(model);
  compute_constraints(model, s, ws);
  EXPECT_EQ(ws.f(0), 0.0);  // nonholonomic: no geometric residual
  // Eᵀu = lateral velocity of P, from the point kinematics (independent formula).
  const PointKinematics kp = point_kinematics(model, model.knife_edges[0].at, s.q, &s.u);
  const Vec2 n = rotation(s.q(2)) * Vec2(0, 1);
  EXPECT_NEAR((ws.Et * s.u)(0), n.dot(kp.v), 1e-14);
  // Dᵀ = d/dt Eᵀ along u (central differences).
  const double h = 1e-6;
  MatX Ep(1, 3), Em(1, 3);
  compute_constraint_jacobian(model, s.q + h * s.u, Ep);
  compute_constraint_jacobian(model, s.q - h * s.u, Em);
  EXPECT_LT(((Ep - Em) / (2 * h) - ws.Dt).cwiseAbs().maxCoeff(), 1e-8);
}

TEST(KnifeEdge, ChaplyginSled_ClassicalMotionAndEnergy) {
  const Model model = parse_mechanism(kSled, "chaplygin-sled");
  for (DynamicsForm form : {DynamicsForm::dual, DynamicsForm::primal}) {
    SimulateOptions o;
    o.form = form;
    o.t_end = 5.0;
    o.rtol = 1e-11;
    o.atol = 1e-12;
    // Admissible initial velocity: v_C = v_P + ω perp(r_C − r_P) = (v0, ω0 a), ω0.
    o.initial_u = Vec3(kV0, kW0 * kA, kW0);
    const SimulateResult r = simulate(model, o);
    ASSERT_EQ(r.status, SimulateStatus::completed) << r.message;
    EXPECT_LT(r.kinetic_removed, 1e-20);  // it was admissible: α u₀ = u₀
    const auto ref = reduced(5.0);
    const double w = r.final.u(2);
    const Vec2 vP = r.final.u.head<2>() +
                    w * perp(Vec2(-kA * std::cos(r.final.q(2)), -kA * std::sin(r.final.q(2))));
    const Vec2 blade(std::cos(r.final.q(2)), std::sin(r.final.q(2)));
    EXPECT_NEAR(vP.dot(blade), ref[0], 1e-8);
    EXPECT_NEAR(w, ref[1], 1e-8);
    EXPECT_NEAR(r.final.measures[0], ref[2], 1e-8);  // heading
    // Positions follow the nonholonomic kinematics: no position correction acts on the row.
    EXPECT_NEAR(r.final.measures[1], ref[3], 1e-8);
    EXPECT_NEAR(r.final.measures[2], ref[4], 1e-8);
    EXPECT_LT(r.energy_max_drift, 1e-10 * r.energy_initial);
    EXPECT_LT(r.max_velocity_residual, 1e-10);
  }
}

// The blade's reaction (named components blade.Fx, blade.Fy, blade.N) against the reduced
// dynamics: the only force is N along the blade normal n, so N = m (lateral acceleration of the
// centre of mass) = m (v ω + a ω̇), with ω̇ = −m a v ω / (J + m a²).
TEST(KnifeEdge, ChaplyginSled_BladeReactionAgainstReducedDynamics) {
  const Model model = parse_mechanism(kSled, "chaplygin-sled");
  SimulateOptions o;
  o.t_end = 1.0;
  o.dt_out = 0.25;
  o.rtol = 1e-11;
  o.atol = 1e-12;
  o.initial_u = Vec3(kV0, kW0 * kA, kW0);
  const SimulateResult r = simulate(model, o);
  ASSERT_EQ(r.status, SimulateStatus::completed) << r.message;
  size_t fx = 99, fy = 99, nn = 99;
  for (size_t k = 0; k < r.components.size(); ++k) {
    if (r.components[k].name == "blade.Fx") fx = k;
    if (r.components[k].name == "blade.Fy") fy = k;
    if (r.components[k].name == "blade.N") nn = k;
  }
  ASSERT_LT(std::max({fx, fy, nn}), r.components.size());
  ASSERT_GE(r.samples.size(), 5u);
  for (const auto& s : r.samples) {
    const auto ref = reduced(s.t);
    const double v = ref[0], w = ref[1];
    const double wdot = -kM * kA * v * w / (kJ + kM * kA * kA);
    const double N = kM * (v * w + kA * wdot);
    EXPECT_NEAR(s.reactions[nn], N, 1e-7) << s.t;
    const Vec2 n = perp(Vec2(std::cos(ref[2]), std::sin(ref[2])));
    EXPECT_NEAR(s.reactions[fx], N * n.x(), 1e-7) << s.t;
    EXPECT_NEAR(s.reactions[fy], N * n.y(), 1e-7) << s.t;
  }
}

TEST(KnifeEdge, ChaplyginSled_AlignsAndReachesTheLimitSpeed) {
  const Model model = parse_mechanism(kSled, "chaplygin-sled");
  SimulateOptions o;
  o.t_end = 60.0;
  o.initial_u = Vec3(kV0, kW0 * kA, kW0);
  const SimulateResult r = simulate(model, o);
  ASSERT_EQ(r.status, SimulateStatus::completed) << r.message;
  const double v_limit = std::sqrt(kV0 * kV0 + (kJ / kM + kA * kA) * kW0 * kW0);
  EXPECT_LT(std::abs(r.final.u(2)), 1e-3 * kW0);                     // ω → 0
  EXPECT_NEAR(r.final.u.head<2>().norm(), v_limit, 1e-4 * v_limit);  // v → v∞
}

TEST(KnifeEdge, FileErrorsNameTheConstraint) {
  std::string text = kSled;
  const std::string bad_type =
      text.replace(text.find("type: knife-edge"), 16, "type: rolling-disc");
  try {
    (void)parse_mechanism(bad_type, "sled.yaml");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(
                  "unknown nonholonomic constraint type 'rolling-disc' (allowed: knife-edge)"),
              std::string::npos)
        << e.what();
  }
  text = kSled;
  const std::string on_ground = text.replace(text.find("point: sled.P"), 13, "point: ground.O");
  try {
    (void)parse_mechanism(on_ground, "sled.yaml");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("knife edge 'blade'"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace orthomech
