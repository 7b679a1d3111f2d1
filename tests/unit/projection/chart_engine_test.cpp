// The chart engine (include/orthomech/projection/chart_engine.hpp) tested directly. Oracles
// written in the test: a dense LU / SVD of the chart's block E_RDᵀ taken from a known Eᵀ (the
// engine reads Eᵀ only through its arguments, so a seeded random or hand-written Eᵀ of the
// model's size is used), the sign of that block's determinant, a block built with prescribed
// singular values, and closed-form geometry (a circle, a four-bar's loop) for the corrector.
#include "orthomech/projection/chart_engine.hpp"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "orthomech/constraints/joints.hpp"
#include "orthomech/constraints/sparse_et.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "support/fixtures.hpp"
#include "unit/analysis/large_mechanisms.hpp"

namespace orthomech {
namespace {

MatX random_matrix(Eigen::Index rows, Eigen::Index cols, unsigned seed) {
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> dist(-1.0, 1.0);
  MatX m(rows, cols);
  for (Eigen::Index j = 0; j < cols; ++j)
    for (Eigen::Index i = 0; i < rows; ++i) m(i, j) = dist(gen);
  return m;
}

VecX random_positive(Eigen::Index size, unsigned seed) {
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> dist(0.5, 2.0);
  VecX v(size);
  for (Eigen::Index i = 0; i < size; ++i) v(i) = dist(gen);
  return v;
}

// The chart's block B = E_RDᵀ (rows R, columns D) of Eᵀ.
MatX block(const MatX& Et, const Chart& c) {
  MatX B(c.rank(), c.rank());
  for (int i = 0; i < c.rank(); ++i)
    for (int k = 0; k < c.rank(); ++k)
      B(i, k) = Et(c.rows[static_cast<size_t>(i)], c.dependent[static_cast<size_t>(k)]);
  return B;
}

// A chart with every row, the given dependent components, the others independent, unit scale.
Chart chart_with(int nc, int n, const std::vector<int>& dependent) {
  Chart c;
  for (int i = 0; i < nc; ++i) c.rows.push_back(i);
  c.dependent = dependent;
  for (int k = 0; k < n; ++k)
    if (std::find(dependent.begin(), dependent.end(), k) == dependent.end())
      c.independent.push_back(k);
  c.row_scale = VecX::Ones(nc);
  return c;
}

// A rigid body pinned to the ground: n = 3, n_c = 2 (the switching tests give their own Eᵀ).
Model pinned_body() {
  return parse_mechanism(R"(orthomech: 1
name: pinned
units: {length: m, angle: rad, mass: kg, time: s, force: N}
ground:
  points: {O: [0, 0]}
bodies:
  - {name: bar, mass: 1, inertia: 0.1, com: [0.5, 0], pose: [0, 0, 0], points: {O: [0, 0]}}
joints:
  - {name: pin, type: revolute, connects: [ground.O, bar.O]}
)",
                         "pinned.yaml");
}

// ---- Solving -----------------------------------------------------------------------------------

// solve, solve_transposed and solve_dependent against a dense LU of the block written here, on
// random Eᵀ of the crank-rocker's size (8 × 9) with a random mass metric.
TEST(ChartEngine, SolvesAgreeWithADenseSolveOfTheBlock) {
  const Model model = test::load_bundled("crank-rocker");
  ASSERT_EQ(model.nc, 8);
  ASSERT_EQ(model.n, 9);
  for (unsigned seed = 1; seed <= 5; ++seed) {
    const MatX Et = random_matrix(model.nc, model.n, seed);
    const VecX A_diag = random_positive(model.n, 100 + seed);
    ChartEngine engine(model, model.nc);
    ASSERT_TRUE(engine.select(Et, A_diag));
    ASSERT_GT(engine.factor(Et, A_diag.cwiseSqrt()), 0.0);
    const Chart& c = engine.chart();
    ASSERT_EQ(c.rank(), 8);
    ASSERT_EQ(c.independent.size(), 1u);
    const MatX B = block(Et, c);
    const Eigen::FullPivLU<MatX> lu(B);
    ASSERT_TRUE(lu.isInvertible());

    // solve: x_D = B⁻¹ b_R, x_I = 0; with every row in R, Eᵀ x = b.
    const VecX b = random_matrix(model.nc, 1, 200 + seed);
    VecX x(model.n);
    engine.solve(b, x);
    const VecX xd = lu.solve(b);
    for (int k = 0; k < c.rank(); ++k)
      EXPECT_NEAR(x(c.dependent[static_cast<size_t>(k)]), xd(k), 1e-10 * (1.0 + xd.norm()));
    EXPECT_EQ(x(c.independent[0]), 0.0);
    EXPECT_LT((Et * x - b).norm(), 1e-10 * (1.0 + b.norm()));

    // solve_transposed: E_RD λ = c_D; for c = E λ₀ it returns λ₀.
    const VecX lambda0 = random_matrix(model.nc, 1, 300 + seed);
    const VecX cvec = Et.transpose() * lambda0;
    VecX lambda(model.nc);
    engine.solve_transposed(cvec, lambda);
    VecX cd(c.rank());
    for (int k = 0; k < c.rank(); ++k) cd(k) = cvec(c.dependent[static_cast<size_t>(k)]);
    const VecX lambda_dense = B.transpose().fullPivLu().solve(cd);
    EXPECT_LT((lambda - lambda_dense).norm(), 1e-10 * (1.0 + lambda_dense.norm()));
    EXPECT_LT((lambda - lambda0).norm(), 1e-9 * (1.0 + lambda0.norm()));

    // solve_dependent: the dependent rows of out ← B⁻¹ rhs, the others untouched.
    const MatX rhs0 = random_matrix(model.nc, 3, 400 + seed);
    MatX rhs = rhs0;
    MatX out = MatX::Constant(model.n, 3, 7.0);
    engine.solve_dependent(rhs, out);
    const MatX X = lu.solve(rhs0);
    for (int k = 0; k < c.rank(); ++k)
      EXPECT_LT((out.row(c.dependent[static_cast<size_t>(k)]) - X.row(k)).norm(),
                1e-10 * (1.0 + X.norm()));
    EXPECT_EQ(out.row(c.independent[0]), MatX::Constant(1, 3, 7.0));
  }
}

// The chart's quality is min |U_kk| / max |U_kk| of the partial-pivoting LU of the scaled block
// G = S_R E_RDᵀ S_D (Eigen's PartialPivLU uses the same pivot rule), and determinant_sign is the
// sign of det G = sign det E_RDᵀ (S_R, S_D > 0).
TEST(ChartEngine, QualityAndDeterminantSignAgreeWithADenseLu) {
  const Model model = test::load_bundled("crank-rocker");
  int positive = 0, negative = 0;
  for (unsigned seed = 1; seed <= 12; ++seed) {
    const MatX Et = random_matrix(model.nc, model.n, 10 + seed);
    const VecX A_diag = random_positive(model.n, 50 + seed);
    const VecX A_sqrt = A_diag.cwiseSqrt();
    ChartEngine engine(model, model.nc);
    ASSERT_TRUE(engine.select(Et, A_diag));
    const double quality = engine.factor(Et, A_sqrt);
    const Chart& c = engine.chart();
    MatX G = block(Et, c);
    for (int k = 0; k < c.rank(); ++k) G.col(k) *= A_sqrt(c.dependent[static_cast<size_t>(k)]);
    G = c.row_scale.asDiagonal() * G;
    const Eigen::PartialPivLU<MatX> lu(G);
    const VecX u = lu.matrixLU().diagonal().cwiseAbs();
    EXPECT_NEAR(quality, u.minCoeff() / u.maxCoeff(), 1e-12);
    EXPECT_NEAR(engine.quality(), quality, 0.0);
    const double det = block(Et, c).determinant();
    ASSERT_GT(std::abs(det), 1e-8);
    const int sign = det > 0.0 ? 1 : -1;
    EXPECT_EQ(engine.determinant_sign(), sign) << "seed " << seed;
    (sign > 0 ? positive : negative) += 1;
    // Exchanging two dependent components in the chart exchanges two columns: the sign flips.
    Chart swapped = c;
    std::swap(swapped.dependent[0], swapped.dependent[1]);
    engine.set_chart(swapped);
    ASSERT_GT(engine.factor(Et, A_sqrt), 0.0);
    EXPECT_EQ(engine.determinant_sign(), -sign) << "seed " << seed;
  }
  EXPECT_GT(positive, 0);  // the test saw both signs
  EXPECT_GT(negative, 0);
}

// A singular block: quality 0.
TEST(ChartEngine, FactorOfASingularBlockReturnsZeroQuality) {
  const Model model = pinned_body();
  ASSERT_EQ(model.n, 3);
  ASSERT_EQ(model.nc, 2);
  ChartEngine engine(model, 2);
  engine.set_chart(chart_with(2, 3, {0, 1}));
  MatX Et(2, 3);
  Et << 1, 2, 0.3,  //
      2, 4, -0.7;   // columns 0 and 1 are parallel
  EXPECT_EQ(engine.factor(Et, VecX::Ones(3)), 0.0);
  engine.set_chart(chart_with(2, 3, {0, 2}));
  EXPECT_GT(engine.factor(Et, VecX::Ones(3)), 0.0);
}

// ---- σ_min
// ---------------------------------------------------------------------------------------

// estimate_sigma_min on a block B̃ = E_RDᵀ diag(√A_D) built with prescribed singular values
// (closed form σ_min), also checked against Eigen's JacobiSVD of the scaled block: an upper bound
// that converges to σ_min with the warm start, and a left vector ŷ with B̃ w = c ŷ, c > 0.
TEST(ChartEngine, EstimateSigmaMinConvergesToTheSvdOfTheScaledBlock) {
  const Model model = test::load_bundled("crank-rocker");
  const int r = model.nc, n = model.n;
  const std::vector<int> dependent = {0, 1, 2, 3, 5, 6, 7, 8};
  const VecX sigma = (VecX(8) << 3.0, 2.5, 2.0, 1.6, 1.2, 0.9, 0.5, 0.02).finished();
  const Eigen::JacobiSVD<MatX> u_svd(random_matrix(r, r, 7), Eigen::ComputeFullU);
  const Eigen::JacobiSVD<MatX> v_svd(random_matrix(r, r, 8), Eigen::ComputeFullU);
  const MatX scaled = u_svd.matrixU() * sigma.asDiagonal() * v_svd.matrixU().transpose();
  const VecX A_sqrt = random_positive(n, 9);
  MatX Et = random_matrix(r, n, 10);  // column 4 (independent) stays random
  for (int k = 0; k < r; ++k)
    Et.col(dependent[static_cast<size_t>(k)]) =
        scaled.col(k) / A_sqrt(dependent[static_cast<size_t>(k)]);
  Chart c = chart_with(r, n, dependent);
  c.row_scale = random_positive(r, 11);  // any row scaling: σ_min is of the unscaled rows
  ChartEngine engine(model, r);
  engine.set_chart(c);
  ASSERT_GT(engine.factor(Et, A_sqrt), 0.0);

  MatX scaled_block = block(Et, c);
  for (int k = 0; k < r; ++k) scaled_block.col(k) *= A_sqrt(dependent[static_cast<size_t>(k)]);
  const Eigen::JacobiSVD<MatX> svd(scaled_block);
  const double sigma_min = svd.singularValues()(r - 1);
  ASSERT_NEAR(sigma_min, 0.02, 1e-12);  // the construction

  VecX w, left;
  double previous = std::numeric_limits<double>::infinity();
  double estimate = 0.0;
  for (int call = 0; call < 6; ++call) {
    estimate = engine.estimate_sigma_min(w, &left);
    EXPECT_GE(estimate, sigma_min * (1.0 - 1e-12)) << "an upper bound, call " << call;
    EXPECT_LE(estimate, previous * (1.0 + 1e-12)) << "decreasing, call " << call;
    previous = estimate;
  }
  // Inverse iteration on B̃ᵀB̃ contracts by (σ_min/σ_{r−1})² = (0.02/0.5)² per step.
  EXPECT_NEAR(estimate, sigma_min, 1e-10);
  EXPECT_NEAR(left.norm(), 1.0, 1e-12);
  const VecX image = scaled_block * w;
  const double cval = image.dot(left);
  EXPECT_GT(cval, 0.0);
  EXPECT_LT((image - cval * left).norm(), 1e-8 * image.norm());
}

// ---- Correcting positions
// ------------------------------------------------------------------------

// The pendulum (a particle on a 1 m rod from the origin): with x dependent and y fixed, Newton
// lands on the circle at x = −√(1 − y²) (the branch it starts on).
TEST(ChartEngine, CorrectPositionsLandsOnTheCircle) {
  const Model model = test::load_bundled("pendulum");
  ASSERT_EQ(model.n, 2);
  ASSERT_EQ(model.nc, 1);
  ChartEngine engine(model, 1);
  engine.set_chart(chart_with(1, 2, {0}));
  ASSERT_GT(engine.factor(MatX::Ones(1, 2), VecX::Ones(2)), 0.0);  // the metric: unit
  VecX q(2), f(1), dq(2);
  q << -1.3, 0.6;
  MatX Et(1, 2);
  ChartCorrection options;
  const ChartCorrectionResult r = engine.correct_positions(q, Et, f, dq, options);
  ASSERT_EQ(r.status, SolveStatus::converged) << r.message;
  EXPECT_FALSE(r.near_singular);
  EXPECT_LE(r.residual, options.tolerance);
  EXPECT_EQ(q(1), 0.6);  // the independent coordinate is not moved
  EXPECT_NEAR(q(0), -std::sqrt(1.0 - 0.36), 1e-12);
  EXPECT_NEAR(q.norm(), 1.0, 1e-12);
  // On return Eᵀ is that of the corrected q: the rod's direction (up to its sign convention).
  const VecX dir = q / q.norm();
  EXPECT_NEAR(std::abs(Et.row(0).dot(dir)) / Et.row(0).norm(), 1.0, 1e-12);
  EXPECT_NEAR(-Et(0, 0) * dir(1) + Et(0, 1) * dir(0), 0.0, 1e-12 * Et.row(0).norm());
}

// Next to the chart's singularity (x ≈ 0 with x dependent) the first Newton step is huge: with
// max_gain it is refused and q is left as it was.
TEST(ChartEngine, CorrectPositionsRefusesAStepBeyondMaxGain) {
  const Model model = test::load_bundled("pendulum");
  ChartEngine engine(model, 1);
  engine.set_chart(chart_with(1, 2, {0}));
  (void)engine.factor(MatX::Ones(1, 2), VecX::Ones(2));
  VecX q(2), f(1), dq(2);
  q << 1e-3, 1.05;
  const VecX q0 = q;
  MatX Et(1, 2);
  ChartCorrection options;
  options.max_gain = 100.0;
  const ChartCorrectionResult r = engine.correct_positions(q, Et, f, dq, options);
  EXPECT_EQ(r.status, SolveStatus::converged);
  EXPECT_TRUE(r.near_singular);
  EXPECT_EQ(q, q0);
  // Without max_gain Newton goes on (far along x): it lands on the circle at y = 1.05 > 1 —
  // impossible — so it cannot converge.
  const ChartCorrectionResult far = engine.correct_positions(q, Et, f, dq, ChartCorrection{});
  EXPECT_NE(far.status, SolveStatus::converged);
}

// Exactly at the chart's singularity (x = 0, x dependent): singular.
TEST(ChartEngine, CorrectPositionsReportsASingularBlock) {
  const Model model = test::load_bundled("pendulum");
  ChartEngine engine(model, 1);
  engine.set_chart(chart_with(1, 2, {0}));
  (void)engine.factor(MatX::Ones(1, 2), VecX::Ones(2));
  VecX q(2), f(1), dq(2);
  q << 0.0, 1.2;
  MatX Et(1, 2);
  const ChartCorrectionResult r = engine.correct_positions(q, Et, f, dq, ChartCorrection{});
  EXPECT_EQ(r.status, SolveStatus::singular);
}

// One iteration is not enough from 0.3 m off: not_converged, with the residual reported.
TEST(ChartEngine, CorrectPositionsStopsAtMaxIterations) {
  const Model model = test::load_bundled("pendulum");
  ChartEngine engine(model, 1);
  engine.set_chart(chart_with(1, 2, {0}));
  (void)engine.factor(MatX::Ones(1, 2), VecX::Ones(2));
  VecX q(2), f(1), dq(2);
  q << -1.3, 0.6;
  MatX Et(1, 2);
  ChartCorrection options;
  options.max_iterations = 1;
  const ChartCorrectionResult r = engine.correct_positions(q, Et, f, dq, options);
  EXPECT_EQ(r.status, SolveStatus::not_converged);
  EXPECT_GT(r.residual, options.tolerance);
  EXPECT_NE(r.message.find("did not converge"), std::string::npos);
}

// The crank-rocker (SI inside: 30/80/60 mm links on a 70 mm ground) with the crank angle
// independent: from a disturbed position, Newton closes the loop. Oracle: the four-bar's geometry
// written here (pins on the bodies' x axes, centres of mass at the links' middles), and the
// rocker angle from the closed-form circle intersection at the fixed crank angle.
TEST(ChartEngine, CorrectPositionsClosesTheFourBarLoop) {
  const Model model = test::load_bundled("crank-rocker");
  const VecX q0 = test::assembled_q(model);
  const auto& crank = model.bodies[static_cast<size_t>(model.find_body("crank"))];
  const auto& coupler = model.bodies[static_cast<size_t>(model.find_body("coupler"))];
  const auto& rocker = model.bodies[static_cast<size_t>(model.find_body("rocker"))];
  const int crank_phi = crank.u_offset + 2;
  std::vector<int> dependent;
  for (int k = 0; k < model.n; ++k)
    if (k != crank_phi) dependent.push_back(k);
  ChartEngine engine(model, model.nc);
  engine.set_chart(chart_with(model.nc, model.n, dependent));
  MatX Et(model.nc, model.n);
  compute_constraint_jacobian(model, q0, Et);
  ASSERT_GT(engine.factor(Et, VecX::Ones(model.n)), 0.0);

  VecX q = q0;
  const VecX disturbance = 0.005 * random_matrix(model.n, 1, 21);  // 5 mm, 0.005 rad
  q += disturbance;
  const double theta = q(crank.q_offset + 2);
  VecX f(model.nc), dq(model.n);
  ChartCorrection options;
  options.max_iterations = 20;  // from 5 mm off: Newton's quadratic phase takes a few steps
  const ChartCorrectionResult r = engine.correct_positions(q, Et, f, dq, options);
  ASSERT_EQ(r.status, SolveStatus::converged) << r.message;
  EXPECT_LE(r.residual, options.tolerance);
  EXPECT_EQ(q(crank.q_offset + 2), theta);

  const auto e = [](double a) { return Vec2(std::cos(a), std::sin(a)); };
  const auto com = [&](const Body& b) { return Vec2(q(b.q_offset), q(b.q_offset + 1)); };
  const double phi_c = q(coupler.q_offset + 2), phi_r = q(rocker.q_offset + 2);
  const Vec2 A0(0, 0), B0(0.07, 0);
  const Vec2 A = A0 + 0.03 * e(theta), B = B0 + 0.06 * e(phi_r);
  EXPECT_LT((com(crank) - (A0 + 0.015 * e(theta))).norm(), 1e-11);
  EXPECT_LT((com(coupler) - (A + 0.04 * e(phi_c))).norm(), 1e-11);
  EXPECT_LT((com(rocker) - (B0 + 0.03 * e(phi_r))).norm(), 1e-11);
  EXPECT_LT((A + 0.08 * e(phi_c) - B).norm(), 1e-11);
  // B on the circle of 80 mm about A and of 60 mm about B0: the intersection on the side of the
  // design (above the line A B0).
  const Vec2 d = B0 - A;
  const double L = d.norm(), a = (L * L + 0.08 * 0.08 - 0.06 * 0.06) / (2.0 * L);
  const double h = std::sqrt(0.08 * 0.08 - a * a);
  const Vec2 mid = A + a * d / L, normal(-d.y() / L, d.x() / L);
  const Vec2 B1 = mid + h * normal, B2 = mid - h * normal;
  const Vec2 expected = (B1 - B).norm() < (B2 - B).norm() ? B1 : B2;
  EXPECT_LT((B - expected).norm(), 1e-11);
}

// Polishing from a converged correction: with Start::prepared (f, Eᵀ and the block's factors
// taken as the corrector left them, as simulate's passage stages do) the same positions and
// residual, bit for bit, as with Start::evaluate (everything evaluated again at q). Oracles: the
// evaluate path; the residual f(q) computed here at the returned q; the engine's factors are
// those at the returned q (a solve equals that of a second engine factorised at Eᵀ(q) there).
TEST(ChartEngine, PolishFromAConvergedCorrectionReusesItsFactors) {
  const Model model = test::load_bundled("crank-rocker");
  const VecX q0 = test::assembled_q(model);
  const int crank_phi = model.bodies[static_cast<size_t>(model.find_body("crank"))].u_offset + 2;
  std::vector<int> dependent;
  for (int k = 0; k < model.n; ++k)
    if (k != crank_phi) dependent.push_back(k);
  const Chart chart = chart_with(model.nc, model.n, dependent);
  const VecX disturbed = q0 + 0.005 * random_matrix(model.n, 1, 22);
  ChartCorrection loose;
  loose.tolerance = 1e-7;  // converged, with room left for polishing
  loose.max_iterations = 20;
  VecX q_result[2];
  double residual[2] = {0.0, 0.0};
  for (const int prepared : {0, 1}) {
    ChartEngine engine(model, model.nc);
    engine.set_chart(chart);
    MatX Et(model.nc, model.n);
    VecX f(model.nc), dq(model.n), q = disturbed;
    ASSERT_EQ(engine.correct_positions(q, Et, f, dq, loose).status, SolveStatus::converged);
    residual[prepared] = engine.polish_positions(
        q, Et, f, dq, 3,
        prepared ? ChartCorrection::Start::prepared : ChartCorrection::Start::evaluate);
    q_result[prepared] = q;
    VecX f_here(model.nc);
    compute_constraint_residual(model, q, f_here);
    EXPECT_EQ(residual[prepared], f_here.cwiseAbs().maxCoeff());
    // Polished to rounding: 6.9e-18 m measured (the links are 30–80 mm); 1e-14 is far below the
    // corrector's 1e-7 and still fails a polish that stopped early.
    EXPECT_LT(residual[prepared], 1e-14);
    MatX Et_here(model.nc, model.n);
    compute_constraint_jacobian(model, q, Et_here);
    ChartEngine fresh(model, model.nc);
    fresh.set_chart(chart);
    ASSERT_GT(fresh.factor(Et_here, VecX::Ones(model.n)), 0.0);
    const VecX rhs = random_matrix(model.nc, 1, 23);
    VecX x_engine(model.n), x_fresh(model.n);
    engine.solve(rhs, x_engine);
    fresh.solve(rhs, x_fresh);
    EXPECT_EQ(x_engine, x_fresh) << (prepared ? "prepared" : "evaluate");
  }
  EXPECT_EQ(q_result[0], q_result[1]);
  EXPECT_EQ(residual[0], residual[1]);
}

// ---- Switching charts
// ----------------------------------------------------------------------------

// update keeps a good chart, leaves a degraded one for the QR's best when that is better by the
// hysteresis factor (recording the switch), and keeps a degraded one when no chart is better.
TEST(ChartEngine, UpdateSwitchesWhenTheQualityDrops) {
  const Model model = pinned_body();
  const VecX ones = VecX::Ones(3);
  ChartEngine engine(model, 2);
  MatX Et(2, 3);
  Et << 1, 0, 0.5,  //
      0, 1, -0.4;
  // The first update chooses a chart (no switch).
  EXPECT_GT(engine.update(Et, ones, ones, 0.0), engine.options().switch_below);
  EXPECT_EQ(engine.switch_count(), 0);

  // Chart D = {0, 1}; its block [[1, 0], [0, ε]] degrades, D = {0, 2} stays good.
  Chart c = chart_with(2, 3, {0, 1});
  engine.set_chart(c);
  const double eps = 1e-3;
  Et << 1, 0, 0.5,  //
      0, eps, -0.4;
  EXPECT_NEAR(engine.factor(Et, ones), eps, 1e-15);  // G = diag(1, ε): quality ε
  const double q = engine.update(Et, ones, ones, 0.25);
  EXPECT_EQ(engine.switch_count(), 1);
  ASSERT_EQ(engine.switches().size(), 1u);
  EXPECT_EQ(engine.switches()[0].t, 0.25);
  EXPECT_NEAR(engine.switches()[0].quality_old, eps, 1e-15);
  EXPECT_EQ(engine.switches()[0].quality_new, q);
  EXPECT_GT(q, engine.options().hysteresis * eps);
  EXPECT_EQ(engine.chart().independent, std::vector<int>{1});  // u_1 moves most: independent
  EXPECT_EQ(engine.quality(), q);

  // A good chart is kept.
  Et << 1, 0, 0.5,  //
      0, 0.9, -0.4;
  engine.set_chart(chart_with(2, 3, {0, 1}));
  (void)engine.update(Et, ones, ones, 0.5);
  EXPECT_EQ(engine.switch_count(), 1);
  EXPECT_EQ(engine.chart().dependent, (std::vector<int>{0, 1}));

  // Every chart is as poor (rows [1, 0, 0] and [δ, ε, ε]): the degraded one is kept.
  Et << 1, 0, 0,  //
      0.5, eps, eps;
  Chart poor = chart_with(2, 3, {0, 1});
  poor.row_scale(1) = 1.0 / Et.row(1).norm();  // the selector's scaling: a fair comparison
  engine.set_chart(poor);
  const double kept = engine.update(Et, ones, ones, 0.75);
  EXPECT_LT(kept, engine.options().switch_below);
  EXPECT_GT(kept, 0.0);
  EXPECT_EQ(engine.switch_count(), 1);
  EXPECT_EQ(engine.chart().dependent, (std::vector<int>{0, 1}));
  EXPECT_EQ(engine.quality(), kept);
}

// A tangent F that moves u_2 most makes u_2 the independent component.
TEST(ChartEngine, SelectFromTangentMakesTheFastestComponentIndependent) {
  const Model model = pinned_body();
  ChartEngine engine(model, 2);
  engine.set_chart(chart_with(2, 3, {1, 2}));
  MatX F(3, 1);
  F << 0.1, -0.3, 1.0;
  engine.select_from_tangent(F, VecX::Ones(3));
  EXPECT_EQ(engine.chart().independent, std::vector<int>{2});
  EXPECT_EQ(engine.chart().dependent, (std::vector<int>{0, 1}));
  EXPECT_EQ(engine.chart().rows, (std::vector<int>{0, 1}));  // rows kept
  // In the mass metric: √M scales the components, u_0 now dominates.
  engine.select_from_tangent(F, (VecX(3) << 100.0, 1.0, 1.0).finished());
  EXPECT_EQ(engine.chart().independent, std::vector<int>{0});
}

// The sparse path (large mechanisms in simulate: the block factorised by KLU, whose pivots are
// reused while the chart holds) against the dense path in the same chart, on the N = 40 four-bar
// chain: solve, solve_transposed and the σ_min estimate agree at six positions along a motion of
// the first coordinate (the engines read Eᵀ(q) only: the positions need not close the loops).
TEST(ChartEngine, SparsePathSolvesAsTheDensePathInTheSameChart) {
  const Model model = test::load_bundled("n-four-bar-40");
  SparseEt Et(model);
  const VecX q0 = model.design_q();
  compute_constraint_jacobian(model, q0, Et);
  const int r = static_cast<int>(Eigen::FullPivLU<MatX>(MatX(Et.matrix())).rank());
  ASSERT_GT(r, ChartEngine::kSparseAbove);
  const VecX A_diag = random_positive(model.n, 7);
  const VecX A_sqrt = A_diag.cwiseSqrt();
  ChartEngine dense(model, r);
  ChartEngine sparse(model, r, ChartFactorisation::sparse_when_large);
  ASSERT_FALSE(dense.sparse());
  ASSERT_TRUE(sparse.sparse());
  ASSERT_TRUE(dense.select(MatX(Et.matrix()), A_diag));
  sparse.set_chart(dense.chart());
  VecX w_dense = VecX::Ones(r), w_sparse = VecX::Ones(r);
  for (int k = 0; k < 6; ++k) {
    VecX q = q0;
    q(0) += 0.02 * k;
    compute_constraint_jacobian(model, q, Et);
    const MatX Ed = MatX(Et.matrix());
    ASSERT_GT(dense.factor(Ed, A_sqrt), 0.0) << k;
    ASSERT_EQ(sparse.factor(Et, A_sqrt), 1.0) << k;
    const VecX b = random_matrix(model.nc, 1, 40 + static_cast<unsigned>(k));
    VecX xd(model.n), xs(model.n);
    dense.solve(b, xd);
    sparse.solve(b, xs);
    EXPECT_LT((xs - xd).norm(), 1e-10 * (1.0 + xd.norm())) << k;
    const VecX c = random_matrix(model.n, 1, 60 + static_cast<unsigned>(k));
    VecX ld(r), ls(r);
    dense.solve_transposed(c, ld);
    sparse.solve_transposed(c, ls);
    EXPECT_LT((ls - ld).norm(), 1e-10 * (1.0 + ld.norm())) << k;
    const double sd = dense.estimate_sigma_min(w_dense);
    const double ss = sparse.estimate_sigma_min(w_sparse);
    EXPECT_NEAR(ss, sd, 1e-10 * sd) << k;
  }
}

// update from Eᵀ on its pattern (what the cycle of a large model calls: no n_c × n matrix) against
// update from the same Eᵀ as a dense matrix (the oracle: the path every smaller cycle was
// validated on), on the N-four-bar at 40 positions, every link at a random angle θ in (−3, 3)
// (jumps between them: the chart degrades), with the switching threshold raised to 0.9 and the
// hysteresis lowered to 1.01 so that the rule is due often and switches (more than 5 times):
// the same quality bit for
// bit at every position, the same charts, the same switches, and Eᵀ F = 0 for the basis built
// from the pattern. Both engine kinds: the dense block (N = 10, n = 63) and the rated sparse one
// (N = 20, n = 123: its QR choice on the pattern, ChartSelector::select_sparse).
TEST(ChartEngine, UpdateOnThePatternFollowsTheDenseUpdate) {
  for (const int N : {10, 20}) {
    const Model model = parse_mechanism(test::n_four_bar_yaml(N, 0.6), "n-four-bar (test)");
    SparseEt Et(model);
    compute_constraint_jacobian(model, model.design_q(), Et);
    const int r = static_cast<int>(Eigen::FullPivLU<MatX>(MatX(Et.matrix())).rank());
    const VecX A_diag = random_positive(model.n, 3);
    const VecX A_sqrt = A_diag.cwiseSqrt();
    ChartEngine on_dense(model, r, ChartFactorisation::rated_sparse_when_large);
    ChartEngine on_pattern(model, r, ChartFactorisation::rated_sparse_when_large);
    EXPECT_EQ(on_pattern.sparse(), N == 20);
    for (ChartEngine* e : {&on_dense, &on_pattern}) {
      e->options().switch_below = 0.9;
      e->options().hysteresis = 1.01;
    }
    int singular = 0;
    for (int k = 0; k < 40; ++k) {
      const double theta = 3.0 * random_matrix(1, 1, 100 + k)(0);
      const Model at = parse_mechanism(test::n_four_bar_yaml(N, theta), "n-four-bar (test)");
      compute_constraint_jacobian(model, at.design_q(), Et);
      const MatX Ed(Et.matrix());
      const double qd = on_dense.update(Ed, A_diag, A_sqrt, k);
      const double qp = on_pattern.update(Et, A_diag, A_sqrt, k);
      ASSERT_EQ(qp, qd) << N << " " << k;
      EXPECT_EQ(on_pattern.chart().rows, on_dense.chart().rows) << N << " " << k;
      EXPECT_EQ(on_pattern.chart().dependent, on_dense.chart().dependent) << N << " " << k;
      EXPECT_EQ(on_pattern.switch_count(), on_dense.switch_count()) << N << " " << k;
      if (!(qp > 0.0)) {
        ++singular;
        continue;
      }
      MatX F(model.n, model.n - r);
      VecX b(model.nc), x(model.n);
      on_pattern.basis(Et, b, x, F);
      // Rounding of the LU solves: at most 5.6e-16 of max |F| when written; 1e-9 leaves room for
      // a poorly conditioned chart and still fails a basis off by a wrong entry.
      EXPECT_LT((Ed * F).cwiseAbs().maxCoeff(), 1e-9 * F.cwiseAbs().maxCoeff()) << N << " " << k;
    }
    // The walk switched charts (12 and 15 times for N = 10 and 20 when written), so the switch
    // path was compared; and the chart was usable at most positions (a random θ is regular: none
    // singular when written).
    EXPECT_GT(on_pattern.switch_count(), 5) << N;
    EXPECT_LT(singular, 5) << N;
  }
}

}  // namespace
}  // namespace orthomech
