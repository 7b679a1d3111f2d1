#pragma once
// The exact reference of the N-four-bar (IFToMM A02, mechanisms/n-four-bar-*.yaml): on the
// parallelogram branch every link turns by the same angle θ (from the +x axis; θ(0) = π/2) and
// every coupler translates, so the motion has one degree of freedom. Kinetic energy
// ½ I θ̇² with I = (N + 1)·mL²/3 (links about their pivots) + N·mL² (couplers, speed L θ̇);
// potential g (N + 1)(L/2) sin θ + g N L sin θ (m = L = 1). Lagrange:
//   I θ̈ = −g ((N + 1)/2 + N) cos θ,   θ(0) = π/2,  θ̇(0) = −1 (B0 moves at x' = 1 m/s)   (R1)
// integrated by classical RK4 at h ≈ 1e-5 s (the global error ~h⁴: far below any row of the
// tables). B0 = (cos θ, sin θ), the top of link 0.
#include <array>
#include <cmath>

namespace orthomech::peers {

inline std::array<double, 2> n_four_bar_b0(int N, double t_end) {
  const double I = (N + 1) / 3.0 + N, c = 9.81 * ((N + 1) / 2.0 + N);
  const auto acc = [&](double th) { return -c * std::cos(th) / I; };  // (R1)
  double th = std::acos(-1.0) / 2.0, w = -1.0;
  const long steps = static_cast<long>(std::ceil(t_end / 1e-5));
  const double h = t_end / static_cast<double>(steps);
  for (long i = 0; i < steps; ++i) {
    const double k1t = w, k1w = acc(th);
    const double k2t = w + 0.5 * h * k1w, k2w = acc(th + 0.5 * h * k1t);
    const double k3t = w + 0.5 * h * k2w, k3w = acc(th + 0.5 * h * k2t);
    const double k4t = w + h * k3w, k4w = acc(th + h * k3t);
    th += h / 6.0 * (k1t + 2 * k2t + 2 * k3t + k4t);
    w += h / 6.0 * (k1w + 2 * k2w + 2 * k3w + k4w);
  }
  return {std::cos(th), std::sin(th)};
}

}  // namespace orthomech::peers
