#pragma once
// Closed forms of the bundled spatial mechanisms (tests), from their geometry alone.
#include <cmath>
#include <numbers>

namespace orthomech::test {

// The RSSR's rocker angle φ(θ) (mechanisms/rssr.yaml, docs/spatial.md (M1)): crank r1 about world z
// through A0 = 0, rocker r2 about world x through B0 = (p, 0, h), coupler L; φ from world y about
// x; P cos φ + Q sin φ + S = 0 on the file's branch, φ = atan2(Q, P) + acos(−S/√(P² + Q²)).
// The file's crank is r1 = 0.1 m; another is a variant of a study (SI units, angles rad).
inline double rssr_rocker_angle(double theta, double r1 = 0.1) {
  const double r2 = 0.2, p = 0.3, h = 0.2, L = 0.42;
  const double P = -2 * r1 * r2 * std::sin(theta), Q = 2 * h * r2;
  const double S = p * p + r1 * r1 + r2 * r2 + h * h - L * L - 2 * p * r1 * std::cos(theta);
  return std::atan2(Q, P) + std::acos(-S / std::hypot(P, Q));
}

struct RssrExtreme {
  double theta = 0.0, phi = 0.0;  // rad
};

// An extreme of the RSSR's rocker angle over a crank turn (sign +1 the maximum, −1 the minimum)
// for crank r1 (m): the best of 3600 samples, refined by golden sections between the samples
// either side (to rounding).
inline RssrExtreme rssr_rocker_extreme(double r1, double sign) {
  const int n = 3600;
  const double step = 2 * std::numbers::pi / n;
  const auto f = [&](double t) { return sign * rssr_rocker_angle(t, r1); };
  int best = 0;
  for (int k = 1; k < n; ++k)
    if (f(k * step) > f(best * step)) best = k;
  double a = (best - 1) * step, b = (best + 1) * step;
  const double g = (std::sqrt(5.0) - 1) / 2;
  for (int i = 0; i < 100; ++i) {
    const double c = b - g * (b - a), d = a + g * (b - a);
    if (f(c) > f(d))
      b = d;
    else
      a = c;
  }
  const double t = 0.5 * (a + b);
  return {t, rssr_rocker_angle(t, r1)};
}

// The RSSR's rocker swing max φ − min φ for crank r1 (m), rad.
inline double rssr_swing(double r1) {
  return rssr_rocker_extreme(r1, 1).phi - rssr_rocker_extreme(r1, -1).phi;
}

}  // namespace orthomech::test
