#pragma once
// An independent reference for the crank-rocker swinging under gravity
// (mechanisms/crank-rocker.yaml without its drive: released at rest at crank angle 60°, open
// assembly). The four-bar has one degree of freedom, the crank angle θ; with the loop closed in
// closed form and the velocity and acceleration analysis of the loop written out, Lagrange's
// equation is
//   m(θ) θ̈ + ½ m'(θ) θ̇² + V'(θ) = 0,                                                       (R2)
//   m(θ) = Σ_k m_k |G_k'|² + J_k φ_k'²,  ½ m'(θ) = Σ_k m_k G_k'·G_k'' + J_k φ_k' φ_k'',
//   V'(θ) = g Σ_k m_k (G_k')_y,
// with G_k the centre of mass and φ_k the angle of link k, (·)' = d/dθ, and J_k = m_k L_k²/12
// (uniform rods). Integrated by classical RK4 at h ≈ 1e-5 s (global error ~h⁴, far below any row
// of the tables). SI units, radians. Nothing here comes from orthomech's formulation: it is the
// textbook loop-closure analysis of a four-bar [e.g. Norton, Design of Machinery, ch. 4, 6, 7].
#include <cmath>
#include <complex>

namespace orthomech::peers {

struct CrankRocker {
  // crank A0A, coupler AB, rocker B0B, ground A0B0 (m); masses (kg): 1 kg per metre of link
  double a = 0.03, b = 0.08, c = 0.06, d = 0.07;
  double m2 = 0.03, m3 = 0.08, m4 = 0.06;
  double g = 9.81;
  double theta0 = std::acos(-1.0) / 3.0;  // the file's design pose, crank 60°

  using C = std::complex<double>;
  // The coupler and rocker angles at crank angle t (the open assembly: B left of A → B0 seen
  // from A, as at the design pose; a Grashof crank never leaves it).
  void angles(double t, double& t3, double& t4) const {
    const C A = std::polar(a, t), B0(d, 0.0);
    const C D = B0 - A;
    const double L = std::abs(D), x = (b * b - c * c + L * L) / (2.0 * L);
    const double h = std::sqrt(std::max(0.0, b * b - x * x));
    const C e = D / L;
    const C B = A + e * C(x, h);  // + h e i: the side of the design pose
    t3 = std::arg(B - A);
    t4 = std::arg(B - B0);
  }

  // θ̈ from (R2) at (θ, θ̇).
  [[nodiscard]] double acceleration(double t, double w) const {
    const C I(0.0, 1.0);
    double t3 = 0.0, t4 = 0.0;
    angles(t, t3, t4);
    const C e2 = std::polar(1.0, t), e3 = std::polar(1.0, t3), e4 = std::polar(1.0, t4);
    // Velocity analysis (θ' = 1): a i e2 + b w3 i e3 = c w4 i e4, for w3 = θ3', w4 = θ4'.
    const double k11 = -b * e3.imag(), k12 = c * e4.imag(), k21 = b * e3.real(),
                 k22 = -c * e4.real(), det = k11 * k22 - k12 * k21;
    const auto solve = [&](double r1, double r2, double& x3, double& x4) {
      x3 = (r1 * k22 - k12 * r2) / det;
      x4 = (k11 * r2 - k21 * r1) / det;
    };
    double w3 = 0.0, w4 = 0.0;
    solve(a * e2.imag(), -a * e2.real(), w3, w4);
    // Acceleration analysis (θ'' = 0): the same matrix, for α3 = θ3'', α4 = θ4''.
    double a3 = 0.0, a4 = 0.0;
    solve(a * e2.real() + b * w3 * w3 * e3.real() - c * w4 * w4 * e4.real(),
          a * e2.imag() + b * w3 * w3 * e3.imag() - c * w4 * w4 * e4.imag(), a3, a4);
    // Centres of mass: G2 = (a/2) e2, G3 = a e2 + (b/2) e3, G4 = d + (c/2) e4; G' and G''.
    const C G2p = 0.5 * a * I * e2, G2pp = -0.5 * a * e2;
    const C G3p = a * I * e2 + 0.5 * b * w3 * I * e3;
    const C G3pp = -a * e2 + 0.5 * b * (a3 * I - w3 * w3) * e3;
    const C G4p = 0.5 * c * w4 * I * e4, G4pp = 0.5 * c * (a4 * I - w4 * w4) * e4;
    const double J2 = m2 * a * a / 12.0, J3 = m3 * b * b / 12.0, J4 = m4 * c * c / 12.0;
    const auto dot = [](C u, C v) { return u.real() * v.real() + u.imag() * v.imag(); };
    const double mass = m2 * std::norm(G2p) + m3 * std::norm(G3p) + m4 * std::norm(G4p) + J2 +
                        J3 * w3 * w3 + J4 * w4 * w4;
    const double half_dm = m2 * dot(G2p, G2pp) + m3 * dot(G3p, G3pp) + m4 * dot(G4p, G4pp) +
                           J3 * w3 * a3 + J4 * w4 * a4;
    const double dV = g * (m2 * G2p.imag() + m3 * G3p.imag() + m4 * G4p.imag());
    return -(half_dm * w * w + dV) / mass;  // (R2)
  }

  // The crank angle (rad) at t_end, released at rest at theta0.
  [[nodiscard]] double crank_angle(double t_end) const {
    double t = theta0, w = 0.0;
    const long steps = static_cast<long>(std::ceil(t_end / 1e-5));
    const double h = t_end / static_cast<double>(steps);
    for (long i = 0; i < steps; ++i) {
      const double k1t = w, k1w = acceleration(t, w);
      const double k2t = w + 0.5 * h * k1w, k2w = acceleration(t + 0.5 * h * k1t, k2t);
      const double k3t = w + 0.5 * h * k2w, k3w = acceleration(t + 0.5 * h * k2t, k3t);
      const double k4t = w + h * k3w, k4w = acceleration(t + h * k3t, k4t);
      t += h / 6.0 * (k1t + 2 * k2t + 2 * k3t + k4t);
      w += h / 6.0 * (k1w + 2 * k2w + 2 * k3w + k4w);
    }
    return t;
  }
};

}  // namespace orthomech::peers
