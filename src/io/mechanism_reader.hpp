#pragma once
// The mechanism file reader (internal to src/io): one Reader per file, shared by the planar
// sections (mechanism_file.cpp) and the spatial ones (spatial_file.cpp, `dimension: 3`,
// docs/file-format.md "Spatial mechanisms"). Not installed; nothing outside src/io includes it.
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "expressions.hpp"
#include "orthomech/error.hpp"
#include "orthomech/io/units.hpp"
#include "orthomech/model/model.hpp"

namespace orthomech::detail {

// Limits of the file beyond the numbers' (docs/file-format.md "Limits").
// Bodies: simulate and info are linear in them (sparse Eᵀ, charts, mobility); the commands with
// dense n × n matrices refuse a model too large for them (ModelTooLarge, projection/workspace.hpp).
constexpr size_t kMaxBodies = 2500;
constexpr size_t kMaxCoefficients = 16;  // a polynomial driver of degree 15 at most
constexpr size_t kMaxListItems = 10000;  // joints, loads, measures, drivers, design positions

// Expressions longer than this are refused (a number is at most kMaxNumberLength characters).
constexpr size_t kMaxExpressionLength = 256;

// The nodes that one `--set PATH=VALUE` wrote into the document, and the label that names it
// in messages ("crank.yaml: --set loads.spring.stiffness=abc").
struct SetNodes {
  std::string label;
  std::vector<YAML::Node> nodes;
};

struct Units {
  double length = 1.0, angle = 1.0, mass = 1.0, time = 1.0, force = 1.0;
};

// Reads one file; `file` names it in every message.
class Reader {
 public:
  explicit Reader(std::string file, std::vector<SetNodes> sets = {})
      : file_(std::move(file)), sets_(std::move(sets)) {}

  Model read(const YAML::Node& root);

 private:
  std::string file_;
  std::vector<SetNodes> sets_;
  detail::Expressions expressions_;
  bool in_parameters_ = false;  // reading `parameters:` (an expression may use those above)
  Units units_;
  Model model_;
  std::vector<std::pair<std::string, Vec2>> ground_points_;

  // ---- error helpers --------------------------------------------------------------------------
  // A node without a place (the empty document, a key that is missing) is a whole-file matter:
  // reported at 1:1.
  // A node that a `--set` wrote is reported at that `--set`.
  [[nodiscard]] SourceLocation loc(const YAML::Node& node) const {
    for (const SetNodes& set : sets_)
      for (const YAML::Node& written : set.nodes)
        if (written.is(node)) return {set.label, 0, 0};
    const YAML::Mark m = node.Mark();
    if (m.is_null()) return {file_, 1, 1};
    return {file_, m.line + 1, m.column + 1};
  }
  [[noreturn]] void fail(const YAML::Node& node, const std::string& element,
                         const std::string& message) const {
    throw InputError(loc(node), element, message);
  }

  static std::string join(const std::vector<std::string>& keys) {
    std::string s;
    for (const auto& k : keys) s += (s.empty() ? "" : ", ") + k;
    return s;
  }

  // A mapping whose keys are all in `allowed` (typos must not pass silently).
  void expect_map(const YAML::Node& node, const std::string& element,
                  const std::vector<std::string>& allowed) const {
    if (!node.IsMap()) fail(node, element, "expected a mapping of keys to values");
    std::set<std::string> seen;
    for (const auto& kv : node) {
      const std::string key = scalar(kv.first, element, "a key");
      if (!seen.insert(key).second) fail(kv.first, element, "key '" + key + "' appears twice");
      if (std::find(allowed.begin(), allowed.end(), key) == allowed.end())
        fail(kv.first, element, "unknown key '" + key + "' (allowed: " + join(allowed) + ")");
    }
  }
  YAML::Node require(const YAML::Node& node, const std::string& key,
                     const std::string& element) const {
    const YAML::Node child = node[key];
    if (!child) fail(node, element, "missing field '" + key + "'");
    if (child.IsNull()) fail(child, element, "field '" + key + "' is empty");
    return child;
  }
  // A number: a plain (unquoted, untagged or !!int/!!float-tagged) YAML scalar of at most
  // kMaxNumberLength characters, or an expression of the file's parameters (docs/file-format.md
  // "Parameters"), finite and within the limits of `quantity` after scaling to SI.
  double number(const YAML::Node& node, const std::string& element, const std::string& field,
                double scale = 1.0, Quantity quantity = Quantity::general) const {
    if (!node.IsScalar()) fail(node, element, "field '" + field + "' must be a number");
    const std::string& tag = node.Tag();
    if (tag != "?" && tag != "tag:yaml.org,2002:float" && tag != "tag:yaml.org,2002:int")
      fail(node, element,
           "field '" + field + "' must be a number, not a quoted or tagged string (got '" +
               clip(node.Scalar()) + "')");
    const bool expressions = !expressions_.parameters().empty();
    const size_t longest = expressions ? kMaxExpressionLength : kMaxNumberLength;
    if (node.Scalar().size() > longest)
      fail(node, element,
           "field '" + field + "' must be a " + (expressions ? "number or expression" : "number") +
               " of at most " + std::to_string(longest) + " characters");
    double v = 0.0;
    if (!YAML::convert<double>::decode(node, v)) v = expression(node, element, field);
    if (!std::isfinite(v) || !std::isfinite(v * scale))
      fail(node, element, "field '" + field + "' must be finite, got '" + node.Scalar() + "'");
    if (quantity == Quantity::mass || quantity == Quantity::inertia) {
      if (!(v > 0.0))
        fail(node, element,
             std::string(quantity == Quantity::mass ? "mass" : "inertia") +
                 " must be positive, got " + node.Scalar());
    }
    const std::string problem = range_problem(v * scale, quantity);
    if (!problem.empty())
      fail(node, element, "field '" + field + "' " + problem + ", got '" + node.Scalar() + "'");
    return v * scale;
  }
  // A field that is not a plain number: an expression of the parameters, or an error naming the
  // field ("must be a number, got 'heavy'" when the file declares no parameters).
  double expression(const YAML::Node& node, const std::string& element,
                    const std::string& field) const {
    const std::string& text = node.Scalar();
    const bool word = !text.empty() && std::all_of(text.begin(), text.end(), [](char c) {
      return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.' || c == '-' ||
             c == '+';
    });
    if (expressions_.parameters().empty() && word && !in_parameters_)
      fail(node, element, "field '" + field + "' must be a number, got '" + clip(text) + "'");
    try {
      return expressions_.evaluate(text);
    } catch (const detail::UnknownName& e) {
      if (in_parameters_)
        fail(node, element,
             "'" + e.name + "' is not a parameter declared above this one (a parameter may use " +
                 "only those before it)");
      fail(node, element, "field '" + field + "': " + e.what());
    } catch (const std::invalid_argument& e) {
      fail(node, element, "field '" + field + "': " + e.what());
    }
  }
  // At most 40 characters of a text, for a message.
  static std::string clip(const std::string& text) {
    return text.size() <= 40 ? text : text.substr(0, 40) + "...";
  }
  double number_field(const YAML::Node& node, const std::string& key, const std::string& element,
                      double scale = 1.0, Quantity quantity = Quantity::general) const {
    return number(require(node, key, element), element, key, scale, quantity);
  }
  double optional_number(const YAML::Node& node, const std::string& key, const std::string& element,
                         double fallback, double scale = 1.0,
                         Quantity quantity = Quantity::general) const {
    const YAML::Node child = node[key];
    return child ? number(child, element, key, scale, quantity) : fallback;
  }
  std::string scalar(const YAML::Node& node, const std::string& element,
                     const std::string& what) const {
    if (!node.IsScalar())
      fail(node, element, what + " must be a plain name or value, not a list or mapping");
    return node.Scalar();
  }
  std::string string_field(const YAML::Node& node, const std::string& key,
                           const std::string& element) const {
    const YAML::Node child = require(node, key, element);
    if (!child.IsScalar()) fail(child, element, "field '" + key + "' must be a string");
    return child.Scalar();
  }
  std::vector<double> numbers(const YAML::Node& node, const std::string& element,
                              const std::string& field, size_t count, double scale = 1.0,
                              Quantity quantity = Quantity::general) const {
    if (!node.IsSequence() || (count > 0 && node.size() != count))
      fail(node, element,
           "field '" + field + "' must be a list of " +
               (count > 0 ? std::to_string(count) + " numbers" : std::string("numbers")));
    std::vector<double> out;
    for (const auto& item : node) out.push_back(number(item, element, field, scale, quantity));
    return out;
  }
  // `friction: {coefficient: μ, radius: r}` of a joint (0 ≤ μ ≤ 10, 0 < r ≤ kMaxLength), or
  // nothing.
  std::optional<JointFriction> joint_friction(const YAML::Node& item, const std::string& element,
                                              double length_scale) const {
    const YAML::Node f = item["friction"];
    if (!f) return std::nullopt;
    if (!f.IsMap()) fail(f, element, "friction must be a mapping {coefficient: MU, radius: R}");
    expect_map(f, element + ": friction", {"coefficient", "radius"});
    JointFriction out;
    out.coefficient = number_field(f, "coefficient", element);
    if (!(out.coefficient >= 0.0 && out.coefficient <= 10.0))
      fail(f["coefficient"], element,
           "friction coefficient must be in [0, 10], got " + f["coefficient"].Scalar());
    out.radius = number_field(f, "radius", element, length_scale, Quantity::length);
    if (!(out.radius > 0.0))
      fail(f["radius"], element, "friction radius must be positive, got " + f["radius"].Scalar());
    return out;
  }
  // `limits: [min, max]` of a revolute or prismatic joint (min ≤ max), or nothing.
  std::optional<Vec2> joint_limits(const YAML::Node& item, const std::string& element, double scale,
                                   Quantity quantity) const {
    const YAML::Node l = item["limits"];
    if (!l) return std::nullopt;
    const auto v = numbers(l, element, "limits", 2, scale, quantity);
    if (!(v[0] <= v[1])) fail(l, element, "limits must be [min, max] with min ≤ max");
    return Vec2(v[0], v[1]);
  }
  // `end_stops: {restitution: e}` (0 ≤ e ≤ 1) of a joint with `limits`, or nothing.
  std::optional<double> end_stops(const YAML::Node& item, const std::string& element) const {
    const YAML::Node s = item["end_stops"];
    if (!s) return std::nullopt;
    if (!item["limits"])
      fail(s, element, "end_stops need the joint's limits: [min, max] (the stops are there)");
    expect_map(s, element + ": end_stops", {"restitution"});
    const double e = number_field(s, "restitution", element);
    if (!(e >= 0.0 && e <= 1.0))
      fail(s["restitution"], element,
           "end_stops restitution must be in [0, 1], got " + s["restitution"].Scalar());
    return e;
  }
  Vec2 vec2(const YAML::Node& node, const std::string& element, const std::string& field,
            double scale, Quantity quantity = Quantity::general) const {
    const auto v = numbers(node, element, field, 2, scale, quantity);
    return Vec2(v[0], v[1]);
  }
  std::string name_of(const YAML::Node& item, const std::string& kind, size_t index,
                      std::set<std::string>& seen) const {
    const std::string plural = kind == "body"              ? "bodies"
                               : kind == "design position" ? "design_positions"
                                                           : kind + "s";
    const std::string anonymous = plural + "[" + std::to_string(index) + "]";
    if (!item.IsMap()) fail(item, anonymous, "expected a mapping with a 'name'");
    std::string name = string_field(item, "name", anonymous);
    if (name.empty()) fail(item["name"], anonymous, "name is empty");
    if (!seen.insert(name).second)
      fail(item["name"], kind + " '" + name + "'",
           "duplicate name: '" + name + "' is defined twice");
    return name;
  }
  YAML::Node list(const YAML::Node& root, const std::string& key) const {
    const YAML::Node node = root[key];
    if (node && !node.IsNull() && !node.IsSequence())
      fail(node, key, "expected a list (items starting with '- ')");
    if (node && node.IsSequence() && node.size() > kMaxListItems)
      fail(node, key, "at most " + std::to_string(kMaxListItems) + " items");
    return node;
  }

  // ---- sections -------------------------------------------------------------------------------
  // name: [x, y] mappings (points); names unique, 'origin' reserved.
  std::vector<std::pair<std::string, Vec2>> points_map(const YAML::Node& pts,
                                                       const std::string& element) const {
    if (!pts.IsMap()) fail(pts, element, "field 'points' must be a mapping name: [x, y]");
    std::vector<std::pair<std::string, Vec2>> out;
    std::set<std::string> seen;
    for (const auto& kv : pts) {
      const std::string name = scalar(kv.first, element, "a point name");
      if (name == "origin") fail(kv.first, element, "point name 'origin' is reserved");
      if (name.find('.') != std::string::npos)
        fail(kv.first, element, "a point name must not contain '.'");
      if (!seen.insert(name).second)
        fail(kv.first, element, "point '" + name + "' is defined twice");
      out.emplace_back(name,
                       vec2(kv.second, element, "points." + name, units_.length, Quantity::length));
    }
    return out;
  }
  void read_units(const YAML::Node& node);
  void read_ground(const YAML::Node& node);
  void read_bodies(const YAML::Node& root);
  void read_joints(const YAML::Node& root);
  void read_nonholonomic(const YAML::Node& root);
  // Loads and measures: one loop for both dimensions; each item's type read by planar_* or
  // spatial_* (nothing for an unknown type).
  void read_loads(const YAML::Node& root);
  void read_measures(const YAML::Node& root);
  std::optional<LoadKind> planar_load(const YAML::Node& item, const std::string& element,
                                      const std::string& type);
  std::optional<MeasureKind> planar_measure(const YAML::Node& item, const std::string& element,
                                            const std::string& type, std::string& unit);
  struct SpringNumbers {
    double stiffness = 0.0, free_length = 0.0, damping = 0.0;  // rotary: free_length = free_angle
  };
  SpringNumbers spring_numbers(const YAML::Node& item, const std::string& element) const;
  SpringNumbers rotary_spring_numbers(const YAML::Node& item, const std::string& element) const;
  void check_gravity(const YAML::Node& item, const std::string& element, double gn);
  bool body_frame(const YAML::Node& item, const std::string& element) const;
  YAML::Node two_points(const YAML::Node& item, const std::string& element) const;
  std::pair<int, int> rigid_body_pair(const YAML::Node& item, const std::string& element) const;
  void read_drivers(const YAML::Node& root);
  void read_design_positions(const YAML::Node& root);
  void read_analysis(const YAML::Node& node);
  void read_initial(const YAML::Node& node);

  int body_ref(const YAML::Node& node, const std::string& element) const {
    if (!node.IsScalar()) fail(node, element, "expected a body name");
    const int b = model_.find_body(node.Scalar());
    if (b == -2) fail(node, element, "body '" + node.Scalar() + "' is not defined");
    return b;
  }
  int rigid_body_ref(const YAML::Node& node, const std::string& element) const {
    const int b = body_ref(node, element);
    if (b != kGround && model_.bodies[static_cast<size_t>(b)].kind == BodyKind::particle)
      fail(node, element, "body '" + node.Scalar() + "' is a particle and has no angle");
    return b;
  }
  // "body.point" → PointRef (s measured from the centre of mass).
  PointRef point_ref(const YAML::Node& node, const std::string& element) const {
    return point_reference<PointRef, Vec2>(
        node, element, ground_points_,
        [](const Body& b) -> const std::vector<std::pair<std::string, Vec2>>& { return b.points; },
        [](const Body& b) { return b.com_local; });
  }
  // "body.point" → a point reference of either dimension: Ref (PointRef, SpatialPointRef) with
  // s = the named point (or "origin") of the body's `points` minus its centre of mass; the ground's
  // points are world positions.
  template <typename Ref, typename Vec, typename PointsOf, typename ComOf>
  Ref point_reference(const YAML::Node& node, const std::string& element,
                      const std::vector<std::pair<std::string, Vec>>& ground, PointsOf points_of,
                      ComOf com_of) const {
    if (!node.IsScalar()) fail(node, element, "expected a point 'body.point'");
    const std::string& text = node.Scalar();
    const auto dot = text.find('.');
    if (dot == std::string::npos)
      fail(node, element, "expected a point 'body.point', got '" + text + "'");
    const std::string body = text.substr(0, dot), point = text.substr(dot + 1);
    Ref p;
    p.label = text;
    p.body = model_.find_body(body);
    if (p.body == -2) fail(node, element, "body '" + body + "' is not defined");
    const auto& points =
        p.body == kGround ? ground : points_of(model_.bodies[static_cast<size_t>(p.body)]);
    const auto it =
        std::find_if(points.begin(), points.end(), [&](const auto& e) { return e.first == point; });
    Vec local = Vec::Zero();
    if (it != points.end()) {
      local = it->second;
    } else if (point != "origin") {
      fail(node, element, "point '" + point + "' is not defined on body '" + body + "'");
    }
    p.s =
        p.body == kGround ? local : Vec(local - com_of(model_.bodies[static_cast<size_t>(p.body)]));
    return p;
  }
  std::pair<PointRef, PointRef> connects(const YAML::Node& item, const std::string& element) const {
    const YAML::Node c = require(item, "connects", element);
    if (!c.IsSequence() || c.size() != 2)
      fail(c, element, "field 'connects' must be a list of two points [body.point, body.point]");
    PointRef a = point_ref(c[0], element), b = point_ref(c[1], element);
    if (a.body == b.body)
      fail(c, element, "connects body '" + model_.body_name(a.body) + "' to itself");
    return {a, b};
  }
  Vec2 unit_axis(const YAML::Node& item, const std::string& element) const {
    const YAML::Node node = item["axis"];
    if (!node) return Vec2::UnitX();
    const Vec2 a = vec2(node, element, "axis", 1.0);
    const double norm = a.stableNorm();  // no underflow for tiny components
    if (!(norm > 0.0)) fail(node, element, "axis must not be zero");
    return a / norm;
  }
  double design_angle(int body) const {
    return body == kGround ? 0.0 : model_.bodies[static_cast<size_t>(body)].design_pose.z();
  }
  double speed_value(const YAML::Node& node, const std::string& element, bool angular) const;
  double speed_text(const std::string& text, bool angular, bool allow_zero = false) const;
  void read_parameters(const YAML::Node& node);
  Table table(const YAML::Node& node, const std::string& element) const;
  ActiveWhile active_while(const YAML::Node& node, const std::string& element) const;
  // The coordinate of joint j (planar or spatial): 0 none, 1 an angle, 2 a length.
  [[nodiscard]] int joint_coordinate(int j) const;

  // ---- spatial sections (`dimension: 3`), spatial_file.cpp --------------------------------------
  std::vector<std::pair<std::string, Vec3>> ground_points3_;
  void read_spatial(const YAML::Node& root);
  void read_spatial_ground(const YAML::Node& node);
  void read_spatial_bodies(const YAML::Node& root);
  void read_spatial_joints(const YAML::Node& root);
  void read_spatial_nonholonomic(const YAML::Node& root);
  std::optional<LoadKind> spatial_load(const YAML::Node& item, const std::string& element,
                                       const std::string& type);
  std::optional<MeasureKind> spatial_measure(const YAML::Node& item, const std::string& element,
                                             const std::string& type, std::string& unit);
  Vec3 vec3(const YAML::Node& node, const std::string& element, const std::string& field,
            double scale, Quantity quantity = Quantity::general) const;
  Vec3 unit_vec3(const YAML::Node& node, const std::string& element,
                 const std::string& field) const;
  std::vector<std::pair<std::string, Vec3>> points_map3(const YAML::Node& pts,
                                                        const std::string& element) const;
  Mat3 spatial_inertia(const YAML::Node& node, const std::string& element) const;
  void check_inertia(const YAML::Node& node, const std::string& element, const Mat3& J) const;
  Quat orientation(const YAML::Node& node, const std::string& element) const;
  SpatialPointRef spatial_point_ref(const YAML::Node& node, const std::string& element) const;
  // A design position's `target` in dimension 3 (docs/file-format.md "Design positions").
  DesignTarget spatial_target(const YAML::Node& t, const std::string& element) const;
  std::pair<SpatialPointRef, SpatialPointRef> spatial_connects(const YAML::Node& item,
                                                               const std::string& element) const;
  int spatial_body_ref(const YAML::Node& node, const std::string& element) const;
  void add_warning(const YAML::Node& node, const std::string& element, const std::string& message);
};

}  // namespace orthomech::detail
