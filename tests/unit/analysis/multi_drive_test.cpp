// Several drivers (issue 13 item 3) on the Stewart platform (docs/spatial.md §4.7), against oracles
// written here: the closed-form inverse kinematics of positions (l_i = |p + R P_i − B_i|) and
// velocities (l̇_i = n_iᵀ(v + ω × R P_i)), forward kinematics at the reference pose of §4.7, the
// Jacobian-transpose equilibrium of the platform under its payload, and the power balance.
#include "orthomech/analysis/multi_drive.hpp"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <cmath>
#include <numbers>

#include "orthomech/model/spatial.hpp"
#include "support/fixtures.hpp"

namespace orthomech {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

struct Geometry {
  std::array<Vec3, 6> B, P;  // base joints (world), platform joints (platform frame)
  Geometry() {
    const double b[6] = {-15, 15, 105, 135, 225, 255}, p[6] = {-45, 45, 75, 165, 195, 285};
    for (int i = 0; i < 6; ++i) {
      B[static_cast<size_t>(i)] = Vec3(std::cos(b[i] * kDeg), std::sin(b[i] * kDeg), 0);
      P[static_cast<size_t>(i)] = 0.5 * Vec3(std::cos(p[i] * kDeg), std::sin(p[i] * kDeg), 0);
    }
  }
};

struct Platform {
  Vec3 p, v, w;  // origin (= centre of mass), its velocity, ω in world
  Mat3 R;
};

Platform platform_of(const Model& m, const VecX& q, const VecX& u) {
  const Body& b = m.bodies[static_cast<size_t>(m.find_body("platform"))];
  Platform out;
  out.p = q.segment<3>(b.q_offset);
  out.R = rotation_matrix(q.segment<4>(b.q_offset + 3).normalized());
  out.v = u.segment<3>(b.u_offset);
  out.w = out.R * u.segment<3>(b.u_offset + 3);
  return out;
}

std::vector<Driver> all_drivers(const Model& m) {
  std::vector<Driver> d;
  for (const char* name : {"L1", "L2", "L3", "L4", "L5", "L6"})
    for (const Driver& x : m.drivers)
      if (x.name == name) d.push_back(x);
  return d;
}

TEST(MultiDrive, StewartLegLengthsAndRatesEqualTheClosedFormInverseKinematics) {
  const Model model = test::load_bundled("stewart-platform");
  MultiDriveOptions o;
  o.drivers = all_drivers(model);
  ASSERT_EQ(o.drivers.size(), 6u);
  o.steps = 41;
  const MultiDriveResult r = run_multi_drive(model, o);
  ASSERT_EQ(r.status, MultiDriveStatus::completed) << r.message;
  EXPECT_EQ(r.dof, 6);
  EXPECT_NEAR(r.t_end, 2.0, 1e-15);  // one period of the 0.5 Hz laws
  ASSERT_EQ(r.points.size(), 41u);
  const Geometry g;
  double moved = 0.0;
  for (const MultiDrivenPoint& pt : r.points) {
    const Platform pl = platform_of(model, pt.q, pt.u);
    moved = std::max(moved, (pl.p - Vec3(0, 0, 1)).norm());
    for (int i = 0; i < 6; ++i) {
      const Vec3 arm = pl.R * g.P[static_cast<size_t>(i)];
      const Vec3 leg = pl.p + arm - g.B[static_cast<size_t>(i)];
      const Vec3 n = leg.normalized();
      EXPECT_NEAR(leg.norm(), pt.inputs(i), 1e-12) << "leg " << i + 1 << " t " << pt.time;
      EXPECT_NEAR(n.dot(pl.v + pl.w.cross(arm)), pt.input_rates(i), 1e-12)
          << "leg " << i + 1 << " t " << pt.time;
      // The harmonic law itself.
      const Driver& d = o.drivers[static_cast<size_t>(i)];
      EXPECT_NEAR(pt.inputs(i),
                  d.initial + d.amplitude * std::sin(2 * std::numbers::pi * d.frequency * pt.time),
                  1e-12);
    }
  }
  EXPECT_GT(moved, 0.01);  // the platform really moves
}

TEST(MultiDrive, StewartForwardKinematicsAtTheReferencePose) {
  const Model model = test::load_bundled("stewart-platform");
  const double l[6] = {1.192830938164, 1.194968162786, 1.235086199685,
                       1.372771831376, 1.287233068037, 1.350179392447};
  MultiDriveOptions o;
  o.drivers = all_drivers(model);
  for (int i = 0; i < 6; ++i) {
    Driver& d = o.drivers[static_cast<size_t>(i)];
    d.profile = Profile::polynomial;
    d.coefficients = {l[i], 0.0};  // held at the reference pose's lengths
  }
  o.t_end = 1.0;
  o.steps = 2;
  const MultiDriveResult r = run_multi_drive(model, o);
  ASSERT_EQ(r.status, MultiDriveStatus::completed) << r.message;
  const Platform pl = platform_of(model, r.points[0].q, r.points[0].u);
  const Mat3 R = rotation_matrix(quaternion_exp(Vec3(0, 0, 10 * kDeg))) *
                 rotation_matrix(quaternion_exp(Vec3(0, 5 * kDeg, 0))) *
                 rotation_matrix(quaternion_exp(Vec3(-5 * kDeg, 0, 0)));
  EXPECT_LT((pl.p - Vec3(0.1, -0.05, 1.1)).norm(), 1e-10);
  EXPECT_LT((pl.R - R).norm(), 1e-10);
}

TEST(MultiDrive, StewartLegForcesEqualTheJacobianTransposeEquilibrium) {
  const Model model = test::load_bundled("stewart-platform");
  MultiDriveOptions o;
  o.drivers = all_drivers(model);
  const double l[6] = {1.192830938164, 1.194968162786, 1.235086199685,
                       1.372771831376, 1.287233068037, 1.350179392447};
  for (int i = 0; i < 6; ++i) {
    o.drivers[static_cast<size_t>(i)].profile = Profile::polynomial;
    o.drivers[static_cast<size_t>(i)].coefficients = {l[i], 0.0};
  }
  o.t_end = 1.0;
  o.steps = 2;
  const MultiDriveResult r = run_multi_drive(model, o);
  ASSERT_EQ(r.status, MultiDriveStatus::completed) << r.message;
  const MultiDrivenPoint& pt = r.points[0];
  EXPECT_LT(pt.u.norm(), 1e-14);  // at rest
  const Platform pl = platform_of(model, pt.q, pt.u);
  const Geometry g;
  // Jᵀ τ + w = 0: leg i pushes the platform with τ_i n_i at R P_i; w = the payload at the centre.
  Eigen::Matrix<double, 6, 6> Jt;
  for (int i = 0; i < 6; ++i) {
    const Vec3 arm = pl.R * g.P[static_cast<size_t>(i)];
    const Vec3 n = (pl.p + arm - g.B[static_cast<size_t>(i)]).normalized();
    Jt.col(i) << n, arm.cross(n);
  }
  Eigen::Matrix<double, 6, 1> w;
  w << 0, 0, -981, 0, 0, 0;
  const Eigen::Matrix<double, 6, 1> tau = Jt.partialPivLu().solve(-w);
  for (int i = 0; i < 6; ++i)
    EXPECT_NEAR(pt.drives(i), tau(i), 1e-10 * tau.cwiseAbs().maxCoeff()) << "leg " << i + 1;
}

TEST(MultiDrive, PowerBalanceOfTheMovingStewartPlatform) {
  const Model model = test::load_bundled("stewart-platform");
  MultiDriveOptions o;
  o.drivers = all_drivers(model);
  o.steps = 21;
  const MultiDriveResult r = run_multi_drive(model, o);
  ASSERT_EQ(r.status, MultiDriveStatus::completed) << r.message;
  const Vec3 payload(0, 0, -981);
  double scale = 0.0, worst = 0.0;
  for (const MultiDrivenPoint& pt : r.points) {
    double rate = 0.0;  // d/dt of the kinetic energy
    for (const Body& b : model.bodies) {
      const Vec3 v = pt.u.segment<3>(b.u_offset), w = pt.u.segment<3>(b.u_offset + 3);
      rate += b.mass * v.dot(pt.udot.segment<3>(b.u_offset)) +
              w.dot(b.spatial.inertia * pt.udot.segment<3>(b.u_offset + 3));
    }
    const Platform pl = platform_of(model, pt.q, pt.u);
    const double input_power = pt.drives.dot(pt.input_rates) + payload.dot(pl.v);
    scale = std::max(scale, std::abs(pt.drives.dot(pt.input_rates)));
    worst = std::max(worst, std::abs(input_power - rate));
  }
  EXPECT_GT(scale, 1.0);
  EXPECT_LT(worst, 1e-9 * scale);
}

// The planar five-bar with two cranks (mechanisms/five-bar.yaml): C at the closed-form circle
// intersection, and the drives' power = d/dt of kinetic plus potential energy.
TEST(MultiDrive, FiveBarCouplerPointAndPowerBalance) {
  const Model model = test::load_bundled("five-bar");
  MultiDriveOptions o;
  o.drivers = model.drivers;
  o.steps = 201;
  const MultiDriveResult r = run_multi_drive(model, o);
  ASSERT_EQ(r.status, MultiDriveStatus::completed) << r.message;
  EXPECT_EQ(r.dof, 2);
  EXPECT_NEAR(r.t_end, 2.0, 1e-15);  // one turn of the 30 rpm crank
  const size_t cx = 2, cy = 3;       // measures C_x, C_y
  ASSERT_EQ(model.measures[cx].name, "C_x");
  double scale = 0.0, worst = 0.0;
  for (const MultiDrivenPoint& p : r.points) {
    const double t1 = p.inputs(0), t2 = p.inputs(1);
    EXPECT_NEAR(t1, 0.5 * std::numbers::pi + 2 * std::numbers::pi * p.time, 1e-12);
    EXPECT_NEAR(t2, 0.5 * std::numbers::pi + std::numbers::pi * p.time, 1e-12);
    const Eigen::Vector2d A(0.1 * std::cos(t1), 0.1 * std::sin(t1));
    const Eigen::Vector2d E(0.3 + 0.1 * std::cos(t2), 0.1 * std::sin(t2));
    const double L = (E - A).norm();
    const Eigen::Vector2d e = (E - A) / L;
    const Eigen::Vector2d C =
        0.5 * (A + E) + std::sqrt(0.09 - 0.25 * L * L) * Eigen::Vector2d(-e.y(), e.x());
    EXPECT_NEAR(p.measures[cx], C.x(), 1e-12) << p.time;
    EXPECT_NEAR(p.measures[cy], C.y(), 1e-12) << p.time;
    double rate = 0.0;
    for (const Body& b : model.bodies) {
      const int k = b.u_offset;
      rate += b.mass * (p.u(k) * p.udot(k) + p.u(k + 1) * p.udot(k + 1)) +
              b.inertia * p.u(k + 2) * p.udot(k + 2) + b.mass * 9.81 * p.u(k + 1);
    }
    const double power = p.drives.dot(p.input_rates);
    scale = std::max(scale, std::abs(power));
    worst = std::max(worst, std::abs(power - rate));
  }
  EXPECT_GT(scale, 0.1);
  EXPECT_LT(worst, 1e-9 * scale);
}

TEST(MultiDrive, WrongCountsAndPeriodlessLawsAreRefused) {
  const Model model = test::load_bundled("stewart-platform");
  MultiDriveOptions o;
  o.drivers = all_drivers(model);
  o.drivers.pop_back();
  MultiDriveResult r = run_multi_drive(model, o);
  EXPECT_EQ(r.status, MultiDriveStatus::invalid_request);
  EXPECT_NE(r.message.find("5 drivers need a mechanism with 5 DOF; this one has 6"),
            std::string::npos)
      << r.message;
  o.drivers = all_drivers(model);
  for (Driver& d : o.drivers) d.profile = Profile::polynomial, d.coefficients = {d.initial, 0.01};
  r = run_multi_drive(model, o);
  EXPECT_EQ(r.status, MultiDriveStatus::invalid_request);
  EXPECT_NE(r.message.find("--t-end"), std::string::npos) << r.message;
}

}  // namespace
}  // namespace orthomech
