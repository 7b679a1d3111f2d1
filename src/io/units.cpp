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

double parse_speed(const std::string& text, bool angular, double bare_factor, bool allow_zero) {
  static const UnitTable angular_units = {
      {"rpm", 2.0 * std::numbers::pi / 60.0}, {"rad/s", 1.0}, {"deg/s", std::numbers::pi / 180.0}};
  static const UnitTable linear_units = {{"m/s", 1.0}, {"mm/s", 1e-3}};
  const double v = parse_with_units(text, angular ? angular_units : linear_units, bare_factor,
                                    "speed", angular ? "revolute" : "prismatic", Quantity::general);
  if (v == 0.0 && !allow_zero) throw std::invalid_argument("the speed must not be zero");
  return v;
}

double parse_position(const std::string& text, bool angular, double bare_factor) {
  static const UnitTable angular_units = {{"deg", std::numbers::pi / 180.0}, {"rad", 1.0}};
  static const UnitTable linear_units = {
      {"m", 1.0}, {"mm", 1e-3}, {"cm", 0.01}, {"in", 0.0254}, {"ft", 0.3048}};
  return parse_with_units(text, angular ? angular_units : linear_units, bare_factor, "input",
                          angular ? "revolute" : "prismatic",
                          angular ? Quantity::angle : Quantity::length);
}

namespace {

const UnitTable& table_of(const std::string& kind) {
  // The names a file may declare (docs/file-format.md "units"), SI per unit.
  static const UnitTable length = {
      {"m", 1.0}, {"cm", 0.01}, {"mm", 0.001}, {"in", 0.0254}, {"ft", 0.3048}};
  static const UnitTable angle = {{"rad", 1.0}, {"deg", std::numbers::pi / 180.0}};
  static const UnitTable mass = {{"kg", 1.0}, {"g", 0.001}, {"lb", 0.45359237}};
  static const UnitTable time = {{"s", 1.0}, {"ms", 0.001}};
  static const UnitTable force = {{"N", 1.0}, {"kN", 1000.0}, {"lbf", 4.4482216152605}};
  if (kind == "length") return length;
  if (kind == "angle") return angle;
  if (kind == "mass") return mass;
  if (kind == "time") return time;
  return force;
}

}  // namespace

std::optional<BaseUnit> base_unit(const std::string& name) {
  const std::pair<const char*, Dimension> kinds[] = {{"length", Dimension::length},
                                                     {"angle", Dimension::angle},
                                                     {"mass", Dimension::mass},
                                                     {"time", Dimension::time},
                                                     {"force", Dimension::force}};
  for (const auto& [kind, dimension] : kinds)
    for (const auto& [n, f] : table_of(kind))
      if (n == name) return BaseUnit{dimension, f};
  return std::nullopt;
}

namespace {

double factor_of(const std::string& kind, const std::string& name) {
  for (const auto& [n, f] : table_of(kind))
    if (n == name) return f;
  throw std::invalid_argument("unknown " + kind + " unit '" + name + "'");
}

}  // namespace

UnitSystem unit_system(const DeclaredUnits& d) {
  UnitSystem u;
  u.length = d.length, u.angle = d.angle, u.mass = d.mass, u.time = d.time, u.force = d.force;
  u.length_si = factor_of("length", d.length);
  u.angle_si = factor_of("angle", d.angle);
  u.mass_si = factor_of("mass", d.mass);
  u.time_si = factor_of("time", d.time);
  u.force_si = factor_of("force", d.force);
  return u;
}

UnitSystem output_units(const Model& model, const std::string& choice) {
  if (choice == "file") return unit_system(model.units);
  if (choice == "si") return UnitSystem{};
  throw std::invalid_argument("--units must be 'file' or 'si', got '" + choice + "'");
}

OutputUnit output_unit(Dimension q, const UnitSystem& u) {
  const std::string &L = u.length, &A = u.angle, &T = u.time, &F = u.force;
  switch (q) {
    case Dimension::none:
      return {"1", 1.0};
    case Dimension::length:
      return {L, u.length_si};
    case Dimension::angle:
      return {A, u.angle_si};
    case Dimension::mass:
      return {u.mass, u.mass_si};
    case Dimension::time:
      return {T, u.time_si};
    case Dimension::force:
      return {F, u.force_si};
    case Dimension::moment:
      return {F + "*" + L, u.force_si * u.length_si};
    case Dimension::velocity:
      return {L + "/" + T, u.length_si / u.time_si};
    case Dimension::angular_velocity:
      return {A + "/" + T, u.angle_si / u.time_si};
    case Dimension::acceleration:
      return {L + "/" + T + "^2", u.length_si / (u.time_si * u.time_si)};
    case Dimension::angular_acceleration:
      return {A + "/" + T + "^2", u.angle_si / (u.time_si * u.time_si)};
    case Dimension::power:
      return {F + "*" + L + "/" + T, u.force_si * u.length_si / u.time_si};
    case Dimension::inertia:
      return {u.mass + "*" + L + "^2", u.mass_si * u.length_si * u.length_si};
    case Dimension::frequency:  // Hz when the time unit is the second
      return {T == "s" ? std::string("Hz") : "1/" + T, 1.0 / u.time_si};
  }
  return {"1", 1.0};
}

Dimension dimension_of(const std::string& s) {
  static const std::vector<std::pair<std::string, Dimension>> names = {
      {"m", Dimension::length},
      {"rad", Dimension::angle},
      {"kg", Dimension::mass},
      {"s", Dimension::time},
      {"N", Dimension::force},
      {"N*m", Dimension::moment},
      {"J", Dimension::moment},
      {"m/s", Dimension::velocity},
      {"rad/s", Dimension::angular_velocity},
      {"m/s^2", Dimension::acceleration},
      {"rad/s^2", Dimension::angular_acceleration},
      {"W", Dimension::power},
      {"kg*m^2", Dimension::inertia},
      {"Hz", Dimension::frequency}};
  for (const auto& [n, q] : names)
    if (n == s) return q;
  return Dimension::none;
}

std::string format_input(double value, bool angular, const UnitSystem& units) {
  const OutputUnit unit = output_unit(angular ? Dimension::angle : Dimension::length, units);
  double v = std::round(unit.from_si(value) * 1e6) / 1e6;
  if (v == 0.0) v = 0.0;  // no "-0"
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.10g %s", v, unit.name.c_str());
  return buf;
}

std::string format_quantity(double value, Dimension q, const UnitSystem& units, int precision) {
  const OutputUnit unit = output_unit(q, units);
  double v = unit.from_si(value);
  if (v == 0.0) v = 0.0;  // no "-0"
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*g %s", precision, v, unit.name.c_str());
  return buf;
}

}  // namespace orthomech
