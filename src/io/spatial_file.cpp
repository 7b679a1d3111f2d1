// The spatial sections of a mechanism file (`dimension: 3`, docs/file-format.md "Spatial
// mechanisms", docs/spatial.md §5): bodies with a position and an orientation, 3-vector points and
// axes, the eleven spatial joint types of constraints/spatial_joints.hpp, spatial loads and
// measures. Parameters, units, `--set`, drivers, design-position inputs, `analysis` and `initial`
// are read by the planar code (mechanism_file.cpp), shared through the Reader.
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <optional>
#include <sstream>

#include "mechanism_reader.hpp"
#include "orthomech/constraints/spatial_joints.hpp"
#include "orthomech/model/reference_direction.hpp"
#include "orthomech/model/spatial.hpp"

namespace orthomech::detail {

namespace {

constexpr double kRadToDeg = 180.0 / std::numbers::pi;
// Unit vectors (axes, pins, orientation columns) are typed with a few digits: they are
// normalised, and two directions count as perpendicular (universal pins) within this cosine
// (3.4 arc-seconds), as parallel (an axis and its `ref`, two orientation axes) below this sine.
constexpr double kPerpendicularCosine = 1e-5;
constexpr double kParallelSine = 1e-6;
// The two points of a joint row must coincide at the design pose to this distance (m), or the
// reader warns (the position solvers close the gap; a large one is most often a typo).
constexpr double kPointGap = 1e-6;

// The rotation of a body at the design pose, and a world point of a body point (body frame).
Mat3 design_rotation(const Model& model, int body) {
  if (body == kGround) return Mat3::Identity();
  return rotation_matrix(model.bodies[static_cast<size_t>(body)].spatial.design_orientation);
}
Vec3 design_world(const Model& model, const SpatialPointRef& p) {
  if (p.body == kGround) return p.s;
  const SpatialBodyData& b = model.bodies[static_cast<size_t>(p.body)].spatial;
  return b.design_position + rotation_matrix(b.design_orientation) * (b.com_local + p.s);
}

Quat to_quaternion(const Mat3& R) {
  const Eigen::Quaterniond q(R);
  Quat e(q.w(), q.x(), q.y(), q.z());
  e /= e.norm();
  return e(0) < 0.0 ? Quat(-e) : e;
}

Mat3 axis_rotation(int axis, double angle) {
  return Eigen::AngleAxisd(angle, Vec3::Unit(axis)).toRotationMatrix();
}

std::string degrees(double radians) {
  std::ostringstream s;
  s.precision(4);
  s << radians * kRadToDeg << "°";
  return s.str();
}

}  // namespace

// ---- small readers -----------------------------------------------------------------------------
Vec3 Reader::vec3(const YAML::Node& node, const std::string& element, const std::string& field,
                  double scale, Quantity quantity) const {
  if (node.IsSequence() && node.size() == 2)
    fail(node, element,
         "field '" + field + "' has 2 coordinates, dimension 3 needs 3 (a list [x, y, z])");
  const auto v = numbers(node, element, field, 3, scale, quantity);
  return Vec3(v[0], v[1], v[2]);
}

Vec3 Reader::unit_vec3(const YAML::Node& node, const std::string& element,
                       const std::string& field) const {
  const Vec3 a = vec3(node, element, field, 1.0);
  const double norm = a.stableNorm();
  if (!(norm > 0.0)) fail(node, element, "field '" + field + "' must not be the zero vector");
  return a / norm;
}

std::vector<std::pair<std::string, Vec3>> Reader::points_map3(const YAML::Node& pts,
                                                              const std::string& element) const {
  if (!pts.IsMap()) fail(pts, element, "field 'points' must be a mapping name: [x, y, z]");
  std::vector<std::pair<std::string, Vec3>> out;
  std::set<std::string> seen;
  for (const auto& kv : pts) {
    const std::string name = scalar(kv.first, element, "a point name");
    if (name == "origin") fail(kv.first, element, "point name 'origin' is reserved");
    if (name.find('.') != std::string::npos)
      fail(kv.first, element, "a point name must not contain '.'");
    if (!seen.insert(name).second) fail(kv.first, element, "point '" + name + "' is defined twice");
    if (kv.second.IsSequence() && kv.second.size() == 2)
      fail(kv.second, element,
           "point '" + name + "' has 2 coordinates, dimension 3 needs 3 ([x, y, z])");
    out.emplace_back(name,
                     vec3(kv.second, element, "points." + name, units_.length, Quantity::length));
  }
  return out;
}

void Reader::add_warning(const YAML::Node& node, const std::string& element,
                         const std::string& message) {
  const SourceLocation w = loc(node);
  std::ostringstream msg;
  msg << w.file << ':' << w.line << ':' << w.column << ": warning: " << element << ": " << message;
  model_.warnings.push_back(msg.str());
}

// inertia: [Jxx, Jyy, Jzz] (body axes principal), [Jxx, Jyy, Jzz, Jxy, Jxz, Jyz] or
// {xx, yy, zz, xy, xz, yz} (products default 0): the tensor
// about the centre of mass in body axes, J_xy = −∫ x y dm (tensor components, not the "products
// of inertia" ∫ x y dm of some CAD programs, which have the opposite sign).
Mat3 Reader::spatial_inertia(const YAML::Node& node, const std::string& element) const {
  const double scale = units_.mass * units_.length * units_.length;
  if (node.IsMap()) {  // {xx, yy, zz, xy, xz, yz}: the same tensor components by name
    expect_map(node, element, {"xx", "yy", "zz", "xy", "xz", "yz"});
    Mat3 J = Mat3::Zero();
    const char* names[3][3] = {{"xx", "xy", "xz"}, {"xy", "yy", "yz"}, {"xz", "yz", "zz"}};
    for (int a = 0; a < 3; ++a)
      for (int b = a; b < 3; ++b)
        J(a, b) = J(b, a) = a == b
                                ? number_field(node, names[a][b], element, scale, Quantity::inertia)
                                : optional_number(node, names[a][b], element, 0.0, scale);
    check_inertia(node, element, J);
    return J;
  }
  if (node.IsScalar())
    fail(node, element,
         "field 'inertia' is one number (the planar form): dimension 3 needs [Jxx, Jyy, Jzz], "
         "[Jxx, Jyy, Jzz, Jxy, Jxz, Jyz] or {xx, yy, zz, xy, xz, yz}");
  if (!node.IsSequence() || (node.size() != 3 && node.size() != 6))
    fail(node, element,
         "field 'inertia' must be [Jxx, Jyy, Jzz], [Jxx, Jyy, Jzz, Jxy, Jxz, Jyz] or "
         "{xx, yy, zz, xy, xz, yz}");
  Vec3 d;
  for (int a = 0; a < 3; ++a)
    d(a) = number(node[static_cast<size_t>(a)], element, "inertia", scale, Quantity::inertia);
  Mat3 J = d.asDiagonal();
  if (node.size() == 6) {
    const double xy = number(node[3], element, "inertia", scale);
    const double xz = number(node[4], element, "inertia", scale);
    const double yz = number(node[5], element, "inertia", scale);
    J(0, 1) = J(1, 0) = xy;
    J(0, 2) = J(2, 0) = xz;
    J(1, 2) = J(2, 1) = yz;
  }
  check_inertia(node, element, J);
  return J;
}

void Reader::check_inertia(const YAML::Node& node, const std::string& element,
                           const Mat3& J) const {
  const double scale = units_.mass * units_.length * units_.length;
  const Eigen::SelfAdjointEigenSolver<Mat3> eig(J);
  const Vec3& p = eig.eigenvalues();  // ascending
  if (!(p(0) > 1e-12 * p(2))) fail(node, element, "the inertia tensor is not positive definite");
  constexpr double kSlack = 1e-9;  // relative: [1, 166.6667, 166.6667] is a slender rod
  if (p(2) > (p(0) + p(1)) * (1.0 + kSlack)) {
    std::ostringstream msg;
    msg.precision(6);
    msg << "the principal moments of inertia " << p(0) / scale << ", " << p(1) / scale << ", "
        << p(2) / scale
        << " violate the triangle inequality (the largest must not exceed the sum of the other "
           "two)";
    fail(node, element, msg.str());
  }
}

// orientation: {axis, angle} | two of {x, y, z} | {euler, sequence} | {quaternion}.
Quat Reader::orientation(const YAML::Node& node, const std::string& element) const {
  const std::string forms =
      "orientation must be one of {axis: [..], angle: a}, two of {x: [..], y: [..], z: [..]}, "
      "{euler: [a1, a2, a3], sequence: zyx}, {quaternion: [e0, e1, e2, e3]}";
  if (!node.IsMap()) fail(node, element, forms);
  if (node["quaternion"]) {
    expect_map(node, element, {"quaternion"});
    const auto v = numbers(node["quaternion"], element, "quaternion", 4);
    Quat e(v[0], v[1], v[2], v[3]);
    const double norm = e.stableNorm();
    if (!(norm > 0.0)) fail(node["quaternion"], element, "the quaternion must not be zero");
    return e / norm;
  }
  if (node["axis"] || node["angle"]) {
    expect_map(node, element, {"axis", "angle"});
    const Vec3 n = unit_vec3(require(node, "axis", element), element, "axis");
    const double a = number_field(node, "angle", element, units_.angle, Quantity::angle);
    Quat e;
    e(0) = std::cos(0.5 * a);
    e.tail<3>() = std::sin(0.5 * a) * n;
    return e;
  }
  if (node["euler"] || node["sequence"]) {
    expect_map(node, element, {"euler", "sequence"});
    const auto a = numbers(require(node, "euler", element), element, "euler", 3, units_.angle,
                           Quantity::angle);
    const std::string seq = string_field(node, "sequence", element);
    const bool valid = seq.size() == 3 &&
                       std::all_of(seq.begin(), seq.end(),
                                   [](char c) { return c == 'x' || c == 'y' || c == 'z'; }) &&
                       seq[0] != seq[1] && seq[1] != seq[2];
    if (!valid)
      fail(node["sequence"], element,
           "sequence must be three of x, y, z with no axis twice in a row (zyx, xyz, zxz, ...), "
           "got '" +
               clip(seq) + "'");
    // Intrinsic: rotate about the body's first axis, then about the new second, then the third.
    Mat3 R = Mat3::Identity();
    for (size_t k = 0; k < 3; ++k) R = R * axis_rotation(seq[k] - 'x', a[k]);
    return to_quaternion(R);
  }
  // Two body axes in world: the first kept, the second made perpendicular to it, the third
  // right-handed.
  std::vector<std::pair<int, YAML::Node>> given;
  for (const auto& kv : node) {
    const std::string key = scalar(kv.first, element, "a key");
    if (key != "x" && key != "y" && key != "z") fail(kv.first, element, forms);
    given.emplace_back(key[0] - 'x', kv.second);
  }
  if (given.size() != 2)
    fail(node, element, "give two of the body axes x, y, z in world (the third follows)");
  const int a = given[0].first, b = given[1].first;
  if (a == b) fail(node, element, "body axis " + std::string(1, char('x' + a)) + " is given twice");
  const Vec3 first = unit_vec3(given[0].second, element, std::string(1, char('x' + a)));
  Vec3 second = unit_vec3(given[1].second, element, std::string(1, char('x' + b)));
  second -= second.dot(first) * first;
  if (!(second.norm() > kParallelSine))
    fail(given[1].second, element,
         "the body axes " + std::string(1, char('x' + a)) + " and " +
             std::string(1, char('x' + b)) + " are parallel");
  second.normalize();
  Mat3 R;
  R.col(a) = first;
  R.col(b) = second;
  const int c = 3 - a - b;
  // e_c = e_{c+1} × e_{c+2} (cyclic)
  R.col(c) = R.col((c + 1) % 3).cross(R.col((c + 2) % 3));
  return to_quaternion(R);
}

SpatialPointRef Reader::spatial_point_ref(const YAML::Node& node,
                                          const std::string& element) const {
  return point_reference<SpatialPointRef, Vec3>(
      node, element, ground_points3_,
      [](const Body& b) -> const std::vector<std::pair<std::string, Vec3>>& {
        return b.spatial.points;
      },
      [](const Body& b) { return b.spatial.com_local; });
}

// target: {point: body.P, at: [x, y, z], tolerance: t, orientation: {..} | direction: {body: [..],
// world: [..]}, angle_tolerance: a} (docs/file-format.md "Design positions"): the point at a world
// position and, optionally, the orientation of the point's body, as a whole (the forms of a body
// pose's `orientation`) or as one body axis along a world direction.
DesignTarget Reader::spatial_target(const YAML::Node& t, const std::string& element) const {
  if (t.IsMap() && t["angle"])
    fail(t["angle"], element,
         "'angle' is a planar body angle; in dimension 3 give 'orientation' (the body frame in "
         "world) or 'direction' ({body: [..], world: [..]}: a body axis along a world direction)");
  expect_map(t, element,
             {"point", "at", "tolerance", "orientation", "direction", "angle_tolerance"});
  DesignTarget target;
  target.spatial_point = spatial_point_ref(require(t, "point", element), element);
  target.spatial_position =
      vec3(require(t, "at", element), element, "at", units_.length, Quantity::length);
  target.tolerance =
      optional_number(t, "tolerance", element, 1e-3, units_.length, Quantity::length);
  if (!(target.tolerance > 0.0)) fail(t["tolerance"], element, "tolerance must be positive");
  if (t["orientation"] && t["direction"])
    fail(t["direction"], element, "give 'orientation' or 'direction', not both");
  const YAML::Node o = t["orientation"] ? t["orientation"] : t["direction"];
  if (o && target.spatial_point.body == kGround)
    fail(o, element,
         "the target point '" + target.spatial_point.label +
             "' is on the ground: an orientation target needs a moving body");
  if (t["orientation"]) target.orientation = orientation(t["orientation"], element);
  if (const YAML::Node d = t["direction"]) {
    if (!d.IsMap())
      fail(d, element,
           "field 'direction' must be a mapping {body: [x, y, z], world: [x, y, z]} (a body axis "
           "in the body frame and the world direction it must point along)");
    expect_map(d, element, {"body", "world"});
    target.direction = std::make_pair(unit_vec3(require(d, "body", element), element, "body"),
                                      unit_vec3(require(d, "world", element), element, "world"));
  }
  if (const YAML::Node a = t["angle_tolerance"]) {
    if (!o)
      fail(a, element, "'angle_tolerance' needs an 'orientation' or a 'direction' to apply to");
    target.angle_tolerance = number(a, element, "angle_tolerance", units_.angle, Quantity::angle);
    if (!(*target.angle_tolerance > 0.0)) fail(a, element, "angle_tolerance must be positive");
  }
  return target;
}

std::pair<SpatialPointRef, SpatialPointRef> Reader::spatial_connects(
    const YAML::Node& item, const std::string& element) const {
  const YAML::Node c = require(item, "connects", element);
  if (!c.IsSequence() || c.size() != 2)
    fail(c, element, "field 'connects' must be a list of two points [body.point, body.point]");
  SpatialPointRef a = spatial_point_ref(c[0], element), b = spatial_point_ref(c[1], element);
  if (a.body == b.body)
    fail(c, element, "connects body '" + model_.body_name(a.body) + "' to itself");
  return {a, b};
}

int Reader::spatial_body_ref(const YAML::Node& node, const std::string& element) const {
  if (!node.IsScalar()) fail(node, element, "expected a body name");
  const int b = model_.find_body(node.Scalar());
  if (b == -2) fail(node, element, "body '" + node.Scalar() + "' is not defined");
  return b;
}

// ---- the file ----------------------------------------------------------------------------------
void Reader::read_spatial(const YAML::Node& root) {
  read_parameters(root["parameters"]);
  read_units(root["units"]);
  read_spatial_ground(root["ground"]);
  read_spatial_bodies(root);
  read_spatial_joints(root);
  read_spatial_nonholonomic(root);
  read_measures(root);  // one loop for both dimensions (mechanism_file.cpp)
  read_loads(root);
  read_drivers(root);
  read_design_positions(root);
  read_analysis(root["analysis"]);
  read_initial(root["initial"]);
  finalize_model(model_);
  if (model_.nc > model_.n + 1000)
    fail(root["joints"], "joints", "far more constraint equations than coordinates");
}

void Reader::read_spatial_ground(const YAML::Node& node) {
  if (!node) return;
  expect_map(node, "ground", {"points"});
  if (const YAML::Node pts = node["points"]) ground_points3_ = points_map3(pts, "ground");
}

void Reader::read_spatial_bodies(const YAML::Node& root) {
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
    expect_map(item, element, {"name", "mass", "inertia", "com", "pose", "points"});
    Body b;
    b.name = name;
    b.kind = BodyKind::spatial;
    b.where = loc(item);
    b.mass = number_field(item, "mass", element, units_.mass, Quantity::mass);
    b.spatial.inertia = spatial_inertia(require(item, "inertia", element), element);
    if (item["com"])
      b.spatial.com_local = vec3(item["com"], element, "com", units_.length, Quantity::length);
    const YAML::Node pose = require(item, "pose", element);
    if (!pose.IsMap())
      fail(pose, element,
           "field 'pose' must be a mapping {position: [x, y, z], orientation: ...} in dimension 3");
    expect_map(pose, element, {"position", "orientation"});
    b.spatial.design_position = vec3(require(pose, "position", element), element, "position",
                                     units_.length, Quantity::length);
    if (const YAML::Node o = pose["orientation"])
      b.spatial.design_orientation = orientation(o, element);
    if (const YAML::Node pts = item["points"]) b.spatial.points = points_map3(pts, element);
    model_.bodies.push_back(std::move(b));
  }
}

// ---- joints ------------------------------------------------------------------------------------
void Reader::read_spatial_joints(const YAML::Node& root) {
  const YAML::Node node = list(root, "joints");
  if (!node || node.IsNull()) return;
  std::set<std::string> seen;
  size_t index = 0;
  for (const auto& item : node) {
    const std::string name = name_of(item, "joint", index++, seen);
    const std::string element = "joint '" + name + "'";
    const std::string type = string_field(item, "type", element);
    SpatialJoint s;
    if (!find_spatial_joint_type(type, s.type))
      fail(item["type"], element,
           "unknown spatial joint type '" + type +
               "' (allowed: spherical, revolute, cylindrical, prismatic, fixed, universal, "
               "planar, point-on-line, point-on-plane, distance, screw)");
    const SpatialJointSpec& spec = spatial_joint_spec(s.type);
    using T = SpatialJointType;
    const bool axial = s.type != T::spherical && s.type != T::distance && s.type != T::universal;
    std::vector<std::string> keys = {"name", "type", "connects"};
    if (axial) keys.insert(keys.end(), {"axis", "ref"});
    if (s.type == T::universal) keys.emplace_back("axes");
    if (s.type == T::screw) keys.emplace_back("pitch");
    if (s.type == T::distance) keys.emplace_back("length");
    if (spec.coordinate != SpatialCoordinate::none)
      keys.insert(keys.end(), {"limits", "end_stops"});
    expect_map(item, element, keys);
    Joint j;
    j.name = name;
    j.where = loc(item);
    std::tie(s.pi, s.pj) = spatial_connects(item, element);
    const Mat3 Ri = design_rotation(model_, s.pi.body), Rj = design_rotation(model_, s.pj.body);
    const Vec3 Pi = design_world(model_, s.pi), Pj = design_world(model_, s.pj);

    // The joint frame A (columns f, g, h) in world at the design pose (docs/spatial.md §2.5).
    Mat3 A = Ri;  // spherical, distance, fixed without an axis: body i's axes
    if (s.type == T::universal) {
      const YAML::Node axes = require(item, "axes", element);
      if (!axes.IsSequence() || axes.size() != 2)
        fail(axes, element,
             "field 'axes' must be a list of two pins [pin1 (first body's frame), pin2 (second "
             "body's frame)]");
      const Vec3 p1 = Ri * unit_vec3(axes[0], element, "axes");
      const Vec3 p2 = Rj * unit_vec3(axes[1], element, "axes");
      if (std::abs(p1.dot(p2)) > kPerpendicularCosine)
        fail(axes, element,
             "the pins are " + degrees(std::acos(std::clamp(p1.dot(p2), -1.0, 1.0))) +
                 " apart at the design pose, they must be perpendicular");
      A.col(0) = p1;
      A.col(1) = (p2 - p2.dot(p1) * p1).normalized();
      A.col(2) = A.col(0).cross(A.col(1));
    } else if (axial && (item["axis"] || s.type != T::fixed)) {
      const Vec3 h_local = unit_vec3(require(item, "axis", element), element, "axis");
      Vec3 f_local = least_aligned(h_local);
      if (const YAML::Node r = item["ref"]) {
        const Vec3 ref = unit_vec3(r, element, "ref");
        f_local = ref - ref.dot(h_local) * h_local;
        if (!(f_local.norm() > kParallelSine)) fail(r, element, "ref is parallel to the axis");
        f_local.normalize();
      }
      A.col(2) = Ri * h_local;
      A.col(0) = Ri * f_local;
      A.col(1) = A.col(2).cross(A.col(0));
    } else if (item["ref"]) {
      fail(item["ref"], element, "a ref needs an axis");
    }
    s.frame_i = Ri.transpose() * A;
    s.frame_j = Rj.transpose() * A;
    s.ref_j = least_aligned(s.frame_j.col(2));  // body j's own default reference direction

    if (s.type == T::screw) {
      s.pitch = number_field(item, "pitch", element, units_.length, Quantity::length);
      if (s.pitch == 0.0) fail(item["pitch"], element, "pitch must not be zero");
    }
    if (s.type == T::distance) {
      s.length = optional_number(item, "length", element, (Pj - Pi).norm(), units_.length,
                                 Quantity::length);
      if (!(s.length > 0.0))
        fail(item["length"] ? item["length"] : item, element,
             "length must be positive (the two points coincide at the design pose: give it)");
    }
    if (spec.coordinate != SpatialCoordinate::none) {
      j.limits = joint_limits(
          item, element, spec.coordinate == SpatialCoordinate::angle ? units_.angle : units_.length,
          spec.coordinate == SpatialCoordinate::angle ? Quantity::angle : Quantity::length);
      j.stop_restitution = end_stops(item, element);
    }

    // The joint's points must satisfy its point rows at the design pose, or the reader warns.
    const Vec3 d = Pj - Pi, h = A.col(2);
    const double L = units_.length;
    const std::string u = " " + model_.units.length;
    std::ostringstream msg;
    msg.precision(6);
    switch (s.type) {
      case T::spherical:
      case T::revolute:
      case T::fixed:
      case T::universal:
        if (d.norm() > kPointGap) msg << "its points are " << d.norm() / L << u << " apart";
        break;
      case T::cylindrical:
      case T::prismatic:
      case T::screw:
      case T::point_on_line:
        if (const double off = (d - d.dot(h) * h).norm(); off > kPointGap)
          msg << "the second point is " << off / L << u << " off the axis through the first";
        break;
      case T::planar:
      case T::point_on_plane:
        if (const double off = std::abs(d.dot(h)); off > kPointGap)
          msg << "the second point is " << off / L << u << " off the plane through the first";
        break;
      case T::distance:
        if (std::abs(d.norm() - s.length) > kPointGap)
          msg << "its points are " << d.norm() / L << u << " apart, the length is " << s.length / L
              << u;
        break;
    }
    if (!msg.str().empty())
      add_warning(item["connects"], element,
                  msg.str() + " at the design pose (the position solvers close the gap)");
    j.kind = s;
    model_.joints.push_back(std::move(j));
  }
}

// ---- nonholonomic constraints ------------------------------------------------------------------
// rolling-disc (docs/spatial.md §3): {name, type, body, radius, axis (body frame), centre (a point
// of the body, default its centre of mass), plane: {point, normal} (world; default the origin,
// +z), t1 (world, in the plane; default the world axis least aligned with the normal, projected)}.
void Reader::read_spatial_nonholonomic(const YAML::Node& root) {
  const YAML::Node node = list(root, "nonholonomic");
  if (!node || node.IsNull()) return;
  std::set<std::string> seen;
  for (const Joint& j : model_.joints) seen.insert(j.name);  // one namespace with the joints
  size_t index = 0;
  for (const auto& item : node) {
    const std::string name = name_of(item, "nonholonomic constraint", index++, seen);
    const std::string what = "nonholonomic constraint '" + name + "'";
    const std::string type = string_field(item, "type", what);
    if (type == "knife-edge")
      fail(item["type"], what,
           "a knife edge is a planar constraint (dimension 2); dimension 3 allows: rolling-disc");
    if (type != "rolling-disc")
      fail(item["type"], what,
           "unknown nonholonomic constraint type '" + type + "' (allowed: rolling-disc)");
    const std::string element = "rolling disc '" + name + "'";
    expect_map(item, element, {"name", "type", "body", "radius", "axis", "centre", "plane", "t1"});
    RollingDisc d;
    d.name = name;
    d.where = loc(item);
    const YAML::Node body = require(item, "body", element);
    d.body = spatial_body_ref(body, element);
    if (d.body == kGround) fail(body, element, "the disc must be a moving body, not the ground");
    d.radius = number_field(item, "radius", element, units_.length, Quantity::length);
    if (!(d.radius > 0.0)) fail(item["radius"], element, "radius must be positive");
    d.axis_local = unit_vec3(require(item, "axis", element), element, "axis");
    if (const YAML::Node c = item["centre"]) {
      const SpatialPointRef p = spatial_point_ref(c, element);
      if (p.body != d.body)
        fail(c, element,
             "the centre must be a point of the disc's body '" + model_.body_name(d.body) + "'");
      d.centre_local = p.s;
    }
    if (const YAML::Node plane = item["plane"]) {
      if (!plane.IsMap())
        fail(plane, element, "field 'plane' must be a mapping {point: [x, y, z], normal: [..]}");
      expect_map(plane, element, {"point", "normal"});
      if (plane["point"])
        d.plane_point =
            vec3(plane["point"], element, "plane.point", units_.length, Quantity::length);
      if (plane["normal"]) d.normal = unit_vec3(plane["normal"], element, "plane.normal");
    }
    d.t1 = least_aligned(d.normal);
    if (const YAML::Node t = item["t1"]) {
      const Vec3 t1 = unit_vec3(t, element, "t1");
      d.t1 = t1 - t1.dot(d.normal) * d.normal;
      if (!(d.t1.norm() > kParallelSine)) fail(t, element, "t1 is parallel to the plane normal");
      d.t1.normalize();
    }
    // At the design pose: the axis must not be along the normal (the contact point is undefined
    // for a disc lying flat), and the disc should touch the plane (else a warning).
    const Mat3 R = design_rotation(model_, d.body);
    const SpatialBodyData& b = model_.bodies[static_cast<size_t>(d.body)].spatial;
    const Vec3 a = R * d.axis_local;
    const double s = d.normal.cross(a).norm();
    if (!(s > kParallelSine))
      fail(item["axis"], element,
           "the disc lies flat on the plane at the design pose (its axis is along the plane "
           "normal): the contact point is undefined");
    const Vec3 centre = b.design_position + R * (b.com_local + d.centre_local);
    const double gap = d.normal.dot(centre - d.plane_point) - d.radius * s;
    if (std::abs(gap) > kPointGap) {
      std::ostringstream msg;
      msg.precision(6);
      msg << "its lowest rim point is " << gap / units_.length << " " << model_.units.length
          << (gap > 0.0 ? " above" : " below")
          << " the plane at the design pose (the position solvers close the gap)";
      add_warning(item, element, msg.str());
    }
    model_.rolling_discs.push_back(std::move(d));
  }
}

// ---- loads and measures (the loop: Reader::read_loads, read_measures) -------------------------
std::optional<LoadKind> Reader::spatial_load(const YAML::Node& item, const std::string& element,
                                             const std::string& type) {
  const double force = units_.force, length = units_.length;
  if (type == "gravity") {
    expect_map(item, element, {"name", "type", "g"});
    SpatialGravity g;  // default (0, 0, −9.81) m/s²: −z is down in 3D
    if (item["g"]) g.g = vec3(item["g"], element, "g", length / (units_.time * units_.time));
    check_gravity(item, element, g.g.norm());
    return g;
  }
  if (type == "force") {
    expect_map(item, element, {"name", "type", "point", "force", "frame", "table", "active_while"});
    SpatialPointForce f;
    f.at = spatial_point_ref(require(item, "point", element), element);
    f.force = vec3(require(item, "force", element), element, "force", force);
    f.body_fixed = body_frame(item, element);
    if (f.body_fixed && f.at.body == kGround)
      fail(item["frame"], element, "a force in the ground's body frame is a world force");
    f.table = table(item["table"], element);
    return f;
  }
  if (type == "torque") {
    expect_map(item, element, {"name", "type", "body", "torque", "frame", "table", "active_while"});
    SpatialTorque t;
    t.body = spatial_body_ref(require(item, "body", element), element);
    if (t.body == kGround) fail(item["body"], element, "a torque on the ground does nothing");
    t.torque = vec3(require(item, "torque", element), element, "torque", force * length);
    t.body_fixed = body_frame(item, element);
    t.table = table(item["table"], element);
    return t;
  }
  if (type == "spring-damper") {
    expect_map(item, element, {"name", "type", "connects", "stiffness", "free_length", "damping"});
    auto [a, b] = spatial_connects(item, element);
    const SpringNumbers k = spring_numbers(item, element);
    return SpatialSpringDamper{a, b, k.stiffness, k.free_length, k.damping};
  }
  if (type == "rotary-spring-damper") {
    expect_map(item, element, {"name", "type", "joint", "stiffness", "free_angle", "damping"});
    const YAML::Node jn = require(item, "joint", element);
    JointSpringDamper r;
    r.joint = model_.find_joint(scalar(jn, element, "field 'joint'"));
    if (r.joint < 0) fail(jn, element, "joint '" + jn.Scalar() + "' is not defined");
    if (joint_coordinate(r.joint) != 1)
      fail(jn, element,
           "joint '" + jn.Scalar() + "' is a " +
               model_.joints[static_cast<size_t>(r.joint)].type_name() +
               " joint, which has no angle (a rotary spring-damper acts on a revolute, "
               "cylindrical or screw joint)");
    const SpringNumbers k = rotary_spring_numbers(item, element);
    r.stiffness = k.stiffness;
    r.free_angle = k.free_length;
    r.damping = k.damping;
    return r;
  }
  return std::nullopt;
}

std::optional<MeasureKind> Reader::spatial_measure(const YAML::Node& item,
                                                   const std::string& element,
                                                   const std::string& type, std::string& unit) {
  if (type == "joint") {
    expect_map(item, element, {"name", "type", "joint", "derivative"});
    const YAML::Node jn = require(item, "joint", element);
    const int j = model_.find_joint(scalar(jn, element, "field 'joint'"));
    if (j < 0) fail(jn, element, "joint '" + jn.Scalar() + "' is not defined");
    const int coordinate = joint_coordinate(j);
    if (coordinate == 0)
      fail(jn, element,
           "joint '" + jn.Scalar() + "' is a " + model_.joints[static_cast<size_t>(j)].type_name() +
               " joint, which has no coordinate (revolute, cylindrical, screw: an angle; "
               "prismatic: a slide)");
    if (coordinate == 1) unit = "rad";
    return JointCoordinate{j};
  }
  if (type == "point") {
    expect_map(item, element, {"name", "type", "point", "component", "derivative"});
    SpatialPointCoordinate p;
    p.point = spatial_point_ref(require(item, "point", element), element);
    const std::string c = string_field(item, "component", element);
    if (c != "x" && c != "y" && c != "z")
      fail(item["component"], element, "component must be 'x', 'y' or 'z', got '" + c + "'");
    p.axis = c[0] - 'x';
    return p;
  }
  if (type == "distance") {
    expect_map(item, element, {"name", "type", "points", "derivative"});
    const YAML::Node pts = two_points(item, element);
    return SpatialPointDistance{spatial_point_ref(pts[0], element),
                                spatial_point_ref(pts[1], element)};
  }
  if (type == "angle") {
    // The angle in [0, π] between a vector fixed in one body and one fixed in another:
    // between: [{body: b1, vector: [..]}, {body: b2, vector: [..]}] (each in its body's frame).
    expect_map(item, element, {"name", "type", "between", "derivative"});
    const YAML::Node between = require(item, "between", element);
    if (!between.IsSequence() || between.size() != 2)
      fail(between, element,
           "field 'between' must be a list of two {body: NAME, vector: [x, y, z]}");
    VectorAngle a;
    for (size_t k = 0; k < 2; ++k) {
      const YAML::Node side = between[k];
      expect_map(side, element, {"body", "vector"});
      const int b = spatial_body_ref(require(side, "body", element), element);
      const Vec3 v = unit_vec3(require(side, "vector", element), element, "vector");
      (k == 0 ? a.bi : a.bj) = b;
      (k == 0 ? a.ai : a.aj) = v;
    }
    unit = "rad";
    return a;
  }
  if (type == "camber" || type == "toe") {
    // {type: camber|toe, body: b, axis: [..]}: the wheel's outboard spin axis in b's frame.
    expect_map(item, element, {"name", "type", "body", "axis", "derivative"});
    WheelAngle w;
    w.body = spatial_body_ref(require(item, "body", element), element);
    w.axis = unit_vec3(require(item, "axis", element), element, "axis");
    w.which = type == "camber" ? WheelAngle::Which::camber : WheelAngle::Which::toe;
    // Both angles are undefined for a vertical spin axis (camber's 1/√(1 − s_z²), toe's
    // atan2(s_x, |s_y|) at s_x = s_y = 0): refused where the file draws it so, not printed as
    // NaN and noise (issue 47).
    const Vec3 s = design_rotation(model_, w.body) * w.axis;
    if (s.x() * s.x() + s.y() * s.y() < 1e-12)
      fail(item["axis"], element,
           type + " is undefined at the design pose: the spin axis is vertical there (world [" +
               std::to_string(s.x()) + ", " + std::to_string(s.y()) + ", " + std::to_string(s.z()) +
               "]); give the wheel's outboard spin axis, horizontal at the design pose");
    unit = "rad";
    return w;
  }
  return std::nullopt;
}

}  // namespace orthomech::detail
