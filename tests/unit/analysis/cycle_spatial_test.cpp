// `cycle` on spatial mechanisms (issue 13 item 1), against independent oracles:
//  - RSSR rocker angle and rate against the closed form (docs/spatial.md (M1)) at every position;
//  - power balance: drive power = Σ (m v·v̇ + ωᵀJω̇) − Σ m g·v, written in the test from the
//    bodies' data (body-frame ω: the gyroscopic term does no work);
//  - a Lagrange-multiplier solve of [M −E −d; Eᵀ 0 0; dᵀ 0 0] with Q̂ (gravity and −ω×Jω) built
//    in the test;
//  - the spatial crank-rocker equals the planar file where the motion is planar, and names its
//    out-of-plane components indeterminate;
//  - Hooke's joint velocity ratio, the spatial slider-crank x_C(φ) (M2), Bennett's closure.
#include <gtest/gtest.h>

#include <Eigen/QR>
#include <cmath>
#include <numbers>
#include <string>

#include "orthomech/analysis/cycle.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/model/measures.hpp"
#include "orthomech/model/spatial.hpp"
#include "support/fixtures.hpp"
#include "support/spatial_energy.hpp"

namespace orthomech {
namespace {

constexpr double kPi = std::numbers::pi;

using test::full_cycle;
using test::measure_index;

size_t component_index(const CycleResult& r, const std::string& name) {
  for (size_t i = 0; i < r.components.size(); ++i)
    if (r.components[i].name == name) return i;
  throw std::invalid_argument("no component " + name);
}

// RSSR (mechanisms/rssr.yaml): crank r1 about z through A0 = 0, rocker r2 about x through
// B0 = (p, 0, h), coupler L. φ from world y about x; the file's branch.
struct Rssr {
  double r1 = 0.1, r2 = 0.2, p = 0.3, h = 0.2, L = 0.42;
  [[nodiscard]] double phi(double theta) const {
    const double P = -2 * r1 * r2 * std::sin(theta), Q = 2 * h * r2;
    const double S = p * p + r1 * r1 + r2 * r2 + h * h - L * L - 2 * p * r1 * std::cos(theta);
    return std::atan2(Q, P) + std::acos(-S / std::hypot(P, Q));
  }
  // dφ/dθ by implicit differentiation of P cos φ + Q sin φ + S = 0.
  [[nodiscard]] double ratio(double theta) const {
    const double f = phi(theta);
    const double P = -2 * r1 * r2 * std::sin(theta), Q = 2 * h * r2;
    const double dP = -2 * r1 * r2 * std::cos(theta), dS = 2 * p * r1 * std::sin(theta);
    return -(dP * std::cos(f) + dS) / (-P * std::sin(f) + Q * std::cos(f));
  }
};

TEST(SpatialCycle, RssrRockerAngleAndRateEqualTheClosedForm) {
  const Model model = test::load_bundled("rssr");
  const CycleResult r = full_cycle(model, 360);
  ASSERT_EQ(r.status, CycleStatus::completed) << r.message;
  ASSERT_EQ(r.points.size(), 360u);
  const size_t crank = measure_index(model, "crank_angle");
  const size_t rocker = measure_index(model, "rocker_angle");
  const size_t rate = measure_index(model, "rocker_rate");
  const Rssr rssr;
  const double omega = 2 * kPi;  // 60 rpm
  double worst_angle = 0.0, worst_rate = 0.0;
  for (size_t k = 0; k < r.points.size(); ++k) {
    const DrivenPointView p = r.points[k];
    const double theta = p.measures[crank];
    EXPECT_NEAR(theta, p.input, 1e-12);
    // Unwrapped over the turn: the input runs from 30° to 389°, the rocker angle is continuous.
    EXPECT_NEAR(p.input, kPi / 6 + 2 * kPi * static_cast<double>(k) / 360.0, 1e-12);
    if (k > 0) {
      EXPECT_LT(std::abs(p.measures[rocker] - r.points[k - 1].measures[rocker]), 0.05);
      EXPECT_GT(p.input, r.points[k - 1].input);
    }
    worst_angle = std::max(worst_angle,
                           std::abs(std::remainder(p.measures[rocker] - rssr.phi(theta), 2 * kPi)));
    worst_rate = std::max(worst_rate, std::abs(p.measures[rate] - omega * rssr.ratio(theta)));
  }
  EXPECT_LT(worst_angle, 1e-10);
  EXPECT_LT(worst_rate, 1e-10);
  // The rocker swings through 180° (129.6° … 237.4°): read continuously, not in (−180°, 180°].
  double top = -1e9;
  for (const DrivenPointView& p : r.points) top = std::max(top, p.measures[rocker]);
  EXPECT_GT(top, kPi);
}

TEST(SpatialCycle, PowerBalanceAtEveryPosition) {
  for (const char* name : {"rssr", "spatial-slider-crank", "crank-rocker-3d", "bennett"}) {
    const Model model = test::load_bundled(name);
    const CycleResult r = full_cycle(model, 180);
    ASSERT_EQ(r.status, CycleStatus::completed) << name << ": " << r.message;
    Vec3 g = Vec3::Zero();
    for (const Load& l : model.loads)
      if (const auto* gr = std::get_if<SpatialGravity>(&l.kind)) g = gr->g;
    ASSERT_GT(g.norm(), 1.0) << name;
    double scale = 0.0, worst = 0.0;
    for (const DrivenPointView& p : r.points) {
      const double drive_power = p.drive * p.input_rate;
      scale = std::max(scale, std::abs(drive_power));
      worst = std::max(worst, std::abs(drive_power - test::spatial_energy_rate(model, p, g)));
    }
    EXPECT_LT(worst, 1e-6 * scale) << name << " (drive power up to " << scale << " W)";
    // The same balance by differences of the reported energies over the time grid (a check that
    // kinetic and potential are the energies of these velocities): second order in the step, 0.3 %
    // of the peak power on the fast crank-rocker at 180 steps.
    for (size_t k = 1; k + 1 < r.points.size(); ++k) {
      const DrivenPointView a = r.points[k - 1], b = r.points[k + 1], c = r.points[k];
      const double dE = (b.kinetic + b.potential - a.kinetic - a.potential) / (b.time - a.time);
      EXPECT_NEAR(dE, c.drive * c.input_rate, 1e-2 * scale) << name << " at " << c.input;
    }
  }
}

TEST(SpatialCycle, ReactionsEqualALagrangeMultiplierSolve) {
  const Model model = test::load_bundled("rssr");
  const CycleResult r = full_cycle(model, 36);
  ASSERT_EQ(r.status, CycleStatus::completed) << r.message;
  const int joint = model.drivers[0].joint;
  const int n = model.n, nc = model.nc;
  const Vec3 g(0, 0, -9.81);
  for (const DrivenPointView& p : r.points) {
    State s(model);
    s.q = p.q;
    s.u = p.u;
    ConstraintWorkspace cw(model);
    compute_constraints(model, s, cw);
    VecX d(n);
    const ScalarKinematics sk = compute_scalar(model, JointCoordinate{joint}, s.q, &s.u, d);
    // M and Q̂ of the bodies (v world, ω body frame): gravity and the gyroscopic −ω × Jω.
    MatX M = MatX::Zero(n, n);
    VecX Q = VecX::Zero(n);
    for (const Body& b : model.bodies) {
      M.block<3, 3>(b.u_offset, b.u_offset) = b.mass * Mat3::Identity();
      M.block<3, 3>(b.u_offset + 3, b.u_offset + 3) = b.spatial.inertia;
      const Vec3 w = s.u.segment<3>(b.u_offset + 3);
      Q.segment<3>(b.u_offset) = b.mass * g;
      Q.segment<3>(b.u_offset + 3) = -w.cross(b.spatial.inertia * w);
    }
    MatX K = MatX::Zero(n + nc + 1, n + nc + 1);
    VecX rhs = VecX::Zero(n + nc + 1);
    K.topLeftCorner(n, n) = M;
    K.block(0, n, n, nc) = -cw.Et.transpose();
    K.block(0, n + nc, n, 1) = -d;
    K.block(n, 0, nc, n) = cw.Et;
    K.block(n + nc, 0, 1, n) = d.transpose();
    rhs.head(n) = Q;
    rhs.segment(n, nc) = -cw.Dtu;
    rhs(n + nc) = p.input_acceleration - sk.ddot_u;
    const VecX x = K.colPivHouseholderQr().solve(rhs);
    EXPECT_LT((x.head(n) - p.udot).norm(), 1e-9 * (1.0 + p.udot.norm()));
    EXPECT_LT((x.segment(n, nc) - p.lambda).norm(), 1e-9 * (1.0 + p.lambda.norm()));
    EXPECT_NEAR(x(n + nc), p.drive, 1e-9 * (1.0 + std::abs(p.drive)));
  }
}

TEST(SpatialCycle, CrankRocker3dEqualsThePlanarFileAndNamesTheOutOfPlaneIndeterminate) {
  const Model planar = test::load_bundled("crank-rocker");
  const Model spatial = test::load_bundled("crank-rocker-3d");
  const CycleResult a = full_cycle(planar, 360), b = full_cycle(spatial, 360);
  ASSERT_EQ(a.status, CycleStatus::completed) << a.message;
  ASSERT_EQ(b.status, CycleStatus::completed) << b.message;
  ASSERT_EQ(a.points.size(), b.points.size());
  EXPECT_EQ(b.redundant, 3);
  double drive_scale = 0.0, force_scale = 0.0;
  for (const DrivenPointView& p : a.points) drive_scale = std::max(drive_scale, std::abs(p.drive));
  for (const DrivenPointView& p : a.points)
    for (const double c : p.reactions) force_scale = std::max(force_scale, std::abs(c));
  for (const char* j : {"A0", "A", "B", "B0"}) {
    for (const char* c : {"Fx", "Fy"}) {
      const std::string name = std::string(j) + "." + c;
      const size_t ia = component_index(a, name), ib = component_index(b, name);
      EXPECT_TRUE(b.determinate[ib]) << name;
      for (size_t k = 0; k < a.points.size(); ++k)
        EXPECT_NEAR(a.points[k].reactions[ia], b.points[k].reactions[ib], 1e-10 * force_scale)
            << name << " at " << a.points[k].input;
    }
    // Out of the plane: Fz, Mx, My are shared by the redundant rows (not unique); the moment
    // about the axis vanishes (a revolute).
    for (const char* c : {"Fz", "Mx", "My"})
      EXPECT_FALSE(b.determinate[component_index(b, std::string(j) + "." + c)]) << j << "." << c;
    EXPECT_TRUE(b.determinate[component_index(b, std::string(j) + ".Mz")]) << j;
  }
  for (size_t k = 0; k < a.points.size(); ++k) {
    EXPECT_NEAR(a.points[k].input, b.points[k].input, 1e-12);
    EXPECT_NEAR(a.points[k].drive, b.points[k].drive, 1e-10 * drive_scale);
  }
}

TEST(SpatialCycle, HookeJointVelocityRatio) {
  const Model model = test::load_bundled("hooke-joint");
  const CycleResult r = full_cycle(model, 360);
  ASSERT_EQ(r.status, CycleStatus::completed) << r.message;
  const size_t t1 = measure_index(model, "theta1"), t2 = measure_index(model, "theta2");
  const size_t w2 = measure_index(model, "omega2");
  const double beta = kPi / 6, omega1 = 2 * kPi;
  for (const DrivenPointView& p : r.points) {
    const double th = p.measures[t1];
    const double s = std::sin(beta) * std::sin(th);
    EXPECT_NEAR(p.measures[w2] / omega1, std::cos(beta) / (1 - s * s), 1e-12) << th;
    // tan θ2 = cos β tan θ1, θ2 on θ1's half turn.
    EXPECT_NEAR(
        std::remainder(p.measures[t2] - std::atan2(std::cos(beta) * std::sin(th), std::cos(th)),
                       2 * kPi),
        0.0, 1e-12)
        << th;
  }
}

TEST(SpatialCycle, SpatialSliderCrankSlideEqualsM2) {
  const Model model = test::load_bundled("spatial-slider-crank");
  const CycleResult r = full_cycle(model, 360);
  ASSERT_EQ(r.status, CycleStatus::completed) << r.message;
  const size_t phi_i = measure_index(model, "crank_angle");
  const size_t x_i = measure_index(model, "slider_x"), v_i = measure_index(model, "slider_v");
  for (const DrivenPointView& p : r.points) {
    const double phi = p.measures[phi_i];
    const double By = 0.1 + 0.08 * std::cos(phi), Bz = 0.12 + 0.08 * std::sin(phi);
    const double x = std::sqrt(0.09 - By * By - Bz * Bz);
    const double xdot = (By * 0.08 * std::sin(phi) - Bz * 0.08 * std::cos(phi)) * 6.0 / x;
    EXPECT_NEAR(p.measures[x_i], x, 1e-10) << phi;
    EXPECT_NEAR(p.measures[v_i], xdot, 1e-10) << phi;
  }
}

TEST(SpatialCycle, BennettClosure) {
  const Model model = test::load_bundled("bennett");
  const CycleResult r = full_cycle(model, 360);
  ASSERT_EQ(r.status, CycleStatus::completed) << r.message;
  const size_t t1 = measure_index(model, "theta1"), t2 = measure_index(model, "theta2");
  const int j3 = model.find_joint("J3"), j4 = model.find_joint("J4");
  const double k = std::sin((kPi / 3 + kPi / 6) / 2) / std::sin((kPi / 3 - kPi / 6) / 2);
  // θ3 = −θ1 and θ4 = −θ2 up to the constant offsets of the joints' reference directions.
  const auto coordinate = [&](int j, const DrivenPointView& p) {
    return compute_scalar(model, JointCoordinate{j}, VecX(p.q), nullptr).value;
  };
  const double c3 = coordinate(j3, r.points[0]) + r.points[0].measures[t1];
  const double c4 = coordinate(j4, r.points[0]) + r.points[0].measures[t2];
  for (const DrivenPointView& p : r.points) {
    const double th1 = p.measures[t1], th2 = p.measures[t2];
    // tan(θ1/2) tan(θ2/2) = k, written without poles.
    EXPECT_NEAR(std::sin(th1 / 2) * std::sin(th2 / 2) - k * std::cos(th1 / 2) * std::cos(th2 / 2),
                0.0, 1e-10)
        << th1;
    EXPECT_NEAR(std::remainder(coordinate(j3, p) + th1 - c3, 2 * kPi), 0.0, 1e-10) << th1;
    EXPECT_NEAR(std::remainder(coordinate(j4, p) + th2 - c4, 2 * kPi), 0.0, 1e-10) << th1;
  }
}

}  // namespace
}  // namespace orthomech
