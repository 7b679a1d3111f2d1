// The rolling disc's rows (docs/spatial.md §3, (D0)) against independent oracles: central
// differences taken through integrate_positions (q ⊕ t·u, the exponential map), at random poses
// where the disc neither touches the plane nor rolls: row n's Eᵀ = ∂f/∂q·B̃; every row's Eᵀu = the
// velocity along n of the body point that is the contact point at this instant (a fixed body point,
// differentiated along the motion); Dᵀ = dEᵀ/dt; Dᵀu row by row = Dᵀ·u; row n's Dᵀu = f̈. The
// height f against the lowest rim point found by a search over the rim.
#include "orthomech/constraints/rolling_disc.hpp"

#include <gtest/gtest.h>

#include <numbers>
#include <random>

#include "orthomech/constraints/joints.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/model/spatial.hpp"
#include "support/spatial_fixtures.hpp"

namespace orthomech {
namespace {

using testing::spatial::body;
using testing::spatial::inertia_a;
using testing::spatial::random_state;
using testing::spatial::unit_quaternion;

// One spatial body with a full inertia tensor carrying a disc whose centre is off the centre of
// mass, on a tilted plane with a general t1.
Model disc_model() {
  Model m;
  m.name = "disc";
  m.dimension = 3;
  m.bodies.push_back(body("wheel", 2.0, Vec3(0.1, -0.3, 0.4), unit_quaternion(0.9, 0.2, -0.3, 0.1),
                          Vec3(0.05, 0.02, -0.04), inertia_a()));
  RollingDisc d;
  d.name = "contact";
  d.body = 0;
  d.radius = 0.25;
  d.axis_local = Vec3(0.2, -0.3, 0.93).normalized();
  d.centre_local = Vec3(0.03, -0.02, 0.05);
  d.plane_point = Vec3(0.1, 0.2, -0.3);
  d.normal = Vec3(0.1, -0.2, 0.97).normalized();
  d.t1 = d.normal.unitOrthogonal();
  d.t1 = (Eigen::AngleAxisd(0.7, d.normal) * d.t1).normalized();
  m.rolling_discs.push_back(d);
  finalize_model(m);
  return m;
}

VecX residual_along(const Model& m, const VecX& q, const VecX& du, double t) {
  VecX qt = q;
  integrate_positions(m, qt, du, t);
  VecX f(m.nc);
  compute_constraint_residual(m, qt, f);
  return f;
}
MatX jacobian_along(const Model& m, const VecX& q, const VecX& du, double t) {
  VecX qt = q;
  integrate_positions(m, qt, du, t);
  MatX Et(m.nc, m.n);
  compute_constraint_jacobian(m, qt, Et);
  return Et;
}

// The lowest point of the rim above the plane by a search over the rim angle (golden section
// refined from the best of 720 samples): the independent oracle of row n's f, and the contact
// point (world).
struct Lowest {
  double height;
  Vec3 point;
};
Lowest lowest_rim_point(const RollingDisc& d, const Vec3& r, const Mat3& R) {
  const Vec3 a = R * d.axis_local, C = r + R * d.centre_local;
  const Vec3 e1 = a.unitOrthogonal(), e2 = a.cross(e1);
  const auto rim = [&](double phi) {
    return Vec3(C + d.radius * (std::cos(phi) * e1 + std::sin(phi) * e2));
  };
  const auto height = [&](double phi) { return d.normal.dot(rim(phi) - d.plane_point); };
  constexpr int kSamples = 720;
  double best = 0.0;
  for (int k = 1; k < kSamples; ++k) {
    const double phi = 2 * std::numbers::pi * k / kSamples;
    if (height(phi) < height(best)) best = phi;
  }
  double lo = best - 2 * std::numbers::pi / kSamples, hi = best + 2 * std::numbers::pi / kSamples;
  const double g = (std::sqrt(5.0) - 1.0) / 2.0;
  for (int it = 0; it < 200; ++it) {
    const double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo);
    if (height(x1) < height(x2))
      hi = x2;
    else
      lo = x1;
  }
  const double phi = 0.5 * (lo + hi);
  return {height(phi), rim(phi)};
}

TEST(RollingDisc, RowNamesAndCount) {
  const Model m = disc_model();
  EXPECT_EQ(m.nc, 3);
  EXPECT_EQ(m.constraint_row_name(0), "rolling disc 'contact', t1");
  EXPECT_EQ(m.constraint_row_name(1), "rolling disc 'contact', t2");
  EXPECT_EQ(m.constraint_row_name(2), "rolling disc 'contact', n");
}

TEST(RollingDisc, RowsMatchIndependentOraclesAtRandomStates) {
  const Model m = disc_model();
  const RollingDisc& d = m.rolling_discs[0];
  const Vec3 t2 = d.normal.cross(d.t1);
  const Vec3 dirs[3] = {d.t1, t2, d.normal};
  std::mt19937_64 rng(2026);
  for (int draw = 0; draw < 20; ++draw) {
    const State s = random_state(m, rng, 0.5);
    ConstraintWorkspace ws(m);
    compute_constraints(m, s, ws);
    const Vec3 r = s.q.head<3>();
    const Mat3 R = rotation_matrix(s.q.segment<4>(3));

    // f: 0 on the nonholonomic rows; the lowest rim point's height on row n.
    const Lowest low = lowest_rim_point(d, r, R);
    EXPECT_EQ(ws.f(0), 0.0);
    EXPECT_EQ(ws.f(1), 0.0);
    EXPECT_NEAR(ws.f(2), low.height, 1e-12);

    // Row n: Eᵀ column k = df/dt along q ⊕ t e_k.
    const double h = 1e-6;
    for (int k = 0; k < m.n; ++k) {
      const VecX ek = VecX::Unit(m.n, k);
      const double fd =
          (residual_along(m, s.q, ek, h)(2) - residual_along(m, s.q, ek, -h)(2)) / (2 * h);
      EXPECT_NEAR(ws.Et(2, k), fd, 1e-8) << "draw " << draw << " column " << k;
    }
    // Every row: Eᵀu = n·(velocity of the body point now at the contact point), by differences
    // of that fixed body point along q ⊕ t u.
    const Vec3 s_body = R.transpose() * (low.point - r);  // body frame, from the centre of mass
    const auto point_along = [&](double t) {
      VecX qt = s.q;
      integrate_positions(m, qt, s.u, t);
      return Vec3(qt.head<3>() + rotation_matrix(qt.segment<4>(3)) * s_body);
    };
    const Vec3 vP = (point_along(h) - point_along(-h)) / (2 * h);
    for (int row = 0; row < 3; ++row)
      EXPECT_NEAR(ws.Et.row(row).dot(s.u), dirs[row].dot(vP), 1e-7) << "row " << row;

    // Dᵀ = dEᵀ/dt along q ⊕ t u.
    const MatX Dt_fd = (jacobian_along(m, s.q, s.u, h) - jacobian_along(m, s.q, s.u, -h)) / (2 * h);
    const double dscale = std::max(1.0, ws.Dt.cwiseAbs().maxCoeff());
    EXPECT_LT((ws.Dt - Dt_fd).cwiseAbs().maxCoeff(), 1e-7 * dscale) << "draw " << draw;
    // Dᵀu row by row (Dᵀ not formed) = Dᵀ·u.
    ConstraintWorkspace rate(m);
    compute_constraint_rate(m, s, rate);
    EXPECT_LT((rate.Dtu - ws.Dt * s.u).cwiseAbs().maxCoeff(), 1e-12 * dscale);
    // Row n: Dᵀu = f̈ along q ⊕ t u (u constant).
    const double h2 = 1e-4;
    const double f2 =
        (residual_along(m, s.q, s.u, h2)(2) - 2.0 * residual_along(m, s.q, s.u, 0)(2) +
         residual_along(m, s.q, s.u, -h2)(2)) /
        (h2 * h2);
    EXPECT_NEAR(ws.Dtu(2), f2, 1e-5 * dscale) << "draw " << draw;
  }
}

// The contact force of λ: λ_t1 t1 + λ_t2 t2 + λ_n k, and Eλ is that force acting at the contact
// point (world force F, body-frame moment Rᵀ(ρ_P × F) about the centre of mass, (R1)).
TEST(RollingDisc, MultipliersAreTheContactForceAtTheContactPoint) {
  const Model m = disc_model();
  const RollingDisc& d = m.rolling_discs[0];
  std::mt19937_64 rng(7);
  const State s = random_state(m, rng, 0.3);
  MatX Et(m.nc, m.n);
  compute_constraint_jacobian(m, s.q, Et);
  const VecX lambda = Vec3(0.3, -1.2, 9.5);
  const Vec3 F = rolling_disc_contact_force(d, lambda);
  const Vec3 t2 = d.normal.cross(d.t1);
  EXPECT_LT((F - (0.3 * d.t1 - 1.2 * t2 + 9.5 * d.normal)).norm(), 1e-14);
  const Mat3 R = rotation_matrix(s.q.segment<4>(3));
  const Vec3 P = lowest_rim_point(d, s.q.head<3>(), R).point;
  const VecX Q = Et.transpose() * lambda;
  EXPECT_LT((Q.head<3>() - F).norm(), 1e-12);
  EXPECT_LT((Q.tail<3>() - R.transpose() * (P - s.q.head<3>()).cross(F)).norm(), 1e-7);
}

}  // namespace
}  // namespace orthomech
