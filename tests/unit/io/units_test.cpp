// Units (src/io/units.cpp): the declared unit systems and their SI factors against the unit
// definitions (1 mm = 1e-3 m, 1° = π/180 rad, 1 rpm = 2π/60 rad/s, 1 g = 1e-3 kg, 1 kN = 1e3 N,
// 1 ms = 1e-3 s), compound output units built from them, and the text written for people. The
// limits of range_problem, parse_speed and parse_position are in units_limits_test.cpp.
#include "orthomech/io/units.hpp"

#include <gtest/gtest.h>

#include <numbers>
#include <stdexcept>
#include <string>

namespace orthomech {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

UnitSystem mm_deg_g_ms_kN() {
  return unit_system(
      DeclaredUnits{.length = "mm", .angle = "deg", .mass = "g", .time = "ms", .force = "kN"});
}

TEST(Units, DeclaredSystemHasTheUnitsSiFactors) {
  const UnitSystem si = unit_system(DeclaredUnits{});
  EXPECT_TRUE(si.is_si());
  EXPECT_EQ(si.length_si, 1.0);
  EXPECT_EQ(si.angle_si, 1.0);
  const UnitSystem u = mm_deg_g_ms_kN();
  EXPECT_FALSE(u.is_si());
  EXPECT_EQ(u.length, "mm");
  EXPECT_DOUBLE_EQ(u.length_si, 1e-3);
  EXPECT_DOUBLE_EQ(u.angle_si, kDeg);
  EXPECT_DOUBLE_EQ(u.mass_si, 1e-3);
  EXPECT_DOUBLE_EQ(u.time_si, 1e-3);
  EXPECT_DOUBLE_EQ(u.force_si, 1e3);
  EXPECT_THROW((void)unit_system(DeclaredUnits{.length = "furlong"}), std::invalid_argument);
}

// A compound unit's size is the product of its base units' sizes.
TEST(Units, CompoundOutputUnitsAreProductsOfTheBaseUnits) {
  const UnitSystem u = mm_deg_g_ms_kN();
  EXPECT_DOUBLE_EQ(output_unit(Dimension::length, u).si, 1e-3);
  EXPECT_DOUBLE_EQ(output_unit(Dimension::moment, u).si, 1e3 * 1e-3);     // kN·mm
  EXPECT_DOUBLE_EQ(output_unit(Dimension::velocity, u).si, 1e-3 / 1e-3);  // mm/ms
  EXPECT_DOUBLE_EQ(output_unit(Dimension::angular_velocity, u).si, kDeg / 1e-3);
  EXPECT_DOUBLE_EQ(output_unit(Dimension::acceleration, u).si, 1e-3 / 1e-6);
  EXPECT_DOUBLE_EQ(output_unit(Dimension::angular_acceleration, u).si, kDeg / 1e-6);
  EXPECT_DOUBLE_EQ(output_unit(Dimension::power, u).si, 1e3 * 1e-3 / 1e-3);
  EXPECT_DOUBLE_EQ(output_unit(Dimension::inertia, u).si, 1e-3 * 1e-6);
  EXPECT_DOUBLE_EQ(output_unit(Dimension::frequency, u).si, 1.0 / 1e-3);
  EXPECT_DOUBLE_EQ(output_unit(Dimension::none, u).si, 1.0);
  EXPECT_EQ(output_unit(Dimension::velocity, u).name, "mm/ms");
  EXPECT_EQ(output_unit(Dimension::angle, u).name, "deg");
  // from_si divides by the unit's size: 0.25 m = 250 mm.
  EXPECT_DOUBLE_EQ(output_unit(Dimension::length, u).from_si(0.25), 250.0);
}

TEST(Units, DimensionOfTheLibrarysSiUnitNames) {
  EXPECT_EQ(dimension_of("m"), Dimension::length);
  EXPECT_EQ(dimension_of("m/s"), Dimension::velocity);
  EXPECT_EQ(dimension_of("m/s^2"), Dimension::acceleration);
  EXPECT_EQ(dimension_of("rad"), Dimension::angle);
  EXPECT_EQ(dimension_of("rad/s"), Dimension::angular_velocity);
  EXPECT_EQ(dimension_of("rad/s^2"), Dimension::angular_acceleration);
  EXPECT_EQ(dimension_of("N"), Dimension::force);
  EXPECT_EQ(dimension_of("N*m"), Dimension::moment);
  EXPECT_EQ(dimension_of("J"), Dimension::moment);
  EXPECT_EQ(dimension_of("W"), Dimension::power);
  EXPECT_EQ(dimension_of("kg"), Dimension::mass);
  EXPECT_EQ(dimension_of("kg*m^2"), Dimension::inertia);
  EXPECT_EQ(dimension_of("s"), Dimension::time);
  EXPECT_EQ(dimension_of("furlong"), Dimension::none);
}

TEST(Units, FormattedValuesAreInTheSystemsUnits) {
  const UnitSystem u = mm_deg_g_ms_kN();
  EXPECT_EQ(format_input(std::numbers::pi / 2.0, true, u), "90 deg");
  EXPECT_EQ(format_input(0.0125, false, u), "12.5 mm");
  EXPECT_EQ(format_input(-1e-12, false, u), "0 mm");  // rounded to 1e-6 mm, never "-0"
  EXPECT_EQ(format_quantity(5e-4, Dimension::length, u), "0.5 mm");
  EXPECT_EQ(format_quantity(-0.0, Dimension::length, u), "0 mm");
  EXPECT_EQ(format_quantity(2.5e-7 * kDeg, Dimension::angle, u), "2.5e-07 deg");
}

TEST(Units, OutputUnitsFileOrSi) {
  Model model;
  model.units = DeclaredUnits{.length = "mm"};
  EXPECT_EQ(output_units(model, "file").length, "mm");
  EXPECT_TRUE(output_units(model, "si").is_si());
  EXPECT_THROW((void)output_units(model, "imperial"), std::invalid_argument);
}

TEST(Units, ParsedPositionsAndSpeedsAreInSi) {
  EXPECT_DOUBLE_EQ(parse_position("30deg", true, 1.0), 30.0 * kDeg);
  EXPECT_DOUBLE_EQ(parse_position("30 deg", true, 1.0), 30.0 * kDeg);
  EXPECT_DOUBLE_EQ(parse_position("0.5 rad", true, kDeg), 0.5);
  EXPECT_DOUBLE_EQ(parse_position("20 mm", false, 1.0), 0.02);
  EXPECT_DOUBLE_EQ(parse_position("45", true, kDeg), 45.0 * kDeg);  // bare: × bare_factor
  EXPECT_DOUBLE_EQ(parse_speed("300rpm", true, 1.0), 300.0 * 2.0 * std::numbers::pi / 60.0);
  EXPECT_DOUBLE_EQ(parse_speed("90 deg/s", true, 1.0), 90.0 * kDeg);
  EXPECT_DOUBLE_EQ(parse_speed("20 mm/s", false, 1.0), 0.02);
  EXPECT_THROW((void)parse_speed("0 rpm", true, 1.0), std::invalid_argument);
  EXPECT_DOUBLE_EQ(parse_speed("0 rpm", true, 1.0, true), 0.0);
  EXPECT_THROW((void)parse_speed("3 m/s", true, 1.0), std::invalid_argument);  // not angular
}

}  // namespace
}  // namespace orthomech
