// Counterweight balancing (src/analysis/balancing.cpp) on the crank-rocker (a₁ = 30, b = 80,
// c = 60 mm; m₁, m₂, m₃ = 0.03, 0.08, 0.06 kg at 15, 40, 30 mm along each link):
//   - a round trip to Berkof and Lowen's full force balance ("A complete method of balancing the
//     shaking force in linkages", 1969): the first moment of crank and rocker about their ground
//     pivots must be m₂ a₁ (r₂/b − 1) = −1.2 kg·mm and −m₂ r₂ c/b = −2.4 kg·mm, so counterweights
//     at 40 mm are 41.25 g and 105 g, both opposite the link;
//   - the balanced file, written by edit_mass_properties, read back and swept again: its shaking
//     force, moment and drive (a new sweep with the new masses: the reactions solved again) are
//     the ones the balancing predicted from the old sweep's motion.
#include "orthomech/analysis/balancing.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "orthomech/analysis/shaking.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/io/mechanism_writer.hpp"
#include "support/fixtures.hpp"

namespace orthomech {
namespace {

std::string file_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

struct Balanced {
  BalanceResult result;
  BalanceTerms swept;  // of the written file's own sweep
};

Balanced balance_and_sweep_again(const BalanceWeights& weights) {
  const std::string path = test::source_path("mechanisms/crank-rocker.yaml");
  const Model model = load_mechanism(path);
  const CycleResult sweep = test::full_cycle(model, 360);
  BalanceOptions o;
  o.sites = {{model.find_body("crank"), 0.04}, {model.find_body("rocker"), 0.04}};
  o.weights = weights;
  o.about = Vec3(0.035, 0.0, 0.0);
  Balanced b;
  b.result = balance_counterweights(model, sweep, o);
  std::vector<MassEdit> edits;
  for (const Counterweight& c : b.result.counterweights)
    edits.push_back({c.body, c.body_mass, c.body_com, c.body_inertia});
  const Model balanced =
      parse_mechanism(edit_mass_properties(file_text(path), path, model, edits), "balanced.yaml");
  b.swept = balance_terms(balanced, test::full_cycle(balanced, 360), o.about);
  return b;
}

TEST(Balancing, RecoversBerkofLowensCounterweightsOfAFourBar) {
  const Balanced b = balance_and_sweep_again({1.0, 0.0, 0.0});
  const BalanceResult& r = b.result;
  ASSERT_EQ(r.status, BalanceStatus::balanced) << r.message;
  ASSERT_EQ(r.counterweights.size(), 2u);
  const double expected_mass[2] = {0.04125, 0.105};
  for (int i = 0; i < 2; ++i) {
    const Counterweight& c = r.counterweights[static_cast<size_t>(i)];
    EXPECT_NEAR(c.mass, expected_mass[i], 1e-6 * expected_mass[i]) << i;
    EXPECT_NEAR(c.position.x(), -0.04, 1e-7) << i;
    EXPECT_NEAR(c.position.y(), 0.0, 1e-7) << i;
  }
  // The crank with its counterweight: 71.25 g with its centre of mass at −1.2/71.25 m·g/g.
  EXPECT_NEAR(r.counterweights[0].body_mass, 0.07125, 1e-8);
  EXPECT_NEAR(r.counterweights[0].body_com.x(), -0.0012 / 0.07125, 1e-9);
  EXPECT_GT(r.before.force_rms, 1.0);
  EXPECT_LT(r.after.force_rms, 1e-6 * r.before.force_rms);
  EXPECT_LT(r.objective_after, 1e-12);
  // The written file's own sweep: no shaking force either, and the moment and drive predicted.
  EXPECT_LT(b.swept.force_peak, 1e-6 * r.before.force_rms);
  EXPECT_NEAR(b.swept.moment_rms, r.after.moment_rms, 1e-6 * r.after.moment_rms);
  EXPECT_NEAR(b.swept.drive_rms, r.after.drive_rms, 1e-6 * r.after.drive_rms);
}

// Weighting the shaking moment and the drive too: a compromise, which lowers the objective, and
// whose predicted terms the balanced file's own sweep confirms (the moment and drive terms of the
// counterweights, checked against the reactions solved with the new masses).
TEST(Balancing, AWeightedCompromiseIsWhatTheBalancedFileDoes) {
  const Balanced b = balance_and_sweep_again({1.0, 1.0, 1.0});
  const BalanceResult& r = b.result;
  ASSERT_EQ(r.status, BalanceStatus::balanced) << r.message;
  EXPECT_LT(r.objective_after, 0.9 * r.objective_before);
  EXPECT_NEAR(b.swept.force_rms, r.after.force_rms, 1e-6 * r.before.force_rms);
  EXPECT_NEAR(b.swept.moment_rms, r.after.moment_rms, 1e-6 * r.before.moment_rms);
  EXPECT_NEAR(b.swept.drive_rms, r.after.drive_rms, 1e-6 * r.before.drive_rms);
}

TEST(Balancing, RefusesWhatItCannotBalance) {
  const Model spatial = test::load_bundled("crank-rocker-3d");
  BalanceOptions o;
  o.sites = {{0, 0.04}};
  EXPECT_EQ(balance_counterweights(spatial, CycleResult{}, o).status,
            BalanceStatus::invalid_request);
  const Model model = test::load_bundled("crank-rocker");
  const CycleResult sweep = test::full_cycle(model, 36);
  o.sites = {{0, 0.04}, {0, 0.05}};
  const BalanceResult twice = balance_counterweights(model, sweep, o);
  EXPECT_EQ(twice.status, BalanceStatus::invalid_request);
  EXPECT_NE(twice.message.find("two counterweight sites"), std::string::npos) << twice.message;
  o.sites = {{0, 0.0}};
  EXPECT_EQ(balance_counterweights(model, sweep, o).status, BalanceStatus::invalid_request);
}

}  // namespace
}  // namespace orthomech
