#pragma once
// Quantities written with a unit, as on the command line ("300rpm", "30 deg") and in mechanism
// files ("speed: 300 rpm"). Values are returned in SI.
#include <cstddef>
#include <optional>
#include <string>

#include "orthomech/model/model.hpp"

namespace orthomech {

// ---- Output units ------------------------------------------------------------------------------
// A system of units for outputs: the file's declared units (default of every command) or SI
// (`--units si`). Compound units are built from the five base ones: a moment is force·length
// ("N*mm"), a velocity length/time ("mm/s"), an angular velocity angle/time ("deg/s").
struct UnitSystem {
  std::string length = "m", angle = "rad", mass = "kg", time = "s", force = "N";
  double length_si = 1.0, angle_si = 1.0, mass_si = 1.0, time_si = 1.0, force_si = 1.0;  // SI/unit
  [[nodiscard]] bool is_si() const {
    return length == "m" && angle == "rad" && mass == "kg" && time == "s" && force == "N";
  }
};
// The units a file declared (names as in docs/file-format.md). Throws std::invalid_argument for
// a name that is not one of them.
[[nodiscard]] UnitSystem unit_system(const DeclaredUnits& declared);
// "file" (the model's declared units) or "si". Throws std::invalid_argument otherwise.
[[nodiscard]] UnitSystem output_units(const Model& model, const std::string& choice);

enum class Dimension {
  none,  // dimensionless: written as is
  length,
  angle,
  mass,
  time,
  force,
  moment,  // also energy and work (force·length)
  velocity,
  angular_velocity,
  acceleration,
  angular_acceleration,
  power,      // force·length/time
  inertia,    // mass·length²
  frequency,  // 1/time
};
// A base unit by the name a file may declare ("mm", "deg", "kg", "ms", "kN"; docs/file-format.md
// "units"): its dimension (length, angle, mass, time or force) and SI per unit; nullopt for any
// other name. A study expression's `75deg` (study/measure_metrics.hpp).
struct BaseUnit {
  Dimension dimension = Dimension::none;
  double si = 1.0;
};
[[nodiscard]] std::optional<BaseUnit> base_unit(const std::string& name);
// A quantity's unit in a system: its name and its size in SI (value_out = value_SI / si).
struct OutputUnit {
  std::string name;
  double si = 1.0;
  [[nodiscard]] double from_si(double v) const { return v / si; }
};
[[nodiscard]] OutputUnit output_unit(Dimension q, const UnitSystem& units);
// The dimension of an SI unit name as the library writes them ("m", "m/s", "m/s^2", "rad", "rad/s",
// "rad/s^2", "N", "N*m", "J", "W", "kg", "kg*m^2", "s"); Dimension::none for anything else.
[[nodiscard]] Dimension dimension_of(const std::string& si_unit);
// A value and its unit for people, in `units`: "90 deg", "12.5 mm" (input rounded to 1e-6 of the
// unit, never "-0"). Library messages use the file's declared units (unit_system(model.units)).
[[nodiscard]] std::string format_input(double value, bool angular, const UnitSystem& units);
// A quantity (SI) with its unit in `units`, `precision` significant digits: "0.5 mm",
// "2.5e-07 deg" (never "-0").
[[nodiscard]] std::string format_quantity(double value, Dimension q, const UnitSystem& units,
                                          int precision = 4);
// ---- limits of every number entering the tool (docs/file-format.md "Limits") -------------------
// The same limits apply to a number from a mechanism file and from the command line; they are
// checked in SI, after the unit conversion. They are wide enough for any real linkage and narrow
// enough that no product or square of two of them overflows a double (so no inf or NaN can come
// out of finite, in-range inputs).
enum class Quantity {
  length,   // |x| <= 1e6 m
  angle,    // |x| <= 1e6 rad
  mass,     // 1e-9 kg <= m <= 1e9 kg (positivity is checked first, with its own message)
  inertia,  // 1e-18 kg*m^2 <= I <= 1e9 kg*m^2
  general,  // every other quantity (force, torque, stiffness, damping, gravity, speed,
            // frequency, polynomial coefficient, table factor, rate, gear ratio): |x| <= 1e12 SI
};
inline constexpr double kMaxLength = 1e6;
inline constexpr double kMaxAngle = 1e6;
inline constexpr double kMinMass = 1e-9, kMaxMass = 1e9;
inline constexpr double kMinInertia = 1e-18, kMaxInertia = 1e9;
inline constexpr double kMaxGeneral = 1e12;
// The most positions of a driven cycle: `analysis: steps` in a file and `cycle --steps`.
inline constexpr int kMaxCycleSteps = 100000;
// The most output samples of `simulate` (t_end / dt_out + 1).
inline constexpr double kMaxOutputSamples = 1e6;
// The tightest relative tolerance of `simulate --rtol` (a step-size control below it asks for
// digits a double does not have) and the smallest coefficient of speed fluctuation of
// `cycle --speed-fluctuation` (the flywheel inertia grows as 1/C_s).
inline constexpr double kMinRtol = 1e-14;
inline constexpr double kMinSpeedFluctuation = 1e-6;
// The longest number text read (characters): longer ones are refused, not parsed.
inline constexpr std::size_t kMaxNumberLength = 64;

// "" when `value` (SI) is finite and within the limits of `q`; otherwise the reason, for a message
// ("must be finite", "must be at most 1e+06 m in magnitude", "must be at least 1e-09 kg").
[[nodiscard]] std::string range_problem(double value, Quantity q);

// A speed: "300rpm", "300 rpm", "31.4 rad/s", "90 deg/s" (angular) or "0.5 m/s", "20 mm/s"
// (linear). A bare number is multiplied by `bare_factor` (SI per the caller's default unit).
// Throws std::invalid_argument with a message naming the allowed units, and when the value is not
// finite or out of the limits (Quantity::general), or zero unless `allow_zero` (a driver's speed
// must not be zero; an initial rate may: at rest in that coordinate).
[[nodiscard]] double parse_speed(const std::string& text, bool angular, double bare_factor,
                                 bool allow_zero = false);

// An input position: "30deg", "30 deg", "0.5 rad" (angular) or "20 mm", "0.02 m" (linear). A bare
// number is multiplied by `bare_factor`. Throws std::invalid_argument (also when out of the limits
// of Quantity::angle or Quantity::length).
[[nodiscard]] double parse_position(const std::string& text, bool angular, double bare_factor);

}  // namespace orthomech
