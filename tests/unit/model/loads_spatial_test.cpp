// Loads on spatial bodies (src/model/loads.cpp; issue 12 item 3), on the two-body models of
// tests/support/spatial_fixtures.hpp.
#include <gtest/gtest.h>

#include <numbers>
#include <random>
#include <string>
#include <variant>

#include "orthomech/constraints/joints.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/model/loads.hpp"
#include "orthomech/model/measures.hpp"
#include "orthomech/model/spatial.hpp"
#include "support/spatial_fixtures.hpp"

namespace orthomech {
namespace {

using testing::spatial::random_state;
using testing::spatial::two_body_model;

// Spatial loads (issue 12 item 3): conservative loads are minus the gradient of their potential
// along q ⊕ t e_k (central differences through integrate), a point force does its virtual work
// (Q·e_k = F·dr_P/dt along q ⊕ t e_k), a torque the work of an equivalent couple of forces, and
// dampers remove exactly the power dissipated_power reports.
TEST(SpatialLoads, AgainstPotentialsVirtualWorkAndDifferences) {
  Model m = two_body_model(SpatialJointType::revolute, 0);
  auto add = [&](LoadKind kind) {
    Load l;
    l.name = "load" + std::to_string(m.loads.size());
    l.kind = std::move(kind);
    m.loads.push_back(l);
  };
  SpatialPointRef a = testing::spatial::point_at(m, 0, Vec3(0.2, 0.1, 0.6));
  SpatialPointRef b = testing::spatial::point_at(m, 1, Vec3(0.7, 0.3, 0.0));
  SpatialPointRef g = testing::spatial::point_at(m, kGround, Vec3(-0.3, 0.2, 0.1));
  add(SpatialGravity{Vec3(0.3, -1.0, -9.81)});
  add(SpatialSpringDamper{a, b, 120.0, 0.35, 0.0});
  add(SpatialSpringDamper{g, b, 80.0, 0.2, 0.0});
  add(JointSpringDamper{0, 7.0, 0.3, 0.0});
  finalize_model(m);
  std::mt19937_64 rng(5);
  const State s = random_state(m, rng, 0.3);
  // Q of the conservative loads alone (compute_applied_forces adds the velocity term: u = 0).
  State at_rest = s;
  at_rest.u.setZero();
  VecX Q(m.n);
  compute_applied_forces(m, at_rest, Q);
  const double h = 1e-6;
  for (int k = 0; k < m.n; ++k) {
    VecX qp = s.q, qm = s.q;
    integrate_positions(m, qp, VecX::Unit(m.n, k), h);
    integrate_positions(m, qm, VecX::Unit(m.n, k), -h);
    const double dV = (potential_energy(m, qp) - potential_energy(m, qm)) / (2 * h);
    EXPECT_NEAR(Q(k), -dV, 1e-6 * std::max(1.0, std::abs(dV))) << "column " << k;
  }
  // A world force at a point: Q·du = F·v_P for any du (v_P by differences of the point).
  Model mf = two_body_model(SpatialJointType::revolute, 0);
  const Vec3 F(3.0, -2.0, 5.0);
  SpatialPointForce pf;
  pf.at = a;
  pf.force = F;
  mf.loads.push_back(Load{"f", pf, {}, {}});
  finalize_model(mf);
  VecX Qf(mf.n);
  compute_applied_forces(mf, at_rest, Qf);
  for (int k = 0; k < mf.n; ++k) {
    VecX qp = s.q, qm = s.q;
    integrate_positions(mf, qp, VecX::Unit(mf.n, k), h);
    integrate_positions(mf, qm, VecX::Unit(mf.n, k), -h);
    const Vec3 rp = spatial_point(spatial_frame(mf, 0, qp, nullptr), a.s).r;
    const Vec3 rm = spatial_point(spatial_frame(mf, 0, qm, nullptr), a.s).r;
    EXPECT_NEAR(Qf(k), F.dot(rp - rm) / (2 * h), 1e-7) << "force, column " << k;
  }
  // A body-fixed torque equals the couple of two opposite body-fixed forces 1 m apart.
  Model mt = two_body_model(SpatialJointType::revolute, 0);
  SpatialTorque tq;
  tq.body = 1;
  tq.torque = Vec3(0.0, 0.0, 2.5);
  tq.body_fixed = true;
  mt.loads.push_back(Load{"t", tq, {}, {}});
  finalize_model(mt);
  Model mc = two_body_model(SpatialJointType::revolute, 0);
  for (double side : {-0.5, 0.5}) {  // F = ±2.5 ŷ at ±0.5 x̂ (body axes): moment 2.5 ẑ
    SpatialPointForce c;
    c.at.body = 1;
    c.at.s = Vec3(side, 0.0, 0.0);
    c.force = Vec3(0.0, side > 0 ? 2.5 : -2.5, 0.0);
    c.body_fixed = true;
    mc.loads.push_back(Load{"c", c, {}, {}});
  }
  finalize_model(mc);
  VecX Qt(mt.n), Qc(mc.n);
  compute_applied_forces(mt, at_rest, Qt);
  compute_applied_forces(mc, at_rest, Qc);
  EXPECT_LT((Qt - Qc).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_GT(Qt.norm(), 1.0);
  // Dampers: with damping, Q·u changes by exactly −dissipated_power.
  Model md = m;
  std::get<SpatialSpringDamper>(md.loads[1].kind).damping = 3.0;
  std::get<JointSpringDamper>(md.loads[3].kind).damping = 0.7;
  VecX Qd(md.n), Qn(m.n);
  compute_applied_forces(md, s, Qd);
  compute_applied_forces(m, s, Qn);
  EXPECT_NEAR((Qd - Qn).dot(s.u), -dissipated_power(md, s), 1e-10);
  EXPECT_GT(dissipated_power(md, s), 0.0);
}

}  // namespace
}  // namespace orthomech
