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

std::string shortest(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

double parse_with_units(const std::string& text, const UnitTable& units, double bare_factor,
                        const std::string& what, const std::string& kind, Quantity quantity) {
  if (text.size() > kMaxNumberLength + 16)
    throw std::invalid_argument(what + " must be a number of at most " +
                                std::to_string(kMaxNumberLength) + " characters with a unit");
  const auto checked = [&](double si) {
    const std::string problem = range_problem(si, quantity);
    if (!problem.empty())
      throw std::invalid_argument(what + " " + problem + ", got '" + text + "'");
    return si;
  };
  std::istringstream in(text);
  double v = 0.0;
  in >> v;
  if (in.fail() || !std::isfinite(v))
    throw std::invalid_argument(what + " must be a number, got '" + text + "'");
  std::string unit, extra;
  in >> unit >> extra;  // "300rpm" and "300 rpm" both leave "rpm" here
  if (!extra.empty())
    throw std::invalid_argument("unexpected text '" + extra + "' after the " + what);
  if (unit.empty()) return checked(v * bare_factor);
  std::string allowed;
  for (const auto& [name, factor] : units) {
    if (unit == name) return checked(v * factor);
    allowed += (allowed.empty() ? "" : ", ") + name;
  }
  throw std::invalid_argument("unknown " + what + " unit '" + unit + "' for a " + kind +
                              " joint (allowed: " + allowed + ")");
}

}  // namespace

std::string range_problem(double v, Quantity q) {
  if (!std::isfinite(v)) return "must be finite";
  const double a = std::abs(v);
  switch (q) {
    case Quantity::length:
      if (a > kMaxLength) return "must be at most " + shortest(kMaxLength) + " m in magnitude";
      break;
    case Quantity::angle:
      if (a > kMaxAngle) return "must be at most " + shortest(kMaxAngle) + " rad in magnitude";
      break;
    case Quantity::mass:
      if (a < kMinMass) return "must be at least " + shortest(kMinMass) + " kg";
      if (a > kMaxMass) return "must be at most " + shortest(kMaxMass) + " kg";
      break;
    case Quantity::inertia:
      if (a < kMinInertia) return "must be at least " + shortest(kMinInertia) + " kg*m^2";
      if (a > kMaxInertia) return "must be at most " + shortest(kMaxInertia) + " kg*m^2";
      break;
    case Quantity::general:
      if (a > kMaxGeneral) return "must be at most " + shortest(kMaxGeneral) + " in magnitude (SI)";
      break;
  }
  return "";
}

double parse_speed(const std::string& text, bool angular, double bare_factor) {
  static const UnitTable angular_units = {
      {"rpm", 2.0 * std::numbers::pi / 60.0}, {"rad/s", 1.0}, {"deg/s", std::numbers::pi / 180.0}};
  static const UnitTable linear_units = {{"m/s", 1.0}, {"mm/s", 1e-3}};
  const double v = parse_with_units(text, angular ? angular_units : linear_units, bare_factor,
                                    "speed", angular ? "revolute" : "prismatic", Quantity::general);
  if (v == 0.0) throw std::invalid_argument("the speed must not be zero");
  return v;
}

double parse_position(const std::string& text, bool angular, double bare_factor) {
  static const UnitTable angular_units = {{"deg", std::numbers::pi / 180.0}, {"rad", 1.0}};
  static const UnitTable linear_units = {{"m", 1.0}, {"mm", 1e-3}};
  return parse_with_units(text, angular ? angular_units : linear_units, bare_factor, "input",
                          angular ? "revolute" : "prismatic",
                          angular ? Quantity::angle : Quantity::length);
}

std::string format_input(double value, bool angular) {
  double v = std::round((angular ? value * 180.0 / std::numbers::pi : value * 1e3) * 1e6) / 1e6;
  if (v == 0.0) v = 0.0;  // no "-0"
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.10g %s", v, angular ? "deg" : "mm");
  return buf;
}

}  // namespace orthomech
