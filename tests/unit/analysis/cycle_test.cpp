// Kinetostatics over a cycle (issue 3): drive and reactions against independent oracles.
//  - power balance: drive power = d/dt(T + V) + dissipated power (energy, by differences in time);
//  - Theorem 5, eq. (91), primal form: R = −βᵀ(Q̂ + dτ) − ω u equals the dual-form E λ;
//  - a Lagrange-multiplier solve of the augmented system [M −E −d; Eᵀ 0 0; dᵀ 0 0];
//  - closed-form kinetostatics of the in-line slider-crank in the quasi-static limit;
//  - the dead point of the double-rocker against its closed form;
//  - redundancy: which reaction components of the triple-crank are determinate.
#include "orthomech/analysis/cycle.hpp"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <Eigen/LU>
#include <map>
#include <numbers>
#include <stdexcept>
#include <vector>

#include "orthomech/analysis/mobility.hpp"
#include "orthomech/analysis/positions.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/model/loads.hpp"
#include "orthomech/model/measures.hpp"
#include "orthomech/projection/dual.hpp"
#include "orthomech/projection/primal.hpp"
#include "support/fixtures.hpp"

namespace orthomech {
namespace {

CycleOptions options_for(const Model& model, int steps, double speed = 0.0) {
  CycleOptions o;
  o.driver = model.drivers.at(0);
  if (speed != 0.0) o.driver.speed = speed;
  o.steps = steps;
  return o;
}

PointRef point_on(const Model& m, const std::string& body, const std::string& point) {
  const int b = m.find_body(body);
  const Body& bd = m.bodies[static_cast<size_t>(b)];
  for (const auto& [name, p] : bd.points)
    if (name == point) return {b, p - bd.com_local, body + "." + point};
  throw std::runtime_error("no point " + body + "." + point);
}

// Power balance τṡ = d(T + V)/dt + P_dissipated at every position k whose five-point stencil
// (k − 2 … k + 2) lies on the uniform time grid and passes `usable` (d/dt by the stencil: error
// O(h⁴)); to `tolerance` × the peak drive power. Returns how many positions were checked.
template <class Usable>
int expect_power_balance(const DrivenPoints& p, double tolerance, Usable usable) {
  if (p.size() < 5) return 0;
  const double h = p[1].time - p[0].time;
  double peak = 0.0;
  for (const auto& x : p)
    if (!x.singular) peak = std::max(peak, std::abs(x.drive * x.input_rate));
  int checked = 0;
  for (size_t k = 2; k + 2 < p.size(); ++k) {
    bool skip = false;
    for (size_t i = k - 2; i <= k + 2; ++i)
      skip = skip || p[i].singular || !usable(p[i]) ||
             std::abs(p[i].time - p[k].time -
                      (static_cast<double>(i) - static_cast<double>(k)) * h) > 1e-9 * h;
    if (skip) continue;
    auto E = [&](size_t i) { return p[i].kinetic + p[i].potential; };
    const double dEdt = (-E(k + 2) + 8.0 * E(k + 1) - 8.0 * E(k - 1) + E(k - 2)) / (12.0 * h);
    EXPECT_NEAR(p[k].drive * p[k].input_rate, dEdt + p[k].dissipated, tolerance * peak)
        << "position " << k << " input " << p[k].input;
    ++checked;
  }
  return checked;
}
const auto kAll = [](const DrivenPointView&) { return true; };

// Power balance: τ ṡ = d/dt (T + V) + P_dissipated, with d/dt by a five-point stencil in time
// (error O(h⁴): h = 2π/3600/ω → ~1e-12 relative).
TEST(Cycle, PowerBalanceAtEveryPosition) {
  Model model = test::load_bundled("crank-rocker");
  // Add a spring-damper (coupler point P to the ground pivot B0) and a rotary damper.
  model.loads.push_back(
      {"spring",
       SpringDamper{point_on(model, "coupler", "P"),
                    PointRef{kGround, Vec2(0.07, 0.0), "ground.B0"}, 200.0, 0.05, 1.5},
       {}});
  model.loads.push_back(
      {"rdamp", RotarySpringDamper{kGround, model.find_body("rocker"), 0.3, 1.2, 0.02}, {}});
  const CycleResult r = run_cycle(model, options_for(model, 3600));
  ASSERT_EQ(r.status, CycleStatus::completed) << r.message;
  EXPECT_EQ(expect_power_balance(r.points, 1e-6, kAll), 3600 - 4);  // all but 2 at each end
}

// The primal form's Theorem 5 (eq. (91), constant M): R_β = −βᵀ Q̂_tot − ω u, with the drive
// force d τ among the loads, against the dual-form E λ; and a Lagrange-multiplier solve.
class CycleReactions : public ::testing::TestWithParam<const char*> {};

TEST_P(CycleReactions, Eq91_PrimalReactionsAndLagrangeMultipliersEqualDual) {
  const Model model = test::load_bundled(GetParam());
  ASSERT_FALSE(model.drivers.empty());
  const int joint = model.drivers[0].joint;
  const double sdot =
      model.drivers[0].profile == Profile::constant_speed ? model.drivers[0].speed : 1.0;
  State s(model);
  s.q = test::assembled_q(model);
  const Mobility mob = compute_mobility(model, s.q);
  ASSERT_EQ(mob.rank, model.nc) << "non-redundant mechanisms only";
  Workspace ws(model, mob.rank);
  DrivenWorkspace w(model, mob.rank);
  DrivenPoint p;
  ASSERT_TRUE(compute_driven(model, joint, sdot, 0.0, s, ws, w, p));
  // Dual: E λ.
  const VecX Elambda = ws.constraints.Et.transpose() * p.lambda;
  // Primal, eq. (91).
  ASSERT_EQ(evaluate_primal(model, s, ws), ProjectionStatus::ok);
  VecX d(model.n);
  (void)compute_scalar(model, JointCoordinate{joint}, s.q, &s.u, d);
  const VecX Qtot = ws.free.Q + p.drive * d;
  const VecX R91 = -ws.primal.beta.transpose() * Qtot - ws.primal.omega * s.u;  // eq. (91)
  EXPECT_LT((Elambda - R91).norm(), 1e-9 * (1.0 + R91.norm())) << "E λ ≠ eq. (91)";
  // Lagrange multipliers: M u̇ − E λ − d τ = Q̂; Eᵀ u̇ = −Dᵀu; dᵀ u̇ = s̈ − ḋu.
  const int n = model.n, nc = model.nc;
  MatX K = MatX::Zero(n + nc + 1, n + nc + 1);
  VecX b = VecX::Zero(n + nc + 1);
  K.topLeftCorner(n, n) = ws.free.M;
  K.block(0, n, n, nc) = -ws.constraints.Et.transpose();
  K.block(0, n + nc, n, 1) = -d;
  K.block(n, 0, nc, n) = ws.constraints.Et;
  K.block(n + nc, 0, 1, n) = d.transpose();
  b.head(n) = ws.free.Q;
  b.segment(n, nc) = -ws.constraints.Dtu;
  b(n + nc) = -compute_scalar(model, JointCoordinate{joint}, s.q, &s.u).ddot_u;
  const VecX x = K.fullPivLu().solve(b);
  EXPECT_LT((x.head(n) - p.udot).norm(), 1e-9 * (1.0 + p.udot.norm())) << "u̇";
  EXPECT_LT((x.segment(nc ? n : n, nc) - p.lambda).norm(), 1e-9 * (1.0 + p.lambda.norm())) << "λ";
  EXPECT_NEAR(x(n + nc), p.drive, 1e-9 * (1.0 + std::abs(p.drive))) << "τ";
}

INSTANTIATE_TEST_SUITE_P(Bundled, CycleReactions,
                         ::testing::Values("crank-rocker", "slider-crank", "watt-six-bar",
                                           "stephenson-six-bar", "quick-return", "andrews-squeezer",
                                           "rssr", "spatial-slider-crank", "double-wishbone"),
                         [](const auto& param_info) {
                           std::string s = param_info.param;
                           for (char& c : s) c = c == '-' ? '_' : c;
                           return s;
                         });

// compute_driven with the caller's Eᵀ, rotation table and input gradient at q
// (DrivenJacobian::current_with_gradient, what the sweep's corrector leaves) gives bit for bit what
// it computes itself (`evaluate`); it does use the caller's gradient (a wrong one changes the
// result), and out.input is the driver's coordinate at q as compute_scalar reads it.
TEST(Cycle, ComputeDrivenWithTheCallersGradientIsBitForBitItsOwn) {
  for (const char* name : {"crank-rocker", "andrews-squeezer", "rssr", "spatial-slider-crank"}) {
    const Model model = test::load_bundled(name);
    const int joint = model.drivers[0].joint;
    State s(model);
    s.q = test::assembled_q(model);
    const int rank = compute_mobility(model, s.q).rank;
    Workspace ws1(model, rank), ws2(model, rank), ws3(model, rank);
    DrivenWorkspace w1(model, rank), w2(model, rank), w3(model, rank);
    DrivenPoint own, given, wrong;
    State s1 = s, s2 = s, s3 = s;
    ASSERT_TRUE(compute_driven(model, joint, 2.0, 0.5, s1, ws1, w1, own)) << name;
    for (auto* c : {&ws2, &ws3}) compute_constraint_jacobian(model, s.q, c->constraints.Et);
    w2.rotations.update(model, s.q);
    w3.rotations.update(model, s.q);
    const double input = compute_scalar(model, JointCoordinate{joint}, s.q, nullptr, w2.d).value;
    w3.d = 1.1 * w2.d;  // a gradient that is not the input's
    ASSERT_TRUE(compute_driven(model, joint, 2.0, 0.5, s2, ws2, w2, given,
                               DrivenJacobian::current_with_gradient))
        << name;
    EXPECT_EQ(own.input, input) << name;
    EXPECT_EQ(given.input, input) << name;
    EXPECT_EQ(given.drive, own.drive) << name;
    EXPECT_EQ(given.u, own.u) << name;
    EXPECT_EQ(given.udot, own.udot) << name;
    EXPECT_EQ(given.lambda, own.lambda) << name;
    EXPECT_EQ(given.tangent, own.tangent) << name;
    // With 1.1 d, dᵀF is 1.1 times larger, which changes the velocities and the drive. Measured
    // wrong/own drive: 0.906, 0.909, 0.916 and 0.682 on the four mechanisms. The correct call
    // matches bit for bit, so a change above 1e-6 cannot be rounding.
    ASSERT_TRUE(compute_driven(model, joint, 2.0, 0.5, s3, ws3, w3, wrong,
                               DrivenJacobian::current_with_gradient))
        << name;
    EXPECT_GT(std::abs(wrong.drive - own.drive), 1e-6 * std::abs(own.drive)) << name;
  }
}

// In-line slider-crank, quasi-static (ω → 0) and without gravity: virtual work gives
// τ = −F_x dx/dθ with x = r cos θ + √(l² − r² sin² θ) [e.g. Norton, Design of Machinery, §13]
// and F_x the gas force on the piston. Inertia terms scale with ω² and vanish.
TEST(Cycle, SliderCrankQuasiStaticDriveMatchesClosedForm) {
  Model model = test::load_bundled("slider-crank");
  std::erase_if(model.loads, [](const Load& l) { return std::holds_alternative<Gravity>(l.kind); });
  const CycleResult r = run_cycle(model, options_for(model, 72, 1e-4));
  ASSERT_EQ(r.status, CycleStatus::completed) << r.message;
  const double rr = 0.05, l = 0.2;
  const auto& gas = std::get<PointForce>(model.loads.at(0).kind);
  for (const auto& p : r.points) {
    const double th = p.input;
    const double root = std::sqrt(l * l - rr * rr * std::sin(th) * std::sin(th));
    const double dxdth = -rr * std::sin(th) - rr * rr * std::sin(th) * std::cos(th) / root;
    const double Fx = gas.force.x() * table_factor(model, gas.table, p.q);
    EXPECT_NEAR(p.drive, -Fx * dxdth, 1e-6 * 2000.0 * rr) << "θ = " << th;
  }
}

// Quasi-static limit: as the speed goes to 0 the drive tends to the static-equilibrium torque
// −Q̂ᵀ(u/ṡ) (virtual work with gravity and the gas force), computed here from the loads alone.
TEST(Cycle, QuasiStaticLimitEqualsStaticEquilibrium) {
  const Model model = test::load_bundled("crank-rocker");
  const CycleResult slow = run_cycle(model, options_for(model, 36, 1e-5));
  ASSERT_EQ(slow.status, CycleStatus::completed);
  for (const auto& p : slow.points) {
    State s(model);
    s.q = p.q;
    VecX Q(model.n);
    compute_applied_forces(model, s, Q);
    const double static_drive = -Q.dot(p.u / 1e-5);  // τ ṡ + Qᵀu = 0, u/ṡ = dq/ds
    EXPECT_NEAR(p.drive, static_drive, 1e-6 * (1.0 + std::abs(static_drive))) << p.input;
  }
}

TEST(Cycle, DoubleRockerStopsAtItsDeadPointWithClosedFormAngle) {
  const Model model = test::load_bundled("double-rocker");
  CycleOptions o = options_for(model, 360);
  o.driver.profile = Profile::constant_speed;
  o.driver.speed = 1.0;
  const CycleResult r = run_cycle(model, o);
  ASSERT_EQ(r.status, CycleStatus::stopped_at_dead_point) << r.message;
  ASSERT_EQ(r.dead_points.size(), 1u);
  // Input a = 60, coupler b = 40, rocker c = 65, ground g = 100 (mm): coupler and rocker in line
  // when |A − B0| = b + c: cos θ = (a² + g² − (b + c)²) / (2 a g).
  const double a = 60, b = 40, c = 65, g = 100;
  const double theta = std::acos((a * a + g * g - (b + c) * (b + c)) / (2 * a * g));
  EXPECT_NEAR(r.dead_points[0].input, theta, 1e-6);
  for (const auto& p : r.points) {
    EXPECT_TRUE(std::isfinite(p.drive));
    for (double v : p.reactions) EXPECT_TRUE(std::isfinite(v));
  }
}

TEST(Cycle, TripleCrankSaysWhichReactionComponentsAreIndeterminate) {
  const Model model = test::load_bundled("triple-crank");
  const CycleResult r = run_cycle(model, options_for(model, 90));
  ASSERT_EQ(r.status, CycleStatus::completed) << r.message;
  EXPECT_EQ(r.redundant, 1);
  int indeterminate = 0;
  for (size_t i = 0; i < r.components.size(); ++i) {
    if (!r.determinate[i]) ++indeterminate;
    // The crank-frame components along each crank (axial) are the indeterminate ones; the
    // transverse ones, which carry the torque, are unique.
    const std::string& name = r.components[i].name;
    if (name.rfind("A", 0) == 0 && name.find("Fy_local") != std::string::npos) {
      EXPECT_TRUE(r.determinate[i]) << name;
    }
    if (name.rfind("A", 0) == 0 && name.find("Fx_local") != std::string::npos) {
      EXPECT_FALSE(r.determinate[i]) << name;
    }
  }
  EXPECT_GT(indeterminate, 0);
  // The cranks pass the line of centres twice per turn (E loses rank there): both are passed.
  ASSERT_EQ(r.singular_positions.size(), 2u);
  EXPECT_NEAR(std::remainder(r.singular_positions[0].input, M_PI), 0.0, 1e-12);
  EXPECT_NEAR(std::remainder(r.singular_positions[1].input, M_PI), 0.0, 1e-12);
  // The drive is unique: power balance holds (gravity only: τ ṡ = d/dt (T + V)).
  const auto& p = r.points;
  const double h = p[1].time - p[0].time;
  for (size_t k = 2; k + 2 < p.size(); ++k) {
    // Positions next to a change point are flagged and their drive is not used.
    bool near_singular = false;
    for (size_t i = k - 2; i <= k + 2; ++i) near_singular = near_singular || p[i].singular;
    if (near_singular) continue;
    auto E = [&](size_t i) { return p[i].kinetic + p[i].potential; };
    const double dEdt = (-E(k + 2) + 8.0 * E(k + 1) - 8.0 * E(k - 1) + E(k - 2)) / (12.0 * h);
    // 90 steps of 4°: five-point stencil error ~ h⁴ E⁽⁵⁾ ≈ 1e-4 of the drive power.
    EXPECT_NEAR(p[k].drive * model.drivers[0].speed, dEdt, 1e-3 * (1.0 + std::abs(dEdt))) << k;
  }
  // Closed form: parallel cranks translate the coupler on a circle; with gravity only,
  // τ = g cos θ (r m_c/2 · 3 + r m_coupler) for the three cranks (com at mid-length) and the
  // coupler; the mechanism file gives the masses.
  double moment = 0.0;
  for (const Body& b : model.bodies) moment += b.mass * (b.name == "coupler" ? 0.05 : 0.025);
  int flagged = 0;
  for (const auto& x : p) {
    if (x.singular) {
      ++flagged;
      continue;
    }
    // 1e-8 N·m = 7e-8 of the peak drive 0.135 N·m (measured: 1.6e-12 N·m at worst, at 184°,
    // 4° past a change point, where q is limited by ε/σ_min of the corrector).
    EXPECT_NEAR(x.drive, 9.81 * moment * std::cos(x.input), 1e-8) << x.input;
  }
  EXPECT_EQ(flagged, 2);
}

// The change points at 180° and 360° are passed at any step count, not only when the grid lands
// on them (0.1° steps pass within 1e-14 of them; 0.05° steps put positions 0.05° from them):
// exactly one singular position each, the sweep completes, the drive stays on its closed form
// (to 1e-6 N·m = 7e-6 of its peak next to a change point, where the accuracy of q is limited
// by ε/σ_min of the locked Jacobian; measured 6.1e-7 N·m at worst, 0.05° from 180° at 7200
// steps), and the indeterminate set is the same as at 90 steps.
TEST(Cycle, TripleCrankPassesChangePointsAtAnyStepCount) {
  const Model model = test::load_bundled("triple-crank");
  double moment = 0.0;
  for (const Body& b : model.bodies) moment += b.mass * (b.name == "coupler" ? 0.05 : 0.025);
  const CycleResult coarse = run_cycle(model, options_for(model, 90));
  for (const int steps : {360, 720, 1000, 3600, 7200}) {
    const CycleResult r = run_cycle(model, options_for(model, steps));
    ASSERT_EQ(r.status, CycleStatus::completed) << steps << ": " << r.message;
    ASSERT_EQ(r.points.size(), static_cast<size_t>(steps));
    ASSERT_EQ(r.singular_positions.size(), 2u) << steps;
    EXPECT_NEAR(std::remainder(r.singular_positions[0].input, M_PI), 0.0, 1e-6) << steps;
    EXPECT_NEAR(std::remainder(r.singular_positions[1].input, M_PI), 0.0, 1e-6) << steps;
    for (const auto& x : r.points) {
      if (x.singular) continue;
      EXPECT_NEAR(x.drive, 9.81 * moment * std::cos(x.input), 1e-6) << steps << " " << x.input;
    }
    EXPECT_EQ(r.determinate, coarse.determinate) << steps;
  }
}

// IFToMM A02 N-four-bar (N = 2) driven at its first crank: its change points at 180° and 360°
// (all links in line, E loses rank) are passed at any step count — grid on them or not — with
// power balance τṡ = d(T + V)/dt at the regular positions away from them.
TEST(Cycle, NFourBarPassesItsChangePoints) {
  const Model model = test::load_bundled("n-four-bar-2");
  for (const int steps : {360, 1000, 3600}) {
    CycleOptions o;
    o.driver.joint = model.find_joint("O0");
    o.driver.speed = 2.0 * std::numbers::pi;
    o.steps = steps;
    const CycleResult r = run_cycle(model, o);
    ASSERT_EQ(r.status, CycleStatus::completed) << steps << ": " << r.message;
    ASSERT_EQ(r.points.size(), static_cast<size_t>(steps));
    ASSERT_EQ(r.singular_positions.size(), 2u) << steps;
    // Located to 2e-4 rad (0.01°): a flagged position (chart quality < 1e-4) or the
    // interpolated sign change of det(E_RDᵀ), not refined further.
    for (const auto& sp : r.singular_positions)
      EXPECT_NEAR(std::remainder(sp.input, std::numbers::pi), 0.0, 2e-4) << steps;
    const int checked = expect_power_balance(
        r.points, 1e-6, [](const DrivenPointView& x) { return x.chart_quality >= 0.05; });
    EXPECT_GT(checked, steps / 2);
  }
}

// A prismatic driver: the slider-crank driven at its piston over a stroke range (the crank
// follows): power balance F ṡ = d(T + V)/dt with F the drive force. The gas force, which has no
// potential, is taken out of the model (its power is not in T + V).
// The corrector's sparse Jacobian (KLU on [E_Rᵀ; dᵀ; I], large models) against its dense LU, the
// independent solve: the same sweep, every position and the drive, with
// CycleOptions::sparse_jacobian_from = 0 on small models — the crank-rocker (chord steps, few
// fallbacks), the redundant triple-crank (all rows: the normal equations, fallbacks next to its
// change points) and the RSSR, whose coupler spin is idle (idle rows; no chord steps, so a
// factorisation at every position). Measured: positions within 6e-15 (triple-crank) and 8e-16
// (RSSR), the drive within 3e-12 of its peak; the crank-rocker bit for bit; 73, 7 and 649 own
// factorisations on each path. Bounds: 1e-9 (m, rad) and 1e-9 of the peak drive.
TEST(Cycle, SparseCorrectorJacobianGivesTheDenseSweep) {
  for (const char* name : {"crank-rocker", "triple-crank", "rssr"}) {
    const Model model = test::load_bundled(name);
    CycleOptions o;
    o.driver = model.drivers.at(0);
    o.steps = 90;
    const CycleResult dense = run_cycle(model, o);
    o.sparse_jacobian_from = 0;
    const CycleResult sparse = run_cycle(model, o);
    ASSERT_EQ(dense.status, CycleStatus::completed) << name << ": " << dense.message;
    ASSERT_EQ(sparse.status, CycleStatus::completed) << name << ": " << sparse.message;
    ASSERT_EQ(sparse.points.size(), dense.points.size()) << name;
    EXPECT_GT(sparse.corrector_factorisations, 0) << name;
    double peak = 0.0, dq = 0.0, ddrive = 0.0;
    for (size_t i = 0; i < dense.points.size(); ++i) {
      const DrivenPointView a = dense.points[i], b = sparse.points[i];
      ASSERT_EQ(a.time, b.time) << name << " " << i;
      peak = std::max(peak, std::abs(a.drive));
      dq = std::max(dq, (a.q - b.q).cwiseAbs().maxCoeff());
      if (drive_reported(a) && drive_reported(b))
        ddrive = std::max(ddrive, std::abs(a.drive - b.drive));
    }
    EXPECT_LT(dq, 1e-9) << name;
    EXPECT_LT(ddrive, 1e-9 * peak) << name;
  }
}

TEST(Cycle, PrismaticDriverPowerBalance) {
  Model model = test::load_bundled("slider-crank");
  std::erase_if(model.loads,
                [](const Load& l) { return std::holds_alternative<PointForce>(l.kind); });
  CycleOptions o;
  o.driver.joint = model.find_joint("slide");
  ASSERT_GE(o.driver.joint, 0);
  o.driver.speed = 2.0;  // m/s
  o.full_cycle = false;
  o.use_start = true;
  o.start = 0.235;  // m, piston positions between the dead centres (150 … 250 mm)
  o.end = 0.175;
  o.steps = 2001;
  const CycleResult r = run_cycle(model, o);
  ASSERT_EQ(r.status, CycleStatus::completed) << r.message;
  ASSERT_EQ(r.points.size(), 2001u);
  EXPECT_NEAR(r.points.front().input, 0.235, 1e-12);
  EXPECT_NEAR(r.points.back().input, 0.175, 1e-12);
  EXPECT_EQ(expect_power_balance(r.points, 1e-6, kAll), 2001 - 4);  // all but 2 at each end
}

// A harmonic driver s = a sin(2π f t): ṡ and s̈ vary and change sign. Power balance
// τ ṡ = d/dt (T + V) at every position (five-point stencil on the uniform time grid), and the
// input follows the law.
TEST(Cycle, HarmonicDriverPowerBalance) {
  const Model model = test::load_bundled("double-rocker");
  CycleOptions o = options_for(model, 2000);
  ASSERT_EQ(o.driver.profile, Profile::harmonic);
  const CycleResult r = run_cycle(model, o);
  ASSERT_EQ(r.status, CycleStatus::completed) << r.message;
  ASSERT_EQ(r.points.size(), 2000u);
  const double w = 2.0 * std::numbers::pi * o.driver.frequency;
  for (const auto& x : r.points)
    EXPECT_NEAR(x.input, o.driver.initial + o.driver.amplitude * std::sin(w * x.time), 1e-12);
  EXPECT_EQ(expect_power_balance(r.points, 1e-6, kAll), 2000 - 4);  // all but 2 at each end
}

// --reverse-at-dead-point: the rocker-driven double-rocker passes both folds (±θ*, closed form)
// and returns to its start configuration; the second half runs on the other assembly branch
// (same input, different coupler angle); power balance holds on both branches.
TEST(Cycle, ReverseAtDeadPointSweepsTheClosedCurve) {
  const Model model = test::load_bundled("double-rocker");
  CycleOptions o = options_for(model, 3600);
  o.driver.profile = Profile::constant_speed;
  o.driver.speed = 1.0;
  o.reverse_at_dead_point = true;
  const CycleResult r = run_cycle(model, o);
  ASSERT_EQ(r.status, CycleStatus::completed) << r.message;
  EXPECT_EQ(r.reversals, 2);
  ASSERT_EQ(r.dead_points.size(), 2u);
  const double a = 60, b = 40, c = 65, g = 100;
  const double theta = std::acos((a * a + g * g - (b + c) * (b + c)) / (2 * a * g));
  EXPECT_NEAR(r.dead_points[0].input, theta, 1e-6);
  EXPECT_NEAR(r.dead_points[1].input, -theta, 1e-6);
  // Back near the start: the last position is within one step of the first, on its branch.
  const auto& p = r.points;
  EXPECT_LT((p.back().q - p.front().q).cwiseAbs().maxCoeff(), 0.02);
  EXPECT_GT(p.back().tangent.dot(p.front().tangent), 0.0);
  // Two branches: at (nearly) the same input the coupler angles differ.
  const int coupler = model.find_measure("coupler_angle");
  ASSERT_GE(coupler, 0);
  const auto& first = p[10];
  double best = 1e9, other_angle = 0.0;
  for (const auto& x : p)
    if (x.time > r.dead_points[0].time && x.time < r.dead_points[1].time &&
        std::abs(x.input - first.input) < best) {
      best = std::abs(x.input - first.input);
      other_angle = x.measures[static_cast<size_t>(coupler)];
    }
  EXPECT_LT(best, 0.01);
  EXPECT_GT(std::abs(other_angle - first.measures[static_cast<size_t>(coupler)]), 0.1);
  // Power balance at points whose stencil does not straddle or approach a fold (next to a fold
  // u = F ṡ/(dᵀF) grows without bound and the stencil's h⁴ error with it).
  EXPECT_GT(expect_power_balance(r.points, 1e-6,
                                 [](const DrivenPointView& x) { return std::abs(x.dTF) >= 0.2; }),
            500);
}

// Results do not depend on the order of bodies and joints in the file: the file is rewritten
// with both lists reversed and the drive and every reaction component (matched by name) agree.
TEST(Cycle, IndependentOfBodyAndJointOrder) {
  for (const std::string name :
       {"crank-rocker", "slider-crank", "andrews-squeezer", "rssr", "bennett", "double-wishbone"}) {
    const std::string path = test::source_path("mechanisms/" + name + ".yaml");
    YAML::Node root = YAML::LoadFile(path);
    for (const char* list : {"bodies", "joints"}) {
      YAML::Node reversed(YAML::NodeType::Sequence);
      for (size_t i = root[list].size(); i-- > 0;) reversed.push_back(root[list][i]);
      root[list] = reversed;
    }
    YAML::Emitter emitter;
    emitter << root;
    const Model a = test::load_bundled(name);
    const Model b = parse_mechanism(emitter.c_str(), name + "-reversed");
    ASSERT_NE(a.joints.front().name, b.joints.front().name) << name;
    const CycleResult ra = run_cycle(a, options_for(a, 72));
    const CycleResult rb = run_cycle(b, options_for(b, 72));
    ASSERT_EQ(ra.status, CycleStatus::completed) << ra.message;
    ASSERT_EQ(rb.status, CycleStatus::completed) << rb.message;
    ASSERT_EQ(ra.points.size(), rb.points.size());
    std::map<std::string, size_t> index_b;
    for (size_t i = 0; i < rb.components.size(); ++i) index_b[rb.components[i].name] = i;
    ASSERT_EQ(index_b.size(), ra.components.size());
    for (size_t k = 0; k < ra.points.size(); ++k) {
      const auto &pa = ra.points[k], &pb = rb.points[k];
      ASSERT_NEAR(pa.input, pb.input, 1e-12);
      EXPECT_NEAR(pa.drive, pb.drive, 1e-9 * (1.0 + std::abs(pa.drive))) << name << " " << k;
      for (size_t i = 0; i < ra.components.size(); ++i) {
        const double va = pa.reactions[i], vb = pb.reactions[index_b.at(ra.components[i].name)];
        EXPECT_NEAR(va, vb, 1e-9 * (1.0 + std::abs(va))) << name << " " << ra.components[i].name;
      }
    }
  }
}

// The compact storage of the positions reads back what the sweep computed: every field of a
// stored position against a fresh compute_driven at its q (same law values) with the reactions,
// measures and energies evaluated the plain way (sin/cos per call, no rotation table).
TEST(Cycle, StoredPositionsEqualAFreshEvaluationAtTheirPosition) {
  const Model model = test::load_bundled("crank-rocker");
  CycleOptions o;
  o.driver = model.drivers.at(0);
  o.steps = 36;
  const CycleResult r = run_cycle(model, o);
  ASSERT_EQ(r.status, CycleStatus::completed) << r.message;
  ASSERT_EQ(r.points.size(), 36u);
  size_t visited = 0;
  for (const DrivenPointView& v : r.points) {  // range-for gives the positions in order
    const DrivenPointView at = r.points[visited++];
    EXPECT_EQ(v.time, at.time);
    EXPECT_EQ(v.q.data(), at.q.data());
  }
  EXPECT_EQ(visited, r.points.size());
  for (const size_t k : {size_t{0}, size_t{1}, size_t{17}, size_t{35}}) {
    const DrivenPointView v = r.points[k];
    State s(model);
    s.q = v.q;
    s.t = v.time;
    Workspace ws(model, r.rank);
    DrivenWorkspace w(model, r.rank);
    DrivenPoint p;
    ASSERT_TRUE(
        compute_driven(model, o.driver.joint, v.input_rate, v.input_acceleration, s, ws, w, p));
    const double tol = 1e-12;
    auto near = [&](const auto& a, const auto& b, const char* what) {
      ASSERT_EQ(a.size(), b.size()) << what;
      for (Eigen::Index i = 0; i < static_cast<Eigen::Index>(a.size()); ++i)
        EXPECT_NEAR(a[static_cast<size_t>(i)], b[static_cast<size_t>(i)],
                    tol * (1.0 + std::abs(b[static_cast<size_t>(i)])))
            << what << "[" << i << "] at position " << k;
    };
    const VecX q = v.q, u = v.u, udot = v.udot, lambda = v.lambda, tangent = v.tangent;
    near(q, p.q, "q");
    near(u, p.u, "u");
    near(udot, p.udot, "udot");
    near(lambda, p.lambda, "lambda");
    near(tangent, p.tangent, "tangent");
    EXPECT_NEAR(v.drive, p.drive, tol * (1.0 + std::abs(p.drive)));
    EXPECT_NEAR(std::abs(v.dTF), std::abs(p.dTF), tol);  // its sign is the chart's (F's)
    EXPECT_NEAR(v.input, compute_scalar(model, JointCoordinate{o.driver.joint}, s.q, nullptr).value,
                tol);
    EXPECT_FALSE(v.singular);
    std::vector<double> reactions;
    compute_reactions(model, s.q, p.lambda, reactions);
    const std::vector<double> stored_reactions(v.reactions.begin(), v.reactions.end());
    near(stored_reactions, reactions, "reactions");
    std::vector<double> measures;
    for (const Measure& m : model.measures)
      measures.push_back(evaluate_measure(model, m, s.q, &s.u, &p.udot));
    const std::vector<double> stored_measures(v.measures.begin(), v.measures.end());
    near(stored_measures, measures, "measures");
    EXPECT_NEAR(v.kinetic, kinetic_energy(model, s), tol);
    EXPECT_NEAR(v.potential, potential_energy(model, s.q), tol);
  }
  // One sweep, one set of vector sizes.
  DrivenPoints points;
  DrivenPoint a;
  a.q = VecX::Ones(3), a.u = VecX::Ones(3), a.udot = VecX::Ones(3), a.tangent = VecX::Ones(3);
  a.lambda = VecX::Ones(2), a.reactions = {1.0, 2.0}, a.measures = {3.0};
  points.push_back(a);
  DrivenPoint b = a;
  b.measures.push_back(4.0);
  EXPECT_THROW(points.push_back(b), std::logic_error);
  EXPECT_EQ(points.size(), 1u);
  EXPECT_EQ(points.back().measures.size(), 1u);
  EXPECT_EQ(points.back().reactions[1], 2.0);
}

// The locked-input corrector's steps are chord steps with the chart's factorisation at the
// previous position and its tangent (no factorisation of their own while they converge tenfold
// per iteration). Every stored position must still be on the mechanism, f(q) = 0, and on the
// input's law, s(q) = s₀ + ω (t − t₀) (both evaluated here, independently of the corrector), and
// the corrector must have fallen back to its own factorisation at no more than 1 % of them (a
// wrong chord step does not converge: every step would fall back). The corrector stops at
// 1e-14 (1 + max |q|); the bounds below leave a factor 10 on f and, on the input, room for the
// rounding of s₀ + ω (t − t₀) and of the joint angle over a turn (≲ 1e-14 rad). Planar
// (crank-rocker, n = 9; slider-crank; Andrews, n = 21, beyond the fixed-order LU kernels),
// redundant (crank-rocker-3d: spatial bodies, 3 redundant rows) and with change points
// (triple-crank).
TEST(Cycle, ChordStepsKeepEveryPositionOnTheMechanismAndTheInputLaw) {
  for (const char* name :
       {"crank-rocker", "slider-crank", "andrews-squeezer", "crank-rocker-3d", "triple-crank"}) {
    const Model model = test::load_bundled(name);
    const int steps = 3600;
    const CycleOptions o = options_for(model, steps);
    const CycleResult r = run_cycle(model, o);
    ASSERT_EQ(r.status, CycleStatus::completed) << name << ": " << r.message;
    ASSERT_EQ(r.points.size(), static_cast<size_t>(steps)) << name;
    EXPECT_LE(r.corrector_factorisations, steps / 100) << name;
    const DrivenPointView first = r.points[0];
    VecX f(model.nc);
    double worst_f = 0.0, worst_input = 0.0;
    for (const DrivenPointView& v : r.points) {
      const VecX q = v.q;
      compute_constraint_residual(model, q, f);
      worst_f = std::max(worst_f, f.cwiseAbs().maxCoeff() / (1.0 + q.cwiseAbs().maxCoeff()));
      const double s = compute_scalar(model, JointCoordinate{o.driver.joint}, q, nullptr).value;
      const double law = first.input + o.driver.speed * (v.time - first.time);
      worst_input = std::max(worst_input, std::abs(std::remainder(s - law, 2.0 * M_PI)));
    }
    EXPECT_LT(worst_f, 1e-13) << name;
    EXPECT_LT(worst_input, 1e-11) << name;
  }
}

// Peaks and RMS against a direct computation from the positions where the drive is reported
// (all of them: the two on change points are bridged on the branch, issue 10 item 3); a revolute
// joint's magnitude is |(Fx, Fy)|.
TEST(Cycle, SummaryPeaksAndRms) {
  const Model model = test::load_bundled("triple-crank");
  const CycleResult r = run_cycle(model, options_for(model, 90));
  ASSERT_EQ(r.status, CycleStatus::completed) << r.message;
  const auto mags = reaction_magnitudes(r);
  ASSERT_EQ(mags.size(), model.joints.size());  // six revolute joints: one |F| each
  const auto summary = summarize_cycle(r, mags, "N*m");
  ASSERT_EQ(summary.size(), 1 + mags.size());
  EXPECT_EQ(summary[0].name, "drive");
  double peak = 0.0, sum2 = 0.0, at = 0.0;
  int n = 0;
  for (const auto& p : r.points) {
    if (!drive_reported(p)) continue;
    ++n;
    sum2 += p.drive * p.drive;
    if (std::abs(p.drive) > peak) peak = std::abs(p.drive), at = p.input;
  }
  EXPECT_EQ(summary[0].samples, n);
  EXPECT_EQ(n, static_cast<int>(r.points.size()));
  EXPECT_DOUBLE_EQ(summary[0].peak, peak);
  EXPECT_DOUBLE_EQ(summary[0].peak_input, at);
  EXPECT_NEAR(summary[0].rms, std::sqrt(sum2 / n), 1e-15 * peak);
  const auto& m = mags[0];
  EXPECT_EQ(m.name, model.joints[0].name + ".|F|");
  const auto& p = r.points[3];
  EXPECT_DOUBLE_EQ(magnitude_at(p, m),
                   std::hypot(p.reactions[static_cast<size_t>(m.components[0])],
                              p.reactions[static_cast<size_t>(m.components[1])]));
  // The triple-crank's pin forces are indeterminate (one self-stress family); the drive is not.
  EXPECT_TRUE(summary[0].determinate);
  EXPECT_FALSE(summary[1].determinate);
}

}  // namespace
}  // namespace orthomech
