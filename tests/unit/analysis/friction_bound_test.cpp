// The least dissipation over the admissible splits of the redundant reactions
// (src/analysis/friction_bound.cpp), against two independent oracles:
//   - a determinate mechanism (the crank-rocker) has one split: the bound is the friction `cycle`
//     finds by its fixed point, to the solvers' accuracy;
//   - the triple crank (one self-stress) with friction in all six pins: the true problem over its
//     one free parameter α, solved in the test — the split parametrised by a singular value
//     decomposition of [E d], the friction moments by their own fixed point s = μ r ‖λ(α, s)‖ at
//     each α, the dissipated power minimised over α by a scan of ±10 times the largest force
//     and golden sections: a global search — against the optimum Ipopt finds.
#include "orthomech/analysis/friction_bound.hpp"

#include <gtest/gtest.h>

#include <Eigen/SVD>
#include <cmath>
#include <string>
#include <vector>

#include "orthomech/analysis/cycle.hpp"
#include "orthomech/analysis/cycle_friction.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/model/measures.hpp"
#include "support/fixtures.hpp"

namespace orthomech {
namespace {

Model with_friction(const std::string& file, const std::vector<const char*>& joints, double mu,
                    double radius_mm) {
  std::vector<FileChange> changes;
  for (const char* j : joints)
    changes.push_back(parse_file_change(std::string("joints.") + j +
                                        ".friction={coefficient: " + std::to_string(mu) +
                                        ", radius: " + std::to_string(radius_mm) + "}"));
  return load_mechanism(test::source_path(file), changes);
}

// The test's own statement of the problem at one position: A = [E d], G, b = A x* + G s*.
struct Oracle {
  MatX A, G, pinv, null;
  VecX b, w, c;
  std::vector<int> rows;

  Oracle(const Model& model, const std::vector<FrictionPin>& pins, int driver,
         const DrivenPointView& p) {
    const int n = model.n, nc = model.nc, np = static_cast<int>(pins.size());
    MatX Et(nc, n);
    const VecX q = p.q, u = p.u;
    compute_constraint_jacobian(model, q, Et);
    VecX d(n);
    (void)compute_scalar(model, JointCoordinate{driver}, q, nullptr, d);
    A.resize(n, nc + 1);
    A << Et.transpose(), d;
    G = MatX::Zero(n, np);
    w.resize(np);
    c.resize(np);
    VecX x(nc + 1), s(np);
    x << p.lambda, p.drive;
    for (int j = 0; j < np; ++j) {
      const FrictionPin& pin = pins[static_cast<std::size_t>(j)];
      const double w1 = pin.u_first < 0 ? 0.0 : u(pin.u_first);
      const double w2 = pin.u_second < 0 ? 0.0 : u(pin.u_second);
      const double sg = w2 > w1 ? 1.0 : -1.0;
      if (pin.u_second >= 0) G(pin.u_second, j) = -sg;
      if (pin.u_first >= 0) G(pin.u_first, j) = sg;
      w(j) = std::abs(w2 - w1);
      c(j) = pin.coefficient * pin.radius;
      rows.push_back(pin.row);
      s(j) = c(j) * p.lambda.segment<2>(pin.row).norm();
    }
    b = A * x + G * s;
    const Eigen::JacobiSVD<MatX> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const VecX sv = svd.singularValues();
    int rank = 0;
    while (rank < sv.size() && sv(rank) > 1e-10 * sv(0)) ++rank;
    pinv = svd.matrixV().leftCols(rank) * sv.head(rank).cwiseInverse().asDiagonal() *
           svd.matrixU().leftCols(rank).transpose();
    null = svd.matrixV().rightCols(nc + 1 - rank);
  }

  // The admissible split at α: s = μ r ‖λ(α, s)‖ by fixed-point iteration; returns Σ |ω| s and
  // the drive there.
  double power(double alpha, double* drive = nullptr) const {
    VecX s = VecX::Zero(w.size()), x;
    for (int it = 0; it < 500; ++it) {
      x = pinv * (b - G * s) + null.col(0) * alpha;
      VecX next(w.size());
      for (Eigen::Index j = 0; j < w.size(); ++j)
        next(j) = c(j) * x.segment<2>(rows[static_cast<std::size_t>(j)]).norm();
      const double change = (next - s).cwiseAbs().maxCoeff();
      s = next;
      if (change <= 1e-16 * (1.0 + s.cwiseAbs().maxCoeff())) break;
    }
    if (drive) *drive = x(x.size() - 1);
    return w.dot(s);
  }

  // min over α: a scan of [−L, L], then golden sections round the best node.
  double least_power(double L, double* drive) const {
    const int nodes = 400;
    int best = 0;
    double best_value = power(-L);
    for (int k = 1; k <= nodes; ++k) {
      const double v = power(-L + 2 * L * k / nodes);
      if (v < best_value) best_value = v, best = k;
    }
    double lo = -L + 2 * L * (best - 1) / nodes, hi = -L + 2 * L * (best + 1) / nodes;
    const double g = (std::sqrt(5.0) - 1.0) / 2.0;
    for (int it = 0; it < 200; ++it) {
      const double a = hi - g * (hi - lo), bb = lo + g * (hi - lo);
      if (power(a) < power(bb))
        hi = bb;
      else
        lo = a;
    }
    return power(0.5 * (lo + hi), drive);
  }
};

TEST(FrictionBound, ADeterminateMechanismHasTheCyclesOwnFriction) {
  const Model model =
      with_friction("mechanisms/crank-rocker.yaml", {"A0", "A", "B", "B0"}, 0.15, 4.0);
  const CycleResult res = test::full_cycle(model, 36);
  ASSERT_EQ(res.status, CycleStatus::completed) << res.message;
  const std::vector<FrictionPin> pins = friction_pins(model);
  const int driver = model.find_joint("A0");
  std::vector<double> moments;
  int checked = 0;
  for (std::size_t k = 0; k < res.points.size(); k += 3) {
    const DrivenPointView p = res.points[k];
    if (!drive_reported(p)) continue;
    const DissipationBound b = least_dissipation(model, pins, driver, p.q, p.u, p.lambda, p.drive);
    ASSERT_TRUE(b.solved) << "position " << k;
    const double P = friction_moments(pins, p.u, p.lambda, moments);
    EXPECT_NEAR(b.power, P, 1e-8 * P) << "position " << k;
    EXPECT_NEAR(b.drive, p.drive, 1e-8 * std::abs(p.drive) + 1e-12) << "position " << k;
    EXPECT_EQ(b.self_stresses, 0);
    ++checked;
  }
  EXPECT_GE(checked, 10);
}

TEST(FrictionBound, TheTripleCranksLeastDissipationIsTheTrueMinimumOverItsSelfStress) {
  const Model model =
      with_friction("mechanisms/triple-crank.yaml", {"O1", "O2", "O3", "A1", "A2", "A3"}, 0.2, 5.0);
  const CycleResult res = test::full_cycle(model, 360);
  ASSERT_EQ(res.status, CycleStatus::completed) << res.message;
  const std::vector<FrictionPin> pins = friction_pins(model);
  const int driver = model.find_joint("O1");
  std::vector<double> moments;
  double largest_gain = 0.0;
  for (const std::size_t k : {20u, 45u, 90u, 200u, 250u}) {
    const DrivenPointView p = res.points[k];
    ASSERT_TRUE(drive_reported(p)) << "position " << k;
    const DissipationBound b = least_dissipation(model, pins, driver, p.q, p.u, p.lambda, p.drive);
    ASSERT_TRUE(b.solved) << "position " << k;
    const Oracle oracle(model, pins, driver, p);
    ASSERT_EQ(oracle.null.cols(), 1) << "one self-stress";
    double drive = 0.0;
    const double least = oracle.least_power(10.0 * p.lambda.cwiseAbs().maxCoeff(), &drive);
    EXPECT_NEAR(b.power, least, 1e-7 * least) << "position " << k;
    EXPECT_NEAR(b.drive, drive, 1e-7 * std::abs(drive)) << "position " << k;
    EXPECT_EQ(b.self_stresses, 1);
    // An admissible split: each moment is its pin's friction, the equation of motion holds.
    for (std::size_t j = 0; j < pins.size(); ++j)
      EXPECT_NEAR(b.moment(static_cast<Eigen::Index>(j)),
                  oracle.c(static_cast<Eigen::Index>(j)) * b.lambda.segment<2>(pins[j].row).norm(),
                  1e-12 * b.moment.maxCoeff());
    VecX x(model.nc + 1);
    x << b.lambda, b.drive;
    EXPECT_LT((oracle.A * x + oracle.G * b.moment - oracle.b).norm(), 1e-12 * oracle.b.norm());
    // The drive's power is the loads' power plus the dissipation: the bound moves τ by ΔP / ṡ.
    const double P = friction_moments(pins, p.u, p.lambda, moments);
    EXPECT_NEAR((b.drive - p.drive) * p.input_rate, b.power - P, 1e-9 * P);
    EXPECT_LE(b.power, P * (1.0 + 1e-12)) << "the minimum-norm split is one of the splits";
    largest_gain = std::max(largest_gain, (P - b.power) / P);
  }
  EXPECT_GT(largest_gain, 1e-3) << "the least dissipation is not the minimum-norm split's";
}

TEST(FrictionBound, TheSweepCarriesTheBoundWhereThePinsAreNotDetermined) {
  const Model model =
      with_friction("mechanisms/triple-crank.yaml", {"O1", "O2", "O3", "A1", "A2", "A3"}, 0.2, 5.0);
  const CycleResult res = test::full_cycle(model, 360);
  ASSERT_EQ(res.status, CycleStatus::completed) << res.message;
  const FrictionSeries s = friction_series(model, res, model.find_joint("O1"), true);
  ASSERT_TRUE(s.bound.computed);
  EXPECT_EQ(s.bound.unsolved, 0);
  EXPECT_GT(s.bound.dissipated, 0.0);
  EXPECT_LT(s.bound.dissipated, s.dissipated);
  // Per position, the drive's power is the loads' power plus the dissipation: with the
  // frictionless drive τ₀ (the same equation without friction), (τ − τ₀) ṡ = D for the bound's
  // split as for the reported one; the least is at most the reported one.
  int positions = 0;
  for (std::size_t k = 0; k < res.points.size(); ++k) {
    if (!s.bound.reported[k]) continue;
    const DrivenPointView p = res.points[k];
    ++positions;
    EXPECT_NEAR((s.bound.drive[k] - p.drive_frictionless) * p.input_rate, s.bound.power[k],
                1e-9 * s.power[k])
        << "position " << k;
    EXPECT_LE(s.bound.power[k], s.power[k] * (1.0 + 1e-12)) << "position " << k;
  }
  EXPECT_GT(positions, 300);
  EXPECT_LT(positions, 360) << "the bridged positions are left out";
  // A determinate mechanism has no bound to compute.
  const Model four_bar =
      with_friction("mechanisms/crank-rocker.yaml", {"A0", "A", "B", "B0"}, 0.15, 4.0);
  const FrictionSeries d =
      friction_series(four_bar, test::full_cycle(four_bar, 36), four_bar.find_joint("A0"), true);
  EXPECT_FALSE(d.bound.computed);
}

}  // namespace
}  // namespace orthomech
