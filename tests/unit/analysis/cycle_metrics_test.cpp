// Design metrics of a sweep (src/analysis/cycle_metrics.cpp) on the crank-rocker (crank a = 30,
// coupler b = 80, rocker c = 60 on a ground d = 70 mm; 300 rpm, gravity only) over one turn,
// against the four-bar's closed forms written here:
//   - transmission angle: cos μ = (b² + c² − BD²) / (2bc) with BD² = a² + d² − 2ad cos θ; its
//     worst deviation from 90° is at θ = 0 (BD = d − a), μ = acos(0.875) (a sample at θ = 0);
//   - rocker stroke: the limit positions are the crank and coupler collinear (A0B = b ± a); in
//     the triangle A0 B0 B the rocker's angle is π − ∠A0B0B; the time ratio is the ratio of the
//     crank angles turned between them (constant crank speed);
//   - drive power of a conservative system over a period has zero mean.
#include "orthomech/analysis/cycle_metrics.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "orthomech/io/mechanism_file.hpp"
#include "support/fixtures.hpp"

namespace orthomech {
namespace {

constexpr double a = 0.03, b = 0.08, c = 0.06, d = 0.07;
constexpr double kPi = std::numbers::pi;

// A named point that no joint uses is a tracer: its x and y ranges are strokes. Andrews' K3 has D
// (the spring's end) and E, B (joints): only K3.D.x and K3.D.y are listed. Their extremes against
// D computed here from each position's body pose, D = r_K3 + R(γ)(D_local − com_local), itself
// checked against the spring_length measure |D − C| (C = (0.014, 0.072) m, the file's ground
// point). The strokes refine the extremes between grid positions: at 360 positions they are at
// or beyond the grid's (measured 2.8e-8 and 3.4e-8 m beyond the minima) and within 1e-8 m of a
// 3600-position grid's (whose own error is about r Δθ²/8 ≈ 4e-9 m).
TEST(CycleMetrics, TracerPointStrokesOnAndrewsSqueezer) {
  const Model model = test::load_bundled("andrews-squeezer");
  const Body& k3 = model.bodies[static_cast<size_t>(model.find_body("K3"))];
  Vec2 d_local = Vec2::Zero();
  for (const auto& [name, local] : k3.points)
    if (name == "D") d_local = local - k3.com_local;
  const Vec2 ground_c(0.014, 0.072);
  size_t spring = 0;
  while (model.measures[spring].name != "spring_length") ++spring;
  // D's extremes over the positions of a sweep.
  auto extremes = [&](const CycleResult& r, Vec2& lo, Vec2& hi) {
    lo = Vec2::Constant(1e300);
    hi = Vec2::Constant(-1e300);
    for (const DrivenPointView& p : r.points) {
      const double g = p.q(k3.q_offset + 2);
      const Vec2 pd = Vec2(p.q(k3.q_offset), p.q(k3.q_offset + 1)) +
                      Vec2(std::cos(g) * d_local.x() - std::sin(g) * d_local.y(),
                           std::sin(g) * d_local.x() + std::cos(g) * d_local.y());
      ASSERT_NEAR((pd - ground_c).norm(), p.measures[spring], 1e-15);
      lo = lo.cwiseMin(pd);
      hi = hi.cwiseMax(pd);
    }
  };
  const CycleResult result = test::full_cycle(model, 360);
  Vec2 lo, hi, lo_fine, hi_fine;
  extremes(result, lo, hi);
  extremes(test::full_cycle(model, 3600), lo_fine, hi_fine);
  CycleMetricsOptions options;
  options.driver_joint = model.find_joint("O");
  const CycleMetrics m = compute_cycle_metrics(model, result, options);
  std::vector<std::string> tracers;
  for (const StrokeMetric& st : m.strokes)
    if (st.name.starts_with("K")) tracers.push_back(st.name);
  ASSERT_EQ(tracers, (std::vector<std::string>{"K3.D.x", "K3.D.y"}));
  for (int axis = 0; axis < 2; ++axis) {
    const auto it = std::find_if(m.strokes.begin(), m.strokes.end(), [&](const StrokeMetric& st) {
      return st.name == (axis == 0 ? "K3.D.x" : "K3.D.y");
    });
    EXPECT_LE(it->min.value, lo(axis) + 1e-15);
    EXPECT_GE(it->max.value, hi(axis) - 1e-15);
    EXPECT_NEAR(it->min.value, lo_fine(axis), 1e-8);
    EXPECT_NEAR(it->max.value, hi_fine(axis), 1e-8);
    EXPECT_NEAR(it->range, it->max.value - it->min.value, 1e-15);
  }
}

TEST(CycleMetrics, CrankRockerAgainstTheFourBarsClosedForms) {
  const Model model = test::load_bundled("crank-rocker");
  const CycleResult result = test::full_cycle(model, 360);
  CycleMetricsOptions options;
  options.driver_joint = model.find_joint("A0");
  options.speed_fluctuation = 0.05;
  const CycleMetrics m = compute_cycle_metrics(model, result, options);

  // Transmission angle.
  ASSERT_EQ(m.loops.size(), 1u);
  EXPECT_FALSE(m.loops[0].slider_crank);
  const double mu_min = std::acos((b * b + c * c - (d - a) * (d - a)) / (2.0 * b * c));
  EXPECT_NEAR(m.loops[0].worst.value, mu_min, 1e-6);
  EXPECT_NEAR(m.loops[0].min.value, mu_min, 1e-6);
  // μ_max where BD² = b² + c² − … is largest, at θ = π: BD = d + a, cos μ = (b² + c² − (a +
  // d)²)/2bc.
  const double mu_max = std::acos((b * b + c * c - (a + d) * (a + d)) / (2.0 * b * c));
  EXPECT_NEAR(m.loops[0].max.value, mu_max, 1e-6);

  // Rocker stroke and time ratio.
  const auto it = std::find_if(m.strokes.begin(), m.strokes.end(),
                               [](const StrokeMetric& s) { return s.name == "rocker_angle"; });
  ASSERT_NE(it, m.strokes.end());
  const auto rocker_angle = [](double l) {  // A0B = l: π − ∠A0B0B
    return kPi - std::acos((d * d + c * c - l * l) / (2.0 * d * c));
  };
  const double psi_ext = rocker_angle(a + b), psi_fold = rocker_angle(b - a);
  EXPECT_NEAR(it->range, std::abs(psi_ext - psi_fold), 1e-6);
  // Crank angles at the limits: along A0→B (extended) and opposite to it (folded).
  const auto crank_angle = [&](double psi, bool extended) {
    const double bx = d + c * std::cos(psi), by = c * std::sin(psi);
    const double along = std::atan2(by, bx);
    return extended ? along : along + kPi;
  };
  const double th_ext = crank_angle(psi_ext, true);
  const double th_fold = crank_angle(psi_fold, false);
  double turn = std::fmod(th_fold - th_ext, 2.0 * kPi);  // extended → folded (crank forward)
  if (turn < 0) turn += 2.0 * kPi;
  const double ratio = turn / (2.0 * kPi - turn);
  EXPECT_EQ(it->maxima, 1);
  ASSERT_TRUE(it->time_ratio.has_value());
  const double got = *it->time_ratio;
  // Which of the two is "forward" depends on the rocker's sense: either ratio or its inverse.
  EXPECT_NEAR(std::min(got, 1.0 / got), std::min(ratio, 1.0 / ratio), 1e-3);
  EXPECT_NEAR(it->forward_time + it->return_time, 60.0 / 300.0, 1e-9);  // one turn at 300 rpm

  // Power of a conservative system over a period.
  ASSERT_TRUE(m.power.available);
  EXPECT_GT(m.power.peak, 0.0);
  EXPECT_LT(std::abs(m.power.mean), 1e-3 * m.power.peak);
  EXPECT_NEAR(m.power.mean_speed, 300.0 * 2.0 * kPi / 60.0, 1e-9);
  EXPECT_NEAR(m.power.energy_fluctuation, m.power.energy_max.value - m.power.energy_min.value,
              1e-15);
  ASSERT_TRUE(m.power.flywheel_inertia.has_value());
  const double w = m.power.mean_speed;
  EXPECT_NEAR(*m.power.flywheel_inertia, m.power.energy_fluctuation / (0.05 * w * w), 1e-15);
  EXPECT_TRUE(m.limits.empty());  // no joint has limits
}

// A time ratio only for one maximum per cycle (issue 51 item 1). A crank turns a gear at twice
// its speed (tests/data/cycle/gear-pair.yaml: gear ratio 2, both pivoted on the ground): the
// gear's point P at radius 30 mm has
// x = 100 + 30 cos(2θ + φ₀), two maxima per turn of the crank, so no time ratio; the crank's own
// point T (x = 40 cos θ) has one maximum and, at constant speed, the time ratio π / π = 1.
TEST(CycleMetrics, TimeRatioOnlyForOneMaximumPerCycle) {
  const Model model =
      load_mechanism(std::string(ORTHOMECH_SOURCE_DIR) + "/tests/data/cycle/gear-pair.yaml");
  const CycleResult result = test::full_cycle(model, 360);
  ASSERT_EQ(result.status, CycleStatus::completed);
  CycleMetricsOptions options;
  options.driver_joint = model.find_joint("O");
  const CycleMetrics m = compute_cycle_metrics(model, result, options);
  auto find = [&](const std::string& name) {
    const auto it = std::find_if(m.strokes.begin(), m.strokes.end(),
                                 [&](const StrokeMetric& s) { return s.name == name; });
    EXPECT_NE(it, m.strokes.end()) << name;
    return it;
  };
  const auto p = find("gear.P.x"), t = find("crank.T.x");
  ASSERT_NE(p, m.strokes.end());
  ASSERT_NE(t, m.strokes.end());
  EXPECT_NEAR(p->range, 0.060, 1e-9);
  EXPECT_EQ(p->maxima, 2);
  EXPECT_FALSE(p->time_ratio.has_value());
  EXPECT_NEAR(t->range, 0.080, 1e-9);
  EXPECT_EQ(t->maxima, 1);
  ASSERT_TRUE(t->time_ratio.has_value());
  EXPECT_NEAR(*t->time_ratio, 1.0, 1e-6);
}

}  // namespace
}  // namespace orthomech
