#pragma once
// Quantities written with a unit, as on the command line ("300rpm", "30 deg") and in mechanism
// files ("speed: 300 rpm"). Values are returned in SI.
#include <string>

namespace orthomech {

// A speed: "300rpm", "300 rpm", "31.4 rad/s", "90 deg/s" (angular) or "0.5 m/s", "20 mm/s"
// (linear). A bare number is multiplied by `bare_factor` (SI per the caller's default unit).
// Throws std::invalid_argument with a message naming the allowed units.
[[nodiscard]] double parse_speed(const std::string& text, bool angular, double bare_factor);

// An input position: "30deg", "30 deg", "0.5 rad" (angular) or "20 mm", "0.02 m" (linear). A bare
// number is multiplied by `bare_factor`. Throws std::invalid_argument.
[[nodiscard]] double parse_position(const std::string& text, bool angular, double bare_factor);

// An input position for people: degrees (angular) or millimetres, rounded to 1e-6 of the unit
// ("77.608916 deg", never "5e-14 deg").
[[nodiscard]] std::string format_input(double value, bool angular);

}  // namespace orthomech
