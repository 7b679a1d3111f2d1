// `assemble` with locks and limits on spatial joint coordinates (issue 12, item 6 leftovers): the
// lock row reads the (P5) angle modulo 2π nearest the lock ((L4) in assembly.cpp), the start is the
// design pose moved to the locks on its branch. Oracles, written here from the geometry alone:
//  - the RSSR's input–output relation (docs/spatial.md (M1)), the file's branch (+acos);
//  - the spatial slider-crank's x_C(φ) (docs/spatial.md (M2));
//  - Hooke's joint: tan θ2 = cos β tan θ1, θ2 in θ1's half-plane (mechanisms/hooke-joint.yaml);
//  - Bennett's closure θ3 = −θ1, θ4 = −θ2, tan(θ1/2) tan(θ2/2) = sin((β+α)/2)/sin((β−α)/2)
//    (docs/spatial.md §4.2), 3 redundant equations;
//  - a KKT check of (A1) with a limit active: W x = Cᵀλ with C by central differences in x.
#include <gtest/gtest.h>

#include <Eigen/QR>
#include <cmath>
#include <numbers>
#include <string>

#include "orthomech/analysis/assembly.hpp"
#include "orthomech/analysis/cycle_metrics.hpp"
#include "orthomech/analysis/positions.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/model/measures.hpp"
#include "support/fixtures.hpp"
#include "support/spatial_oracles.hpp"

namespace orthomech {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;
// The assembled pose closes every row to 1e-12 (m, rad); an output angle or slide read from it
// agrees with its closed form to this (the brief's 1e-9; observed ≤ 1e-12).
constexpr double kClosedForm = 1e-9;

double wrap(double a) { return std::remainder(a, 2 * kPi); }

double measure(const Model& m, const std::string& name, const VecX& q) {
  const int k = m.find_measure(name);
  EXPECT_GE(k, 0) << name;
  return evaluate_measure(m, m.measures[static_cast<size_t>(k)], q, nullptr, nullptr);
}

AssemblyResult assemble_locked(const Model& m, const std::string& joint, double value) {
  AssemblyOptions o;
  o.locks.push_back({m.find_joint(joint), value});
  return assemble(m, m.design_q(), o);
}

void expect_closed(const Model& m, const AssemblyResult& r) {
  ASSERT_TRUE(r.status == AssemblyStatus::assembled || r.status == AssemblyStatus::unchanged)
      << r.message;
  VecX f(m.nc);
  compute_constraint_residual(m, r.q, f);
  EXPECT_LT(f.cwiseAbs().maxCoeff(), 1e-12);
  for (const Body& b : m.bodies)  // unit quaternions
    EXPECT_NEAR(r.q.segment<4>(b.q_offset + 3).norm(), 1.0, 1e-14) << b.name;
}

using test::rssr_rocker_angle;

TEST(SpatialLocks, RssrCrankLockGivesTheRockerAngleOfM1OnTheFilesBranch) {
  const Model m = test::load_bundled("rssr");
  // Every quarter and a few in between, among them a lock given past a full turn (390° = 30°)
  // and one the other way round (−150° = 210°): the crank goes the short way to it.
  for (double deg : {0.0, 30.0, 45.0, 90.0, 135.0, 180.0, 225.0, 270.0, 315.0, 390.0, -150.0}) {
    const AssemblyResult r = assemble_locked(m, "A0", deg * kDeg);
    expect_closed(m, r);
    const double theta = measure(m, "crank_angle", r.q);
    EXPECT_NEAR(wrap(theta - deg * kDeg), 0.0, 1e-12) << deg;
    EXPECT_NEAR(wrap(measure(m, "rocker_angle", r.q) - rssr_rocker_angle(deg * kDeg)), 0.0,
                kClosedForm)
        << deg;
    EXPECT_LT(r.residual, 1e-12);
  }
}

TEST(SpatialLocks, SpatialSliderCrankLockGivesTheSlideOfM2) {
  const Model m = test::load_bundled("spatial-slider-crank");
  for (double deg : {0.0, 45.0, 90.0, 135.0, 180.0, 225.0, 270.0, 315.0}) {
    const double phi = deg * kDeg;
    const AssemblyResult r = assemble_locked(m, "A0", phi);
    expect_closed(m, r);
    const double xc = std::sqrt(0.09 - std::pow(0.1 + 0.08 * std::cos(phi), 2) -
                                std::pow(0.12 + 0.08 * std::sin(phi), 2));  // (M2)
    EXPECT_NEAR(measure(m, "slider_x", r.q), xc, kClosedForm) << deg;
  }
  // The slide locked instead (a prismatic coordinate, m): the crank angle that gives it, on the
  // branch of the drawing (φ = 90°, the crank moving towards φ = 45° as x_C falls to 0.1852 m).
  const double phi = 60 * kDeg;
  const double xc = std::sqrt(0.09 - std::pow(0.1 + 0.08 * std::cos(phi), 2) -
                              std::pow(0.12 + 0.08 * std::sin(phi), 2));
  const AssemblyResult r = assemble_locked(m, "slide", xc);
  expect_closed(m, r);
  EXPECT_NEAR(measure(m, "slider_x", r.q), xc, 1e-12);
  EXPECT_NEAR(wrap(measure(m, "crank_angle", r.q) - phi), 0.0, kClosedForm);
}

TEST(SpatialLocks, HookeJointLockGivesTheOutputAngleOfItsClosedForm) {
  const Model m = test::load_bundled("hooke-joint");
  const double beta = 30 * kDeg;
  for (double deg : {0.0, 20.0, 45.0, 89.0, 100.0, 170.0, 200.0, 300.0}) {
    const double t1 = deg * kDeg;
    const AssemblyResult r = assemble_locked(m, "R1", t1);
    expect_closed(m, r);
    // tan θ2 = cos β tan θ1 with θ2 in θ1's half-plane: atan2(cos β sin θ1, cos θ1).
    const double t2 = std::atan2(std::cos(beta) * std::sin(t1), std::cos(t1));
    EXPECT_NEAR(wrap(measure(m, "theta2", r.q) - t2), 0.0, kClosedForm) << deg;
  }
}

// Bennett's linkage has 3 redundant equations: Ipopt keeps the independent rows of f at the start
// (on the manifold) and the polish keeps that row set with the lock row (re-ranking the rows off
// the manifold, where the redundant ones regain rank, made the step singular).
TEST(SpatialLocks, BennettLockSatisfiesItsClosureWithThreeRedundantEquations) {
  const Model m = test::load_bundled("bennett");
  const double a = 30 * kDeg, b = 60 * kDeg;
  const double k = std::sin((b + a) / 2) / std::sin((b - a) / 2);
  for (double deg : {20.0, 75.0, 140.0, 200.0, -100.0, 10.0, 170.0}) {
    const double t1 = deg * kDeg;
    const AssemblyResult r = assemble_locked(m, "J1", t1);
    expect_closed(m, r);
    const double t2 = measure(m, "theta2", r.q);
    // tan(θ1/2) tan(θ2/2) = k without poles: sin(θ1/2) sin(θ2/2) = k cos(θ1/2) cos(θ2/2).
    EXPECT_NEAR(std::sin(t1 / 2) * std::sin(t2 / 2) - k * std::cos(t1 / 2) * std::cos(t2 / 2), 0.0,
                kClosedForm)
        << deg;
    EXPECT_NEAR(wrap(joint_coordinate(m, m.find_joint("J3"), r.q) + t1), 0.0, kClosedForm) << deg;
    EXPECT_NEAR(wrap(joint_coordinate(m, m.find_joint("J4"), r.q) + t2), 0.0, kClosedForm) << deg;
  }
  // The file's values (docs/spatial.md §4.2).
  const AssemblyResult r = assemble_locked(m, "J1", 20 * kDeg);
  EXPECT_NEAR(measure(m, "theta2", r.q), 172.6144863489 * kDeg, 1e-11);
}

TEST(SpatialLocks, ALockAtTheDesignPoseLeavesItUnchanged) {
  const Model m = test::load_bundled("bennett");  // closed to 7e-17 at θ1 = 75°
  const VecX q0 = m.design_q();
  const double t1 = joint_coordinate(m, m.find_joint("J1"), q0);
  // The same angle a turn later reads the same (L4).
  const AssemblyResult r = assemble_locked(m, "J1", t1 + 2 * kPi);
  ASSERT_EQ(r.status, AssemblyStatus::unchanged) << r.message;
  EXPECT_EQ(r.q, q0);
}

TEST(SpatialLocks, ALockOutOfReachCannotCloseAndNamesTheLock) {
  const Model m = test::load_bundled("rssr");
  // The rocker swings over 129.6°…237.4° only: 90° is out of reach.
  const AssemblyResult r = assemble_locked(m, "B0", 90 * kDeg);
  EXPECT_EQ(r.status, AssemblyStatus::cannot_close) << r.message;
  EXPECT_NE(r.message.find("with joint 'B0' locked at 90 deg"), std::string::npos) << r.message;
  EXPECT_FALSE(r.gaps.empty());
  // The least-squares pose keeps the lock, to the tolerance of Ipopt's last iterate of (A2)
  // (limited-memory Hessian; 4e-5 rad observed), far from the 40° the rocker would need to move.
  EXPECT_NEAR(wrap(joint_coordinate(m, m.find_joint("B0"), r.q) - 90 * kDeg), 0.0, 1e-3);
}

// A measure's value locked: the RSSR's rocker point B at height z = h + r2 sin φ with φ = 170°
// (from the drawn 158.1°, the rocker turning on): the rocker at φ and the crank where (M1) puts
// the rocker there on the file's branch. Out of reach (z above h + r2 = 0.4 m): named.
TEST(SpatialLocks, AMeasuresValueIsLockedOnTheFilesBranch) {
  const Model m = test::load_bundled("rssr");
  const double phi = 170 * kDeg, z = 0.2 + 0.2 * std::sin(phi);
  AssemblyOptions o;
  JointLock l;
  l.measure = m.find_measure("B_z");
  l.value = z;
  o.locks.push_back(l);
  const AssemblyResult r = assemble(m, m.design_q(), o);
  expect_closed(m, r);
  EXPECT_NEAR(measure(m, "B_z", r.q), z, 1e-12);
  EXPECT_NEAR(wrap(measure(m, "rocker_angle", r.q) - phi), 0.0, kClosedForm);
  EXPECT_NEAR(wrap(rssr_rocker_angle(measure(m, "crank_angle", r.q)) - phi), 0.0, kClosedForm);
  // A joint measure locks its joint (read modulo a turn).
  JointLock crank;
  crank.measure = m.find_measure("crank_angle");
  crank.value = (90 + 360) * kDeg;
  o.locks = {crank};
  const AssemblyResult c = assemble(m, m.design_q(), o);
  expect_closed(m, c);
  EXPECT_NEAR(wrap(measure(m, "rocker_angle", c.q) - rssr_rocker_angle(90 * kDeg)), 0.0,
              kClosedForm);

  o.locks = {l};
  o.locks[0].value = 0.45;
  const AssemblyResult far = assemble(m, m.design_q(), o);
  EXPECT_EQ(far.status, AssemblyStatus::cannot_close) << far.message;
  EXPECT_NE(far.message.find("with measure 'B_z' locked at 450 mm"), std::string::npos)
      << far.message;
}

TEST(SpatialLocks, AJointWithoutACoordinateCannotBeLocked) {
  const Model m = test::load_bundled("rssr");
  AssemblyOptions o;
  o.locks.push_back({m.find_joint("A"), 0.0});  // spherical
  try {
    (void)assemble(m, m.design_q(), o);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("joint 'A' has no coordinate to lock (a spherical joint"),
              std::string::npos)
        << e.what();
  }
}

// Limits on a spatial angle are bounds of (A1), read modulo 2π nearest their middle: with the
// crank limited to [200°, 220°] and the file drawn at 30°, the crank ends at the nearer bound
// (200°, reached the short way round through 180°, a limit interval across the (−π, π] seam) and
// the rocker at (M1) there; with a lock inside, the lock holds; with a lock outside, no pose
// closes and the message names the lock.
TEST(SpatialLocks, LimitsOnASpatialAngleAreBoundsReadModuloATurn) {
  Model m = test::load_bundled("rssr");
  const int A0 = m.find_joint("A0");
  m.joints[static_cast<size_t>(A0)].limits = Vec2(200 * kDeg, 220 * kDeg);
  AssemblyOptions o;
  o.locks.push_back({A0, 215 * kDeg});
  const AssemblyResult locked = assemble(m, m.design_q(), o);
  expect_closed(m, locked);
  EXPECT_NEAR(wrap(measure(m, "rocker_angle", locked.q) - rssr_rocker_angle(215 * kDeg)), 0.0,
              kClosedForm);

  // Compared with its limits, the angle reads modulo a turn nearest their middle: 215°, not the
  // (P5) angle's −145° (cycle_metrics' limit_coordinate, used for limit blocks and excursions).
  EXPECT_NEAR(limit_coordinate(m, A0, locked.q), 215 * kDeg, 1e-12);
  EXPECT_FALSE(outside_limits(m, A0, locked.q));

  o.locks[0].value = 100 * kDeg;
  const AssemblyResult outside = assemble(m, m.design_q(), o);
  EXPECT_NE(outside.status, AssemblyStatus::assembled);
  EXPECT_NE(outside.message.find("joint 'A0' locked at 100 deg"), std::string::npos)
      << outside.message;

  // Without a lock the crank goes to a bound; the mechanism has DOF 1, so (A1) is the nearest
  // admissible pose to the drawing in the mass metric among those with the crank in the limits.
  const AssemblyResult free = assemble(m, m.design_q());
  expect_closed(m, free);
  const double theta = measure(m, "crank_angle", free.q);
  const double at_bound =
      std::min(std::abs(wrap(theta - 200 * kDeg)), std::abs(wrap(theta - 220 * kDeg)));
  EXPECT_LT(at_bound, 1e-10) << theta / kDeg;
  EXPECT_NEAR(wrap(measure(m, "rocker_angle", free.q) - rssr_rocker_angle(theta)), 0.0,
              kClosedForm);
}

// A slide limit on the spatial slider-crank: [0.25, 0.3] m keeps x_C from its drawn 0.2 m, so
// the slide ends at the nearer bound 0.25 m. With the slide row C = ∂(f, s)/∂x is square (DOF 1),
// so W x = Cᵀλ only fixes λ (C by central differences in x, q = q₀ ⊕ x): the multiplier of the
// bound must be that of a lower bound holding the pose back (λ > 0); at the upper bound or on the
// wrong side it would not be.
TEST(SpatialLocks, ASlideLimitIsAnActiveBoundAtAKktPoint) {
  Model m = test::load_bundled("spatial-slider-crank");
  const int slide = m.find_joint("slide");
  m.joints[static_cast<size_t>(slide)].limits = Vec2(0.25, 0.3);
  VecX q0 = m.design_q();
  normalize_coordinates(m, q0);
  const AssemblyResult r = assemble(m, q0);
  expect_closed(m, r);
  EXPECT_NEAR(measure(m, "slider_x", r.q), 0.25, 1e-10);
  VecX x(m.n);
  difference_positions(m, r.q, q0, x);
  MatX M(m.n, m.n);
  compute_mass_matrix(m, q0, M);
  const double h = 1e-7;
  MatX C(m.nc + 1, m.n);
  for (int k = 0; k < m.n; ++k) {
    VecX qp = q0, qm = q0, fp(m.nc), fm(m.nc);
    integrate_positions(m, qp, x + h * VecX::Unit(m.n, k), 1.0);
    integrate_positions(m, qm, x - h * VecX::Unit(m.n, k), 1.0);
    compute_constraint_residual(m, qp, fp);
    compute_constraint_residual(m, qm, fm);
    C.col(k).head(m.nc) = (fp - fm) / (2 * h);
    C(m.nc, k) = (joint_coordinate(m, slide, qp) - joint_coordinate(m, slide, qm)) / (2 * h);
  }
  const VecX g = M * x;
  const VecX lambda = C.transpose().completeOrthogonalDecomposition().solve(g);
  EXPECT_LT((C.transpose() * lambda - g).norm(), 1e-6 * g.norm());
  // A lower bound that holds the pose back: ∇φ = λ ∇s with λ > 0 (the distance would fall
  // with a smaller slide).
  EXPECT_GT(lambda(m.nc), 0.0);
  EXPECT_GT(x.norm(), 1e-3);
}

}  // namespace
}  // namespace orthomech
