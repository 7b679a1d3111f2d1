// Outputs of a cycle (src/io/cycle_output.cpp): the position columns (body frames, not centres
// of mass, and named points) against the crank-rocker's poses as written in its file, and the
// atomic write (the text read back, no temporary left, a failure naming the file).
#include "orthomech/io/cycle_output.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "support/cli_runner.hpp"
#include "support/fixtures.hpp"

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

TEST(CycleOutput, WriteFileAtomically) {
  const test::TempDir dir("orthomech_cycle_output_", true);
  const std::filesystem::path file = dir.path / "out.csv";
  write_file_atomically(file, "a,b\n1,2\n");
  EXPECT_EQ(test::read_text(file), "a,b\n1,2\n");
  write_file_atomically(file, "replaced\n");
  EXPECT_EQ(test::read_text(file), "replaced\n");
  EXPECT_FALSE(std::filesystem::exists(file.string() + ".tmp"));
  const std::filesystem::path missing = dir.path / "no-such-dir" / "out.csv";
  try {
    write_file_atomically(missing, "x");
    FAIL() << "writing into a missing directory must throw";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(missing.string()), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace orthomech
