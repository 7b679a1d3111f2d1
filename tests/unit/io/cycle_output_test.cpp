// Outputs of a cycle (src/io/cycle_output.cpp): the position columns (body frames, not centres
// of mass, and named points) against the crank-rocker's poses as written in its file, and the
// atomic write (the text read back, no temporary left, a failure naming the file).
#include "orthomech/io/cycle_output.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "orthomech/analysis/cycle.hpp"
#include "orthomech/io/file_writer.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "support/cli_runner.hpp"
#include "support/fixtures.hpp"
#include "unit/analysis/large_mechanisms.hpp"

namespace orthomech {
namespace {

TEST(CycleOutput, PositionColumnsAreTheBodyFramesAndNamedPoints) {
  const Model model = test::load_bundled("crank-rocker");
  const std::vector<PositionColumn> cols = position_columns(model);
  std::vector<double> values;
  compute_output_positions(model, model.design_q(), values);
  ASSERT_EQ(values.size(), cols.size());
  const auto value = [&](const std::string& name) {
    for (size_t i = 0; i < cols.size(); ++i)
      if (cols[i].name == name) return values[i];
    ADD_FAILURE() << "no column " << name;
    return std::nan("");
  };
  // The poses of mechanisms/crank-rocker.yaml (mm, deg) in SI.
  const double deg = M_PI / 180.0;
  EXPECT_NEAR(value("crank.x"), 0.0, 1e-15);
  EXPECT_NEAR(value("crank.y"), 0.0, 1e-15);
  EXPECT_NEAR(value("crank.angle"), 60.0 * deg, 1e-15);
  EXPECT_NEAR(value("coupler.x"), 0.015000000000000004, 1e-15);
  EXPECT_NEAR(value("coupler.y"), 0.025980762113533157, 1e-15);
  EXPECT_NEAR(value("rocker.x"), 0.07, 1e-15);
  EXPECT_NEAR(value("rocker.angle"), 71.79755360961532 * deg, 1e-14);
  // coupler.P = pose + R(φ) (40, 20) mm.
  const double phi = 22.812053275345825 * deg;
  EXPECT_NEAR(value("coupler.P.x"),
              0.015000000000000004 + 0.04 * std::cos(phi) - 0.02 * std::sin(phi), 1e-15);
  EXPECT_NEAR(value("coupler.P.y"),
              0.025980762113533157 + 0.04 * std::sin(phi) + 0.02 * std::cos(phi), 1e-15);
  for (const PositionColumn& c : cols)
    EXPECT_EQ(c.dimension, c.name.ends_with(".angle") ? Dimension::angle : Dimension::length)
        << c.name;
}

// At a change point the sweep does not bridge (here: bridging switched off) the velocities and
// accelerations come from a failing chart: their cells are empty, as the drive's, and every other
// position keeps its values. Before, they were written (garbage of up to 1e15 m/s² on the
// N = 60 four-bar), set the column's noise floor and printed every acceleration of the cycle as
// 0. Reference: the N-four-bar driven at constant ω by link0 translates every coupler on a circle
// of 1 m and turns every link about its pivot: a = −ω² (cos θ, sin θ) for a coupler's centre,
// half of it for a link's, θ the input.
TEST(CycleOutput, RatesAtAnUnbridgedChangePointAreEmptyAndEveryOtherPositionKeepsItsValues) {
  const double omega = 2.0 * std::numbers::pi;  // 60 rpm
  const Model model = parse_mechanism(
      test::n_four_bar_yaml(2, std::numbers::pi / 2) +
          "measures:\n  - {name: B0_vx, type: point, point: link0.B, component: x, derivative: "
          "1}\n  - {name: B0_x, type: point, point: link0.B, component: x}\n"
          "drivers:\n  - {name: motor, joint: O0, speed: 60 rpm}\n",
      "n-four-bar-2 (test)");
  CycleOptions o;
  o.driver = model.drivers[0];
  o.steps = 36;
  o.bridge_change_points = false;
  const CycleResult r = run_cycle(model, o);
  ASSERT_EQ(r.status, CycleStatus::completed) << r.message;
  const test::TempDir dir("orthomech_cycle_rates_", true);
  const auto file = dir.path / "cycle.csv";
  (void)write_cycle_csv(file, model, r, reaction_magnitudes(r), true, UnitSystem{});
  std::istringstream text(test::read_text(file));
  std::string line;
  std::getline(text, line);
  std::vector<std::string> header;
  {
    std::istringstream h(line);
    for (std::string cell; std::getline(h, cell, ',');) header.push_back(cell);
  }
  const auto column = [&](const std::string& name) {
    for (size_t i = 0; i < header.size(); ++i)
      if (header[i] == name) return i;
    ADD_FAILURE() << "no column " << name;
    return size_t{0};
  };
  const size_t ax = column("coupler1.ax [m/s^2]"), ay = column("coupler1.ay [m/s^2]");
  const size_t lx = column("link0.ax [m/s^2]"), vx = column("link0.vx [m/s]");
  const size_t mv = column("B0_vx [m/s]"), mx = column("B0_x [m]");
  int singular = 0, checked = 0;
  for (size_t k = 0; std::getline(text, line); ++k) {
    std::vector<std::string> cells;
    std::istringstream row(line);
    for (std::string cell; std::getline(row, cell, ',');) cells.push_back(cell);
    cells.resize(header.size());
    const DrivenPointView p = r.points[k];
    EXPECT_FALSE(cells[mx].empty());  // a position measure is always reported
    if (p.singular) {
      ++singular;
      EXPECT_TRUE(cells[ax].empty() && cells[lx].empty() && cells[vx].empty() && cells[mv].empty())
          << "row " << k;
      continue;
    }
    const double th = p.input, w2 = omega * omega;
    EXPECT_NEAR(std::stod(cells[ax]), -w2 * std::cos(th), 1e-7) << "row " << k;
    EXPECT_NEAR(std::stod(cells[ay]), -w2 * std::sin(th), 1e-7) << "row " << k;
    EXPECT_NEAR(std::stod(cells[lx]), -0.5 * w2 * std::cos(th), 1e-7) << "row " << k;
    EXPECT_NEAR(std::stod(cells[mv]), -omega * std::sin(th), 1e-9) << "row " << k;
    ++checked;
  }
  EXPECT_EQ(singular, 2);  // 180° and 360°, not bridged
  EXPECT_EQ(checked, 34);
}

// The names in a directory, sorted.
std::vector<std::string> entries(const std::filesystem::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

TEST(CycleOutput, WriteFile) {
  const test::TempDir dir("orthomech_cycle_output_", true);
  const std::filesystem::path file = dir.path / "out.csv";
  write_file(file, "a,b\n1,2\n");
  EXPECT_EQ(test::read_text(file), "a,b\n1,2\n");
  write_file(file, "replaced\n");
  EXPECT_EQ(test::read_text(file), "replaced\n");
  EXPECT_EQ(entries(dir.path), std::vector<std::string>{"out.csv"});  // no temporary left
  const std::filesystem::path missing = dir.path / "no-such-dir" / "out.csv";
  try {
    write_file(missing, "x");
    FAIL() << "writing into a missing directory must throw";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(missing.string()), std::string::npos) << e.what();
  }
}

// write_cycle_csv streams its rows into a temporary file and renames it onto FILE when complete
// (the N = 1000 four-bar's table, 230 MB, is no longer held whole in memory): the file written is
// the one read back with every row, an existing file is replaced, and a table that fails while
// it is written (an extra column with a value too few, checked after the first columns) leaves
// the existing file as it was and no temporary file.
TEST(CycleOutput, CsvIsStreamedAndReplacedOnlyWhenComplete) {
  const Model model = parse_mechanism(test::n_four_bar_yaml(2, std::numbers::pi / 2) +
                                          "drivers:\n  - {name: motor, joint: O0, speed: 60 rpm}\n",
                                      "n-four-bar-2 (test)");
  CycleOptions o;
  o.driver = model.drivers[0];
  o.steps = 36;
  const CycleResult r = run_cycle(model, o);
  ASSERT_EQ(r.status, CycleStatus::completed) << r.message;
  const test::TempDir dir("orthomech_cycle_stream_", true);
  const auto file = dir.path / "cycle.csv";
  write_file(file, "before\n");
  ExtraColumn extra{.name = "index",
                    .dimension = Dimension::length,
                    .values = {},
                    .reported = {},
                    .before_limits = false};
  for (size_t k = 0; k < r.points.size(); ++k) extra.values.push_back(static_cast<double>(k));
  (void)write_cycle_csv(file, model, r, reaction_magnitudes(r), true, UnitSystem{}, {extra});
  const std::string text = test::read_text(file);
  EXPECT_EQ(static_cast<size_t>(std::count(text.begin(), text.end(), '\n')), r.points.size() + 1);
  EXPECT_NE(text.find(",index [m]\n"), std::string::npos);
  EXPECT_EQ(text.substr(text.rfind(',') + 1), std::to_string(r.points.size() - 1) + "\n");
  EXPECT_EQ(entries(dir.path), std::vector<std::string>{"cycle.csv"});  // no temporary left

  write_file(file, "before\n");
  extra.values.pop_back();
  EXPECT_THROW(
      (void)write_cycle_csv(file, model, r, reaction_magnitudes(r), true, UnitSystem{}, {extra}),
      std::invalid_argument);
  EXPECT_EQ(test::read_text(file), "before\n");
  EXPECT_EQ(entries(dir.path), std::vector<std::string>{"cycle.csv"});  // no temporary left
}

// The shaking columns go before `limits`, in the world frame, empty where a position's rates
// are not reported: the CSV's cells are the series' values (planar: force x, y and moment z).
TEST(CycleOutput, ShakingColumnsBeforeLimitsWithTheSeriesValues) {
  const Model model = test::load_bundled("crank-rocker");
  const CycleResult r = test::full_cycle(model, 12);
  ShakingSeries s = shaking_series(model, r, Vec3(0.01, 0.0, 0.0));
  s.reported[3] = false;  // as at an unbridged change point
  const test::TempDir dir("orthomech_cycle_shaking_", true);
  const auto file = dir.path / "cycle.csv";
  (void)write_cycle_csv(file, model, r, reaction_magnitudes(r), true, UnitSystem{},
                        shaking_columns(model, s));
  std::istringstream in(test::read_text(file));
  std::string line;
  std::getline(in, line);
  const std::string tail = "shaking force x [N],shaking force y [N],shaking moment z [N*m],limits";
  ASSERT_GE(line.size(), tail.size());
  EXPECT_EQ(line.substr(line.size() - tail.size()), tail);
  for (size_t k = 0; std::getline(in, line); ++k) {
    std::vector<std::string> cells;
    std::stringstream row(line);
    for (std::string c; std::getline(row, c, ',');) cells.push_back(c);
    if (line.back() == ',') cells.emplace_back();  // the empty `limits`
    ASSERT_GE(cells.size(), 4u);
    const size_t n = cells.size();
    if (k == 3) {
      EXPECT_TRUE(cells[n - 4].empty() && cells[n - 2].empty()) << line;
      continue;
    }
    EXPECT_NEAR(std::stod(cells[n - 4]), s.force[k].x(), 1e-10 * s.force[k].norm());
    EXPECT_NEAR(std::stod(cells[n - 3]), s.force[k].y(), 1e-10 * s.force[k].norm());
    EXPECT_NEAR(std::stod(cells[n - 2]), s.moment[k].z(), 1e-10 * std::abs(s.moment[k].z()));
  }
  const Model spatial = test::load_bundled("rssr");
  const auto cols =
      shaking_columns(spatial, shaking_series(spatial, test::full_cycle(spatial, 6), Vec3::Zero()));
  ASSERT_EQ(cols.size(), 6u);
  EXPECT_EQ(cols[2].name, "shaking force z");
  EXPECT_EQ(cols[5].name, "shaking moment z");
  EXPECT_TRUE(cols[0].before_limits);
}

}  // namespace
}  // namespace orthomech
