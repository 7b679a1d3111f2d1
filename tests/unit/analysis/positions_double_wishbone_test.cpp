// The double-wishbone suspension (mechanisms/double-wishbone.yaml, docs/spatial.md §4.8) and the
// camber and toe measures (docs/file-format.md "Spatial mechanisms", Measures). Oracles, all
// written here: a loop solve of the §4.8 geometry by our own Newton in four unknowns (the
// upper-arm angle and the upright's rotation vector), with Rodrigues' formula and the points
// typed from docs/spatial.md; the parallelogram linkage, whose upright translates (camber = toe = 0
// exactly); the first-order toe change of a tie-rod length change from the geometry of the
// kingpin axis; central differences of the measures along q ⊕ t u.
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <cmath>
#include <functional>
#include <numbers>
#include <random>

#include "orthomech/analysis/mobility.hpp"
#include "orthomech/analysis/positions.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/model/measures.hpp"
#include "orthomech/model/spatial.hpp"
#include "support/fixtures.hpp"
#include "support/spatial_fixtures.hpp"

namespace orthomech {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

// ---- the independent loop solve --------------------------------------------------------------
struct Geometry {  // docs/spatial.md §4.8, m: x forward, y outboard (left wheel), z up
  Vec3 LAf, LAr, LBJ, UAf, UAr, UBJ, TRi, TRo, WC;
};
const Geometry kWishbone{{0.15, 0.25, 0.15},  {-0.15, 0.25, 0.15}, {0.0, 0.70, 0.12},
                         {0.12, 0.35, 0.45},  {-0.12, 0.35, 0.45}, {0.0, 0.66, 0.42},
                         {-0.12, 0.28, 0.20}, {-0.12, 0.68, 0.18}, {0.0, 0.75, 0.27}};
// (i) of §4.8: UA = LA + (0, 0, 0.3), UBJ = LBJ + (0, 0, 0.3), tie rod = inner + (LBJ − LA).
const Geometry kParallelogram{{0.15, 0.25, 0.15},  {-0.15, 0.25, 0.15}, {0.0, 0.70, 0.12},
                              {0.15, 0.25, 0.45},  {-0.15, 0.25, 0.45}, {0.0, 0.70, 0.42},
                              {-0.12, 0.25, 0.20}, {-0.12, 0.70, 0.17}, {0.0, 0.75, 0.27}};

// exp(θ̃) a by Rodrigues' formula.
Vec3 rotate(const Vec3& theta, const Vec3& a) {
  const double t = theta.norm();
  if (t == 0.0) return a;
  const Vec3 k = theta / t;
  return std::cos(t) * a + std::sin(t) * k.cross(a) + (1.0 - std::cos(t)) * k.dot(a) * k;
}

struct Loop {
  double beta = 0.0;          // upper-arm angle about UA_f − UA_r
  Vec3 theta = Vec3::Zero();  // the upright's rotation from the design pose (world)
  Vec3 lbj, ubj, tro, s, wc;  // ball joints, outer tie-rod point, spin axis, wheel centre
  [[nodiscard]] double camber() const { return -std::asin(s.z()); }
  [[nodiscard]] double toe() const { return std::atan2(s.x(), s.y()); }
};

// Newton on r(β, θ) = [LBJ(ψ) + R(θ)(UBJ − LBJ) − UBJ(β); (|T(θ) − TRi|² − L²)/(2L)] = 0 from
// `guess`, Jacobian by central differences, solved by Eigen's LU (no orthomech solver).
Loop solve_loop(const Geometry& g, double psi, double tie_rod, Loop guess) {
  const Vec3 la = (g.LAf - g.LAr).normalized(), ua = (g.UAf - g.UAr).normalized();
  const Vec3 lbj = g.LAr + rotate(psi * la, g.LBJ - g.LAr);
  const auto residual = [&](const Eigen::Vector4d& x) {
    const Vec3 th = x.tail<3>();
    const Vec3 ubj = g.UAr + rotate(x(0) * ua, g.UBJ - g.UAr);
    const Vec3 t = lbj + rotate(th, g.TRo - g.LBJ) - g.TRi;
    Eigen::Vector4d r;
    r.head<3>() = lbj + rotate(th, g.UBJ - g.LBJ) - ubj;
    r(3) = (t.squaredNorm() - tie_rod * tie_rod) / (2.0 * tie_rod);
    return r;
  };
  Eigen::Vector4d x(guess.beta, guess.theta.x(), guess.theta.y(), guess.theta.z());
  for (int it = 0; it < 50 && residual(x).cwiseAbs().maxCoeff() > 1e-16; ++it) {
    Eigen::Matrix4d J;
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector4d h = 1e-7 * Eigen::Vector4d::Unit(k);
      J.col(k) = (residual(x + h) - residual(x - h)) / 2e-7;
    }
    x -= J.fullPivLu().solve(residual(x));
  }
  EXPECT_LT(residual(x).cwiseAbs().maxCoeff(), 1e-15) << "psi " << psi;
  Loop l;
  l.beta = x(0);
  l.theta = x.tail<3>();
  l.lbj = lbj;
  l.ubj = g.UAr + rotate(l.beta * ua, g.UBJ - g.UAr);
  l.tro = lbj + rotate(l.theta, g.TRo - g.LBJ);
  l.s = rotate(l.theta, Vec3::UnitY());
  l.wc = lbj + rotate(l.theta, g.WC - g.LBJ);
  return l;
}
double design_tie_rod(const Geometry& g) { return (g.TRo - g.TRi).norm(); }

double measure(const Model& m, const std::string& name, const VecX& q) {
  const int k = m.find_measure(name);
  EXPECT_GE(k, 0) << name;
  return evaluate_measure(m, m.measures[static_cast<size_t>(k)], q, nullptr, nullptr);
}

Model wishbone() { return load_mechanism(test::source_path("mechanisms/double-wishbone.yaml")); }

// ---- the tests ----------------------------------------------------------------------------------
TEST(DoubleWishbone, OneDegreeOfFreedomRank17) {
  const Model m = wishbone();
  const VecX q = m.design_q();
  const Mobility mob = compute_mobility(m, q);
  EXPECT_EQ(mob.n, 18);
  EXPECT_EQ(mob.nc, 17);
  EXPECT_EQ(mob.rank, 17);
  EXPECT_EQ(mob.dof, 1);
  EXPECT_TRUE(mob.redundant.empty());
  // The drawn pose: every joint holds, ψ = 0, camber = toe = 0, wheel centre at 0.27 m.
  VecX f(m.nc);
  compute_constraint_residual(m, q, f);
  EXPECT_LT(f.cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_NEAR(measure(m, "psi", q), 0.0, 1e-15);
  EXPECT_NEAR(measure(m, "camber", q), 0.0, 1e-15);
  EXPECT_NEAR(measure(m, "toe", q), 0.0, 1e-15);
  EXPECT_NEAR(measure(m, "wheel_z", q), 0.27, 1e-15);
}

// Lower-arm angle ψ over ±15° in 1° steps (each step starts from the last), the input locked:
// camber, toe, wheel travel and the upper-arm angle equal the independent loop solve.
void sweep(const Model& m, const Geometry& g,
           const std::function<void(int, const VecX&, const Loop&)>& check) {
  PositionOptions hold;
  hold.locked_joint = m.find_joint("LA");
  ASSERT_GE(hold.locked_joint, 0);
  for (const int step : {1, -1}) {
    VecX q = m.design_q();
    Loop loop;
    for (int degrees = step; std::abs(degrees) <= 15; degrees += step) {
      hold.locked_value = degrees * kDeg;
      ASSERT_EQ(project_positions(m, q, hold).status, SolveStatus::converged) << degrees;
      loop = solve_loop(g, degrees * kDeg, design_tie_rod(g), loop);
      check(degrees, q, loop);
    }
  }
}

TEST(DoubleWishbone, CamberToeAndTravelEqualAnIndependentLoopSolve) {
  const Model m = wishbone();
  double max_camber = 0.0, max_toe = 0.0;
  sweep(m, kWishbone, [&](int degrees, const VecX& q, const Loop& loop) {
    EXPECT_NEAR(measure(m, "psi", q), degrees * kDeg, 1e-12);
    EXPECT_NEAR(measure(m, "camber", q), loop.camber(), 1e-10) << degrees;
    EXPECT_NEAR(measure(m, "toe", q), loop.toe(), 1e-10) << degrees;
    EXPECT_NEAR(measure(m, "wheel_z", q), loop.wc.z(), 1e-10) << degrees;
    EXPECT_NEAR(measure(m, "upper_arm_angle", q), loop.beta, 1e-10) << degrees;
    max_camber = std::max(max_camber, std::abs(loop.camber()));
    max_toe = std::max(max_toe, std::abs(loop.toe()));
    // The file's comment block quotes the ±15° values (degrees, 10 decimals).
    if (degrees == 15) {
      EXPECT_NEAR(loop.camber() / kDeg, -0.6444896031, 1e-9);
      EXPECT_NEAR(loop.toe() / kDeg, -1.4995938796, 1e-9);
      EXPECT_NEAR(loop.wc.z(), 0.388042643165, 1e-11);
    }
    if (degrees == -15) {
      EXPECT_NEAR(loop.camber() / kDeg, -2.3994656528, 1e-9);
      EXPECT_NEAR(loop.toe() / kDeg, 1.1157706516, 1e-9);
      EXPECT_NEAR(loop.wc.z(), 0.156514583466, 1e-11);
    }
  });
  // Not a trivial comparison: camber and toe move by degrees over the travel.
  EXPECT_GT(max_camber, 2.0 * kDeg);
  EXPECT_GT(max_toe, 1.0 * kDeg);
}

// docs/spatial.md §4.8 (i): equal, parallel arms and a tie rod parallel to them: the upright
// translates on a circle, camber and toe stay 0 while the wheel travels as the independent
// solve says.
TEST(DoubleWishbone, ParallelogramKeepsCamberAndToeZero) {
  const Model m =
      load_mechanism(test::source_path("tests/data/spatial/double-wishbone-parallelogram.yaml"));
  EXPECT_EQ(compute_mobility(m, m.design_q()).dof, 1);
  sweep(m, kParallelogram, [&](int degrees, const VecX& q, const Loop& loop) {
    EXPECT_NEAR(measure(m, "camber", q), 0.0, 1e-12) << degrees;
    EXPECT_NEAR(measure(m, "toe", q), 0.0, 1e-12) << degrees;
    EXPECT_NEAR(measure(m, "wheel_z", q), loop.wc.z(), 1e-10) << degrees;
    // The translation: the wheel centre moves as the lower ball joint.
    EXPECT_NEAR(measure(m, "wheel_z", q) - 0.27, loop.lbj.z() - 0.12, 1e-10) << degrees;
  });
}

// docs/spatial.md §4.8 (ii): at fixed ψ the ball joints stay where they are, so a tie-rod length
// change δ turns the upright about the kingpin axis k (LBJ → UBJ) by dγ = δ/((ρ × e)·k), ρ the
// outer tie-rod point from LBJ, e the tie rod's unit vector; toe changes by (dt/dγ) dγ with
// dt/dγ = (s_y (k × s)_x − s_x (k × s)_y)/(s_x² + s_y²): Δtoe = δ/ℓ, ℓ = (ρ × e)·k/(dt/dγ), the
// steering-arm lever. Checked by changing the `distance` row's length in the model.
TEST(DoubleWishbone, TieRodLengthChangeTurnsToeByDeltaOverTheSteeringArm) {
  const Model m = wishbone();
  const int tie = m.find_joint("tie_rod");
  ASSERT_GE(tie, 0);
  PositionOptions hold;
  hold.locked_joint = m.find_joint("LA");
  ASSERT_GE(hold.locked_joint, 0);
  const double L = design_tie_rod(kWishbone), delta = 1e-6;
  for (const int degrees : {0, -10, 10}) {
    const int step = degrees < 0 ? -1 : 1;
    Loop loop = solve_loop(kWishbone, 0.0, L, Loop{});
    for (int d = step; degrees != 0 && d != degrees + step; d += step)
      loop = solve_loop(kWishbone, d * kDeg, L, loop);
    const Vec3 k = (loop.ubj - loop.lbj).normalized();
    const Vec3 rho = loop.tro - loop.lbj;
    const Vec3 e = (loop.tro - kWishbone.TRi).normalized();
    const Vec3 ks = k.cross(loop.s);
    const double dt_dgamma = (loop.s.y() * ks.x() - loop.s.x() * ks.y()) /
                             (loop.s.x() * loop.s.x() + loop.s.y() * loop.s.y());
    const double lever = rho.cross(e).dot(k) / dt_dgamma;
    EXPECT_GT(std::abs(lever), 0.05) << degrees;  // about 0.12 m: the tie rod's offset from k
    double toe[2];
    for (int side = 0; side < 2; ++side) {
      Model changed = m;
      std::get<SpatialJoint>(changed.joints[static_cast<size_t>(tie)].kind).length =
          L + (side == 0 ? delta : -delta);
      VecX q = m.design_q();
      for (int d = 0; d != degrees + step; d += step) {  // continued from the design pose
        PositionOptions h = hold;
        h.locked_value = d * kDeg;
        ASSERT_EQ(project_positions(changed, q, h).status, SolveStatus::converged);
        if (degrees == 0) break;
      }
      toe[side] = measure(changed, "toe", q);
      // The independent solve with the changed length agrees too.
      const Loop l2 = solve_loop(kWishbone, degrees * kDeg, L + (side == 0 ? delta : -delta), loop);
      EXPECT_NEAR(toe[side], l2.toe(), 1e-10);
    }
    const double slope = (toe[0] - toe[1]) / (2.0 * delta);
    EXPECT_NEAR(slope, 1.0 / lever, 1e-6 / std::abs(lever)) << degrees << "°, lever " << lever;
  }
}

// The camber and toe measures' rates and accelerations against central differences of their
// values along q ⊕ t u (integrate_positions), their Jacobian rows against the rates, and their
// values against the definitions; on the suspension (u an admissible motion) and on a free body
// turned so that its spin axis points to −y (a right wheel: toe = atan2(s_x, −s_y)).
TEST(DoubleWishbone, CamberAndToeRatesAndAccelerationsEqualDifferences) {
  const Model m = wishbone();
  const int upright = m.find_body("upright");
  std::vector<std::pair<Model, State>> cases;
  {
    PositionOptions hold;
    hold.locked_joint = m.find_joint("LA");
    State s(m);
    s.q = m.design_q();
    for (int d = 1; d <= 12; ++d) {
      hold.locked_value = d * kDeg;
      ASSERT_EQ(project_positions(m, s.q, hold).status, SolveStatus::converged);
    }
    MatX Et(m.nc, m.n);
    compute_constraint_jacobian(m, s.q, Et);
    const Eigen::FullPivLU<MatX> lu(Et);
    ASSERT_EQ(lu.kernel().cols(), 1);
    s.u = 3.0 * lu.kernel().col(0).normalized();  // ψ̇ a few rad/s
    cases.emplace_back(m, s);
  }
  {
    // A right wheel: the upright turned half a turn about z plus a random tilt.
    Model r = m;
    std::mt19937_64 rng(5);
    State s = testing::spatial::random_state(r, rng, 0.3);
    VecX half = VecX::Zero(r.n);
    half(r.bodies[static_cast<size_t>(upright)].u_offset + 5) = std::numbers::pi;
    integrate_positions(r, s.q, half, 1.0);
    cases.emplace_back(r, s);
  }
  for (size_t c = 0; c < cases.size(); ++c) {
    const Model& model = cases[c].first;
    const State& s = cases[c].second;
    const Mat3 R = spatial_frame(model, upright, s.q, nullptr).R;
    const Vec3 spin = R * Vec3::UnitY();
    EXPECT_EQ(spin.y() < 0.0, c == 1);
    const VecX zero = VecX::Zero(model.n);
    for (const auto which : {WheelAngle::Which::camber, WheelAngle::Which::toe}) {
      const WheelAngle w{upright, Vec3::UnitY(), which};
      const Measure pos{"m", w, 0, "", {}}, vel{"m", w, 1, "", {}}, acc{"m", w, 2, "", {}};
      const double expected = which == WheelAngle::Which::camber
                                  ? -std::asin(spin.z())
                                  : std::atan2(spin.x(), std::abs(spin.y()));
      EXPECT_NEAR(evaluate_measure(model, pos, s.q, nullptr, nullptr), expected, 1e-14)
          << c << " " << int(which);
      const auto value_at = [&](double dt) {
        VecX qt = s.q;
        integrate_positions(model, qt, s.u, dt);
        return evaluate_measure(model, pos, qt, nullptr, nullptr);
      };
      const double h = 1e-5, h2 = 1e-4;
      const double rate = evaluate_measure(model, vel, s.q, &s.u, nullptr);
      EXPECT_NEAR(rate, (value_at(h) - value_at(-h)) / (2 * h), 1e-8) << c << " " << int(which);
      EXPECT_NEAR(evaluate_measure(model, acc, s.q, &s.u, &zero),
                  (value_at(h2) - 2 * value_at(0) + value_at(-h2)) / (h2 * h2), 1e-5)
          << c << " " << int(which);
      VecX d(model.n);
      compute_scalar(model, w, s.q, &s.u, d);
      EXPECT_NEAR(d.dot(s.u), rate, 1e-12) << c;
      EXPECT_GT(std::abs(rate), 1e-3) << c;  // the motion moves the measure
    }
  }
}

// The reader: `camber` and `toe` take `body` and `axis` (normalised); a missing axis or another
// key is an error naming the measure.
TEST(DoubleWishbone, CamberAndToeMeasuresAreRead) {
  const Model m = wishbone();
  const auto& toe =
      std::get<WheelAngle>(m.measures[static_cast<size_t>(m.find_measure("toe"))].kind);
  EXPECT_EQ(toe.which, WheelAngle::Which::toe);
  EXPECT_EQ(toe.body, m.find_body("upright"));
  EXPECT_EQ(toe.axis, Vec3::UnitY());
  const Measure& rate = m.measures[static_cast<size_t>(m.find_measure("camber_rate"))];
  EXPECT_EQ(std::get<WheelAngle>(rate.kind).which, WheelAngle::Which::camber);
  EXPECT_EQ(rate.derivative, 1);
  EXPECT_EQ(rate.unit, "rad/s");
  const std::string base =
      "orthomech: 1\ndimension: 3\nname: w\n"
      "units: {length: m, angle: deg, mass: kg, time: s, force: N}\n"
      "bodies:\n  - {name: hub, mass: 1, inertia: [1, 1, 1], pose: {position: [0, 0, 0]}}\n"
      "measures:\n";
  const Model ok =
      parse_mechanism(base + "  - {name: t, type: toe, body: hub, axis: [0, -2, 0]}\n", "w.yaml");
  EXPECT_EQ(std::get<WheelAngle>(ok.measures[0].kind).axis, Vec3(0, -1, 0));
  for (const std::string& bad : {std::string("  - {name: t, type: toe, body: hub}\n"),
                                 std::string("  - {name: t, type: camber, body: hub, axis: [0, 1, "
                                             "0], side: left}\n")}) {
    try {
      (void)parse_mechanism(base + bad, "w.yaml");
      ADD_FAILURE() << bad;
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find("measure 't'"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace orthomech
