#include "orthomech/io/units.hpp"

#include <cmath>
#include <cstdio>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <utility>
#include <vector>

namespace orthomech {

namespace {

using UnitTable = std::vector<std::pair<std::string, double>>;

double parse_with_units(const std::string& text, const UnitTable& units, double bare_factor,
                        const std::string& what, const std::string& kind) {
  std::istringstream in(text);
  double v = 0.0;
  in >> v;
  if (in.fail() || !std::isfinite(v))
    throw std::invalid_argument(what + " must be a number, got '" + text + "'");
  std::string unit, extra;
  in >> unit >> extra;  // "300rpm" and "300 rpm" both leave "rpm" here
  if (!extra.empty())
    throw std::invalid_argument("unexpected text '" + extra + "' after the " + what);
  if (unit.empty()) return v * bare_factor;
  std::string allowed;
  for (const auto& [name, factor] : units) {
    if (unit == name) return v * factor;
    allowed += (allowed.empty() ? "" : ", ") + name;
  }
  throw std::invalid_argument("unknown " + what + " unit '" + unit + "' for a " + kind +
                              " joint (allowed: " + allowed + ")");
}

}  // namespace

double parse_speed(const std::string& text, bool angular, double bare_factor) {
  static const UnitTable angular_units = {
      {"rpm", 2.0 * std::numbers::pi / 60.0}, {"rad/s", 1.0}, {"deg/s", std::numbers::pi / 180.0}};
  static const UnitTable linear_units = {{"m/s", 1.0}, {"mm/s", 1e-3}};
  return parse_with_units(text, angular ? angular_units : linear_units, bare_factor, "speed",
                          angular ? "revolute" : "prismatic");
}

double parse_position(const std::string& text, bool angular, double bare_factor) {
  static const UnitTable angular_units = {{"deg", std::numbers::pi / 180.0}, {"rad", 1.0}};
  static const UnitTable linear_units = {{"m", 1.0}, {"mm", 1e-3}};
  return parse_with_units(text, angular ? angular_units : linear_units, bare_factor, "input",
                          angular ? "revolute" : "prismatic");
}

std::string format_input(double value, bool angular) {
  double v = std::round((angular ? value * 180.0 / std::numbers::pi : value * 1e3) * 1e6) / 1e6;
  if (v == 0.0) v = 0.0;  // no "-0"
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.10g %s", v, angular ? "deg" : "mm");
  return buf;
}

}  // namespace orthomech
