// The one Gauss–Newton position corrector (projection/gauss_newton.hpp), against
//  - the closed-form radial projection onto a circle (a particle on a distance joint: the mass
//    metric is isotropic, so every minimum-norm step is radial and the limit is x/|x|);
//  - the closed-form intersection of the circle with a tangent-constrained row (validate's
//    Newton on [f = 0; tᵀ(q ⊖ q_pred) = 0], Euclidean metric);
//  - the first-order optimality of a mass-metric projection of a small perturbation: the move
//    Δ = q* ⊖ q₀ is M-orthogonal to the admissible velocities at q* (SVD null space of Eᵀ,
//    independent of the corrector), on a planar four-bar and on a spatial body (nq ≠ n);
//  - the descent rules (a step that does not lower the residual is not taken), the row subset
//    and the acceptance after the last iteration.
#include "orthomech/projection/gauss_newton.hpp"

#include <gtest/gtest.h>

#include <Eigen/SVD>
#include <cmath>

#include "orthomech/constraints/joints.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/model/free_system.hpp"
#include "support/fixtures.hpp"

namespace orthomech {
namespace {

// A particle on a circle of radius 1, twice (a redundant row), or with the second row on a
// circle of radius `second`.
std::string circle_yaml(const char* second = "1") {
  return std::string(R"(
orthomech: 1
name: circle
ground:
  points: {O: [0, 0]}
bodies:
  - {name: p, type: particle, mass: 2.5, pose: [1.3, 0.4]}
joints:
  - {name: rod, type: distance, connects: [ground.O, p.origin], length: 1}
  - {name: rod2, type: distance, connects: [ground.O, p.origin], length: )") +
         second + "}\n";
}
const std::string kCircle = circle_yaml();

const char* const kTop = R"(
orthomech: 1
dimension: 3
name: top
ground:
  points: {O: [0, 0, 0]}
bodies:
  - name: top
    mass: 1.3
    inertia: [0.002, 0.003, 0.004]
    com: [0.01, -0.02, 0.1]
    pose: {position: [0, 0, 0], orientation: {axis: [0.3, 1, 0.2], angle: 30}}
    points: {tip: [0, 0, 0]}
joints:
  - {name: tip, type: spherical, connects: [ground.O, top.tip]}
)";

const ExtraRows kNone{};

double max_abs_f(const Model& m, const VecX& q) {
  VecX f(m.nc);
  compute_constraint_residual(m, q, f);
  return f.cwiseAbs().maxCoeff();
}

TEST(GaussNewton, MassMetricProjectionOntoACircleIsRadial) {
  const Model m = parse_mechanism(kCircle, "circle.yaml");
  VecX q = m.design_q();
  const Vec2 x0(1.3, 0.4);
  const GaussNewtonResult r = gauss_newton_positions(m, q, kNone, {});
  ASSERT_TRUE(r.converged);
  EXPECT_LE(r.residual, 1e-12);
  EXPECT_GE(r.steps, 1);
  // f = (|x|² − 1)/2 ≤ 1e-12 puts |x| within 1e-12 of 1; a step off the ray would be O(0.3).
  const Vec2 exact = x0 / x0.norm();
  EXPECT_NEAR(q(0), exact.x(), 2e-12);
  EXPECT_NEAR(q(1), exact.y(), 2e-12);
}

TEST(GaussNewton, RowSubsetStepsOnItsRowsAndMeasuresAll) {
  // The second row at another length: with only row 0 in the step the point lands on |x| = 1,
  // where row 1 is not satisfied, so the residual (all rows) stays large.
  const Model other = parse_mechanism(circle_yaml("2"), "circle.yaml");
  VecX q = other.design_q();
  GaussNewtonOptions o;
  o.f_rows = {0};
  o.descent = GaussNewtonOptions::Descent::free;
  o.max_iterations = 20;
  const GaussNewtonResult r = gauss_newton_positions(other, q, kNone, o);
  EXPECT_FALSE(r.converged);
  EXPECT_NEAR(Vec2(q(0), q(1)).norm(), 1.0, 1e-14);  // on row 0's circle
  VecX f(other.nc);
  compute_constraint_residual(other, q, f);
  EXPECT_LE(std::abs(f(0)), 1e-14);
  EXPECT_NEAR(r.residual, std::abs(f(1)), 0.0);
  EXPECT_GT(r.residual, 0.1);
}

TEST(GaussNewton, TangentRowEuclideanMeetsTheClosedFormIntersection) {
  const Model m = parse_mechanism(kCircle, "circle.yaml");
  const VecX q_pred = (VecX(2) << 1.0, 0.3).finished();
  const VecX t = (VecX(2) << 0.0, 1.0).finished();
  const ExtraRows tangent{1, [&](const VecX& x, Eigen::Ref<VecX> g, Eigen::Ref<MatX> G) {
                            g(0) = t.dot(x - q_pred);
                            G.row(0) = t.transpose();
                          }};
  GaussNewtonOptions o;
  o.metric = GaussNewtonOptions::Metric::euclidean;
  o.descent = GaussNewtonOptions::Descent::free;
  o.extra_tolerance = 1e-13;
  VecX q = q_pred;
  const GaussNewtonResult r = gauss_newton_positions(m, q, tangent, o);
  ASSERT_TRUE(r.converged);
  EXPECT_NEAR(q(0), std::sqrt(1.0 - 0.09), 2e-12);
  EXPECT_NEAR(q(1), 0.3, 1e-13);
}

// Δ = q* ⊖ q₀ and the SVD null space N of Eᵀ(q*): |Nᵀ M Δ| / (|Δ|_M |N|_M) is O(|Δ|).
double orthogonality(const Model& m, const VecX& q0, const VecX& q) {
  VecX d(m.n);
  difference_positions(m, q, q0, d);
  MatX Et(m.nc, m.n), M(m.n, m.n);
  compute_constraint_jacobian(m, q, Et);
  compute_mass_matrix(m, q, M);
  const Eigen::JacobiSVD<MatX> svd(Et, Eigen::ComputeFullV);
  const int rank = static_cast<int>(svd.rank());
  const MatX N = svd.matrixV().rightCols(m.n - rank);
  double worst = 0.0;
  for (int k = 0; k < N.cols(); ++k) {
    const VecX v = N.col(k);
    worst = std::max(worst,
                     std::abs(v.dot(M * d)) / (std::sqrt(d.dot(M * d)) * std::sqrt(v.dot(M * v))));
  }
  return worst;
}

TEST(GaussNewton, SmallPerturbationLandsAtTheMassMetricClosestPointToFirstOrder) {
  for (const char* which : {"four-bar", "top"}) {
    const Model m = std::string(which) == "top" ? parse_mechanism(kTop, "top.yaml")
                                                : test::load_bundled("crank-rocker");
    VecX q = std::string(which) == "top" ? m.design_q() : test::assembled_q(m);
    if (std::string(which) == "top") {
      ASSERT_TRUE(gauss_newton_positions(m, q, kNone, {}).converged);
    }
    for (const double size : {1e-3, 1e-5}) {
      VecX push = VecX::LinSpaced(m.n, 0.3, 1.1);
      for (int k = 0; k < m.n; k += 2) push(k) = -push(k);
      VecX q0 = q;
      integrate_positions(m, q0, push, size);
      VecX x = q0;
      const GaussNewtonResult r = gauss_newton_positions(m, x, kNone, {});
      ASSERT_TRUE(r.converged) << which;
      EXPECT_LE(max_abs_f(m, x), 1e-12) << which;
      if (m.nq != m.n) {
        EXPECT_NEAR(x.tail<4>().norm(), 1.0, 1e-15);
      }
      // First order in the move: 1.9e-3 and 2.4e-3 at 1e-3, 100 times less at 1e-5; a Euclidean
      // step gives 0.18 (four-bar) and 0.68 (top) at both sizes.
      EXPECT_LE(orthogonality(m, q0, x), 5.0 * size) << which << " at " << size;
    }
  }
}

TEST(GaussNewton, AStepThatDoesNotLowerTheResidualIsNotTaken) {
  const Model m = parse_mechanism(kCircle, "circle.yaml");
  const VecX q0 = m.design_q();
  GaussNewtonOptions o;
  o.residual = [](const VecX&) { return 1.0; };  // never falls
  for (const auto descent :
       {GaussNewtonOptions::Descent::monotone, GaussNewtonOptions::Descent::backtrack}) {
    o.descent = descent;
    VecX q = q0;
    const GaussNewtonResult r = gauss_newton_positions(m, q, kNone, o);
    EXPECT_FALSE(r.converged);
    EXPECT_EQ(r.steps, 0);
    EXPECT_EQ(q, q0);
  }
  o.descent = GaussNewtonOptions::Descent::free;  // taken anyway
  o.max_iterations = 3;
  VecX q = q0;
  const GaussNewtonResult r = gauss_newton_positions(m, q, kNone, o);
  EXPECT_FALSE(r.converged);
  EXPECT_EQ(r.steps, 3);
  EXPECT_NE(q, q0);
}

TEST(GaussNewton, BacktrackingFromNearTheCentreReachesTheCircle) {
  // From |x| = 0.204 the full step lands at |x| = 2.55, where f = (|x|² − 1)/2 is 2.8 against
  // 0.48 at the start: a monotone iteration stops there, the backtracking one halves it twice.
  const Model m = parse_mechanism(kCircle, "circle.yaml");
  const VecX start = (VecX(2) << 0.2, 0.04).finished();
  GaussNewtonOptions o;
  o.descent = GaussNewtonOptions::Descent::monotone;
  VecX q = start;
  const GaussNewtonResult stopped = gauss_newton_positions(m, q, kNone, o);
  EXPECT_FALSE(stopped.converged);
  EXPECT_EQ(stopped.steps, 0);
  o.descent = GaussNewtonOptions::Descent::backtrack;
  const GaussNewtonResult r = gauss_newton_positions(m, q, kNone, o);
  ASSERT_TRUE(r.converged);
  const Vec2 x0(start(0), start(1));
  EXPECT_NEAR(q(0), x0.x() / x0.norm(), 2e-12);
  EXPECT_NEAR(q(1), x0.y() / x0.norm(), 2e-12);
}

TEST(GaussNewton, AcceptAfterTheLastIteration) {
  const Model m = parse_mechanism(kCircle, "circle.yaml");
  GaussNewtonOptions o;
  o.tolerance = -1.0;  // unreachable: only the acceptance can end it converged
  o.max_iterations = 6;
  o.descent = GaussNewtonOptions::Descent::free;
  VecX q = m.design_q();
  const GaussNewtonResult none = gauss_newton_positions(m, q, kNone, o);
  EXPECT_FALSE(none.converged);
  EXPECT_EQ(none.stop, GaussNewtonResult::Stop::iterations);
  EXPECT_EQ(none.steps, 6);
  o.accept = 1e-12;
  q = m.design_q();
  const GaussNewtonResult r = gauss_newton_positions(m, q, kNone, o);
  EXPECT_TRUE(r.converged);
  EXPECT_EQ(r.stop, GaussNewtonResult::Stop::converged);
  EXPECT_LE(max_abs_f(m, q), 1e-12);
  o.accept = -1.0;  // and without it: never converged, whatever the last q
  q = m.design_q();
  EXPECT_FALSE(gauss_newton_positions(m, q, kNone, o).converged);
}

}  // namespace
}  // namespace orthomech
