// Shaking force and moment (src/analysis/shaking.cpp) against three independent oracles:
//   - central differences in time of the momenta P = Σ m v_G and H_O = Σ [(r_G − O) × m v_G +
//     R J ω] computed here from each position's q and u (the sweep's velocities, not its
//     accelerations), on the planar crank-rocker and the spatial RSSR (whose bodies turn about
//     non-principal, changing axes: the ω × J ω term);
//   - the reactions: the frame carries λ of every joint to the ground (the force of the moving
//     body on the ground, docs/notation.md) and the reaction −τ of the motor, so F_s = Σ λ − W
//     and M_s = Σ (r_J − O) × λ − τ − Σ (r_G − O) × m g by the momentum balance of the moving
//     bodies (the reactions come from the multipliers, a solve of their own);
//   - Berkof and Lowen's full force balance of a four-bar ("A complete method of balancing the
//     shaking force in linkages", J. Eng. Ind. 1969), by linearly independent vectors: with the
//     coupler's centre of mass at r₂ along AB, the crank's at −m₂ a₁ (1 − r₂/b)/m₁ along A0A and
//     the rocker's at −m₂ r₂ c/(b m₃) along B0B, the total centre of mass does not move.
#include "orthomech/analysis/shaking.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "orthomech/analysis/reactions.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/model/spatial.hpp"
#include "support/fixtures.hpp"

namespace orthomech {
namespace {

// P and H_O of a state, from its velocities.
MomentumRate momenta(const Model& model, const VecX& q, const VecX& u, const Vec3& about) {
  MomentumRate m;  // (linear, angular): the momenta themselves here
  for (const Body& b : model.bodies) {
    const int o = b.q_offset, v = b.u_offset;
    if (b.kind == BodyKind::spatial) {
      const Vec3 r = q.segment<3>(o), mv = b.mass * u.segment<3>(v);
      m.linear += mv;
      m.angular += (r - about).cross(mv) +
                   rotation_matrix(q.segment<4>(o + 3)) * (b.spatial.inertia * u.segment<3>(v + 3));
    } else {
      const Vec3 r(q(o), q(o + 1), 0.0), mv(b.mass * u(v), b.mass * u(v + 1), 0.0);
      m.linear += mv;
      m.angular += (r - about).cross(mv);
      if (b.kind == BodyKind::rigid) m.angular.z() += b.inertia * u(v + 2);
    }
  }
  return m;
}

// Over a full cycle of `steps` positions (uniform in time, the last followed by the first):
// max |F_s + ΔP/Δt| and max |M_s + ΔH/Δt| by central differences, relative to the peaks.
void expect_momentum_differences(const Model& model, int steps, const Vec3& about, double tol) {
  const CycleResult r = test::full_cycle(model, steps);
  ASSERT_EQ(r.status, CycleStatus::completed) << r.message;
  const size_t n = r.points.size();
  const double dt = r.points[1].time - r.points[0].time;
  const ShakingSeries s = shaking_series(model, r, about);
  std::vector<MomentumRate> mom;
  for (size_t k = 0; k < n; ++k) mom.push_back(momenta(model, r.points[k].q, r.points[k].u, about));
  double f_err = 0.0, m_err = 0.0, f_peak = 0.0, m_peak = 0.0;
  for (size_t k = 0; k < n; ++k) {
    ASSERT_TRUE(s.reported[k]);
    const MomentumRate& next = mom[(k + 1) % n];
    const MomentumRate& prev = mom[(k + n - 1) % n];
    const Vec3 dP = (next.linear - prev.linear) / (2.0 * dt);
    const Vec3 dH = (next.angular - prev.angular) / (2.0 * dt);
    f_err = std::max(f_err, (s.force[k] + dP).norm());
    m_err = std::max(m_err, (s.moment[k] + dH).norm());
    f_peak = std::max(f_peak, s.force[k].norm());
    m_peak = std::max(m_peak, s.moment[k].norm());
  }
  EXPECT_GT(f_peak, 0.0);
  EXPECT_GT(m_peak, 0.0);
  EXPECT_LT(f_err, tol * f_peak) << "force error " << f_err << " of a peak " << f_peak;
  EXPECT_LT(m_err, tol * m_peak) << "moment error " << m_err << " of a peak " << m_peak;
}

// Crank-rocker at 300 rpm, 3600 positions (Δθ = 0.1°): the differences' error is about
// Δθ²/6 ≈ 5e-7 of the peak; about a point off the pivots so that the r × m a terms count.
TEST(Shaking, PlanarCrankRockerIsMinusTheRateOfItsMomenta) {
  expect_momentum_differences(test::load_bundled("crank-rocker"), 3600, Vec3(0.02, -0.01, 0.0),
                              1e-5);
}

// The RSSR: its coupler and rocker turn about axes that move in space, so d/dt(R J ω) carries
// R (ω × J ω) besides R J ω̇.
TEST(Shaking, SpatialRssrIsMinusTheRateOfItsMomenta) {
  expect_momentum_differences(test::load_bundled("rssr"), 3600, Vec3(0.1, 0.05, -0.02), 1e-5);
}

// The frame's side of the same balance, through the multipliers: F_s = λ_A0 + λ_B0 − W and
// M_s = Σ (r_J − O) × λ_J − τ − Σ (r_G − O) × m g on the crank-rocker with its weight.
TEST(Shaking, CrankRockerBalancesItsGroundReactionsAndDrive) {
  const Model model = test::load_bundled("crank-rocker");
  const CycleResult r = test::full_cycle(model, 72);
  ASSERT_EQ(r.status, CycleStatus::completed) << r.message;
  const Vec3 about(0.01, 0.03, 0.0);
  const ShakingSeries s = shaking_series(model, r, about);
  auto component = [&](const std::string& name) {
    for (size_t i = 0; i < r.components.size(); ++i)
      if (r.components[i].name == name) return i;
    ADD_FAILURE() << "no component " << name;
    return size_t{0};
  };
  const size_t a0x = component("A0.Fx"), a0y = component("A0.Fy");
  const size_t b0x = component("B0.Fx"), b0y = component("B0.Fy");
  const Vec3 g(0.0, -9.81, 0.0), rA0(0.0, 0.0, 0.0), rB0(0.07, 0.0, 0.0);
  double scale = 0.0;
  for (const Body& b : model.bodies) scale += b.mass * g.norm();
  for (size_t k = 0; k < r.points.size(); ++k) {
    const DrivenPointView p = r.points[k];
    const Vec3 lA0(p.reactions[a0x], p.reactions[a0y], 0.0);
    const Vec3 lB0(p.reactions[b0x], p.reactions[b0y], 0.0);
    Vec3 weight = Vec3::Zero(), weight_moment = Vec3::Zero();
    for (const Body& b : model.bodies) {
      const Vec3 rG(p.q(b.q_offset), p.q(b.q_offset + 1), 0.0);
      weight += b.mass * g;
      weight_moment += (rG - about).cross(b.mass * g);
    }
    const Vec3 force = lA0 + lB0 - weight;
    const Vec3 moment = (rA0 - about).cross(lA0) + (rB0 - about).cross(lB0) -
                        Vec3(0.0, 0.0, p.drive) - weight_moment;
    EXPECT_NEAR((s.force[k] - force).norm(), 0.0, 1e-9 * scale) << "position " << k;
    EXPECT_NEAR((s.moment[k] - moment).norm(), 0.0, 1e-9 * scale * 0.1) << "position " << k;
  }
}

// The crank-rocker (a₁ = 30, b = 80, c = 60 mm; m₁, m₂, m₃ = 0.03, 0.08, 0.06 kg, coupler's
// centre of mass r₂ = 40 mm along AB) with Berkof and Lowen's counterweighted crank and rocker:
// m₁ r₁ = −m₂ a₁ (1 − r₂/b) = −1.2 kg·mm, so r₁ = −40 mm; m₃ r₃ = −m₂ r₂ c/b = −2.4 kg·mm, so
// r₃ = −40 mm. Its shaking force is 0 to rounding over the cycle (here against the unbalanced
// mechanism's peak), its shaking moment is not (force balance leaves the moment).
TEST(Shaking, BerkofLowenBalancedFourBarHasNoShakingForce) {
  const Model plain = test::load_bundled("crank-rocker");
  const Model balanced = load_mechanism(test::source_path("mechanisms/crank-rocker.yaml"),
                                        {parse_file_change("bodies.crank.com=[-40, 0]"),
                                         parse_file_change("bodies.rocker.com=[-40, 0]")});
  const CycleResult r0 = test::full_cycle(plain, 360);
  const ShakingSummaries before =
      summarize_shaking(plain, r0, shaking_series(plain, r0, Vec3::Zero()));
  const CycleResult r = test::full_cycle(balanced, 360);
  ASSERT_EQ(r.status, CycleStatus::completed) << r.message;
  const ShakingSummaries after =
      summarize_shaking(balanced, r, shaking_series(balanced, r, Vec3::Zero()));
  ASSERT_EQ(before.magnitudes[0].name, "shaking force");
  EXPECT_GT(before.magnitudes[0].peak, 1.0);  // N: 0.17 kg at ~30 m/s² and more
  EXPECT_LT(after.magnitudes[0].peak, 1e-9 * before.magnitudes[0].peak);
  EXPECT_GT(after.magnitudes[1].peak, 1e-3 * before.magnitudes[1].peak);
  EXPECT_EQ(after.magnitudes[0].samples, 360);
  // The summaries are those of the series: RMS of |F_s| and the components' extremes.
  ASSERT_EQ(before.components.size(), 2u);
  EXPECT_EQ(before.components[0].name, "shaking force x");
  EXPECT_LE(before.components[0].max.value, before.magnitudes[0].peak);
  EXPECT_LE(before.magnitudes[0].rms, before.magnitudes[0].peak);
}

}  // namespace
}  // namespace orthomech
