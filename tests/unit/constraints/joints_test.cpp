// Every joint's f, Eᵀ and Dᵀ against central finite differences (issue 2 §2, docs/design.md §3).
// For planar bodies B̃ = I, so Eᵀ = ∂f/∂q and Dᵀ = d/dt Eᵀ(q + t u) at t = 0.
#include "orthomech/constraints/joints.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <vector>

#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/model/free_system.hpp"
#include "support/zoo.hpp"

namespace orthomech {
namespace {

// Central differences with h = 1e-6 on O(1) functions: truncation ~h² ≈ 1e-12, rounding
// ~eps/h ≈ 1e-10; 1e-7 leaves margin and still catches any wrong term (O(1) errors).
constexpr double kFdStep = 1e-6;
constexpr double kFdTol = 1e-7;

State zoo_state(const Model& model, unsigned salt) {
  State s(model);
  s.q = model.design_q();
  for (int k = 0; k < model.n; ++k)
    s.u(k) = std::sin(1.3 * k + 0.7 * salt) * 2.0 + 0.1 * salt;  // deterministic, non-trivial
  return s;
}

TEST(Joints, Eq23_EtEqualsCentralDifferenceOfF) {
  const Model model = parse_mechanism(test::kZooYaml, "zoo");
  ASSERT_EQ(model.nc, 2 + 2 + 3 + 1 + 1 + 1 + 2 + 2 + 1);
  for (unsigned salt = 0; salt < 3; ++salt) {
    const State s = zoo_state(model, salt);
    ConstraintWorkspace ws(model);
    compute_constraints(model, s, ws);
    VecX fp(model.nc), fm(model.nc);
    for (int k = 0; k < model.n; ++k) {
      VecX qp = s.q, qm = s.q;
      qp(k) += kFdStep;
      qm(k) -= kFdStep;
      compute_constraint_residual(model, qp, fp);
      compute_constraint_residual(model, qm, fm);
      const VecX fd = (fp - fm) / (2.0 * kFdStep);
      for (int r = 0; r < model.nc; ++r)
        EXPECT_NEAR(ws.Et(r, k), fd(r), kFdTol) << model.constraint_row_name(r) << ", column " << k;
    }
  }
}

TEST(Joints, Eq76_DtEqualsTimeDerivativeOfEt) {
  const Model model = parse_mechanism(test::kZooYaml, "zoo");
  for (unsigned salt = 0; salt < 3; ++salt) {
    const State s = zoo_state(model, salt);
    ConstraintWorkspace ws(model);
    compute_constraints(model, s, ws);
    MatX Ep(model.nc, model.n), Em(model.nc, model.n);
    compute_constraint_jacobian(model, s.q + kFdStep * s.u, Ep);
    compute_constraint_jacobian(model, s.q - kFdStep * s.u, Em);
    const MatX fd = (Ep - Em) / (2.0 * kFdStep);
    for (int r = 0; r < model.nc; ++r)
      for (int k = 0; k < model.n; ++k)
        EXPECT_NEAR(ws.Dt(r, k), fd(r, k), kFdTol * (1.0 + s.u.norm()))
            << model.constraint_row_name(r) << ", column " << k;
    // The convective term is Dᵀu, and equals d²f/dt² along the straight line q + t u.
    VecX fp(model.nc), f0(model.nc), fm(model.nc);
    const double h = 1e-4;  // second difference: truncation h² ~ 1e-8, rounding eps/h² ~ 1e-8
    compute_constraint_residual(model, s.q + h * s.u, fp);
    compute_constraint_residual(model, s.q, f0);
    compute_constraint_residual(model, s.q - h * s.u, fm);
    const VecX second = (fp - 2.0 * f0 + fm) / (h * h);
    for (int r = 0; r < model.nc; ++r)
      EXPECT_NEAR(ws.Dtu(r), second(r), 1e-5 * (1.0 + s.u.squaredNorm()))
          << model.constraint_row_name(r);
  }
}

// compute_constraint_rate forms Dᵀu row by row without Dᵀ: the same values as Dᵀ·u from
// compute_constraints (whose Dᵀ the test above checks against differences), with or without a
// caller's rotation table, and Dᵀ is left as it was.
TEST(Joints, Eq76_ConstraintRateGivesDtuWithoutFormingDt) {
  const Model model = parse_mechanism(test::kZooYaml, "zoo");
  for (unsigned salt = 0; salt < 3; ++salt) {
    const State s = zoo_state(model, salt);
    ConstraintWorkspace full(model);
    compute_constraints(model, s, full);
    const VecX oracle = full.Dt * s.u;
    BodyPoses rotations(model);
    rotations.update(model, s.q);
    for (const bool with_table : {false, true}) {
      ConstraintWorkspace ws(model);
      ws.Dt.setConstant(std::numeric_limits<double>::quiet_NaN());
      if (with_table)
        compute_constraint_rate(model, s, rotations, ws);
      else
        compute_constraint_rate(model, s, ws);
      for (int r = 0; r < model.nc; ++r)
        EXPECT_NEAR(ws.Dtu(r), oracle(r), 1e-12 * (1.0 + s.u.squaredNorm()))
            << model.constraint_row_name(r) << (with_table ? " (rotation table)" : "");
      EXPECT_TRUE(ws.Dt.array().isNaN().all()) << "Dᵀ must not be formed";
    }
  }
}

// f and Eᵀ in one pass, with and without the bodies' rotations at q: the same f and Eᵀ as the
// separate calls (Eᵀ checked above against differences); the rotations are R(φ_b) of each body's
// angle (the identity for particles).
TEST(Joints, ResidualAndJacobianWithTheRotationTable) {
  const Model model = parse_mechanism(test::kZooYaml, "zoo");
  const State s = zoo_state(model, 1);
  VecX f(model.nc), f_ref(model.nc);
  MatX Et(model.nc, model.n), Et_ref(model.nc, model.n);
  BodyPoses rotations(model);
  rotations.update(model, s.q);
  compute_constraint_residual(model, s.q, f_ref);
  compute_constraint_jacobian(model, s.q, Et_ref);
  compute_constraint_residual_and_jacobian(model, s.q, f, Et);
  EXPECT_EQ((f - f_ref).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ((Et - Et_ref).cwiseAbs().maxCoeff(), 0.0);
  compute_constraint_residual_and_jacobian(model, s.q, rotations, f, Et);
  EXPECT_LT((f - f_ref).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_LT((Et - Et_ref).cwiseAbs().maxCoeff(), 1e-15);
  for (size_t b = 0; b < model.bodies.size(); ++b) {
    const Body& body = model.bodies[b];
    const double phi = body.kind == BodyKind::rigid ? s.q(body.q_offset + 2) : 0.0;
    const Eigen::Matrix2d R{{std::cos(phi), -std::sin(phi)}, {std::sin(phi), std::cos(phi)}};
    EXPECT_LT((rotations[static_cast<int>(b)] - R).cwiseAbs().maxCoeff(), 1e-15) << b;
  }
}

TEST(Joints, Eq20_ResidualOfEachTypeMatchesItsGeometry) {
  // Closed-form geometry at an assembled pose: a revolute pin on the ground point of a bar.
  const Model m = parse_mechanism(R"(
orthomech: 1
ground: {points: {O: [1, 2]}}
bodies:
  - {name: bar, mass: 1, inertia: 1, pose: [1, 2, 0.3], points: {O: [0, 0], E: [2, 0]}}
joints:
  - {name: pin, type: revolute, connects: [ground.O, bar.O]}
  - {name: rod, type: distance, connects: [ground.O, bar.E]}
)",
                                  "inline");
  VecX f(m.nc);
  compute_constraint_residual(m, m.design_q(), f);
  EXPECT_NEAR(f.norm(), 0.0, 1e-15);  // drawn length is taken from the design pose
  VecX q = m.design_q();
  q(0) += 0.1;  // move the bar right by 0.1: pin x residual = ground − bar = −0.1
  compute_constraint_residual(m, q, f);
  EXPECT_NEAR(f(0), -0.1, 1e-15);
  EXPECT_NEAR(f(1), 0.0, 1e-15);
}

}  // namespace
}  // namespace orthomech
