#pragma once
// Andrews' squeezing mechanism in the test set's relative coordinates (Test Set for IVP Solvers,
// Univ. Bari, Mazzia & Magherini, problem `andrews`; /work/shared/references.md §1), as a
// GeneralSystem (model/general_system.hpp) with configuration-dependent M(q):
// q = (β, Θ, γ, Φ, δ, Ω, ε).
// The test set writes M q̈ = f − Gᵀλ with f including −Ṁq̇ + ∂T/∂q; our ṗ = Q̂ + Eλ needs
// Q̂ = ∂T/∂q + Q = f + Ṁ q̇ (L1), and our λ is minus the published one (E = Gᵀ).
#include <array>
#include <cmath>

#include "orthomech/model/general_system.hpp"
#include "support/andrews_reference.hpp"

namespace orthomech::test {

namespace andrews {
constexpr double m1 = .04325, m2 = .00365, m3 = .02373, m4 = .00706, m5 = .07050, m6 = .00706,
                 m7 = .05498;
constexpr double xa = -.06934, ya = -.00227, xb = -.03635, yb = .03273, xc = .014, yc = .072;
constexpr double c0 = 4530.0, i1 = 2.194e-6, i2 = 4.410e-7, i3 = 5.255e-6, i4 = 5.667e-7,
                 i5 = 1.169e-5, i6 = 5.667e-7, i7 = 1.912e-5;
constexpr double d = 28e-3, da = 11.5e-3, e = 2e-2, ea = 1.421e-2, rr = 7e-3, ra = 9.2e-4,
                 l0 = 7.785e-2, ss = 3.5e-2, sa = 1.874e-2, sb = 1.043e-2, sc = 1.8e-2, sd = 2e-2,
                 ta = 2.308e-2, tb = 9.16e-3, u = 4e-2, ua = 1.228e-2, ub = 4.49e-3, zf = 2e-2,
                 zt = 4e-2, fa = 1.421e-2, mom = 3.3e-2;

// A term c·cos(wᵀq) or c·sin(wᵀq) of a constraint g_i.
struct Term {
  double c;
  bool cosine;
  std::array<double, 7> w;
};
// g1…g6 of the test set as trigonometric terms plus constants (indices β0 Θ1 γ2 Φ3 δ4 Ω5 ε6).
inline const std::array<std::vector<Term>, 6>& constraint_terms() {
  static const std::array<std::vector<Term>, 6> g = {
      std::vector<Term>{{rr, true, {1, 0, 0, 0, 0, 0, 0}},
                        {-d, true, {1, 1, 0, 0, 0, 0, 0}},
                        {-ss, false, {0, 0, 1, 0, 0, 0, 0}}},
      std::vector<Term>{{rr, false, {1, 0, 0, 0, 0, 0, 0}},
                        {-d, false, {1, 1, 0, 0, 0, 0, 0}},
                        {ss, true, {0, 0, 1, 0, 0, 0, 0}}},
      std::vector<Term>{{rr, true, {1, 0, 0, 0, 0, 0, 0}},
                        {-d, true, {1, 1, 0, 0, 0, 0, 0}},
                        {-e, false, {0, 0, 0, 1, 1, 0, 0}},
                        {-zt, true, {0, 0, 0, 0, 1, 0, 0}}},
      std::vector<Term>{{rr, false, {1, 0, 0, 0, 0, 0, 0}},
                        {-d, false, {1, 1, 0, 0, 0, 0, 0}},
                        {e, true, {0, 0, 0, 1, 1, 0, 0}},
                        {-zt, false, {0, 0, 0, 0, 1, 0, 0}}},
      std::vector<Term>{{rr, true, {1, 0, 0, 0, 0, 0, 0}},
                        {-d, true, {1, 1, 0, 0, 0, 0, 0}},
                        {-zf, true, {0, 0, 0, 0, 0, 1, 1}},
                        {-u, false, {0, 0, 0, 0, 0, 0, 1}}},
      std::vector<Term>{{rr, false, {1, 0, 0, 0, 0, 0, 0}},
                        {-d, false, {1, 1, 0, 0, 0, 0, 0}},
                        {-zf, false, {0, 0, 0, 0, 0, 1, 1}},
                        {u, true, {0, 0, 0, 0, 0, 0, 1}}}};
  return g;
}
constexpr std::array<double, 6> kConstants = {-xb, -yb, -xa, -ya, -xa, -ya};

inline double dot7(const std::array<double, 7>& w, const VecX& x) {
  double s = 0;
  for (int k = 0; k < 7; ++k) s += w[static_cast<size_t>(k)] * x(k);
  return s;
}

inline void mass(const VecX& q, MatX& M) {
  const double cth = std::cos(q(1)), sph = std::sin(q(3)), som = std::sin(q(5));
  M.setZero(7, 7);
  M(0, 0) = m1 * ra * ra + m2 * (rr * rr - 2 * da * rr * cth + da * da) + i1 + i2;
  M(1, 0) = M(0, 1) = m2 * (da * da - da * rr * cth) + i2;
  M(1, 1) = m2 * da * da + i2;
  M(2, 2) = m3 * (sa * sa + sb * sb) + i3;
  M(3, 3) = m4 * (e - ea) * (e - ea) + i4;
  M(4, 3) = M(3, 4) = m4 * ((e - ea) * (e - ea) + zt * (e - ea) * sph) + i4;
  M(4, 4) = m4 * (zt * zt + 2 * zt * (e - ea) * sph + (e - ea) * (e - ea)) +
            m5 * (ta * ta + tb * tb) + i4 + i5;
  M(5, 5) = m6 * (zf - fa) * (zf - fa) + i6;
  M(6, 5) = M(5, 6) = m6 * ((zf - fa) * (zf - fa) - u * (zf - fa) * som) + i6;
  M(6, 6) = m6 * ((zf - fa) * (zf - fa) - 2 * u * (zf - fa) * som + u * u) +
            m7 * (ua * ua + ub * ub) + i6 + i7;
}

// Ṁ = ∂M/∂Θ Θ̇ + ∂M/∂Φ Φ̇ + ∂M/∂Ω Ω̇ (the only configuration-dependent entries).
inline void mass_rate(const VecX& q, const VecX& v, MatX& Md) {
  const double sth = std::sin(q(1)), cph = std::cos(q(3)), com = std::cos(q(5));
  Md.setZero(7, 7);
  Md(0, 0) = 2 * m2 * da * rr * sth * v(1);
  Md(0, 1) = Md(1, 0) = m2 * da * rr * sth * v(1);
  Md(3, 4) = Md(4, 3) = m4 * zt * (e - ea) * cph * v(3);
  Md(4, 4) = 2 * m4 * zt * (e - ea) * cph * v(3);
  Md(5, 6) = Md(6, 5) = -m6 * u * (zf - fa) * com * v(5);
  Md(6, 6) = -2 * m6 * u * (zf - fa) * com * v(5);
}

// The test set's f(q, q̇) (spring on body 3, torque mom, velocity terms).
inline void testset_f(const VecX& q, const VecX& v, VecX& f) {
  const double sibe = std::sin(q(0)), sith = std::sin(q(1)), coth = std::cos(q(1));
  const double siga = std::sin(q(2)), coga = std::cos(q(2)), siph = std::sin(q(3)),
               coph = std::cos(q(3)), siom = std::sin(q(5)), coom = std::cos(q(5));
  (void)sibe;
  (void)siph;
  (void)siom;
  const double bep = v(0), thp = v(1), php = v(3), dep = v(4), omp = v(5), epp = v(6);
  const double xd = sd * coga + sc * siga + xb, yd = sd * siga - sc * coga + yb;
  const double L = std::sqrt((xd - xc) * (xd - xc) + (yd - yc) * (yd - yc));
  const double F = -c0 * (L - l0) / L, fx = F * (xd - xc), fy = F * (yd - yc);
  f.resize(7);
  f(0) = mom - m2 * da * rr * thp * (thp + 2 * bep) * sith;
  f(1) = m2 * da * rr * bep * bep * sith;
  f(2) = fx * (sc * coga - sd * siga) + fy * (sd * coga + sc * siga);
  f(3) = m4 * zt * (e - ea) * dep * dep * coph;
  f(4) = -m4 * zt * (e - ea) * php * (php + 2 * dep) * coph;
  f(5) = -m6 * u * (zf - fa) * epp * epp * coom;
  f(6) = m6 * u * (zf - fa) * omp * (omp + 2 * epp) * coom;
  (void)coth;
}

}  // namespace andrews

inline GeneralSystem andrews_relative_system() {
  using namespace andrews;
  GeneralSystem s;
  s.n = 7;
  s.nc = 6;
  s.mass = [](const VecX& q, MatX& M) { mass(q, M); };
  s.mass_rate = [](const VecX& q, const VecX& v, MatX& Md) { mass_rate(q, v, Md); };
  s.forces = [](const VecX& q, const VecX& v, double, VecX& Q) {
    testset_f(q, v, Q);
    MatX Md;
    mass_rate(q, v, Md);
    Q += Md * v;  // (L1): Q̂ = f + Ṁ q̇
  };
  s.residual = [](const VecX& q, VecX& f) {
    f.resize(6);
    for (int i = 0; i < 6; ++i) {
      f(i) = kConstants[static_cast<size_t>(i)];
      for (const Term& t : constraint_terms()[static_cast<size_t>(i)]) {
        const double a = dot7(t.w, q);
        f(i) += t.c * (t.cosine ? std::cos(a) : std::sin(a));
      }
    }
  };
  s.jacobian = [](const VecX& q, MatX& Et) {
    Et.setZero(6, 7);
    for (int i = 0; i < 6; ++i)
      for (const Term& t : constraint_terms()[static_cast<size_t>(i)]) {
        const double a = dot7(t.w, q);
        const double dd = t.cosine ? -t.c * std::sin(a) : t.c * std::cos(a);
        for (int k = 0; k < 7; ++k) Et(i, k) += dd * t.w[static_cast<size_t>(k)];
      }
  };
  // Dᵀ = Ėᵀ: d/dt of −c sin(a) w (cosine term) is −c cos(a) (wᵀv) w, of c cos(a) w (sine
  // term) −c sin(a) (wᵀv) w.
  s.jacobian_rate = [](const VecX& q, const VecX& v, MatX& Dt) {
    Dt.setZero(6, 7);
    for (int i = 0; i < 6; ++i)
      for (const Term& t : constraint_terms()[static_cast<size_t>(i)]) {
        const double a = dot7(t.w, q), wv = dot7(t.w, v);
        const double dd = -t.c * (t.cosine ? std::cos(a) : std::sin(a)) * wv;
        for (int k = 0; k < 7; ++k) Dt(i, k) += dd * t.w[static_cast<size_t>(k)];
      }
  };
  s.q0 = Eigen::Map<const VecX>(kAnglesT0.data(), 7);
  s.coordinates = {"beta", "Theta", "gamma", "Phi", "delta", "Omega", "epsilon"};
  return s;
}

// The Model that runs it through the engine (simulate, crosscheck, projections).
inline Model andrews_relative() {
  return make_general_model("andrews-relative", andrews_relative_system());
}

// Published consistent initial values (β, Θ, γ, Φ, δ, Ω, ε) at t = 0.
inline VecX andrews_q0() { return Eigen::Map<const VecX>(andrews::kAnglesT0.data(), 7); }

}  // namespace orthomech::test
