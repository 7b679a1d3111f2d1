#include "orthomech/synthesis/function_generation.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <string>

#include "orthomech/check.hpp"

namespace orthomech::synthesis {

namespace {

constexpr double kPi = std::numbers::pi;
// |K1|, |K2| below this (relative to 1) mean a link of (near) infinite length.
constexpr double kTinyCoefficient = 1e-14;
// A precision pair is "on the other branch" when the chosen branch misses it by more than this
// (radians) and the other branch is at least twice as close.
constexpr double kBranchMiss = 1e-6;

double wrap_angle(double x) { return std::remainder(x, 2.0 * kPi); }

// Solves (L11) / (L12): the linear system [cos φ_i, −cos ψ_i, 1] K = cos(φ_i − ψ_i).
// Returns false when the pairs do not determine K (rank < 3).
bool solve_freudenstein(const std::vector<AnglePair>& pairs, Eigen::Vector3d& K) {
  const auto n = static_cast<Eigen::Index>(pairs.size());
  Eigen::MatrixXd M(n, 3);
  Eigen::VectorXd rhs(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const AnglePair& pr = pairs[static_cast<std::size_t>(i)];
    M(i, 0) = std::cos(pr.phi);
    M(i, 1) = -std::cos(pr.psi);
    M(i, 2) = 1.0;
    rhs(i) = std::cos(pr.phi - pr.psi);  // (L9)
  }
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(M);
  if (qr.rank() < 3) return false;
  K = qr.solve(rhs);
  return K.allFinite();
}

// Output-angle error of pair `pr` on branch `branch` (the oracle: circle intersection).
double output_error(const FunctionSynthesisResult& r, const AnglePair& pr, int branch) {
  const FourBarPosition pos = calc_position(r.linkage, pr.phi + r.input_offset, branch);
  if (!pos.assembles) return kPi;
  return std::abs(wrap_angle(pos.follower_angle - r.output_offset - pr.psi));
}

// Step 3: the branch that reproduces the pairs best; a defect when some pair is clearly on the
// other branch.
void choose_branch(const std::vector<AnglePair>& pairs, FunctionSynthesisResult& r) {
  std::array<double, 2> worst{0.0, 0.0};
  for (const AnglePair& pr : pairs) {
    worst[0] = std::max(worst[0], output_error(r, pr, 1));
    worst[1] = std::max(worst[1], output_error(r, pr, -1));
  }
  r.linkage.branch = worst[0] <= worst[1] ? 1 : -1;
  r.max_output_error = std::min(worst[0], worst[1]);
  for (const AnglePair& pr : pairs) {
    const double on = output_error(r, pr, r.linkage.branch);
    const double off = output_error(r, pr, -r.linkage.branch);
    if (on > kBranchMiss && off < 0.5 * on) {
      r.status = SynthesisStatus::branch_defect;
      r.message = "the precision points lie on different assembly branches (worst output error " +
                  std::to_string(r.max_output_error) + " rad on the better branch)";
      return;
    }
  }
  r.status = SynthesisStatus::ok;
  r.message = "ok";
}

}  // namespace

// Freudenstein synthesis [Freudenstein 1955] (docs/synthesis.md (L9)–(L12)):
//   1. K from the linear system (L11) (3 pairs, exact) or its least-squares solution (L12);
//   2. the lengths from (L10) with signed a, c: c = −d/K1, a = −d/K2,
//      b² = a² + c² + d² − 2ac·K3; a negative a (c) is |a| (|c|) with the input (output) offset π;
//   3. the branch from the pairs, checked by calc_position (circle intersection).
FunctionSynthesisResult synthesize_function_generator(const std::vector<AnglePair>& pairs,
                                                      double ground_length) {
  check_argument(pairs.size() >= 3, "synthesize_function_generator", "pairs",
                 "needs at least 3 precision pairs");
  check_argument(ground_length > 0.0 && std::isfinite(ground_length),
                 "synthesize_function_generator", "ground_length", "must be positive");
  FunctionSynthesisResult r;
  const double d = ground_length;
  // Step 1: K (L11)/(L12).
  if (!solve_freudenstein(pairs, r.K)) {
    r.message = "the precision pairs do not determine K1, K2, K3 (rank-deficient system)";
    return r;
  }
  // Step 2: the link lengths (L10).
  if (std::abs(r.K(0)) < kTinyCoefficient || std::abs(r.K(1)) < kTinyCoefficient) {
    r.message = "K1 or K2 vanishes: the follower or the crank would be infinitely long";
    return r;
  }
  const double c = -d / r.K(0);
  const double a = -d / r.K(1);
  const double b2 = a * a + c * c + d * d - 2.0 * a * c * r.K(2);
  if (!(b2 > 0.0)) {
    r.message = "no real coupler: b² = " + std::to_string(b2);
    return r;
  }
  r.linkage.A0 = Vec2::Zero();
  r.linkage.B0 = Vec2(d, 0.0);
  r.linkage.a = std::abs(a);
  r.linkage.b = std::sqrt(b2);
  r.linkage.c = std::abs(c);
  r.input_offset = a < 0.0 ? kPi : 0.0;
  r.output_offset = c < 0.0 ? kPi : 0.0;
  // Step 3: the branch (checked through the circle-intersection oracle).
  choose_branch(pairs, r);
  return r;
}

std::vector<double> chebyshev_spacing(int n, double x0, double x1) {
  check_argument(n >= 1, "chebyshev_spacing", "n", "must be at least 1");
  std::vector<double> x(static_cast<std::size_t>(n));
  for (int j = 1; j <= n; ++j)  // (L13)
    x[static_cast<std::size_t>(j - 1)] =
        0.5 * (x0 + x1) - 0.5 * (x1 - x0) * std::cos((2.0 * j - 1.0) * kPi / (2.0 * n));
  return x;
}

std::vector<AnglePair> map_to_angles(const std::function<double(double)>& f,
                                     const std::vector<double>& x, const AngleMap& map) {
  check_argument(map.x1 != map.x0, "map_to_angles", "map", "needs x1 ≠ x0");
  const double y0 = f(map.x0), y1 = f(map.x1);
  check_argument(y1 != y0 && std::isfinite(y0) && std::isfinite(y1), "map_to_angles", "f",
                 "must take different finite values at x0 and x1");
  std::vector<AnglePair> pairs;
  pairs.reserve(x.size());
  for (const double xi : x)
    pairs.push_back({map.phi_start + (xi - map.x0) / (map.x1 - map.x0) * map.phi_range,
                     map.psi_start + (f(xi) - y0) / (y1 - y0) * map.psi_range});
  return pairs;
}

}  // namespace orthomech::synthesis
