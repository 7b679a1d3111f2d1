#pragma once
// Generated large planar mechanisms for the mobility tests and benchmark (issue 18 item 2), as
// mechanism-file text (parse_mechanism), with closed-form mobility:
//   - pendulum_chain_yaml(N): N links of 1 m, link0 pinned to the ground, link k to the tip of
//     link k−1 (revolutes), laid out at angles that vary along the chain. n = 3N, n_c = 2N,
//     rank 2N, DOF N (an open chain: every revolute adds two independent rows).
//   - n_four_bar_yaml(N, theta): IFToMM A02 (as scripts/gen_mechanisms.py writes it) with every
//     link at the angle theta. n = 3(2N + 1), n_c = 2(3N + 1): rank n_c, DOF 1 for
//     0 < theta < π; at theta = 0 (all links and couplers on the x axis: the change point)
//     rank n_c − N, DOF N + 1 (mechanisms/n-four-bar-40.yaml, "Facts tests rely on").
#include <cmath>
#include <sstream>
#include <string>

namespace orthomech::test {

inline void large_mechanism_header(std::ostringstream& y, const char* name, int N) {
  y << "orthomech: 1\nname: " << name << N
    << "\nunits: {length: m, angle: rad, mass: kg, time: s, force: N}\n";
}

inline std::string pendulum_chain_yaml(int N) {
  std::ostringstream y;
  y.precision(17);
  large_mechanism_header(y, "pendulum-chain-", N);
  y << "ground:\n  points: {O: [0, 0]}\nbodies:\n";
  double x = 0.0, z = 0.0;
  for (int k = 0; k < N; ++k) {
    const double phi = -0.5 + 0.3 * std::sin(0.7 * k);  // no two neighbours aligned
    y << "  - {name: link" << k << ", mass: 1, inertia: 0.08333333333333333, com: [0.5, 0], pose: ["
      << x << ", " << z << ", " << phi << "], points: {O: [0, 0], B: [1, 0]}}\n";
    x += std::cos(phi);
    z += std::sin(phi);
  }
  y << "joints:\n  - {name: J0, type: revolute, connects: [ground.O, link0.O]}\n";
  for (int k = 1; k < N; ++k)
    y << "  - {name: J" << k << ", type: revolute, connects: [link" << k - 1 << ".B, link" << k
      << ".O]}\n";
  y << "loads:\n  - {name: weight, type: gravity, g: [0, -9.81]}\n";
  return y.str();
}

inline std::string n_four_bar_yaml(int N, double theta) {
  std::ostringstream y;
  y.precision(17);
  large_mechanism_header(y, "n-four-bar-", N);
  y << "ground:\n  points: {";
  for (int k = 0; k <= N; ++k) y << (k ? ", " : "") << "O" << k << ": [" << k << ", 0]";
  y << "}\nbodies:\n";
  const double c = std::cos(theta), s = std::sin(theta);
  for (int k = 0; k <= N; ++k)
    y << "  - {name: link" << k << ", mass: 1, inertia: 0.08333333333333333, com: [0.5, 0], pose: ["
      << k << ", 0, " << theta << "], points: {O: [0, 0], B: [1, 0]}}\n";
  for (int k = 0; k < N; ++k)
    y << "  - {name: coupler" << k
      << ", mass: 1, inertia: 0.08333333333333333, com: [0.5, 0], pose: [" << k + c << ", " << s
      << ", 0], points: {L: [0, 0], R: [1, 0]}}\n";
  y << "joints:\n";
  for (int k = 0; k <= N; ++k)
    y << "  - {name: O" << k << ", type: revolute, connects: [ground.O" << k << ", link" << k
      << ".O]}\n";
  for (int k = 0; k < N; ++k) {
    y << "  - {name: L" << k << ", type: revolute, connects: [coupler" << k << ".L, link" << k
      << ".B]}\n";
    y << "  - {name: R" << k << ", type: revolute, connects: [coupler" << k << ".R, link" << k + 1
      << ".B]}\n";
  }
  y << "loads:\n  - {name: weight, type: gravity, g: [0, -9.81]}\n";
  return y.str();
}

}  // namespace orthomech::test
