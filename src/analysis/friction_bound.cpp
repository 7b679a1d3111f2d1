#include "orthomech/analysis/friction_bound.hpp"

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

#include "../solvers/nlopt_minimize.hpp"
#include "orthomech/check.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/model/measures.hpp"

namespace orthomech {

namespace {

// Relative size of a pivot below which [E d] counts as rank deficient there (the redundant
// rows' pivots are rounding, ~1e-16; a genuine one is far above).
constexpr double kRankThreshold = 1e-10;
// The moments' fixed point: converged when no moment moves by more than this fraction of the
// largest; at most this many passes.
constexpr double kMomentTolerance = 1e-14;
constexpr int kMomentPasses = 200;

double entry(const VecX& u, int i) { return i < 0 ? 0.0 : u(i); }

// The problem at one position: every solution of the equation of motion with the pins' moments
// s is (λ; τ) = x* − K (s − s*) + Z α.
struct SplitProblem {
  int r = 0, p = 0;       // self-stresses, pins
  MatX Z, K;              // (nc + 1) × r, (nc + 1) × p
  VecX x0, s0;            // x* = (λ*, τ*), s*
  VecX c, w;              // μ_j r_j, |ω_j|
  std::vector<int> rows;  // each pin's first multiplier row
  // Scratch of moments() (one problem per position, one thread).
  mutable VecX x, s, next;

  // The admissible split at α: s = μ r ‖λ(α, s)‖ by fixed-point iteration from s*, x the
  // solution there. False when it does not settle (μ r large against the lever arms).
  bool moments(const Eigen::Ref<const VecX>& alpha) const {
    s = s0;
    for (int pass = 0; pass < kMomentPasses; ++pass) {
      x = x0;
      x.noalias() -= K * (s - s0);
      if (r > 0) x.noalias() += Z * alpha;
      for (int j = 0; j < p; ++j)
        next(j) = c(j) * x.segment<2>(rows[static_cast<size_t>(j)]).norm();
      const double change = (next - s).cwiseAbs().maxCoeff();
      s.swap(next);
      if (change <= kMomentTolerance * std::max(s.cwiseAbs().maxCoeff(), 1e-300)) return true;
    }
    return false;
  }
};

// Step 1: G (the friction loads per unit moment), x*, s*, and the parametrisation of every
// solution of [E d] x = b − G s: K = [E d]⁺ G, Z = null([E d]) (orthonormal).
SplitProblem split_problem(const Model& model, const std::vector<FrictionPin>& pins,
                           int driver_joint, const VecX& q, const VecX& u, const VecX& lambda,
                           double drive) {
  const int n = model.n, nc = model.nc;
  const int p = static_cast<int>(pins.size());
  MatX Et(nc, n);
  compute_constraint_jacobian(model, q, Et);
  VecX d(n);
  (void)compute_scalar(model, JointCoordinate{driver_joint}, q, nullptr, d);
  MatX A(n, nc + 1);
  A.leftCols(nc) = Et.transpose();
  A.col(nc) = d;
  MatX G = MatX::Zero(n, p);
  SplitProblem sp;
  sp.p = p;
  sp.c.resize(p);
  sp.w.resize(p);
  sp.s0.resize(p);
  for (int j = 0; j < p; ++j) {
    const FrictionPin& pin = pins[static_cast<std::size_t>(j)];
    const double w = entry(u, pin.u_second) - entry(u, pin.u_first);
    const double sg = w > 0.0 ? 1.0 : w < 0.0 ? -1.0 : 0.0;
    if (pin.u_second >= 0) G(pin.u_second, j) -= sg;
    if (pin.u_first >= 0) G(pin.u_first, j) += sg;
    sp.c(j) = pin.coefficient * pin.radius;
    sp.w(j) = std::abs(w);
    sp.rows.push_back(pin.row);
    sp.s0(j) = sp.c(j) * lambda.segment<2>(pin.row).norm();
  }
  // The null space of A: the trailing columns of Q in the rank-revealing QR of Aᵀ.
  Eigen::ColPivHouseholderQR<MatX> qr_t(nc + 1, n);
  qr_t.setThreshold(kRankThreshold);
  qr_t.compute(A.transpose());
  sp.r = nc + 1 - static_cast<int>(qr_t.rank());
  const MatX Q = qr_t.householderQ();
  sp.Z = Q.rightCols(sp.r);
  Eigen::CompleteOrthogonalDecomposition<MatX> cod(n, nc + 1);
  cod.setThreshold(kRankThreshold);
  cod.compute(A);
  sp.K = cod.solve(G);
  sp.x0.resize(nc + 1);
  sp.x0 << lambda, drive;
  sp.x.resize(nc + 1);
  sp.s.resize(p);
  sp.next.resize(p);
  return sp;
}

// Step 2: the least dissipation over α ∈ [−L, L]^r, L ten times the largest reported force
// (an optimum on the box's edge is not reported: the box was too small).
bool minimise(const SplitProblem& sp, VecX& alpha, int& evaluations) {
  const double L = 10.0 * std::max(sp.x0.head(sp.x0.size() - 1).cwiseAbs().maxCoeff(), 1e-300);
  const VecX lower = VecX::Constant(sp.r, -L), upper = VecX::Constant(sp.r, L);
  const auto dissipation = [&sp](const VecX& a) {
    return sp.moments(a) ? sp.w.dot(sp.s) : std::numeric_limits<double>::max();
  };
  solvers::NloptSettings settings;
  settings.xtol_abs = 1e-13 * L;
  settings.max_evaluations = 2000;
  const solvers::NloptOutcome out =
      solvers::minimize_bounded(dissipation, VecX::Zero(sp.r), lower, upper, settings);
  evaluations = out.evaluations;
  alpha = out.x;
  const bool interior =
      ((upper - alpha).minCoeff() > 1e-6 * L) && ((alpha - lower).minCoeff() > 1e-6 * L);
  return (out.kind == solvers::NloptOutcomeKind::converged ||
          out.kind == solvers::NloptOutcomeKind::roundoff) &&
         interior && out.value < std::numeric_limits<double>::max();
}

}  // namespace

DissipationBound least_dissipation(const Model& model, const std::vector<FrictionPin>& pins,
                                   int driver_joint, const VecX& q, const VecX& u,
                                   const VecX& lambda, double drive) {
  check_argument(driver_joint >= 0 && static_cast<std::size_t>(driver_joint) < model.joints.size(),
                 "least_dissipation", "driver_joint", "is not a joint of the model");
  check_argument(q.size() == model.nq && u.size() == model.n && lambda.size() == model.nc,
                 "least_dissipation", "q, u, lambda", "must have the model's sizes");
  const SplitProblem sp = split_problem(model, pins, driver_joint, q, u, lambda, drive);
  DissipationBound out;
  out.self_stresses = sp.r;
  VecX alpha = VecX::Zero(sp.r);
  if (sp.r > 0 && !minimise(sp, alpha, out.evaluations)) return out;
  if (!sp.moments(alpha)) return out;
  out.solved = true;
  out.alpha = alpha;
  out.lambda = sp.x.head(model.nc);
  out.drive = sp.x(model.nc);
  out.moment = sp.s;
  out.power = sp.w.dot(sp.s);
  return out;
}

}  // namespace orthomech
