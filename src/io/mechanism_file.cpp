#include "orthomech/io/mechanism_file.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <numbers>
#include <optional>
#include <set>
#include <sstream>
#include <tuple>

#include "expressions.hpp"
#include "mechanism_reader.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/constraints/spatial_joints.hpp"
#include "orthomech/io/units.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/model/measures.hpp"
#include "yaml_walk.hpp"

namespace orthomech {

namespace detail {

// ---- parameters --------------------------------------------------------------------------------
// parameters: {NAME: VALUE, …}: named design variables in the file's units; a value is a number or
// an expression of the parameters above it. Any number of the file may be an expression of them.
void Reader::read_parameters(const YAML::Node& node) {
  if (!node || node.IsNull()) return;
  if (!node.IsMap()) fail(node, "parameters", "expected a mapping name: value");
  if (node.size() > kMaxListItems)
    fail(node, "parameters", "at most " + std::to_string(kMaxListItems) + " parameters");
  for (const auto& kv : node) {
    const std::string name = scalar(kv.first, "parameters", "a parameter name");
    const std::string element = "parameter '" + name + "'";
    in_parameters_ = true;
    const double value = number(kv.second, element, "value");
    in_parameters_ = false;
    try {
      expressions_.define(name, value);
    } catch (const std::invalid_argument& e) {
      fail(kv.first, "parameters", e.what());
    }
  }
}

// ---- units -------------------------------------------------------------------------------------
void Reader::read_units(const YAML::Node& node) {
  if (!node) return;
  expect_map(node, "units", {"length", "angle", "mass", "time", "force"});
  auto declared = [this](const std::string& key) -> std::string& {
    DeclaredUnits& d = model_.units;
    return key == "length"  ? d.length
           : key == "angle" ? d.angle
           : key == "mass"  ? d.mass
           : key == "time"  ? d.time
                            : d.force;
  };
  auto pick = [&](const std::string& key, const std::vector<std::pair<std::string, double>>& table,
                  double& out) {
    const YAML::Node v = node[key];
    if (!v) return;
    if (!v.IsScalar()) fail(v, "units", "unit of " + key + " must be a name");
    for (const auto& [name, factor] : table)
      if (v.Scalar() == name) {
        out = factor;
        declared(key) = name;
        return;
      }
    std::vector<std::string> names;
    names.reserve(table.size());
    for (const auto& e : table) names.push_back(e.first);
    fail(v, "units",
         "unknown " + key + " unit '" + v.Scalar() + "' (allowed: " + join(names) + ")");
  };
  pick("length", {{"m", 1.0}, {"cm", 0.01}, {"mm", 0.001}, {"in", 0.0254}, {"ft", 0.3048}},
       units_.length);
  pick("angle", {{"rad", 1.0}, {"deg", std::numbers::pi / 180.0}}, units_.angle);
  pick("mass", {{"kg", 1.0}, {"g", 0.001}, {"lb", 0.45359237}}, units_.mass);
  pick("time", {{"s", 1.0}, {"ms", 0.001}}, units_.time);
  pick("force", {{"N", 1.0}, {"kN", 1000.0}, {"lbf", 4.4482216152605}}, units_.force);
}

void Reader::read_ground(const YAML::Node& node) {
  if (!node) return;
  expect_map(node, "ground", {"points", "outline"});
  if (const YAML::Node pts = node["points"]) ground_points_ = points_map(pts, "ground");
}

// ---- bodies ------------------------------------------------------------------------------------
void Reader::read_bodies(const YAML::Node& root) {
  const YAML::Node node = list(root, "bodies");
  if (!node || node.IsNull() || node.size() == 0)
    fail(node ? node : root, "bodies", "a mechanism needs at least one moving body");
  if (node.size() > kMaxBodies)
    fail(node, "bodies",
         "at most " + std::to_string(kMaxBodies) + " moving bodies, got " +
             std::to_string(node.size()));
  std::set<std::string> seen;
  size_t index = 0;
  for (const auto& item : node) {
    const std::string name = name_of(item, "body", index++, seen);
    const std::string element = "body '" + name + "'";
    if (name == "ground") fail(item["name"], element, "'ground' is reserved for the fixed frame");
    if (name.find('.') != std::string::npos)
      fail(item["name"], element, "a body name must not contain '.'");
    Body b;
    b.name = name;
    b.where = loc(item);
    const YAML::Node type = item["type"];
    if (type) {
      const std::string t = scalar(type, element, "field 'type'");
      if (t == "particle")
        b.kind = BodyKind::particle;
      else if (t != "rigid")
        fail(type, element, "unknown body type '" + type.Scalar() + "' (allowed: rigid, particle)");
    }
    if (b.kind == BodyKind::rigid)
      expect_map(item, element,
                 {"name", "type", "mass", "inertia", "com", "pose", "points", "outline"});
    else
      expect_map(item, element, {"name", "type", "mass", "pose", "points", "outline"});
    b.mass = number_field(item, "mass", element, units_.mass, Quantity::mass);
    if (b.kind == BodyKind::rigid) {
      b.inertia = number_field(item, "inertia", element,
                               units_.mass * units_.length * units_.length, Quantity::inertia);
      if (item["com"])
        b.com_local = vec2(item["com"], element, "com", units_.length, Quantity::length);
    }
    const YAML::Node pose = require(item, "pose", element);
    if (b.kind == BodyKind::rigid) {
      if (!pose.IsSequence() || pose.size() != 3)
        fail(pose, element, "field 'pose' must be a list of 3 numbers");
      b.design_pose = Vec3(number(pose[0], element, "pose", units_.length, Quantity::length),
                           number(pose[1], element, "pose", units_.length, Quantity::length),
                           number(pose[2], element, "pose", units_.angle, Quantity::angle));
    } else {
      const auto p = numbers(pose, element, "pose", 2, units_.length, Quantity::length);
      b.design_pose = Vec3(p[0], p[1], 0.0);
    }
    if (const YAML::Node pts = item["points"]) b.points = points_map(pts, element);
    if (const YAML::Node outline = item["outline"]) {
      if (!outline.IsSequence()) fail(outline, element, "field 'outline' must be a list of [x, y]");
      for (const auto& p : outline)
        b.outline.push_back(vec2(p, element, "outline", units_.length, Quantity::length));
    }
    model_.bodies.push_back(std::move(b));
  }
}

// ---- joints ------------------------------------------------------------------------------------
void Reader::read_joints(const YAML::Node& root) {
  const YAML::Node node = list(root, "joints");
  if (!node || node.IsNull()) return;
  std::set<std::string> seen;
  size_t index = 0;
  const VecX q0 = [&] {
    Model tmp = model_;
    finalize_model(tmp);
    return tmp.design_q();
  }();
  for (const auto& item : node) {
    const std::string name = name_of(item, "joint", index++, seen);
    const std::string element = "joint '" + name + "'";
    const std::string type = string_field(item, "type", element);
    Joint j;
    j.name = name;
    j.where = loc(item);
    auto no_particles = [&](const PointRef& a, const PointRef& b) {
      for (const PointRef* p : {&a, &b})
        if (p->body != kGround &&
            model_.bodies[static_cast<size_t>(p->body)].kind == BodyKind::particle)
          fail(item["connects"], element,
               "body '" + model_.body_name(p->body) + "' is a particle and has no angle; a " +
                   type + " joint needs rigid bodies");
    };
    if (type == "revolute") {
      expect_map(item, element, {"name", "type", "connects", "limits", "end_stops", "friction"});
      auto [a, b] = connects(item, element);
      j.kind = Revolute{a, b};
      j.limits = joint_limits(item, element, units_.angle, Quantity::angle);
      j.stop_restitution = end_stops(item, element);
      j.friction = joint_friction(item, element, units_.length);
      if (j.friction) no_particles(a, b);  // the friction moment acts on both bodies' angles
    } else if (type == "prismatic" || type == "fixed") {
      if (type == "prismatic")
        expect_map(item, element,
                   {"name", "type", "connects", "axis", "angle", "limits", "end_stops"});
      else
        expect_map(item, element, {"name", "type", "connects", "angle"});
      auto [a, b] = connects(item, element);
      no_particles(a, b);
      const double phi0 =
          optional_number(item, "angle", element, design_angle(b.body) - design_angle(a.body),
                          units_.angle, Quantity::angle);
      if (type == "prismatic") {
        j.kind = Prismatic{a, b, unit_axis(item, element), phi0};
        j.limits = joint_limits(item, element, units_.length, Quantity::length);
        j.stop_restitution = end_stops(item, element);
      } else {
        j.kind = Fixed{a, b, phi0};
      }
    } else if (type == "pin-in-slot") {
      expect_map(item, element, {"name", "type", "connects", "axis"});
      auto [a, b] = connects(item, element);
      if (a.body != kGround &&
          model_.bodies[static_cast<size_t>(a.body)].kind == BodyKind::particle)
        fail(item["connects"], element, "the slot body must be rigid or the ground");
      j.kind = PinInSlot{a, b, unit_axis(item, element)};
    } else if (type == "gear") {
      expect_map(item, element, {"name", "type", "bodies", "ratio", "carrier"});
      GearPair g;
      std::tie(g.bi, g.bj) = rigid_body_pair(item, element);
      if (g.bi == g.bj) fail(item["bodies"], element, "a gear pair needs two different bodies");
      g.carrier = item["carrier"] ? rigid_body_ref(item["carrier"], element) : kGround;
      g.ratio = number_field(item, "ratio", element);
      if (g.ratio == 0.0) fail(item["ratio"], element, "ratio must not be zero");
      const double pc = design_angle(g.carrier);
      g.c0 = (design_angle(g.bj) - pc) - g.ratio * (design_angle(g.bi) - pc);
      j.kind = g;
    } else if (type == "distance") {
      expect_map(item, element, {"name", "type", "connects", "length"});
      auto [a, b] = connects(item, element);
      Distance d{a, b, 0.0};
      const VecX* none = nullptr;
      Model tmp = model_;
      finalize_model(tmp);
      const double drawn =
          (point_kinematics(tmp, b, q0, none).r - point_kinematics(tmp, a, q0, none).r).norm();
      d.length = optional_number(item, "length", element, drawn, units_.length, Quantity::length);
      if (!(d.length > 0.0))
        fail(item["length"] ? item["length"] : item, element, "length must be positive");
      j.kind = d;
    } else {
      fail(item["type"], element,
           "unknown joint type '" + type +
               "' (allowed: revolute, prismatic, fixed, pin-in-slot, gear, distance)");
    }
    model_.joints.push_back(std::move(j));
  }
}

// ---- nonholonomic constraints ------------------------------------------------------------------
void Reader::read_nonholonomic(const YAML::Node& root) {
  const YAML::Node node = list(root, "nonholonomic");
  if (!node || node.IsNull()) return;
  std::set<std::string> seen;
  for (const Joint& j : model_.joints) seen.insert(j.name);  // one namespace with the joints
  size_t index = 0;
  for (const auto& item : node) {
    const std::string name = name_of(item, "nonholonomic constraint", index++, seen);
    const std::string element = "knife edge '" + name + "'";
    const std::string type = string_field(item, "type", element);
    if (type != "knife-edge")
      fail(item["type"], element,
           "unknown nonholonomic constraint type '" + type + "' (allowed: knife-edge)");
    expect_map(item, element, {"name", "type", "point", "axis"});
    KnifeEdge k;
    k.name = name;
    k.where = loc(item);
    k.at = point_ref(require(item, "point", element), element);
    if (k.at.body == kGround ||
        model_.bodies[static_cast<size_t>(k.at.body)].kind != BodyKind::rigid)
      fail(item["point"], element, "a knife edge needs a point on a rigid moving body");
    k.axis_local = unit_axis(item, element);
    model_.knife_edges.push_back(std::move(k));
  }
}

Table Reader::table(const YAML::Node& node, const std::string& element) const {
  Table t;
  if (!node) return t;
  expect_map(node, element, {"measure", "points", "wrap"});
  const YAML::Node m = require(node, "measure", element);
  t.measure = model_.find_measure(m.Scalar());
  if (t.measure < 0) fail(m, element, "measure '" + m.Scalar() + "' is not defined");
  const Measure& measure = model_.measures[static_cast<size_t>(t.measure)];
  if (measure.derivative != 0) fail(m, element, "a table needs a position measure (derivative 0)");
  const double scale = measure.unit == "rad" ? units_.angle : units_.length;
  const YAML::Node pts = require(node, "points", element);
  if (!pts.IsSequence() || pts.size() < 2)
    fail(pts, element, "table 'points' needs at least two [x, factor] pairs");
  for (const auto& p : pts) {
    if (!p.IsSequence() || p.size() != 2)
      fail(p, element, "field 'points' must be a list of [x, factor] pairs");
    t.points.emplace_back(number(p[0], element, "points", scale,
                                 measure.unit == "rad" ? Quantity::angle : Quantity::length),
                          number(p[1], element, "points"));
  }
  for (size_t k = 1; k < t.points.size(); ++k)
    if (!(t.points[k].first > t.points[k - 1].first))
      fail(pts[k], element, "table points must be in increasing order of the measure");
  // A table over an angle wraps with the turn unless `wrap: false` (docs/file-format.md).
  t.wrap = measure.unit == "rad";
  if (const YAML::Node w = node["wrap"]) {
    if (!w.IsScalar() || (w.Scalar() != "true" && w.Scalar() != "false"))
      fail(w, element, "wrap must be true or false");
    t.wrap = w.Scalar() == "true";
    if (t.wrap && measure.unit != "rad")
      fail(w, element,
           "only a table over an angle can wrap (measure '" + measure.name + "' is a " +
               (measure.unit == "m" ? "length" : measure.unit) + ")");
  }
  constexpr double kTurnSlack = 1e-9;  // rad: a table over exactly [0°, 360°] is one turn
  if (t.wrap &&
      t.points.back().first - t.points.front().first > 2.0 * std::numbers::pi + kTurnSlack)
    fail(pts, element,
         "the table spans more than one turn of '" + measure.name +
             "' and wraps with the turn: give wrap: false to key it on the unwrapped angle");
  return t;
}

// `active_while: {measure: NAME, velocity: positive|negative}`: the load acts only while the
// position measure's rate has that sign.
ActiveWhile Reader::active_while(const YAML::Node& node, const std::string& element) const {
  expect_map(node, element, {"measure", "velocity"});
  const YAML::Node m = require(node, "measure", element);
  ActiveWhile a;
  a.measure = model_.find_measure(scalar(m, element, "a measure name"));
  if (a.measure < 0) fail(m, element, "measure '" + m.Scalar() + "' is not defined");
  if (model_.measures[static_cast<size_t>(a.measure)].derivative != 0)
    fail(m, element, "active_while needs a position measure (derivative 0); its velocity is used");
  const YAML::Node v = require(node, "velocity", element);
  const std::string sign = scalar(v, element, "velocity");
  if (sign == "positive")
    a.sign = 1;
  else if (sign == "negative")
    a.sign = -1;
  else
    fail(v, element, "velocity must be 'positive' or 'negative', got '" + sign + "'");
  return a;
}

// ---- loads and measures: one loop for planar and spatial files --------------------------------
// Each item: a unique name, the element's label for messages, its type; the type's keys are read
// by planar_load / spatial_load (spatial_file.cpp), which return nothing for an unknown type.
void Reader::read_loads(const YAML::Node& root) {
  const YAML::Node node = list(root, "loads");
  if (!node || node.IsNull()) return;
  std::set<std::string> seen;
  size_t index = 0;
  for (const auto& item : node) {
    const std::string name = name_of(item, "load", index++, seen);
    const std::string element = "load '" + name + "'";
    const std::string type = string_field(item, "type", element);
    Load l;
    l.name = name;
    l.where = loc(item);
    std::optional<LoadKind> kind = model_.dimension == 3 ? spatial_load(item, element, type)
                                                         : planar_load(item, element, type);
    if (!kind)
      fail(item["type"], element,
           "unknown load type '" + type +
               "' (allowed: gravity, force, torque, spring-damper, rotary-spring-damper)");
    l.kind = std::move(*kind);
    if (const YAML::Node aw = item["active_while"]) l.active_while = active_while(aw, element);
    model_.loads.push_back(std::move(l));
  }
}

std::optional<LoadKind> Reader::planar_load(const YAML::Node& item, const std::string& element,
                                            const std::string& type) {
  const double force = units_.force, length = units_.length;
  if (type == "gravity") {
    expect_map(item, element, {"name", "type", "g"});
    Gravity g;
    if (item["g"]) g.g = vec2(item["g"], element, "g", length / (units_.time * units_.time));
    check_gravity(item, element, g.g.norm());
    return g;
  }
  if (type == "force") {
    expect_map(item, element, {"name", "type", "point", "force", "frame", "table", "active_while"});
    PointForce f;
    f.at = point_ref(require(item, "point", element), element);
    f.force = vec2(require(item, "force", element), element, "force", force);
    f.body_fixed = body_frame(item, element);
    f.table = table(item["table"], element);
    return f;
  }
  if (type == "torque") {
    expect_map(item, element, {"name", "type", "body", "torque", "table", "active_while"});
    Torque t;
    t.body = rigid_body_ref(require(item, "body", element), element);
    if (t.body == kGround) fail(item["body"], element, "a torque on the ground does nothing");
    t.torque = number_field(item, "torque", element, force * length);
    t.table = table(item["table"], element);
    return t;
  }
  if (type == "spring-damper") {
    expect_map(item, element, {"name", "type", "connects", "stiffness", "free_length", "damping"});
    auto [a, b] = connects(item, element);
    const SpringNumbers k = spring_numbers(item, element);
    return SpringDamper{a, b, k.stiffness, k.free_length, k.damping};
  }
  if (type == "rotary-spring-damper") {
    expect_map(item, element, {"name", "type", "bodies", "stiffness", "free_angle", "damping"});
    RotarySpringDamper r;
    std::tie(r.bi, r.bj) = rigid_body_pair(item, element);
    if (r.bi == r.bj)
      fail(item["bodies"], element, "a rotary spring-damper needs two different bodies");
    const SpringNumbers k = rotary_spring_numbers(item, element);
    r.stiffness = k.stiffness;
    r.free_angle = k.free_length;
    r.damping = k.damping;
    return r;
  }
  return std::nullopt;
}

// A gravity far from the Earth's after unit conversion is most often a unit slip (g: [0, -9.81]
// in a mm file is 0.00981 m/s²): a warning, not an error (docs/file-format.md).
void Reader::check_gravity(const YAML::Node& item, const std::string& element, double gn) {
  constexpr double kEarth = 9.81, kFactor = 2.0;  // warn outside [g/2, 2 g]
  if (gn >= kEarth / kFactor && gn <= kEarth * kFactor) return;
  std::ostringstream msg;
  msg << "|g| = " << gn << " m/s^2 after unit conversion (the file's length unit is "
      << model_.units.length << ", time " << model_.units.time
      << "), far from 9.81 m/s^2: is the unit right?";
  add_warning(item["g"] ? item["g"] : item, element, msg.str());
}

// `frame: world|body` of a force or torque (default world): true for body.
bool Reader::body_frame(const YAML::Node& item, const std::string& element) const {
  const YAML::Node fr = item["frame"];
  if (!fr) return false;
  if (!fr.IsScalar()) fail(fr, element, "frame must be 'world' or 'body'");
  if (fr.Scalar() == "body") return true;
  if (fr.Scalar() != "world")
    fail(fr, element, "frame must be 'world' or 'body', got '" + fr.Scalar() + "'");
  return false;
}

// stiffness, free_length, damping of a spring-damper (in this order; none negative).
Reader::SpringNumbers Reader::spring_numbers(const YAML::Node& item,
                                             const std::string& element) const {
  const double force = units_.force, length = units_.length;
  SpringNumbers k;
  k.stiffness = number_field(item, "stiffness", element, force / length);
  k.free_length = optional_number(item, "free_length", element, 0.0, length, Quantity::length);
  k.damping = optional_number(item, "damping", element, 0.0, force * units_.time / length);
  if (k.stiffness < 0.0 || k.damping < 0.0 || k.free_length < 0.0)
    fail(item, element, "stiffness, free_length and damping must not be negative");
  return k;
}

// stiffness, free_angle (in free_length), damping of a rotary spring-damper (none negative).
Reader::SpringNumbers Reader::rotary_spring_numbers(const YAML::Node& item,
                                                    const std::string& element) const {
  const double force = units_.force, length = units_.length, angle = units_.angle;
  SpringNumbers k;
  k.stiffness = number_field(item, "stiffness", element, force * length / angle);
  k.free_length = optional_number(item, "free_angle", element, 0.0, angle, Quantity::angle);
  k.damping = optional_number(item, "damping", element, 0.0, force * length * units_.time / angle);
  if (k.stiffness < 0.0 || k.damping < 0.0)
    fail(item, element, "stiffness and damping must not be negative");
  return k;
}

void Reader::read_measures(const YAML::Node& root) {
  const YAML::Node node = list(root, "measures");
  if (!node || node.IsNull()) return;
  std::set<std::string> seen;
  size_t index = 0;
  const bool spatial = model_.dimension == 3;
  for (const auto& item : node) {
    const std::string name = name_of(item, "measure", index++, seen);
    const std::string element = "measure '" + name + "'";
    const std::string type = string_field(item, "type", element);
    Measure m;
    m.name = name;
    m.where = loc(item);
    std::string unit = "m";
    std::optional<MeasureKind> kind = spatial ? spatial_measure(item, element, type, unit)
                                              : planar_measure(item, element, type, unit);
    if (!kind)
      fail(item["type"], element,
           "unknown measure type '" + type + "' (allowed: joint, point, distance, angle" +
               (spatial ? ", camber, toe)" : ")"));
    m.kind = std::move(*kind);
    if (const YAML::Node d = item["derivative"]) {
      const double v = number(d, element, "derivative");
      if (v != 0.0 && v != 1.0 && v != 2.0) fail(d, element, "derivative must be 0, 1 or 2");
      m.derivative = static_cast<int>(v);
    }
    m.unit = unit + (m.derivative == 1 ? "/s" : m.derivative == 2 ? "/s^2" : "");
    model_.measures.push_back(std::move(m));
  }
}

// `bodies: [b1, b2]` of a gear, a rotary spring-damper or an angle measure: two rigid bodies
// (or the ground).
std::pair<int, int> Reader::rigid_body_pair(const YAML::Node& item,
                                            const std::string& element) const {
  const YAML::Node bodies = require(item, "bodies", element);
  if (!bodies.IsSequence() || bodies.size() != 2)
    fail(bodies, element, "field 'bodies' must be a list of two bodies");
  return {rigid_body_ref(bodies[0], element), rigid_body_ref(bodies[1], element)};
}

// The `points` of a distance measure: a list of two.
YAML::Node Reader::two_points(const YAML::Node& item, const std::string& element) const {
  const YAML::Node pts = require(item, "points", element);
  if (!pts.IsSequence() || pts.size() != 2)
    fail(pts, element, "field 'points' must be a list of two points");
  return pts;
}

std::optional<MeasureKind> Reader::planar_measure(const YAML::Node& item,
                                                  const std::string& element,
                                                  const std::string& type, std::string& unit) {
  if (type == "joint") {
    expect_map(item, element, {"name", "type", "joint", "derivative"});
    const YAML::Node jn = require(item, "joint", element);
    const int j = model_.find_joint(jn.Scalar());
    if (j < 0) fail(jn, element, "joint '" + jn.Scalar() + "' is not defined");
    const JointKind& kind = model_.joints[static_cast<size_t>(j)].kind;
    if (std::holds_alternative<Revolute>(kind)) {
      const auto& r = std::get<Revolute>(kind);
      for (int b : {r.pi.body, r.pj.body})
        if (b != kGround && model_.bodies[static_cast<size_t>(b)].kind == BodyKind::particle)
          fail(jn, element, "joint '" + jn.Scalar() + "' connects a particle: it has no angle");
      unit = "rad";
    } else if (!std::holds_alternative<Prismatic>(kind)) {
      fail(jn, element, "joint '" + jn.Scalar() + "' is neither revolute nor prismatic");
    }
    return JointCoordinate{j};
  }
  if (type == "point") {
    expect_map(item, element, {"name", "type", "point", "component", "derivative"});
    PointCoordinate p;
    p.point = point_ref(require(item, "point", element), element);
    const std::string c = string_field(item, "component", element);
    if (c == "x")
      p.axis = 0;
    else if (c == "y")
      p.axis = 1;
    else
      fail(item["component"], element, "component must be 'x' or 'y', got '" + c + "'");
    return p;
  }
  if (type == "distance") {
    expect_map(item, element, {"name", "type", "points", "derivative"});
    const YAML::Node pts = two_points(item, element);
    return PointDistance{point_ref(pts[0], element), point_ref(pts[1], element)};
  }
  if (type == "angle") {
    expect_map(item, element, {"name", "type", "body", "bodies", "derivative"});
    BodyAngle a;
    if (item["body"] && item["bodies"])
      fail(item, element, "give either 'body' or 'bodies', not both");
    if (item["body"]) {
      a.bj = rigid_body_ref(item["body"], element);
    } else {
      std::tie(a.bi, a.bj) = rigid_body_pair(item, element);
    }
    unit = "rad";
    return a;
  }
  return std::nullopt;
}

// A speed or rate: a number (the file's units), a number with its unit ('300 rpm'), or an
// expression of the parameters (the file's units).
double Reader::speed_text(const std::string& text, bool angular, bool allow_zero) const {
  const double bare = (angular ? units_.angle : units_.length) / units_.time;
  try {
    return parse_speed(text, angular, bare, allow_zero);
  } catch (const std::invalid_argument&) {
    if (expressions_.parameters().empty() || text.size() > kMaxExpressionLength) throw;
    // The same limits as a plain number's (parse_speed: Quantity::general in SI).
    const double v = expressions_.evaluate(text) * bare;
    const std::string problem = range_problem(v, Quantity::general);
    if (!problem.empty()) throw std::invalid_argument("'" + text + "' " + problem);
    if (v == 0.0 && !allow_zero) throw std::invalid_argument("the speed must not be zero");
    return v;
  }
}

double Reader::speed_value(const YAML::Node& node, const std::string& element, bool angular) const {
  if (!node.IsScalar()) fail(node, element, "speed must be a number or a string like '300 rpm'");
  try {
    return speed_text(node.Scalar(), angular);
  } catch (const std::invalid_argument& e) {
    fail(node, element, e.what());
  }
}

// ---- drivers -----------------------------------------------------------------------------------
void Reader::read_drivers(const YAML::Node& root) {
  const YAML::Node node = list(root, "drivers");
  if (!node || node.IsNull()) return;
  std::set<std::string> seen;
  size_t index = 0;
  for (const auto& item : node) {
    const std::string name = name_of(item, "driver", index++, seen);
    const std::string element = "driver '" + name + "'";
    expect_map(
        item, element,
        {"name", "joint", "profile", "speed", "initial", "amplitude", "frequency", "coefficients"});
    Driver d;
    d.name = name;
    d.where = loc(item);
    const YAML::Node jn = require(item, "joint", element);
    d.joint = model_.find_joint(jn.Scalar());
    if (d.joint < 0) fail(jn, element, "joint '" + jn.Scalar() + "' is not defined");
    const int coordinate = joint_coordinate(d.joint);
    const bool angular = coordinate == 1;
    if (coordinate == 0)
      fail(jn, element,
           "joint '" + jn.Scalar() +
               (model_.dimension == 3
                    ? "' is a " + model_.joints[static_cast<size_t>(d.joint)].type_name() +
                          " joint, which has no coordinate, and cannot be driven (drivable: "
                          "revolute, prismatic, cylindrical, screw)"
                    : "' is neither revolute nor prismatic and cannot be driven"));
    const double unit = angular ? units_.angle : units_.length;
    const Quantity position = angular ? Quantity::angle : Quantity::length;
    const std::string profile =
        item["profile"] ? scalar(item["profile"], element, "field 'profile'") : "constant-speed";
    // Each profile has its own keys; a key of another profile is a mistake, not ignored.
    const auto only = [&](const std::vector<std::string>& keys) {
      for (const char* key : {"speed", "initial", "amplitude", "frequency", "coefficients"})
        if (item[key] && std::find(keys.begin(), keys.end(), key) == keys.end())
          fail(item[key], element,
               "key '" + std::string(key) + "' does not belong to a " + profile +
                   " driver (its keys: " + join(keys) + ")");
    };
    if (profile == "constant-speed") {
      only({"speed"});
      d.profile = Profile::constant_speed;
      d.speed = speed_value(require(item, "speed", element), element, angular);
    } else if (profile == "harmonic") {
      only({"initial", "amplitude", "frequency"});
      d.profile = Profile::harmonic;
      d.initial = optional_number(item, "initial", element, 0.0, unit, position);
      d.amplitude = number_field(item, "amplitude", element, unit, position);
      if (d.amplitude == 0.0) fail(item["amplitude"], element, "amplitude must not be zero");
      d.frequency = number_field(item, "frequency", element, 1.0 / units_.time);
      if (!(d.frequency > 0.0)) fail(item["frequency"], element, "frequency must be positive");
    } else if (profile == "polynomial") {
      only({"coefficients"});
      d.profile = Profile::polynomial;
      const YAML::Node c = require(item, "coefficients", element);
      d.coefficients = numbers(c, element, "coefficients", 0);
      if (d.coefficients.size() < 2 || d.coefficients.size() > kMaxCoefficients)
        fail(c, element,
             "a polynomial driver needs 2 to " + std::to_string(kMaxCoefficients) +
                 " coefficients [c0, c1, ...] (s = c0 + c1 t + ...)");
      for (size_t k = 0; k < d.coefficients.size(); ++k) {
        d.coefficients[k] *= unit / std::pow(units_.time, static_cast<double>(k));
        const std::string problem = range_problem(d.coefficients[k], Quantity::general);
        if (!problem.empty()) fail(c[k], element, "coefficient in SI " + problem);
      }
    } else {
      fail(item["profile"], element,
           "unknown profile '" + profile + "' (allowed: constant-speed, harmonic, polynomial)");
    }
    model_.drivers.push_back(std::move(d));
  }
}

void Reader::read_design_positions(const YAML::Node& root) {
  const YAML::Node node = list(root, "design_positions");
  if (!node || node.IsNull()) return;
  std::set<std::string> seen;
  size_t index = 0;
  for (const auto& item : node) {
    const std::string name = name_of(item, "design position", index++, seen);
    const std::string element = "design position '" + name + "'";
    expect_map(item, element, {"name", "inputs", "target"});
    DesignPosition p;
    p.name = name;
    p.where = loc(item);
    if (const YAML::Node inputs = item["inputs"]) {
      if (!inputs.IsMap()) fail(inputs, element, "field 'inputs' must be a mapping joint: value");
      std::set<std::string> seen_inputs;
      for (const auto& kv : inputs) {
        if (!seen_inputs.insert(scalar(kv.first, element, "a joint name")).second)
          fail(kv.first, element, "input '" + kv.first.Scalar() + "' is given twice");
        const int j = model_.find_joint(kv.first.Scalar());
        if (j < 0) fail(kv.first, element, "joint '" + kv.first.Scalar() + "' is not defined");
        const bool angular = joint_coordinate(j) == 1;
        if (joint_coordinate(j) == 0)
          fail(kv.first, element, "joint '" + kv.first.Scalar() + "' has no scalar input");
        p.inputs.emplace_back(j, number(kv.second, element, "inputs." + kv.first.Scalar(),
                                        angular ? units_.angle : units_.length,
                                        angular ? Quantity::angle : Quantity::length));
      }
    }
    if (const YAML::Node t = item["target"]) {
      if (model_.dimension == 3) {  // spatial_file.cpp
        p.target = spatial_target(t, element);
        model_.design_positions.push_back(std::move(p));
        continue;
      }
      expect_map(t, element, {"point", "at", "angle", "tolerance"});
      DesignTarget target;
      target.point = point_ref(require(t, "point", element), element);
      target.position =
          vec2(require(t, "at", element), element, "at", units_.length, Quantity::length);
      if (t["angle"])
        target.angle = number(t["angle"], element, "angle", units_.angle, Quantity::angle);
      target.tolerance =
          optional_number(t, "tolerance", element, 1e-3, units_.length, Quantity::length);
      if (!(target.tolerance > 0.0)) fail(t["tolerance"], element, "tolerance must be positive");
      p.target = target;
    }
    model_.design_positions.push_back(std::move(p));
  }
}

int Reader::joint_coordinate(int j) const {
  const JointKind& kind = model_.joints[static_cast<size_t>(j)].kind;
  if (const auto* s = std::get_if<SpatialJoint>(&kind)) {
    const SpatialCoordinate c = spatial_joint_spec(s->type).coordinate;
    return c == SpatialCoordinate::angle ? 1 : c == SpatialCoordinate::slide ? 2 : 0;
  }
  return std::holds_alternative<Revolute>(kind)    ? 1
         : std::holds_alternative<Prismatic>(kind) ? 2
                                                   : 0;
}

void Reader::read_analysis(const YAML::Node& node) {
  if (!node) return;
  expect_map(node, "analysis", {"driver", "steps"});
  if (const YAML::Node d = node["driver"]) {
    model_.analysis.driver = scalar(d, "analysis", "field 'driver'");
    const bool found = std::any_of(model_.drivers.begin(), model_.drivers.end(),
                                   [&](const Driver& dr) { return dr.name == d.Scalar(); });
    if (!found) fail(d, "analysis", "driver '" + d.Scalar() + "' is not defined");
  }
  if (const YAML::Node s = node["steps"]) {
    const double v = number(s, "analysis", "steps");
    if (v < 2.0 || v != std::floor(v) || v > kMaxCycleSteps)
      fail(s, "analysis",
           "steps must be an integer from 2 to " + std::to_string(kMaxCycleSteps) +
               " (as the option --steps)");
    model_.analysis.steps = static_cast<int>(v);
  }
}

// ---- initial velocities ------------------------------------------------------------------------
// initial: {rates: {MEASURE: RATE, …}}: the rate of each named measure's position quantity at
// t = 0, in the file's length or angle unit per time unit, or a string with its unit ('1 m/s',
// '30 rpm'). A velocity measure (derivative: 1) names the same quantity as its position measure
// (its value at t = 0 is the rate); an acceleration measure has no rate to give.
void Reader::read_initial(const YAML::Node& node) {
  if (!node) return;
  expect_map(node, "initial", {"rates"});
  const YAML::Node rates = require(node, "rates", "initial");
  if (!rates.IsMap()) fail(rates, "initial", "field 'rates' must be a mapping measure: rate");
  std::set<std::string> seen;
  for (const auto& kv : rates) {
    const std::string name = scalar(kv.first, "initial", "a measure name");
    if (!seen.insert(name).second)
      fail(kv.first, "initial", "the rate of measure '" + name + "' is given twice");
    const int m = model_.find_measure(name);
    if (m < 0) fail(kv.first, "initial", "measure '" + name + "' is not defined");
    const Measure& measure = model_.measures[static_cast<size_t>(m)];
    if (measure.derivative == 2)
      fail(kv.first, "initial",
           "measure '" + name + "' is an acceleration: give the rate of a position measure");
    const bool angular = measure.unit.rfind("rad", 0) == 0;
    const std::string what = "the rate of measure '" + name + "'";
    if (!kv.second.IsScalar() || kv.second.Scalar().empty())
      fail(kv.second, "initial", what + " must be a number or a string like '1 m/s'");
    InitialRateSpec spec;
    spec.measure = m;
    try {
      spec.rate = speed_text(kv.second.Scalar(), angular, /*allow_zero=*/true);  // at rest
    } catch (const std::invalid_argument& e) {
      // parse_speed speaks of a joint's speed; here it is a measure's rate.
      std::string message = e.what();
      const std::pair<std::string, std::string> rewrites[] = {
          {"the speed must", "it must"},
          {"speed must", "it must"},
          {"unknown speed unit", "unknown unit"},
          {" for a revolute joint", " for the rate of an angle"},
          {" for a prismatic joint", " for the rate of a length"}};
      for (const auto& [from, to] : rewrites)
        if (const auto at = message.find(from); at != std::string::npos)
          message.replace(at, from.size(), to);
      fail(kv.second, "initial", what + ": " + message);
    }
    spec.where = loc(kv.first);
    model_.initial.rates.push_back(spec);
  }
}

Model Reader::read(const YAML::Node& root) {
  if (!root.IsDefined() || root.IsNull())
    throw InputError({file_, 1, 1}, "file",
                     "the file holds no mechanism (empty, or only comments): expected a mapping "
                     "at the top level (orthomech: 1, bodies: ...)");
  if (!root.IsMap())
    fail(root, "file", "expected a mapping at the top level (orthomech: 1, bodies: ...)");
  expect_map(root, "file",
             {"orthomech", "dimension", "name", "description", "units", "ground", "bodies",
              "joints", "loads", "measures", "drivers", "design_positions", "analysis",
              "nonholonomic", "initial", "parameters"});
  const YAML::Node version = require(root, "orthomech", "file");
  if (version.IsScalar() && version.Tag() != "?")
    fail(version, "file",
         "the format version must be the plain number 1, not a quoted or tagged string");
  if (!version.IsScalar() || version.Scalar() != "1")
    fail(version, "file",
         "unsupported format version '" +
             (version.IsScalar() ? clip(version.Scalar()) : std::string("(not a number)")) +
             "' (this build reads 1)");
  model_.file = file_;
  // name and description: text (a plain or quoted scalar), not a list or mapping.
  const auto text_field = [&](const char* key) {
    const YAML::Node node = root[key];
    if (!node || node.IsNull()) return std::string();
    if (!node.IsScalar()) fail(node, "file", "field '" + std::string(key) + "' must be text");
    return node.Scalar();
  };
  model_.name = text_field("name");
  if (model_.name.empty()) {
    const auto slash = file_.find_last_of('/');
    model_.name = file_.substr(slash == std::string::npos ? 0 : slash + 1);
  }
  model_.description = text_field("description");
  if (const YAML::Node dimension = root["dimension"]) {
    if (!dimension.IsScalar() || dimension.Tag() != "?" ||
        (dimension.Scalar() != "2" && dimension.Scalar() != "3"))
      fail(dimension, "file", "dimension must be 2 (planar) or 3 (spatial)");
    model_.dimension = dimension.Scalar() == "3" ? 3 : 2;
  }
  if (model_.dimension == 3) {
    read_spatial(root);  // spatial_file.cpp
    return std::move(model_);
  }
  read_parameters(root["parameters"]);
  read_units(root["units"]);
  read_ground(root["ground"]);
  read_bodies(root);
  read_joints(root);
  read_nonholonomic(root);
  read_measures(root);
  read_loads(root);
  read_drivers(root);
  read_design_positions(root);
  read_analysis(root["analysis"]);
  read_initial(root["initial"]);
  finalize_model(model_);
  if (model_.nc > model_.n + 1000)
    fail(root["joints"], "joints", "far more constraint equations than coordinates");
  return std::move(model_);
}

// yaml-cpp reports an unclosed '[' or '{' where the input ends; point at the bracket instead.
}  // namespace detail

namespace {

using detail::check_yaml_document;
using detail::Reader;
using detail::SetNodes;
using detail::walk_yaml_value;
using detail::YamlWalkError;

SourceLocation unclosed_bracket(const std::string& text, const std::string& origin) {
  std::vector<std::pair<char, SourceLocation>> open;
  int line = 1, column = 0;
  bool comment = false;
  char quote = 0;
  for (const char ch : text) {
    ++column;
    if (ch == '\n') {
      ++line;
      column = 0;
      comment = false;
      continue;
    }
    if (comment) continue;
    if (quote) {
      if (ch == quote) quote = 0;
      continue;
    }
    if (ch == '#')
      comment = true;
    else if (ch == '"' || ch == '\'')
      quote = ch;
    else if (ch == '[' || ch == '{')
      open.push_back({ch, {origin, line, column}});
    else if ((ch == ']' || ch == '}') && !open.empty())
      open.pop_back();
  }
  return open.empty() ? SourceLocation{origin, 0, 0} : open.back().second;
}

// ---- --set PATH=VALUE
// ------------------------------------------------------------------------------ Every node of
// `value` (the value and all it holds), to name the `--set` in messages; a value that holds
// itself through an alias, or expands beyond the limit, is refused at its `--set`
// (yaml_walk.hpp: the one walk over YAML values).
void collect_nodes(const YAML::Node& value, std::vector<YAML::Node>& out, const std::string& label,
                   const std::string& element) {
  try {
    walk_yaml_value(value, [&](const YAML::Node& n) { out.push_back(n); });
  } catch (const YamlWalkError& e) {
    out.clear();
    throw InputError({label, 0, 0}, element, e.what());
  }
}

std::string names_in(const YAML::Node& node) {
  std::string names;
  const auto add = [&](const std::string& name) { names += (names.empty() ? "" : ", ") + name; };
  if (node.IsMap()) {
    for (const auto& kv : node)
      if (kv.first.IsScalar()) add(kv.first.Scalar());
  } else if (node.IsSequence()) {
    for (const auto& item : node)
      if (item.IsMap() && item["name"] && item["name"].IsScalar()) add(item["name"].Scalar());
  }
  return names.empty() ? std::string("none") : names;
}

// The item of a list named `segment` (its `name`), or at index `segment`; a null node if none.
YAML::Node list_item(const YAML::Node& list, const std::string& segment) {
  for (const auto& item : list)
    if (item.IsMap() && item["name"] && item["name"].IsScalar() && item["name"].Scalar() == segment)
      return item;
  if (!segment.empty() && segment.size() <= 6 &&
      std::all_of(segment.begin(), segment.end(), [](char c) { return c >= '0' && c <= '9'; })) {
    const size_t index = std::stoul(segment);
    if (index < list.size()) return list[index];
  }
  return YAML::Node(YAML::NodeType::Undefined);
}

// Writes one change into the document (a path of map keys and list item names or indices; a
// one-segment path names a parameter when the file declares it). A new key may be added at the
// last segment only, so that a typo in the middle of a path is an error, not a silent no-op.
//
// With `read` given, nothing is written: the text of the single value at the path goes to *read.
SetNodes apply_change(YAML::Node& root, const FileChange& change, const std::string& origin,
                      std::string* read = nullptr, YAML::Mark* read_mark = nullptr) {
  SetNodes written{
      origin + (read ? ": " + change.path : ": --set " + change.path + "=" + change.value), {}};
  const auto fail = [&](const std::string& element, const std::string& message) {
    throw InputError({written.label, 0, 0}, element, message);
  };
  YAML::Node value;
  try {
    if (!read) value = YAML::Load(change.value);
  } catch (const YAML::Exception& e) {
    fail(change.path, "the value is not valid YAML: " + e.msg);
  }
  if (!read && (!value.IsDefined() || value.IsNull())) fail(change.path, "the value is empty");
  if (!root.IsMap()) fail("file", "the file holds no mapping to change");

  std::vector<std::string> segments;
  std::stringstream path(change.path);
  for (std::string segment; std::getline(path, segment, '.');) segments.push_back(segment);
  if (segments.empty() || change.path.back() == '.' ||
      std::any_of(segments.begin(), segments.end(), [](const auto& g) { return g.empty(); }))
    fail(change.path, "the path has an empty segment (write it as bodies.crank.mass)");
  const YAML::Node& top = root;
  if (segments.size() == 1 && !top[segments[0]] && top["parameters"] && top["parameters"].IsMap() &&
      top["parameters"][segments[0]])
    segments.insert(segments.begin(), "parameters");

  YAML::Node node = root;
  std::string at;
  for (size_t i = 0; i < segments.size(); ++i) {
    const std::string& segment = segments[i];
    const bool last = i + 1 == segments.size();
    const std::string here = at.empty() ? segment : at + "." + segment;
    const YAML::Node& current = node;
    if (!current.IsMap() && !current.IsSequence())
      fail(here, "'" + at + "' is a single value: it has no '" + segment + "'");
    YAML::Node child = current.IsMap() ? current[segment] : list_item(current, segment);
    if (current.IsMap()) {
      if (!child && last && !read) {
        node[segment] = value;
        for (const auto& kv : current)  // the new key too: the reader checks it like any key
          if (kv.first.IsScalar() && kv.first.Scalar() == segment)
            written.nodes.push_back(kv.first);
        collect_nodes(value, written.nodes, written.label, change.path);
        return written;
      }
      if (!child)
        fail(here, "no key '" + segment + "' in " + (at.empty() ? "the file" : "'" + at + "'") +
                       " (keys: " + names_in(current) + ")");
    } else if (!child) {
      fail(here,
           "no item named '" + segment + "' in '" + at + "' (names: " + names_in(current) + ")");
    }
    if (last && read) {
      if (!child.IsScalar()) fail(here, "'" + here + "' is not a single value");
      *read = child.Scalar();
      if (read_mark) *read_mark = child.Mark();
      return written;
    }
    if (last) {
      child = value;
      collect_nodes(child, written.nodes, written.label, change.path);
      return written;
    }
    node.reset(child);
    at = here;
  }
  return written;
}

Model parse_text(const std::string& text, const std::string& origin,
                 const std::vector<FileChange>& changes) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    if (e.msg.find("flow not found") != std::string::npos) {
      const SourceLocation where = unclosed_bracket(text, origin);
      if (where.line > 0) throw InputError(where, "YAML", "this bracket is never closed");
    }
    throw InputError({origin, e.mark.line + 1, e.mark.column + 1}, "YAML", e.msg);
  }
  check_yaml_document(root, origin);
  try {
    std::vector<SetNodes> sets;
    sets.reserve(changes.size());
    for (const FileChange& change : changes) sets.push_back(apply_change(root, change, origin));
    return Reader(origin, std::move(sets)).read(root);
  } catch (const YAML::Exception& e) {  // anything yaml-cpp still throws: report, do not crash
    throw InputError(
        {origin, e.mark.is_null() ? 1 : e.mark.line + 1, e.mark.is_null() ? 1 : e.mark.column + 1},
        "YAML", e.msg);
  }
}

}  // namespace

std::string file_value(const std::string& text, const std::string& origin,
                       const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw InputError({origin, e.mark.line + 1, e.mark.column + 1}, "YAML", e.msg);
  }
  std::string value;
  (void)apply_change(root, {path, ""}, origin, &value);
  return value;
}

std::string with_file_values(const std::string& text, const std::string& origin,
                             const std::vector<FileChange>& changes) {
  // Each value's place in the text: its node's mark and the plain scalar's length there.
  struct Edit {
    size_t at = 0, length = 0;
    const FileChange* change = nullptr;
  };
  std::vector<Edit> edits;
  for (const FileChange& c : changes) {
    YAML::Node root = YAML::Load(text);
    std::string value;
    YAML::Mark mark;
    (void)apply_change(root, {c.path, ""}, origin, &value, &mark);
    const auto at = static_cast<size_t>(mark.pos);
    if (mark.pos < 0 || text.compare(at, value.size(), value) != 0)
      throw InputError({origin, mark.line + 1, mark.column + 1}, c.path,
                       "the value is not written as plain text (quoted or over several lines): "
                       "it cannot be replaced in place");
    edits.push_back({at, value.size(), &c});
  }
  std::sort(edits.begin(), edits.end(), [](const Edit& a, const Edit& b) { return a.at > b.at; });
  std::string out = text;
  for (size_t k = 0; k < edits.size(); ++k) {
    if (k > 0 && edits[k].at + edits[k].length > edits[k - 1].at)
      throw InputError({origin, 0, 0}, edits[k].change->path, "two paths name one value");
    out.replace(edits[k].at, edits[k].length, edits[k].change->value);
  }
  for (const FileChange& c : changes)
    if (file_value(out, origin, c.path) != c.value)
      throw InputError({origin, 0, 0}, c.path, "the value did not read back as written");
  return out;
}

FileChange parse_file_change(const std::string& text) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0 || eq + 1 == text.size())
    throw std::invalid_argument("'" + text +
                                "' must be PATH=VALUE (for example loads.spring.stiffness=4000)");
  return {text.substr(0, eq), text.substr(eq + 1)};
}

Model load_mechanism(const std::string& path, const std::vector<FileChange>& changes) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw InputError({path, 0, 0}, "file",
                     std::filesystem::exists(path, ec) ? "cannot open the file: not a regular file"
                                                       : "cannot open the file: no such file");
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  if (!in && !in.eof()) throw InputError({path, 0, 0}, "file", "cannot open the file: read error");
  return parse_text(text.str(), path, changes);
}

Model parse_mechanism(const std::string& text, const std::string& origin,
                      const std::vector<FileChange>& changes) {
  return parse_text(text, origin, changes);
}

}  // namespace orthomech
