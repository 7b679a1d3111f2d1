#include "orthomech/synthesis/four_bar.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace orthomech::synthesis {

namespace {

constexpr double kPi = std::numbers::pi;

// Counter-clockwise perpendicular of v.
Vec2 perp(const Vec2& v) { return {-v.y(), v.x()}; }

Vec2 unit_at(double angle) { return {std::cos(angle), std::sin(angle)}; }

// Coupler point and frame of a position whose A and B are known ((L5)).
void finish_position(const FourBar& linkage, FourBarPosition& pos) {
  const Vec2 AB = pos.B - pos.A;
  const Vec2 B0B = pos.B - linkage.B0;
  pos.coupler_angle = std::atan2(AB.y(), AB.x());
  pos.follower_angle = std::atan2(B0B.y(), B0B.x());
  const Vec2 ex = unit_at(pos.coupler_angle);
  pos.P = pos.A + linkage.coupler_point.x() * ex + linkage.coupler_point.y() * perp(ex);  // (L5)
  pos.frame_angle = pos.coupler_angle + linkage.coupler_frame_angle;
}

}  // namespace

double ground_length(const FourBar& linkage) noexcept { return (linkage.B0 - linkage.A0).norm(); }

double ground_angle(const FourBar& linkage) noexcept {
  const Vec2 g = linkage.B0 - linkage.A0;
  return std::atan2(g.y(), g.x());
}

FourBarPosition calc_position(const FourBar& linkage, double theta) noexcept {
  return calc_position(linkage, theta, linkage.branch);
}

// Circle intersection (docs/synthesis.md (L1)–(L5)):
//   (L1) A = A0 + a (cos θ, sin θ)
//   (L2) r = B0 − A, e = |r|, u = r / e, n = u rotated by +90°
//   (L3) x = (b² − c² + e²) / (2e),  h = √(b² − x²)   (B's coordinates along u and n from A)
//   (L4) B = A + x u + branch · h n
//   (L5) β = arg(B − A), ψ = arg(B − B0), P = A + R(β)(p, q), cos μ = (b² + c² − e²) / (2bc)
// Outside the assembly range h² < 0: h is taken 0 (the stretched or folded configuration) and
// the gap e − (b + c) or |b − c| − e is reported.
FourBarPosition calc_position(const FourBar& linkage, double theta, int branch) noexcept {
  FourBarPosition pos;
  const double a = linkage.a, b = linkage.b, c = linkage.c;
  // Step 1: the crank pin (L1).
  pos.A = linkage.A0 + a * unit_at(theta);
  // Step 2: the diagonal A → B0 (L2).
  const Vec2 r = linkage.B0 - pos.A;
  const double e = r.norm();
  const Vec2 u = e > 0.0 ? Vec2(r / e) : unit_at(theta);
  // Step 3: the closure gap and B's coordinates along the diagonal (L3).
  pos.closure_gap = std::max({e - (b + c), std::abs(b - c) - e, 0.0});
  pos.assembles = pos.closure_gap == 0.0 && e > 0.0;
  const double x = e > 0.0 ? std::clamp((b * b - c * c + e * e) / (2.0 * e), -b, b) : b;
  const double h = std::sqrt(std::max(b * b - x * x, 0.0));
  // Step 4: B on the chosen branch (L4).
  const double side = branch >= 0 ? 1.0 : -1.0;
  pos.B = pos.A + x * u + side * h * perp(u);
  // Step 5: angles, coupler point, transmission angle (L5).
  finish_position(linkage, pos);
  const double cos_mu = b > 0.0 && c > 0.0 ? (b * b + c * c - e * e) / (2.0 * b * c) : 1.0;
  pos.transmission_angle = std::acos(std::clamp(cos_mu, -1.0, 1.0));
  return pos;
}

const char* to_string(GrashofType type) noexcept {
  switch (type) {
    case GrashofType::crank_rocker:
      return "crank-rocker";
    case GrashofType::double_crank:
      return "double-crank";
    case GrashofType::rocker_crank:
      return "rocker-crank";
    case GrashofType::grashof_double_rocker:
      return "Grashof double-rocker";
    case GrashofType::triple_rocker:
      return "non-Grashof triple-rocker";
    case GrashofType::change_point:
      return "change point";
  }
  return "?";
}

// Grashof's criterion (L6): with s the shortest, l the longest and p, q the other two links,
// s + l < p + q lets the shortest link turn fully relative to its neighbours; the shortest
// link's place names the type [Norton 2012, ch. 2]. Ties for the shortest are resolved in the
// order crank, ground, follower, coupler (a full-turning crank is reported first).
GrashofType classify_grashof(const FourBar& linkage, double relative_tolerance) noexcept {
  const double d = ground_length(linkage);
  const std::array<double, 4> links{linkage.a, d, linkage.c, linkage.b};  // tie order
  const auto shortest = std::min_element(links.begin(), links.end());
  const double s = *shortest;
  const double l = *std::max_element(links.begin(), links.end());
  const double sum = links[0] + links[1] + links[2] + links[3];
  const double excess = (s + l) - (sum - s - l);  // (s + l) − (p + q)
  if (std::abs(excess) <= relative_tolerance * (s + l)) return GrashofType::change_point;
  if (excess > 0.0) return GrashofType::triple_rocker;
  switch (shortest - links.begin()) {
    case 0:
      return GrashofType::crank_rocker;
    case 1:
      return GrashofType::double_crank;
    case 2:
      return GrashofType::rocker_crank;
    default:
      return GrashofType::grashof_double_rocker;
  }
}

// Assembly range of the crank (L7): with α = θ − θ_g, e² = a² + d² − 2ad cos α and the loop
// closes iff (b − c)² ≤ e² ≤ (b + c)², i.e.
//   cos α ≤ k_hi = (a² + d² − (b − c)²) / (2ad)   → |α| ≥ acos(k_hi)
//   cos α ≥ k_lo = (a² + d² − (b + c)²) / (2ad)   → |α| ≤ acos(k_lo).
CrankRange calc_crank_range(const FourBar& linkage) noexcept {
  CrankRange range;
  const double a = linkage.a, b = linkage.b, c = linkage.c;
  const double d = ground_length(linkage);
  const double theta_g = ground_angle(linkage);
  if (a * d <= 0.0) {  // the diagonal does not depend on θ: everywhere or nowhere
    const double e = a + d;
    const bool ok = e <= b + c && e >= std::abs(b - c);
    range.full_turn = ok;
    range.upper = ok ? kPi : 0.0;
    range.count = ok ? 1 : 0;
    range.intervals[0] = {theta_g - kPi, theta_g + kPi};
    return range;
  }
  const double k_hi = (a * a + d * d - (b - c) * (b - c)) / (2.0 * a * d);
  const double k_lo = (a * a + d * d - (b + c) * (b + c)) / (2.0 * a * d);
  if (k_hi < -1.0 || k_lo > 1.0) return range;  // assembles nowhere
  range.lower = std::acos(std::min(k_hi, 1.0));
  range.upper = std::acos(std::max(k_lo, -1.0));
  if (range.lower > range.upper) return range;
  const bool from_zero = k_hi >= 1.0, to_pi = k_lo <= -1.0;
  range.full_turn = from_zero && to_pi;
  if (range.full_turn) {
    range.count = 1;
    range.intervals[0] = {theta_g - kPi, theta_g + kPi};
  } else if (from_zero) {
    range.count = 1;
    range.intervals[0] = {theta_g - range.upper, theta_g + range.upper};
  } else if (to_pi) {
    range.count = 1;
    range.intervals[0] = {theta_g + range.lower, theta_g + 2.0 * kPi - range.lower};
  } else {
    range.count = 2;
    range.intervals[0] = {theta_g + range.lower, theta_g + range.upper};
    range.intervals[1] = {theta_g - range.upper, theta_g - range.lower};
  }
  return range;
}

const char* to_string(SynthesisStatus status) noexcept {
  switch (status) {
    case SynthesisStatus::ok:
      return "ok";
    case SynthesisStatus::no_linkage:
      return "no linkage";
    case SynthesisStatus::branch_defect:
      return "branch defect";
    case SynthesisStatus::not_converged:
      return "not converged";
  }
  return "?";
}

// Slider-crank (L8): A = O + r (cos θ, sin θ); in the line frame (t, n) A − O = (u, v); the
// slider B = O + e n + s t with |B − A| = l gives (s − u)² + (e − v)² = l², so
// s = u + branch · √(l² − (e − v)²); outside the range the root is taken 0 (gap |e − v| − l).
SliderCrankPosition calc_position(const SliderCrank& linkage, double theta) noexcept {
  SliderCrankPosition pos;
  const Vec2 t = unit_at(linkage.line_angle);
  const Vec2 n = perp(t);
  pos.A = linkage.O + linkage.r * unit_at(theta);
  const double u = (pos.A - linkage.O).dot(t);
  const double v = (pos.A - linkage.O).dot(n);
  const double dv = linkage.offset - v;
  const double root2 = linkage.l * linkage.l - dv * dv;
  pos.closure_gap = std::max(std::abs(dv) - linkage.l, 0.0);
  pos.assembles = root2 >= 0.0 && linkage.l > 0.0;
  const double side = linkage.branch >= 0 ? 1.0 : -1.0;
  pos.s = u + side * std::sqrt(std::max(root2, 0.0));
  pos.B = linkage.O + linkage.offset * n + pos.s * t;
  const Vec2 AB = pos.B - pos.A;
  pos.coupler_angle = std::atan2(AB.y(), AB.x());
  const Vec2 ex = unit_at(pos.coupler_angle);
  pos.P = pos.A + linkage.coupler_point.x() * ex + linkage.coupler_point.y() * perp(ex);
  return pos;
}

}  // namespace orthomech::synthesis
