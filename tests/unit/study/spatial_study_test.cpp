// Design studies of spatial mechanisms (docs/cli.md "sweep": spatial files), against independent
// oracles:
//   - the other formulation: mechanisms/crank-rocker-3d.yaml is mechanisms/crank-rocker.yaml
//     rebuilt with spatial bodies and joints, so a grid over the crank length gives, variant by
//     variant, the planar study's metrics (the drive, the joint forces, every measure's extremes,
//     inputs at the extremes and time ratio, a traced point's deviation);
//   - a closed form: the RSSR four-bar (mechanisms/rssr.yaml) has its rocker angle φ(θ) in closed
//     form (the file's header, with the crank length r1 a parameter), so the swing max φ − min φ
//     and the crank angles at the extremes are found by a dense search and a golden-section
//     refinement (support/spatial_oracles.hpp);
//   - a rigid translation: shifting both ground points by (dx, dy, dz) translates the whole RSSR,
//     so a traced point's deviation is exactly √(dx² + dy² + dz²) at every input (z included).
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>
#include <string>
#include <vector>

#include "orthomech/study/study.hpp"
#include "support/cli_runner.hpp"
#include "support/spatial_oracles.hpp"

namespace orthomech {
namespace {

constexpr double kDeg = 180.0 / std::numbers::pi;

std::map<std::string, double> by_name(const VariantResult& r) {
  std::map<std::string, double> m;
  for (const auto& [name, value] : r.metrics) m[name] = value;
  return m;
}

// Every variant of a study, in order (the nominal file `name` of mechanisms/).
std::vector<VariantResult> run_study(const std::string& name, const std::string& study_text) {
  const std::string file = test::bundled_file(name);
  const std::string mechanism = test::read_text(file);
  Study study = parse_study(study_text, "s.yaml", mechanism, file);
  attach_nominal_paths(study, mechanism, file);
  std::vector<VariantResult> out;
  for (long k = 0; k < variant_count(study); ++k)
    out.push_back(evaluate_variant(mechanism, file, study, k, variant_values(study, k)));
  return out;
}

TEST(SpatialStudy, CrankRocker3dGivesThePlanarStudysMetrics) {
  const std::string study = R"(study: grid
steps: 72
parameters:
  - {name: crank, path: bodies.crank.points.A.0, values: [28, 30, 32]}
metrics: {cycle: true, deviation: [coupler.P]}
)";
  const std::vector<VariantResult> planar = run_study("crank-rocker", study);
  const std::vector<VariantResult> spatial = run_study("crank-rocker-3d", study);
  ASSERT_EQ(planar.size(), 3u);
  ASSERT_EQ(spatial.size(), 3u);
  for (size_t k = 0; k < planar.size(); ++k) {
    ASSERT_EQ(planar[k].status, "completed") << planar[k].message;
    ASSERT_EQ(spatial[k].status, "completed") << spatial[k].message;
    EXPECT_EQ(spatial[k].positions, planar[k].positions);
    const auto p = by_name(planar[k]);
    const auto s = by_name(spatial[k]);
    // The columns both have: the spatial file has no four-bar transmission angle (a planar check)
    // and adds the revolutes' moments; the planar file has more measures.
    int compared = 0;
    for (const auto& [column, value] : s) {
      const auto it = p.find(column);
      if (it == p.end()) continue;
      ++compared;
      // The two formulations agree to ~3e-11 relative (measured: the rocker's time ratio and the
      // crank angle at its maximum); a grid step off would be 1e-2.
      if (std::isnan(it->second))
        EXPECT_TRUE(std::isnan(value)) << column;
      else
        EXPECT_NEAR(value, it->second, 1e-9 * std::max(1.0, std::abs(it->second)))
            << "variant " << k << " column " << column;
    }
    // drive (4), the four joints' |F| peaks, power (2), dead points, the deviation (2) and the
    // measures rocker_angle, P_x, P_y (7 columns each).
    EXPECT_GE(compared, 4 + 4 + 2 + 1 + 2 + 21) << "variant " << k;
    EXPECT_EQ(s.count("rocker_angle.time_ratio"), 1u);
    EXPECT_EQ(s.count("A0.|F|.peak"), 1u);
  }
  // The crank changes the swing: the metrics are the variant's, not the nominal's.
  EXPECT_GT(std::abs(by_name(spatial[2])["rocker_angle.range"] -
                     by_name(spatial[0])["rocker_angle.range"]),
            1.0);
}

// The difference of two crank angles in degrees, up to whole turns.
double angle_gap_deg(double a_deg, double b_deg) {
  return std::abs(std::remainder(a_deg - b_deg, 360.0));
}

// examples/rssr-study.yaml: the crank 90 … 110 mm, its swing as the expression `swing`.
TEST(SpatialStudy, RssrSwingFollowsTheClosedForm) {
  const std::vector<VariantResult> v = run_study(
      "rssr", test::read_text(std::string(ORTHOMECH_SOURCE_DIR) + "/examples/rssr-study.yaml"));
  const double r1s[] = {90, 95, 100, 105, 110};
  ASSERT_EQ(v.size(), 5u);
  for (size_t k = 0; k < v.size(); ++k) {
    ASSERT_EQ(v[k].status, "completed") << v[k].message;
    const auto m = by_name(v[k]);
    const test::RssrExtreme hi = test::rssr_rocker_extreme(r1s[k] / 1000, 1),
                            lo = test::rssr_rocker_extreme(r1s[k] / 1000, -1);
    // 360 positions 1° apart, the extremes refined by a parabola through three samples (an
    // error of order h³, h = 1°): the swing and the maximum within 5e-4° of the closed form
    // (measured ≤ 1.0e-4° and ≤ 8.1e-5°); the crank angle at an extreme within 0.02° (measured
    // ≤ 4.5e-3°; a sample off would be 1°).
    EXPECT_NEAR(m.at("rocker_angle.range"), (hi.phi - lo.phi) * kDeg, 5e-4) << "r1 " << r1s[k];
    EXPECT_EQ(m.at("swing"), m.at("rocker_angle.range"));
    EXPECT_NEAR(m.at("rocker_angle.max"), hi.phi * kDeg, 5e-4) << "r1 " << r1s[k];
    EXPECT_LT(angle_gap_deg(m.at("rocker_angle.max_at"), hi.theta * kDeg), 0.02)
        << "r1 " << r1s[k] << ": " << m.at("rocker_angle.max_at") << " vs " << hi.theta * kDeg;
    EXPECT_LT(angle_gap_deg(m.at("rocker_angle.min_at"), lo.theta * kDeg), 0.02)
        << "r1 " << r1s[k] << ": " << m.at("rocker_angle.min_at") << " vs " << lo.theta * kDeg;
    // The time ratio forward/return at constant crank speed: the crank angle from the minimum
    // to the maximum over the angle from the maximum back to the minimum. The extremes' crank
    // angles are within 4.5e-3° (above): the ratio within 1e-4 (measured ≤ 1.7e-5).
    const double forward =
        std::fmod(hi.theta - lo.theta + 4 * std::numbers::pi, 2 * std::numbers::pi);
    EXPECT_NEAR(m.at("rocker_angle.time_ratio"), forward / (2 * std::numbers::pi - forward), 1e-4)
        << "r1 " << r1s[k];
  }
}

TEST(SpatialStudy, RigidTranslationDeviatesEveryPointByTheShiftInSpace) {
  std::string text = test::read_text(test::bundled_file("rssr"));
  const std::string units = "units: {length: mm, angle: deg, mass: kg, time: s, force: N}\n";
  const std::string ground = "points: {A0: [0, 0, 0], B0: [300, 0, 200]}";
  ASSERT_NE(text.find(units), std::string::npos);
  ASSERT_NE(text.find(ground), std::string::npos);
  text.replace(text.find(ground), ground.size(),
               "points: {A0: [dx, dy, dz], B0: [300 + dx, dy, 200 + dz]}");
  text.insert(text.find(units) + units.size(), "parameters: {dx: 0, dy: 0, dz: 0}\n");
  Study study = parse_study(R"(study: grid
steps: 72
parameters:
  - {path: dx, values: [0, 0.3]}
  - {path: dz, values: [0, -0.4, 1.2]}
metrics: {cycle: true, deviation: [coupler.B, rocker.B, crank.A]}
)",
                            "s.yaml", text, "m.yaml");
  attach_nominal_paths(study, text, "m.yaml");
  ASSERT_TRUE(study.nominal && study.nominal->available) << study.nominal->message;
  ASSERT_EQ(variant_count(study), 6);
  for (long k = 0; k < variant_count(study); ++k) {
    const std::vector<double> x = variant_values(study, k);
    const VariantResult r = evaluate_variant(text, "m.yaml", study, k, x);
    ASSERT_EQ(r.status, "completed") << r.message;
    const auto m = by_name(r);
    const double shift = std::hypot(x[0], x[1]);
    for (const std::string point : {"coupler.B", "rocker.B", "crank.A"}) {
      // Each position is solved to ~1e-12 m, the file in mm.
      EXPECT_NEAR(m.at("deviation." + point + ".max"), shift, 1e-8) << point << " variant " << k;
      EXPECT_NEAR(m.at("deviation." + point + ".rms"), shift, 1e-8) << point << " variant " << k;
    }
  }
}

}  // namespace
}  // namespace orthomech
