// The pins' friction over a sweep (src/analysis/cycle_friction.cpp) on the crank-rocker with
// friction in all four pins, against the drive's own accounts: over one turn a frictionless
// conservative mechanism takes back all the work it gets, so the energy the pins dissipate is
// the work of the drive with friction, the mean drive power times the period
// (compute_cycle_metrics, its own trapezoid rule); and "drive without friction" is the drive of
// the same mechanism swept without friction.
#include "orthomech/analysis/cycle_friction.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "orthomech/analysis/cycle_metrics.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "support/fixtures.hpp"

namespace orthomech {
namespace {

TEST(CycleFriction, DissipatedEnergyIsTheDrivesWorkOverATurn) {
  const std::string path = test::source_path("mechanisms/crank-rocker.yaml");
  std::vector<FileChange> changes;
  for (const char* j : {"A0", "A", "B", "B0"})
    changes.push_back(
        parse_file_change(std::string("joints.") + j + ".friction={coefficient: 0.15, radius: 4}"));
  const Model model = load_mechanism(path, changes);
  const CycleResult res = test::full_cycle(model, 720);
  ASSERT_EQ(res.status, CycleStatus::completed) << res.message;
  const FrictionSeries s = friction_series(model, res, model.find_joint("A0"), true);
  ASSERT_EQ(s.pins.size(), 4u);
  EXPECT_TRUE(s.converged);
  EXPECT_TRUE(s.determinate[0] && s.determinate[3]);
  CycleMetricsOptions mo;
  mo.driver_joint = model.find_joint("A0");
  const CycleMetrics metrics = compute_cycle_metrics(model, res, mo);
  const double period = 720 * (res.points[1].time - res.points[0].time);
  EXPECT_GT(s.dissipated, 0.0);
  EXPECT_NEAR(s.dissipated, metrics.power.mean * period, 1e-6 * s.dissipated);

  const Model plain = load_mechanism(path);
  const CycleResult ref = test::full_cycle(plain, 720);
  const std::vector<SeriesSummary> sums = summarize_friction(model, res, s, "N*m");
  ASSERT_EQ(sums.size(), 6u);  // the drive without friction, four pins, the power
  EXPECT_EQ(sums[0].name, "drive without friction");
  EXPECT_EQ(sums[1].name, "A0 friction moment");
  const SeriesSummary plain_drive = summarize_cycle(ref, {}, "N*m")[0];
  EXPECT_NEAR(sums[0].rms, plain_drive.rms, 1e-12 * plain_drive.rms);
  EXPECT_NEAR(sums[0].max.value, plain_drive.max.value, 1e-12 * plain_drive.peak);
}

TEST(CycleFriction, EfficiencyIsTheLoadsWorkOverTheDrivesWork) {
  // A process torque T = 100 N*mm resisting the rocker while it swings up (active_while): over a
  // turn it takes T times the rocker's swing, which the cosine law gives at the two dead centres
  // (A0B = b + a = 110 mm and b − a = 50 mm, B0B = 60 mm, A0B0 = 70 mm). That is the frictionless
  // drive's net work W0; with friction the drive's work W is measured by compute_cycle_metrics'
  // own rule, and η = W0 / W. (The switched torque's jumps cost the trapezoid rule half a step's
  // swing each: 3600 positions hold W0 to 2e-3.)
  const std::string path = test::source_path("mechanisms/crank-rocker.yaml");
  std::vector<FileChange> changes = {parse_file_change(
      "loads=[{name: weight, type: gravity, g: [0, -9810]}, {name: process, type: torque, body: "
      "rocker, torque: -100, active_while: {measure: rocker_angle, velocity: positive}}]")};
  for (const char* j : {"A0", "A", "B", "B0"})
    changes.push_back(
        parse_file_change(std::string("joints.") + j + ".friction={coefficient: 0.15, radius: 4}"));
  const Model model = load_mechanism(path, changes);
  const int positions = 3600;
  const CycleResult res = test::full_cycle(model, positions);
  ASSERT_EQ(res.status, CycleStatus::completed) << res.message;
  const FrictionSeries s = friction_series(model, res, model.find_joint("A0"), true);
  auto beta = [](double L) {
    return std::acos((70.0 * 70.0 + 60.0 * 60.0 - L * L) / (2 * 70 * 60));
  };
  const double swing = beta(110.0) - beta(50.0);  // rad
  const double W0 = 0.1 * swing;                  // J (100 N*mm = 0.1 N*m)
  EXPECT_NEAR(s.drive_work_frictionless, W0, 2e-3 * W0);
  CycleMetricsOptions mo;
  mo.driver_joint = model.find_joint("A0");
  const CycleMetrics metrics = compute_cycle_metrics(model, res, mo);
  const double W = metrics.power.mean * positions * (res.points[1].time - res.points[0].time);
  EXPECT_NEAR(s.drive_work, W, 1e-9 * W);
  EXPECT_NEAR(s.drive_work - s.drive_work_frictionless, s.dissipated, 1e-6 * s.dissipated);
  EXPECT_NEAR(s.efficiency, W0 / W, 2e-3 * W0 / W);
  EXPECT_GT(s.efficiency, 0.0);
  EXPECT_LT(s.efficiency, 1.0);
  // Without the process torque the loads take no net work: no efficiency.
  std::vector<FileChange> frictional(changes.begin() + 1, changes.end());
  const Model idle = load_mechanism(path, frictional);
  const FrictionSeries idle_s =
      friction_series(idle, test::full_cycle(idle, 720), idle.find_joint("A0"), true);
  EXPECT_TRUE(std::isnan(idle_s.efficiency));
}

}  // namespace
}  // namespace orthomech
