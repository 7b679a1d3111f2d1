#include "orthomech/synthesis/rssr.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "../solvers/nlopt_minimize.hpp"
#include "orthomech/check.hpp"
#include "orthomech/model/reference_direction.hpp"

namespace orthomech::synthesis {

namespace {

constexpr double kPi = std::numbers::pi;
// An axis reference within this sine of the direction is parallel (the spatial reader's rule).
constexpr double kParallelSine = 1e-9;
// A precision pair is "on the other branch" when the chosen branch misses it by more than this
// (radians) and the other branch is at least twice as close (function_generation.cpp's rule).
constexpr double kBranchMiss = 1e-6;
// The Levenberg–Marquardt polish (L57) stops when a step changes no coordinate by more than this
// relative amount, or the cost falls below kCostFloor (rad²).
constexpr double kStepTolerance = 1e-14;
constexpr double kCostFloor = 1e-30;
constexpr int kPolishIterations = 20000;
// Beyond this damping (relative to diag JᵀJ) a rejected step is a steepest-descent step of
// relative size ~1e-20: no descent is left.
constexpr double kMaxDamping = 1e20;
constexpr int kMaxPairs = 1000;
// The polish (L57) starts from up to this many distinct local minima of the outer search (two
// closer than kSameDesign × the search radius in every coordinate are one), lowest cost first,
// and stops at the first whose cost reaches kExactCost (rad²: every pair met to ~1e-12 rad).
constexpr size_t kPolishStarts = 4;
constexpr double kSameDesign = 1e-6;
constexpr double kExactCost = 1e-24;
// A design is degenerate when a crank's radius (its spherical centre's distance from its axis) or
// the coupler is below this fraction of the axes' distance |P2 − P1| (1 m if they meet): with
// B on the output axis ψ no longer moves B, and the law (L53) can fit any pairs through the
// ill-conditioned S / √(P² + Q²).
constexpr double kMinLink = 1e-3;
// Axes whose common normal is shorter than this fraction of |P2 − P1| intersect.
constexpr double kIntersecting = 1e-6;

double wrap_angle(double x) { return std::remainder(x, 2.0 * kPi); }

Mat3 rot_z(double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  Mat3 R;
  R << c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0;
  return R;
}

}  // namespace

Mat3 axis_frame(const RevoluteAxis& axis) {
  check_argument(axis.direction.allFinite() && axis.direction.norm() > 0.0, "axis_frame",
                 "direction", "must be a finite non-zero vector");
  const Vec3 u = axis.direction.normalized();
  // Without a reference: the spatial reader's default rule (model/reference_direction.hpp).
  Vec3 e = axis.reference ? *axis.reference : least_aligned(u);
  check_argument(e.allFinite(), "axis_frame", "reference", "must be finite");
  e -= e.dot(u) * u;
  check_argument(
      e.norm() > kParallelSine * std::max(1.0, axis.reference ? axis.reference->norm() : 1.0),
      "axis_frame", "reference", "is parallel to the direction");
  e.normalize();
  Mat3 E;
  E.col(0) = e;
  E.col(1) = u.cross(e);
  E.col(2) = u;
  return E;
}

// ---- closed-form position ---------------------------------------------------------------------
// (L50) A(φ) = P1 + E1 Rz(φ) a; B(ψ) = P2 + E2 Rz(ψ) b.
// (L51) |B(ψ) − A(φ)|² = L². With ρ = E2ᵀ(P2 − A(φ)) (the output axis point seen from A, in the
//   output frame), B − A = E2 (ρ + Rz(ψ) b) and ρ·Rz(ψ)b = cos ψ (ρx bx + ρy by)
//   + sin ψ (ρy bx − ρx by) + ρz bz, so (L51) is
// (L52) P cos ψ + Q sin ψ + S = 0,  P = 2(ρx bx + ρy by),  Q = 2(ρy bx − ρx by),
//   S = |ρ|² + |b|² + 2 ρz bz − L²;
// (L53) it assembles iff |S| ≤ √(P² + Q²), and ψ = atan2(Q, P) + σ acos(−S/√(P² + Q²)), σ = ±1.
RssrPosition calc_position(const Rssr& linkage, double phi, int branch) {
  const Mat3 E1 = axis_frame(linkage.input), E2 = axis_frame(linkage.output);
  RssrPosition pos;
  pos.A = linkage.input.point + E1 * (rot_z(phi) * linkage.a);  // (L50)
  const Vec3 rho = E2.transpose() * (linkage.output.point - pos.A);
  const Vec3& b = linkage.b;
  const double L = linkage.coupler;
  const double P = 2.0 * (rho.x() * b.x() + rho.y() * b.y());                            // (L52)
  const double Q = 2.0 * (rho.y() * b.x() - rho.x() * b.y());                            // (L52)
  const double S = rho.squaredNorm() + b.squaredNorm() + 2.0 * rho.z() * b.z() - L * L;  // (L52)
  const double R = std::hypot(P, Q);
  pos.assembles = std::abs(S) <= R;
  pos.closure_gap = pos.assembles ? 0.0 : std::abs(S) - R;
  const double c = R > 0.0 ? std::clamp(-S / R, -1.0, 1.0) : (S > 0.0 ? -1.0 : 1.0);
  pos.psi = std::atan2(Q, P) + (branch >= 0 ? 1.0 : -1.0) * std::acos(c);  // (L53)
  pos.B = linkage.output.point + E2 * (rot_z(pos.psi) * b);                // (L50)
  return pos;
}

RssrPosition calc_position(const Rssr& linkage, double phi) {
  return calc_position(linkage, phi, linkage.branch);
}

// ---- synthesis --------------------------------------------------------------------------------

namespace {

// The seven design coordinates x = (a_x, a_y, a_z, b_x, b_y, b_z, L) and the names of (L58).
constexpr std::array<const char*, 7> kNames = {"a_x", "a_y", "a_z", "b_x", "b_y", "b_z", "L"};
// The convention of (L58): held with n pairs, in this order, the last 7 − n.
constexpr std::array<int, 4> kHoldOrder = {5, 2, 1, 4};  // b_z, a_z, a_y, b_y

// The problem, fixed once: axes, pairs, which coordinates are free.
struct Problem {
  const std::vector<AnglePair>& pairs;
  Rssr base;  // axes, held values
  Mat3 E1, E2;
  std::array<bool, 7> free{};       // x_k free
  std::vector<int> free_a, free_b;  // free indices among a (0..2) and b (0..2)
  std::vector<int> free_all;        // free indices among the seven
};

// The length below which a crank radius or the coupler makes a design degenerate (kMinLink).
double min_link(const Problem& pb) {
  const double d = (pb.base.output.point - pb.base.input.point).norm();
  return kMinLink * (d > 0.0 ? d : 1.0);
}
bool degenerate(const Problem& pb, const Eigen::Matrix<double, 7, 1>& x) {
  const double m = min_link(pb);
  return std::hypot(x(0), x(1)) < m || std::hypot(x(3), x(4)) < m || x(6) < m;
}

Rssr with_x(const Problem& pb, const Eigen::Matrix<double, 7, 1>& x) {
  Rssr r = pb.base;
  r.a = x.segment<3>(0);
  r.b = x.segment<3>(3);
  r.coupler = x(6);
  return r;
}

// (L54)–(L55) For a fixed a, the closure (L51) at pair i, with ρ_i = E2ᵀ(P2 − A(φ_i)) and
// w_i = Rz(ψ_i)ᵀ ρ_i, is |ρ_i|² + |b|² + 2 w_i·b − L² = 0: LINEAR in (b, μ), μ = |b|² − L²,
//   2 w_i·b + μ = −|ρ_i|²                                                                 (L54)
// (held b coordinates on the right). Solved by least squares (exact for as many pairs as
// unknowns); L = √(|b|² − μ) (L55). False when the system is rank-deficient or |b|² ≤ μ.
bool solve_coupler_side(const Problem& pb, const Vec3& a, Vec3& b, double& L) {
  const auto n = static_cast<Eigen::Index>(pb.pairs.size());
  const auto m = static_cast<Eigen::Index>(pb.free_b.size()) + 1;
  Eigen::MatrixXd M(n, m);
  Eigen::VectorXd rhs(n);
  b = pb.base.b;  // the held values stay
  for (Eigen::Index i = 0; i < n; ++i) {
    const AnglePair& pr = pb.pairs[static_cast<size_t>(i)];
    const Vec3 A = pb.base.input.point + pb.E1 * (rot_z(pr.phi) * a);
    const Vec3 rho = pb.E2.transpose() * (pb.base.output.point - A);
    const Vec3 w = rot_z(pr.psi).transpose() * rho;
    rhs(i) = -rho.squaredNorm();  // (L54)
    for (int k = 0; k < 3; ++k)
      if (!pb.free[static_cast<size_t>(3 + k)]) rhs(i) -= 2.0 * w(k) * b(k);
    for (size_t j = 0; j < pb.free_b.size(); ++j)
      M(i, static_cast<Eigen::Index>(j)) = 2.0 * w(pb.free_b[j]);
    M(i, m - 1) = 1.0;
  }
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(M);
  if (qr.rank() < m) return false;
  const Eigen::VectorXd z = qr.solve(rhs);
  for (size_t j = 0; j < pb.free_b.size(); ++j) b(pb.free_b[j]) = z(static_cast<Eigen::Index>(j));
  const double L2 = b.squaredNorm() - z(m - 1);  // (L55)
  if (!(L2 > 0.0) || !z.allFinite()) return false;
  L = std::sqrt(L2);
  return true;
}

// (L56) The output-angle cost of a design on branch σ: Σ_i wrap(ψ_σ(φ_i) − ψ_i)², plus
// (gap_i / L²)² for a pair where it does not assemble (gap_i = |S| − √(P² + Q²) of (L53);
// continuous at the boundary, where ψ_σ is the clamped acos).
double branch_cost(const Rssr& r, const std::vector<AnglePair>& pairs, int branch) {
  double cost = 0.0;
  for (const AnglePair& pr : pairs) {
    const RssrPosition p = calc_position(r, pr.phi, branch);
    const double e = wrap_angle(p.psi - pr.psi);
    cost += e * e;
    if (!p.assembles) {
      const double scale = std::max(r.coupler * r.coupler, 1e-300);
      cost += (p.closure_gap / scale) * (p.closure_gap / scale);
    }
  }
  return cost;
}

// Step 1 (L56): the outer search over a's free coordinates, (b, L) from (L54)–(L55), the cost
// min over σ; multistart BOBYQA from quasi-random starts. Returns the designs x of the distinct
// local minima with a real coupler, lowest cost first, at most kPolishStarts.
std::vector<Eigen::Matrix<double, 7, 1>> outer_search(const Problem& pb,
                                                      const RssrSynthesisOptions& o,
                                                      int& evaluations) {
  const double pen = 1e3 * static_cast<double>(pb.pairs.size());  // no coupler: worse than any
  const auto design = [&](const Eigen::VectorXd& y, Eigen::Matrix<double, 7, 1>& x) {
    Vec3 a = pb.base.a, b;
    for (size_t j = 0; j < pb.free_a.size(); ++j) a(pb.free_a[j]) = y(static_cast<Eigen::Index>(j));
    double L = 0.0;
    if (!solve_coupler_side(pb, a, b, L)) return false;
    x << a, b, L;
    return true;
  };
  const auto f = [&](const Eigen::VectorXd& y) {
    Eigen::Matrix<double, 7, 1> x;
    if (!design(y, x) || degenerate(pb, x)) return pen;
    const Rssr r = with_x(pb, x);
    return std::min(branch_cost(r, pb.pairs, 1), branch_cost(r, pb.pairs, -1));
  };
  double radius = o.search_radius;
  if (!(radius > 0.0)) {
    radius = 2.0 * (pb.base.output.point - pb.base.input.point).norm();
    if (!(radius > 0.0)) radius = 1.0;
  }
  const auto k = static_cast<Eigen::Index>(pb.free_a.size());
  const Eigen::VectorXd lo = Eigen::VectorXd::Constant(k, -radius);
  const Eigen::VectorXd hi = Eigen::VectorXd::Constant(k, radius);
  solvers::MultistartSettings s;
  s.starts = o.starts;
  s.seed = o.seed;
  s.local.max_evaluations = o.local_evaluations;
  s.local.xtol_abs = 1e-13 * radius;
  const solvers::MultistartOutcome out = solvers::minimize_multistart(f, lo, hi, s);
  evaluations = out.evaluations;
  if (out.best.kind == solvers::NloptOutcomeKind::callback_error && out.best.error)
    std::rethrow_exception(out.best.error);
  std::vector<const solvers::NloptOutcome*> order;
  for (const solvers::NloptOutcome& l : out.locals)
    if (std::isfinite(l.value) && l.value < pen) order.push_back(&l);
  std::stable_sort(order.begin(), order.end(),
                   [](const auto* p, const auto* q) { return p->value < q->value; });
  std::vector<Eigen::Matrix<double, 7, 1>> designs;
  for (const solvers::NloptOutcome* l : order) {
    Eigen::Matrix<double, 7, 1> x;
    if (!design(l->x, x) || degenerate(pb, x)) continue;
    const bool seen = std::any_of(designs.begin(), designs.end(), [&](const auto& y) {
      return (y - x).cwiseAbs().maxCoeff() <= kSameDesign * radius;
    });
    if (!seen) designs.push_back(x);
    if (designs.size() == kPolishStarts) break;
  }
  return designs;
}

// (L57) Residuals r_i = wrap(ψ_σ(φ_i; x) − ψ_i) and their Jacobian over the free coordinates by
// implicit differentiation of F(ψ, x) = |B(ψ) − A(φ)|² − L² = 0: ∂ψ/∂x = −(∂F/∂x)/(∂F/∂ψ), with
// d = B − A: ∂F/∂ψ = 2 d·(u2 × (B − P2)), ∂F/∂a = −2 (E1 Rz(φ))ᵀ d, ∂F/∂b = 2 (E2 Rz(ψ))ᵀ d,
// ∂F/∂L = −2L. False when a pair does not assemble or sits at a dead point (∂F/∂ψ = 0).
bool residuals(const Problem& pb, const Eigen::Matrix<double, 7, 1>& x, int branch,
               Eigen::VectorXd& r, Eigen::MatrixXd& J) {
  const Rssr lk = with_x(pb, x);
  const Vec3 u2 = pb.E2.col(2);
  for (size_t i = 0; i < pb.pairs.size(); ++i) {
    const AnglePair& pr = pb.pairs[i];
    const RssrPosition p = calc_position(lk, pr.phi, branch);
    if (!p.assembles) return false;
    const auto row = static_cast<Eigen::Index>(i);
    r(row) = wrap_angle(p.psi - pr.psi);
    const Vec3 d = p.B - p.A;
    const double Fpsi = 2.0 * d.dot(u2.cross(p.B - lk.output.point));
    if (!(std::abs(Fpsi) > 0.0)) return false;
    Eigen::Matrix<double, 7, 1> Fx;
    Fx.segment<3>(0) = -2.0 * (pb.E1 * rot_z(pr.phi)).transpose() * d;
    Fx.segment<3>(3) = 2.0 * (pb.E2 * rot_z(p.psi)).transpose() * d;
    Fx(6) = -2.0 * lk.coupler;
    for (size_t j = 0; j < pb.free_all.size(); ++j)
      J(row, static_cast<Eigen::Index>(j)) = -Fx(pb.free_all[j]) / Fpsi;
  }
  return true;
}

// Step 2 (L57): Levenberg–Marquardt on every free coordinate from the outer search's design:
// each step the least-squares solution of [J; √λ D] δ = [−r; 0] by QR (D² = diag JᵀJ; QR, not
// the normal equations: the law is ill-conditioned for short input ranges, cond J ≈ 10⁶ over
// 70°), λ lowered ×0.3 on a step that lowers the cost and raised ×4 on one that does not, down
// to λ → 0 (Gauss–Newton) near the solution; the near-gauge valley is curved and long, hence the
// many cheap iterations. True when it stopped on a small step, a vanishing cost, or no descent
// at any damping (a minimum at this precision).
bool polish(const Problem& pb, int branch, Eigen::Matrix<double, 7, 1>& x, int& iterations) {
  const auto n = static_cast<Eigen::Index>(pb.pairs.size());
  const auto m = static_cast<Eigen::Index>(pb.free_all.size());
  Eigen::VectorXd r(n), r_try(n), rhs = Eigen::VectorXd::Zero(n + m);
  Eigen::MatrixXd J(n, m), J_try(n, m), Ja(n + m, m);
  if (!residuals(pb, x, branch, r, J)) return false;
  double cost = r.squaredNorm(), lambda = 1e-3;
  for (iterations = 0; iterations < kPolishIterations; ++iterations) {
    if (cost < kCostFloor) return true;
    const Eigen::VectorXd D = J.colwise().norm().transpose().cwiseMax(1e-300);
    Ja.topRows(n) = J;
    Ja.bottomRows(m) = (std::sqrt(lambda) * D).asDiagonal();
    rhs.head(n) = -r;
    const Eigen::VectorXd step = Ja.colPivHouseholderQr().solve(rhs);
    Eigen::Matrix<double, 7, 1> x_try = x;
    for (Eigen::Index j = 0; j < m; ++j) x_try(pb.free_all[static_cast<size_t>(j)]) += step(j);
    const bool small =
        step.cwiseAbs().maxCoeff() <= kStepTolerance * (1.0 + x.cwiseAbs().maxCoeff());
    if (step.allFinite() && residuals(pb, x_try, branch, r_try, J_try) &&
        r_try.squaredNorm() <= cost) {
      x = x_try, r = r_try, J = J_try, cost = r.squaredNorm();
      lambda = std::max(lambda / 3.0, 1e-30);
      if (small) return true;
    } else {
      lambda *= 2.0;
      if (lambda > kMaxDamping) return true;  // no descent at any damping: a minimum
    }
  }
  return false;
}

// Step 3: the branch checked on every pair by the closed form (L53), as function_generation.cpp.
void judge(const std::vector<AnglePair>& pairs, bool converged, RssrSynthesisResult& res) {
  double worst = 0.0, sum = 0.0;
  bool defect = false;
  for (const AnglePair& pr : pairs) {
    const RssrPosition on = calc_position(res.linkage, pr.phi);
    const RssrPosition off = calc_position(res.linkage, pr.phi, -res.linkage.branch);
    const double e_on = on.assembles ? std::abs(wrap_angle(on.psi - pr.psi)) : kPi;
    const double e_off = off.assembles ? std::abs(wrap_angle(off.psi - pr.psi)) : kPi;
    worst = std::max(worst, e_on);
    sum += e_on * e_on;
    if (e_on > kBranchMiss && e_off < 0.5 * e_on) defect = true;
  }
  res.max_output_error = worst;
  res.rms_output_error = std::sqrt(sum / static_cast<double>(pairs.size()));
  char m[200];
  if (defect) {
    res.status = SynthesisStatus::branch_defect;
    std::snprintf(m, sizeof m,
                  "the pairs lie on different assembly branches (worst output error %.3g rad on "
                  "the better branch)",
                  worst);
  } else if (!converged) {
    res.status = SynthesisStatus::not_converged;
    std::snprintf(m, sizeof m,
                  "the Levenberg-Marquardt polish did not converge (worst output error %.3g rad)",
                  worst);
  } else {
    res.status = SynthesisStatus::ok;
    std::snprintf(m, sizeof m, "ok (worst output error %.3g rad)", worst);
  }
  res.message = m;
}

}  // namespace

// Synthesis (docs/synthesis.md (L54)–(L58)):
//   0. the convention (L58): with n < 7 pairs the last 7 − n of (b_z, a_z, a_y, b_y) are held;
//   1. the outer search (L56) over a's free coordinates, (b, L) by linear least squares
//      (L54)–(L55), multistart BOBYQA on the output-angle cost, both branches;
//   2. the Levenberg–Marquardt polish (L57) of every free coordinate on the chosen branch;
//   3. the branch and the errors checked by the closed form (L53) on every pair.
RssrSynthesisResult synthesize_rssr(const RevoluteAxis& input, const RevoluteAxis& output,
                                    const std::vector<AnglePair>& pairs,
                                    const RssrSynthesisOptions& options) {
  check_argument(pairs.size() >= 3 && pairs.size() <= kMaxPairs, "synthesize_rssr", "pairs",
                 "needs 3 to 1000 input-output pairs");
  for (const AnglePair& pr : pairs)
    check_argument(std::isfinite(pr.phi) && std::isfinite(pr.psi), "synthesize_rssr", "pairs",
                   "must be finite angles");
  check_argument(options.starts >= 1, "synthesize_rssr", "options.starts", "must be at least 1");
  Problem pb{pairs, {}, axis_frame(input), axis_frame(output), {}, {}, {}, {}};
  pb.base.input = input;
  pb.base.output = output;
  pb.base.a = options.held_a;
  pb.base.b = options.held_b;
  RssrSynthesisResult res;
  // Intersecting axes: B at their common point closes the loop at every input, an exact
  // solution of (L54) for every a that hides the true one (the step finds only it).
  const Vec3 u1 = pb.E1.col(2), u2 = pb.E2.col(2), n = u1.cross(u2);
  const Vec3 d12 = output.point - input.point;
  if (n.norm() > kParallelSine &&
      std::abs(d12.dot(n.normalized())) <= kIntersecting * std::max(d12.norm(), 1e-300)) {
    res.linkage = pb.base;
    res.message =
        "the input and output axes intersect: the rocker's pin at their common point closes "
        "the loop at every input, so (L54) cannot single out a linkage; give axes with a common "
        "normal of non-zero length";
    return res;
  }
  // Step 0: the held coordinates (L58): with n < 7 pairs the last 7 − n of b_z, a_z, a_y, b_y.
  pb.free.fill(true);
  const int held = std::max(0, 7 - static_cast<int>(pairs.size()));
  for (int k = 0; k < held; ++k) {
    pb.free[static_cast<size_t>(kHoldOrder[static_cast<size_t>(k)])] = false;
    res.held.emplace_back(kNames[static_cast<size_t>(kHoldOrder[static_cast<size_t>(k)])]);
  }
  for (int k = 0; k < 7; ++k)
    if (pb.free[static_cast<size_t>(k)]) {
      pb.free_all.push_back(k);
      if (k < 3) pb.free_a.push_back(k);
      if (k >= 3 && k < 6) pb.free_b.push_back(k - 3);
    }
  // Step 1: the outer search (L56).
  const std::vector<Eigen::Matrix<double, 7, 1>> starts =
      outer_search(pb, options, res.evaluations);
  if (starts.empty()) {
    res.linkage = pb.base;
    res.message =
        "no design assembles with a real coupler (|b|² ≤ μ or a singular system (L54)) and cranks "
        "off their axes";
    return res;
  }
  // Step 2: the polish (L57) from each start on its better branch; the lowest final cost wins
  // (a start the polish cannot begin from, a pair off its branch, keeps the search's design).
  double best = std::numeric_limits<double>::infinity();
  bool converged = false;
  for (const Eigen::Matrix<double, 7, 1>& x : starts) {
    const Rssr start = with_x(pb, x);
    const int branch = branch_cost(start, pairs, 1) <= branch_cost(start, pairs, -1) ? 1 : -1;
    Eigen::Matrix<double, 7, 1> xp = x;
    int iterations = 0;
    const bool ok = polish(pb, branch, xp, iterations);
    res.polish_iterations += iterations;
    const Eigen::Matrix<double, 7, 1>& xf = ok || iterations > 0 ? xp : x;
    if (degenerate(pb, xf)) continue;  // the polish ran into a crank on its axis
    Rssr lk = with_x(pb, xf);
    lk.branch = branch;
    const double cost = branch_cost(lk, pairs, branch);
    if (cost < best) best = cost, converged = ok, res.linkage = lk;
    if (best < kExactCost) break;
  }
  if (!std::isfinite(best)) {
    res.linkage = pb.base;
    res.message = "every polished design has a crank on its axis or no coupler (degenerate)";
    return res;
  }
  // Step 3: the check (L53).
  judge(pairs, converged, res);
  return res;
}

// ---- the mechanism file -----------------------------------------------------------------------

namespace {

std::string num(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.17g", v == 0.0 ? 0.0 : v);
  return b;
}
std::string vec(const Vec3& v, double scale) {
  std::string out = "[";
  for (int i = 0; i < 3; ++i) {
    if (i > 0) out += ", ";
    out += num(v(i) / scale);
  }
  out += ']';
  return out;
}

// A body of the file: mass = mass per length × its length (at least 1 mm), isotropic inertia
// m ℓ²/12 about the centre of mass (the triangle inequality holds), com at `com`.
void body(std::ostringstream& out, const RssrFileOptions& o, const std::string& name, double length,
          const Vec3& com, const Vec3& origin, const Vec3& z, const Vec3& x,
          const std::string& points) {
  const double L = o.length_si, ell = std::max(length, 1e-3), m = o.mass_per_length * ell;
  const double J = m * ell * ell / 12.0 / (L * L);
  out << "  - name: " << name << "\n    mass: " << num(m) << "\n    inertia: [" << num(J) << ", "
      << num(J) << ", " << num(J) << "]\n    com: " << vec(com, L)
      << "\n    pose:\n      position: " << vec(origin, L)
      << "\n      orientation: {z: " << vec(z, 1.0) << ", x: " << vec(x, 1.0)
      << "}\n    points: " << points << "\n";
}

}  // namespace

std::string rssr_file(const Rssr& lk, const std::vector<AnglePair>& pairs,
                      const RssrFileOptions& o) {
  check_argument(!pairs.empty(), "rssr_file", "pairs", "needs at least one pair");
  const Mat3 E1 = axis_frame(lk.input), E2 = axis_frame(lk.output);
  const double L = o.length_si, ang = o.angle_si;
  const RssrPosition p0 = calc_position(lk, pairs.front().phi);
  check_argument(p0.assembles, "rssr_file", "pairs", "the first pair's input does not assemble");
  // The design pose at the first pair: the cranks' frames E_k Rz(angle), the coupler's x along
  // A→B and its z ⟂ to A→B and u2.
  const Vec3 xc = (p0.B - p0.A).normalized();
  Vec3 zc = lk.output.direction.normalized().cross(xc);
  check_argument(zc.norm() > 1e-6, "rssr_file", "linkage",
                 "has its coupler along the output axis at the first pair");
  zc.normalize();
  const Mat3 C1 = E1 * rot_z(pairs.front().phi), C2 = E2 * rot_z(p0.psi);
  std::ostringstream out;
  out << "# " << o.name << ".yaml — an RSSR function generator from " << o.origin << " ("
      << pairs.size() << " input-output pairs; docs/synthesis.md, \"Spatial RSSR function\n"
      << "#   generation\", (L50)-(L59)).\n"
      << "# Frames: crank and rocker frames are the axes' frames E_k = [e_k, u_k x e_k, u_k] "
         "turned\n"
      << "#   by the joint angle (joint A0 reads the input phi from its ref e1 about u1, joint B0\n"
      << "#   the output psi from e2 about u2); the coupler's x runs A->B. Joints A and B are\n"
      << "#   spherical: the coupler's spin about AB is idle (DOF 2, one of it idle). Bodies: "
         "mass\n"
      << "#   per length, isotropic inertia m l^2/12. Design pose: the first pair.\n"
      << "# Coupler length L = " << num(lk.coupler / L) << " " << o.length_unit
      << "; branch sigma = " << lk.branch << " of (L53).\n"
      << "# Design positions p1..pn: input A0 = phi_i, target rocker.B at B(psi_i) (L50).\n";
  out << "orthomech: 1\ndimension: 3\nname: " << o.name
      << "\ndescription: \"RSSR function generator, coupler " << num(lk.coupler / L) << " "
      << o.length_unit << "\"\n";
  out << "units: {length: " << o.length_unit << ", angle: " << o.angle_unit
      << ", mass: kg, time: s, force: N}\n";
  out << "ground:\n  points: {A0: " << vec(lk.input.point, L) << ", B0: " << vec(lk.output.point, L)
      << "}\n";
  out << "bodies:\n";
  body(out, o, "crank", lk.a.norm(), lk.a / 2.0, lk.input.point, C1.col(2), C1.col(0),
       "{O: [0, 0, 0], A: " + vec(lk.a, L) + "}");
  body(out, o, "coupler", lk.coupler, Vec3(lk.coupler / 2.0, 0.0, 0.0), p0.A, zc, xc,
       "{A: [0, 0, 0], B: [" + num(lk.coupler / L) + ", 0, 0]}");
  body(out, o, "rocker", lk.b.norm(), lk.b / 2.0, lk.output.point, C2.col(2), C2.col(0),
       "{O: [0, 0, 0], B: " + vec(lk.b, L) + "}");
  out << "joints:\n"
      << "  - {name: A0, type: revolute, connects: [ground.A0, crank.O], axis: "
      << vec(E1.col(2), 1.0) << ", ref: " << vec(E1.col(0), 1.0) << "}\n"
      << "  - {name: A, type: spherical, connects: [crank.A, coupler.A]}\n"
      << "  - {name: B, type: spherical, connects: [coupler.B, rocker.B]}\n"
      << "  - {name: B0, type: revolute, connects: [ground.B0, rocker.O], axis: "
      << vec(E2.col(2), 1.0) << ", ref: " << vec(E2.col(0), 1.0) << "}\n";
  out << "measures:\n"
      << "  - {name: input_angle, type: joint, joint: A0}\n"
      << "  - {name: output_angle, type: joint, joint: B0}\n"
      << "  - {name: output_rate, type: joint, joint: B0, derivative: 1}\n";
  out << "drivers:\n  - {name: motor, joint: A0, speed: " << num(o.speed) << " rad/s}\n";
  out << "design_positions:\n";
  for (size_t i = 0; i < pairs.size(); ++i) {
    // (L59) design position i: input φ_i, target rocker.B at B(ψ_i) of (L50).
    const Vec3 B = output_pin(lk, pairs[i].psi);
    out << "  - name: p" << i + 1 << "\n    inputs: {A0: " << num(pairs[i].phi / ang)
        << "}\n    target: {point: rocker.B, at: " << vec(B, L)
        << ", tolerance: " << num(o.tolerance / L) << "}\n";
  }
  out << "analysis: {driver: motor, steps: 360}\n";
  return out.str();
}

Vec3 output_pin(const Rssr& linkage, double psi) {
  return linkage.output.point + axis_frame(linkage.output) * (rot_z(psi) * linkage.b);
}

double transmission_index(const Rssr& linkage, const RssrPosition& position) {
  const Vec3 d = position.B - position.A;
  const Vec3 t = linkage.output.direction.normalized().cross(position.B - linkage.output.point);
  if (d.norm() == 0.0 || t.norm() == 0.0) return 0.0;
  return std::abs(d.normalized().dot(t.normalized()));
}

bool input_turns_fully(const Rssr& linkage) {
  constexpr int kSamples = 1440;  // every quarter degree
  for (int k = 0; k < kSamples; ++k)
    if (!calc_position(linkage, 2.0 * std::numbers::pi * k / kSamples).assembles) return false;
  return true;
}

}  // namespace orthomech::synthesis
