#pragma once
// Closed forms of the bundled spatial mechanisms (tests), from their geometry alone.
#include <cmath>

namespace orthomech::test {

// The RSSR's rocker angle φ(θ) (mechanisms/rssr.yaml, docs/spatial.md (M1)): crank r1 about world z
// through A0 = 0, rocker r2 about world x through B0 = (p, 0, h), coupler L; φ from world y about
// x; P cos φ + Q sin φ + S = 0 on the file's branch, φ = atan2(Q, P) + acos(−S/√(P² + Q²)).
inline double rssr_rocker_angle(double theta) {
  const double r1 = 0.1, r2 = 0.2, p = 0.3, h = 0.2, L = 0.42;
  const double P = -2 * r1 * r2 * std::sin(theta), Q = 2 * h * r2;
  const double S = p * p + r1 * r1 + r2 * r2 + h * h - L * L - 2 * p * r1 * std::cos(theta);
  return std::atan2(Q, P) + std::acos(-S / std::hypot(P, Q));
}

}  // namespace orthomech::test
