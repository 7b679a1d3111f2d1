#include "orthomech/synthesis/task.hpp"

#include <yaml-cpp/yaml.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "../io/yaml_walk.hpp"
#include "orthomech/error.hpp"
#include "orthomech/io/units.hpp"

namespace orthomech::synthesis {

const char* to_string(TaskKind kind) noexcept {
  switch (kind) {
    case TaskKind::motion:
      return "motion";
    case TaskKind::path:
      return "path";
    case TaskKind::function:
      return "function";
  }
  return "?";
}

const char* to_string(TaskTiming timing) noexcept {
  switch (timing) {
    case TaskTiming::prescribed:
      return "prescribed";
    case TaskTiming::free_start:
      return "free_start";
    case TaskTiming::free:
      return "free";
  }
  return "?";
}

const char* to_string(TaskLinkage linkage) noexcept {
  switch (linkage) {
    case TaskLinkage::four_bar:
      return "four-bar";
    case TaskLinkage::slider_crank:
      return "slider-crank";
    case TaskLinkage::rssr:
      return "rssr";
  }
  return "?";
}

namespace {

// The most targets of a task: a least-squares fit of more is not a design task.
constexpr size_t kMaxTargets = 1000;

// Reads one task document; every refusal names the node's place (house style, "Errors").
class TaskReader {
 public:
  explicit TaskReader(std::string file) : file_(std::move(file)) {}

  SynthesisTask read(const YAML::Node& root) {
    expect_keys(root, "task file",
                {"orthomech-synthesis",
                 "name",
                 "units",
                 "task",
                 "poses",
                 "points",
                 "pairs",
                 "ground",
                 "timing",
                 "crank_angles",
                 "fixed_pivot",
                 "ground_angle",
                 "crank",
                 "follower",
                 "require",
                 "search",
                 "mechanism",
                 "rank_by",
                 "tolerance",
                 "linkage",
                 "axes",
                 "held"});
    if (!root["orthomech-synthesis"] || root["orthomech-synthesis"].as<std::string>() != "1")
      fail(root, "orthomech-synthesis",
           "a synthesis task starts with `orthomech-synthesis: 1` (the format's version)");
    SynthesisTask t;
    t.file = file_;
    t.name = root["name"] ? root["name"].as<std::string>() : "synthesis";
    units(root["units"], t);
    kind(root, t);
    linkage(root, t);
    targets(root, t);
    requirements(root, t);
    return t;
  }

 private:
  std::string file_;

  [[noreturn]] void fail(const YAML::Node& node, const std::string& element,
                         const std::string& message) const {
    orthomech::detail::fail_at(file_, node, element, message);
  }
  void expect_keys(const YAML::Node& node, const std::string& element,
                   const std::vector<std::string>& allowed) const {
    orthomech::detail::expect_keys(file_, node, element, allowed);
  }
  double number(const YAML::Node& node, const std::string& element, double lo, double hi) const {
    double v = 0.0;
    if (!node.IsScalar() || !YAML::convert<double>::decode(node, v) || !std::isfinite(v))
      fail(node, element, "expected a finite number");
    if (v < lo || v > hi) {
      std::ostringstream m;
      m << "must be in [" << lo << ", " << hi << "], got " << v;
      fail(node, element, m.str());
    }
    return v;
  }
  std::vector<double> row(const YAML::Node& node, const std::string& element, size_t size) const {
    if (!node.IsSequence() || node.size() != size)
      fail(node, element, "expected a list of " + std::to_string(size) + " numbers");
    std::vector<double> v;
    for (const auto& x : node) v.push_back(number(x, element, -kMaxGeneral, kMaxGeneral));
    return v;
  }
  // A list of rows of `size` numbers, between `least` and kMaxTargets of them.
  std::vector<std::vector<double>> rows(const YAML::Node& node, const std::string& element,
                                        size_t size, size_t least) const {
    if (!node.IsSequence()) fail(node, element, "expected a list");
    if (node.size() < least || node.size() > kMaxTargets)
      fail(node, element,
           "needs " + std::to_string(least) + " to " + std::to_string(kMaxTargets) +
               " entries, got " + std::to_string(node.size()));
    std::vector<std::vector<double>> out;
    for (const auto& r : node) out.push_back(row(r, element, size));
    return out;
  }

  void units(const YAML::Node& node, SynthesisTask& t) const {
    if (!node) return;
    expect_keys(node, "units", {"length", "angle"});
    DeclaredUnits d;
    d.length = node["length"] ? node["length"].as<std::string>() : "mm";
    d.angle = node["angle"] ? node["angle"].as<std::string>() : "deg";
    try {
      const UnitSystem u = unit_system(d);
      t.length_unit = u.length, t.angle_unit = u.angle;
      t.length_si = u.length_si, t.angle_si = u.angle_si;
    } catch (const std::invalid_argument& e) {
      fail(node, "units", e.what());
    }
  }

  void kind(const YAML::Node& root, SynthesisTask& t) const {
    const YAML::Node k = root["task"];
    if (!k) fail(root, "task", "missing `task:` (motion, path or function)");
    const std::string s = k.as<std::string>();
    if (s == "motion")
      t.kind = TaskKind::motion;
    else if (s == "path")
      t.kind = TaskKind::path;
    else if (s == "function")
      t.kind = TaskKind::function;
    else
      fail(k, "task", "unknown task '" + s + "' (motion, path or function)");
  }

  // `linkage: four-bar | slider-crank | rssr` (function and path tasks; default four-bar; an RSSR
  // generates functions only).
  void linkage(const YAML::Node& root, SynthesisTask& t) const {
    const YAML::Node k = root["linkage"];
    if (!k) return;
    const std::string s = k.IsScalar() ? k.as<std::string>() : "";
    if (s == "four-bar")
      t.linkage = TaskLinkage::four_bar;
    else if (s == "slider-crank")
      t.linkage = TaskLinkage::slider_crank;
    else if (s == "rssr")
      t.linkage = TaskLinkage::rssr;
    else
      fail(k, "linkage", "unknown linkage '" + s + "' (four-bar, slider-crank or rssr)");
    if (t.kind == TaskKind::motion && t.linkage != TaskLinkage::four_bar)
      fail(k, "linkage", "motion generation synthesises four-bars only");
    if (t.kind == TaskKind::path && t.linkage == TaskLinkage::rssr)
      fail(k, "linkage", "an RSSR is synthesised as a function generator (task: function) only");
  }

  void targets(const YAML::Node& root, SynthesisTask& t) const {
    const double L = t.length_si, A = t.angle_si;
    const auto only = [&](const char* key) {
      for (const char* k : {"poses", "points", "pairs", "ground", "timing", "crank_angles",
                            "fixed_pivot", "ground_angle", "crank", "follower"})
        if (root[k] && std::string(k) != key && !allowed_with(t.kind, k))
          fail(root[k], k,
               std::string("`") + k + "` does not belong to a " + to_string(t.kind) + " task");
    };
    if (t.linkage != TaskLinkage::rssr)
      for (const char* k : {"axes", "held"})
        if (root[k])
          fail(root[k], k,
               std::string("`") + k + "` belongs to an RSSR function task (`linkage: rssr`)");
    switch (t.kind) {
      case TaskKind::motion: {
        only("poses");
        if (!root["poses"])
          fail(root, "poses", "a motion task needs `poses: [[x, y, angle], ...]`");
        for (const auto& p : rows(root["poses"], "poses", 3, 2)) {
          t.positions.emplace_back(p[0] * L, p[1] * L);
          t.angles.push_back(p[2] * A);
        }
        given_pivots(root, t);
        break;
      }
      case TaskKind::path: {
        only("points");
        if (!root["points"]) fail(root, "points", "a path task needs `points: [[x, y], ...]`");
        for (const auto& p : rows(root["points"], "points", 2, 3))
          t.positions.emplace_back(p[0] * L, p[1] * L);
        path_timing(root, t);
        break;
      }
      case TaskKind::function: {
        only("pairs");
        if (t.linkage == TaskLinkage::slider_crank) {
          slider_pairs(root, t);
          break;
        }
        if (t.linkage == TaskLinkage::rssr) {
          rssr_pairs(root, t);
          break;
        }
        if (!root["pairs"])
          fail(root, "pairs", "a function task needs `pairs: [[input, output], ...]`");
        if (!root["ground"])
          fail(root, "ground", "a function task needs the ground length `ground:`");
        t.ground = number(root["ground"], "ground", 1e-9, kMaxGeneral) * L;
        for (const auto& p : rows(root["pairs"], "pairs", 2, 3)) {
          t.inputs.push_back(p[0] * A);
          t.outputs.push_back(p[1] * A);
        }
        break;
      }
    }
  }
  // A function task's `pairs` without a `ground` (a slider-crank, an RSSR): `needs` says what a
  // row is, `no_ground` why there is no ground length; the outputs in `output_si` per unit.
  void pairs_without_ground(const YAML::Node& root, SynthesisTask& t, const std::string& needs,
                            const std::string& no_ground, double output_si) const {
    if (!root["pairs"]) fail(root, "pairs", needs);
    if (root["ground"]) fail(root["ground"], "ground", no_ground);
    for (const auto& p : rows(root["pairs"], "pairs", 2, 3)) {
      t.inputs.push_back(p[0] * t.angle_si);
      t.outputs.push_back(p[1] * output_si);
    }
  }
  // A slider-crank's function pairs: [crank angle from the slider line, slider position]; no
  // ground length (the linkage's size follows from the positions).
  void slider_pairs(const YAML::Node& root, SynthesisTask& t) const {
    pairs_without_ground(
        root, t,
        "a slider-crank function task needs `pairs: [[crank angle, slider position], ...]`",
        "a slider-crank function task takes no `ground` (its pairs give the slider positions)",
        t.length_si);
  }
  // An RSSR's pairs [φ, ψ] (angles about the input and output axes), its `axes:` and `held:`.
  void rssr_pairs(const YAML::Node& root, SynthesisTask& t) const {
    pairs_without_ground(
        root, t, "an RSSR function task needs `pairs: [[input angle, output angle], ...]`",
        "an RSSR function task takes no `ground` (its axes place the frame: `axes:`)", t.angle_si);
    const YAML::Node axes = root["axes"];
    if (!axes || !axes.IsMap())
      fail(axes ? axes : root, "axes",
           "an RSSR task needs `axes: {input: {point: [x, y, z], direction: [x, y, z]}, output: "
           "{...}}` (an optional `ref:` per axis: the direction its angle is measured from)");
    expect_keys(axes, "axes", {"input", "output"});
    t.input_axis = axis(axes, "input", t.length_si);
    t.output_axis = axis(axes, "output", t.length_si);
    if (const YAML::Node h = root["held"]) {
      if (!h.IsMap()) fail(h, "held", "expected `held: {a: [x, y, z], b: [x, y, z]}`");
      expect_keys(h, "held", {"a", "b"});
      for (const char* key : {"a", "b"})
        if (const YAML::Node v = h[key]) {
          const auto xyz = row(v, std::string("held.") + key, 3);
          (std::string(key) == "a" ? t.held_a : t.held_b) =
              Vec3(xyz[0], xyz[1], xyz[2]) * t.length_si;
        }
    }
  }
  // One revolute axis of `axes:`: point (length units), direction and optional ref (unit-free).
  RevoluteAxis axis(const YAML::Node& axes, const char* role, double L) const {
    const YAML::Node a = axes[role];
    const std::string r = std::string("axes.") + role;
    if (!a || !a.IsMap())
      fail(a ? a : axes, r,
           "expected `" + std::string(role) +
               ": {point: [x, y, z], direction: "
               "[x, y, z]}` (and an optional `ref: [x, y, z]`)");
    expect_keys(a, r, {"point", "direction", "ref"});
    RevoluteAxis out;
    if (!a["point"] || !a["direction"]) fail(a, r, "an axis needs `point:` and `direction:`");
    const auto p = row(a["point"], r + ".point", 3), d = row(a["direction"], r + ".direction", 3);
    out.point = Vec3(p[0], p[1], p[2]) * L;
    out.direction = Vec3(d[0], d[1], d[2]);
    if (out.direction.norm() < 1e-12) fail(a["direction"], r + ".direction", "is a zero vector");
    if (const YAML::Node e = a["ref"]) {
      const auto v = row(e, r + ".ref", 3);
      const Vec3 ref(v[0], v[1], v[2]);
      if (ref.cross(out.direction.normalized()).norm() < 1e-9 * std::max(1.0, ref.norm()))
        fail(e, r + ".ref", "is zero or parallel to the axis' direction");
      out.reference = ref;
    }
    return out;
  }
  static bool allowed_with(TaskKind kind, const std::string& key) {
    if (kind == TaskKind::path)
      return key == "timing" || key == "crank_angles" || key == "fixed_pivot" ||
             key == "ground_angle";
    if (kind == TaskKind::function) return key == "ground";
    return key == "crank" || key == "follower";  // motion
  }

  // A motion task's `crank:` and `follower:` (2–4 poses): which pivots each pose count admits
  // (synthesize_motion_few_poses, docs/synthesis.md (L26)–(L32)).
  void given_pivots(const YAML::Node& root, SynthesisTask& t) const {
    const size_t n = t.positions.size();
    const YAML::Node poses = root["poses"];
    for (const char* role : {"crank", "follower"}) {
      const YAML::Node d = root[role];
      TaskPivots& p = std::string(role) == "crank" ? t.crank : t.follower;
      const std::string r = role;
      if (d && n >= 5)
        fail(d, role,
             "with " + std::to_string(n) +
                 " poses no pivot can be given: 5 poses allow only the finitely many Burmester "
                 "dyads (more: a least-squares fit); give pivots with 2 to 4 poses");
      if (n >= 5) continue;
      if (d) {
        if (!d.IsMap())
          fail(d, role,
               "expected `" + r +
                   ": {fixed_pivot: [x, y]}` or "
                   "`{moving_pivot: [x, y]}`");
        expect_keys(d, role, {"fixed_pivot", "moving_pivot"});
        for (const char* key : {"fixed_pivot", "moving_pivot"})
          if (const YAML::Node v = d[key]) {
            const auto xy = row(v, r + "." + key, 2);
            (std::string(key) == "fixed_pivot" ? p.fixed_pivot : p.moving_pivot) =
                Vec2(xy[0] * t.length_si, xy[1] * t.length_si);
          }
      }
      const YAML::Node at = d ? d : poses;
      const bool f = p.fixed_pivot.has_value(), m = p.moving_pivot.has_value();
      if (n == 2 && !(f && m))
        fail(at, role,
             "2 poses need the " + r + "'s moving pivot and a guess of its fixed pivot: `" + r +
                 ": {moving_pivot: [x, y], fixed_pivot: [x, y]}` (the moving pivot in the world "
                 "at the first pose; the guess moves onto the perpendicular bisector)");
      if (n == 3 && f == m)
        fail(at, role,
             "3 poses need exactly one of the " + r + "'s pivots: `" + r +
                 ": {fixed_pivot: [x, y]}` or `" + r +
                 ": {moving_pivot: [x, y]}` (in the world, at the first pose); the other "
                 "follows");
      if (n == 4 && f && m)
        fail(at, role,
             "4 poses take at most one of the " + r +
                 "'s pivots (the other follows from its curve)");
    }
  }

  void path_timing(const YAML::Node& root, SynthesisTask& t) const {
    const YAML::Node timing = root["timing"];
    const std::string s =
        timing ? timing.as<std::string>() : (root["crank_angles"] ? "prescribed" : "free");
    if (s == "prescribed")
      t.timing = TaskTiming::prescribed;
    else if (s == "free_start")
      t.timing = TaskTiming::free_start;
    else if (s == "free")
      t.timing = TaskTiming::free;
    else
      fail(timing, "timing", "unknown timing '" + s + "' (prescribed, free_start or free)");
    const YAML::Node angles = root["crank_angles"];
    if (t.timing == TaskTiming::free) {
      if (angles) fail(angles, "crank_angles", "free timing takes no crank angles");
    } else {
      if (!angles || !angles.IsSequence() || angles.size() != t.positions.size())
        fail(angles ? angles : root, "crank_angles",
             "timed points need one crank angle per point (" + std::to_string(t.positions.size()) +
                 ")");
      for (const auto& a : angles)
        t.inputs.push_back(number(a, "crank_angles", -kMaxGeneral, kMaxGeneral) * t.angle_si);
    }
    if (const YAML::Node p = root["fixed_pivot"]) {
      const auto v = row(p, "fixed_pivot", 2);
      t.fixed_pivot = Vec2(v[0] * t.length_si, v[1] * t.length_si);
    }
    if (const YAML::Node g = root["ground_angle"])
      t.ground_angle = number(g, "ground_angle", -kMaxGeneral, kMaxGeneral) * t.angle_si;
  }

  void requirements(const YAML::Node& root, SynthesisTask& t) const {
    if (const YAML::Node r = root["require"]) {
      expect_keys(r, "require", {"crank_rocker", "min_transmission"});
      if (r["crank_rocker"]) t.crank_rocker = r["crank_rocker"].as<bool>();
      if (t.crank_rocker && t.linkage != TaskLinkage::four_bar)
        fail(r["crank_rocker"], "crank_rocker",
             std::string("a Grashof crank-rocker is a four-bar requirement; this task's linkage "
                         "is a ") +
                 (t.linkage == TaskLinkage::rssr ? "spatial RSSR" : "slider-crank"));
      if (r["min_transmission"])
        t.min_transmission = number(r["min_transmission"], "min_transmission", 0.0,
                                    90.0 * 0.017453292519943295 / t.angle_si) *
                             t.angle_si;
    }
    if (const YAML::Node tol = root["tolerance"])
      t.tolerance = number(tol, "tolerance", 0.0, kMaxGeneral) * t.length_si;
    if (const YAML::Node s = root["search"]) {
      expect_keys(s, "search", {"seed", "starts"});
      if (s["seed"])
        t.seed = static_cast<unsigned long>(number(s["seed"], "seed", 0, 4294967295.0));
      if (s["starts"]) t.starts = static_cast<int>(number(s["starts"], "starts", 1, 100000));
    }
    if (const YAML::Node m = root["mechanism"]) {
      expect_keys(m, "mechanism", {"mass_per_length", "speed"});
      if (m["mass_per_length"])
        t.mass_per_length =
            number(m["mass_per_length"], "mass_per_length", 1e-12, 1e12) / t.length_si;
      if (m["speed"]) {
        try {
          t.speed = parse_speed(m["speed"].as<std::string>(), true, t.angle_si);
        } catch (const std::invalid_argument& e) {
          fail(m["speed"], "speed", e.what());
        }
      }
    }
    if (const YAML::Node r = root["rank_by"]) {
      t.rank_by = r.as<std::string>();
      if (t.rank_by != "transmission" && t.rank_by != "error" && t.rank_by != "drive_torque" &&
          t.rank_by != "pin_force")
        fail(r, "rank_by",
             "rank_by is `transmission` (the worst transmission angle, largest first), `error` "
             "(the distance to the targets), `drive_torque` (the peak drive torque over the "
             "cycle) or `pin_force` (the largest joint force over the cycle), smallest first");
    }
  }
};

}  // namespace

SynthesisTask parse_synthesis_task(const std::string& text, const std::string& origin) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw InputError({origin, e.mark.line + 1, e.mark.column + 1}, "YAML", e.msg);
  }
  if (!root.IsDefined() || root.IsNull())
    throw InputError({origin, 1, 1}, "task file", "the task file is empty");
  orthomech::detail::check_yaml_document(root, origin);
  try {
    return TaskReader(origin).read(root);
  } catch (const YAML::Exception& e) {
    throw InputError(
        {origin, e.mark.is_null() ? 1 : e.mark.line + 1, e.mark.is_null() ? 1 : e.mark.column + 1},
        "YAML", e.msg);
  }
}

SynthesisTask load_synthesis_task(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError({path, 0, 0}, "task file", "cannot open the task file");
  std::ostringstream text;
  text << in.rdbuf();
  return parse_synthesis_task(text.str(), path);
}

}  // namespace orthomech::synthesis
