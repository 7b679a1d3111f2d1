// The study file (docs/cli.md "sweep" and "optimize"): grid, Monte Carlo and optimize studies,
// read with every element checked against the mechanism file, errors at their line.
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

#include "../io/yaml_walk.hpp"
#include "orthomech/error.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/io/render.hpp"
#include "orthomech/io/units.hpp"
#include "orthomech/study/study.hpp"

namespace orthomech {

namespace {

constexpr long kMaxVariants = 1'000'000'000;

// ---- reading the study file ---------------------------------------------------------------------
class StudyReader {
 public:
  StudyReader(std::string file, const std::string& mechanism, std::string mechanism_origin)
      : file_(std::move(file)),
        mechanism_(mechanism),
        mechanism_origin_(std::move(mechanism_origin)) {}

  Study read(const YAML::Node& root) {
    if (!root.IsMap()) fail(root, "study", "expected a mapping (study: grid, parameters: ...)");
    expect_keys(root, "study",
                {"study", "samples", "seed", "steps", "parameters", "best", "metrics",
                 "expressions", "objective", "constraints", "algorithm", "evaluations", "tolerance",
                 "starts", "drivers", "t_end"});
    Study s;
    const YAML::Node kind = require(root, "study", "study");
    const std::string k = kind.IsScalar() ? kind.Scalar() : "";
    if (k == "grid")
      s.kind = StudyKind::grid;
    else if (k == "monte-carlo")
      s.kind = StudyKind::monte_carlo;
    else if (k == "optimize")
      s.kind = StudyKind::optimize;
    else
      fail(kind, "study", "study must be 'grid', 'monte-carlo' or 'optimize', got '" + k + "'");
    if (s.kind == StudyKind::monte_carlo) {
      s.samples = integer(require(root, "samples", "study"), "study", "samples", 1, kMaxVariants);
      if (root["seed"])
        s.seed = static_cast<std::uint64_t>(integer(root["seed"], "study", "seed", 0, 1L << 62));
    } else if (root["samples"] || (root["seed"] && s.kind != StudyKind::optimize)) {
      fail(root["samples"] ? root["samples"] : root["seed"], "study",
           "'samples' and 'seed' belong to a monte-carlo study");
    }
    if (s.kind == StudyKind::optimize) {
      if (root["seed"])
        s.seed = static_cast<std::uint64_t>(integer(root["seed"], "study", "seed", 0, 1L << 62));
      goal(root, s.goal);
    } else {
      for (const char* key :
           {"objective", "constraints", "algorithm", "evaluations", "tolerance", "starts"})
        if (root[key])
          fail(root[key], "study", std::string("'") + key + "' belongs to an optimize study");
    }
    if (root["steps"])
      s.steps = static_cast<int>(integer(root["steps"], "study", "steps", 2, kMaxCycleSteps));
    drivers(root, s);
    const YAML::Node params = require(root, "parameters", "study");
    if (!params.IsSequence() || params.size() == 0)
      fail(params, "parameters", "expected a list of parameters (- {path: ..., values: [...]})");
    // Column names are SQL identifiers (study_db.cpp): equal up to case is the same column.
    std::set<std::string> names{"variant", "status", "message"}, paths;
    for (const auto& item : params) {
      StudyParameter p = parameter(item, s.kind);
      const std::string element = "parameter '" + p.name + "'";
      if (!paths.insert(p.path).second)
        fail(item["path"], element, "path '" + p.path + "' is listed twice");
      if (!names.insert(folded(p.name)).second)
        fail(item, element,
             is_column(p.name) ? "the name '" + p.name +
                                     "' is a column of the study's table (variant, status, "
                                     "message): give the parameter another name"
                               : "the name is listed twice (names equal up to case are one "
                                 "column)");
      s.parameters.push_back(std::move(p));
    }
    if (const YAML::Node best = root["best"]) {
      if (s.kind != StudyKind::grid) fail(best, "best", "'best' belongs to a grid study");
      expect_keys(best, "best", {"metric", "order", "count"});
      if (best["metric"]) s.best_metric = text(best["metric"], "best", "metric");
      if (best["order"]) {
        const std::string o = text(best["order"], "best", "order");
        if (o != "min" && o != "max") fail(best["order"], "best", "order must be 'min' or 'max'");
        s.best_largest = o == "max";
      }
      if (best["count"])
        s.best_count = static_cast<int>(integer(best["count"], "best", "count", 1, 1000));
    }
    if (variant_count(s) > kMaxVariants)
      fail(params, "parameters", "the grid has more than 1e9 variants");
    if (const YAML::Node m = root["metrics"]) s.metrics = metrics(m);
    if (const YAML::Node e = root["expressions"]) s.metrics.expressions = expressions(e);
    add_goal_expressions(root, s);
    try {
      s.metrics.at = measure_at_requests(s.metrics.expressions);
    } catch (const std::invalid_argument& e) {
      fail(root["expressions"] ? root["expressions"] : root, "expressions", e.what());
    }
    if (!s.drivers.empty() && !s.metrics.at.empty())
      fail(root["expressions"] ? root["expressions"] : root, "expressions",
           "at(" + s.metrics.at.front().measure +
               ", …) needs the input of one driver; a study with several drivers has none");
    if (!s.drivers.empty() && !s.metrics.deviation.empty())
      fail(root["metrics"], "metrics",
           "'deviation' compares paths at the inputs of one driver; a study with several drivers "
           "has none");
    check_metric_names(root, s);
    return s;
  }

 private:
  std::string file_;
  const std::string& mechanism_;
  std::string mechanism_origin_;
  mutable std::vector<YAML::Node> goal_nodes_;  // the goal's expressions' nodes, in order

  [[noreturn]] void fail(const YAML::Node& node, const std::string& element,
                         const std::string& message) const {
    detail::fail_at(file_, node, element, message);
  }
  void expect_keys(const YAML::Node& node, const std::string& element,
                   const std::vector<std::string>& allowed) const {
    detail::expect_keys(file_, node, element, allowed);
  }
  YAML::Node require(const YAML::Node& node, const std::string& key,
                     const std::string& element) const {
    const YAML::Node child = node[key];
    if (!child || child.IsNull()) fail(node, element, "missing field '" + key + "'");
    return child;
  }
  std::string text(const YAML::Node& node, const std::string& element,
                   const std::string& field) const {
    if (!node.IsScalar() || node.Scalar().empty())
      fail(node, element, "field '" + field + "' must be text");
    return node.Scalar();
  }
  double number(const YAML::Node& node, const std::string& element,
                const std::string& field) const {
    double v = 0.0;
    if (!node.IsScalar() || !YAML::convert<double>::decode(node, v) || !std::isfinite(v))
      fail(node, element, "field '" + field + "' must be a finite number");
    return v;
  }
  long integer(const YAML::Node& node, const std::string& element, const std::string& field,
               long lo, long hi) const {
    long v = 0;
    if (!node.IsScalar() || !YAML::convert<long>::decode(node, v) || v < lo || v > hi)
      fail(node, element,
           "field '" + field + "' must be an integer from " + std::to_string(lo) + " to " +
               std::to_string(hi));
    return v;
  }
  // The file's value at the path (the path must name a single value of the file).
  std::string file_text(const YAML::Node& item, const StudyParameter& p,
                        const std::string& element) const {
    try {
      return file_value(mechanism_, mechanism_origin_, p.path);
    } catch (const InputError& e) {
      fail(item["path"], element,
           "path '" + p.path + "' in " + mechanism_origin_ + ": " + e.message());
    }
  }
  // drivers: [A, B] (the file's drivers, each once) and t_end: T (the file's time unit, > 0).
  void drivers(const YAML::Node& root, Study& s) const {
    const YAML::Node list = root["drivers"];
    if (!list) {
      if (root["t_end"]) fail(root["t_end"], "study", "'t_end' belongs to a study with 'drivers'");
      return;
    }
    if (!list.IsSequence() || list.size() == 0)
      fail(list, "drivers", "expected a list of the file's drivers ([left, right])");
    const Model model = parse_mechanism(mechanism_, mechanism_origin_, {});
    std::string known;
    for (const Driver& d : model.drivers) known += (known.empty() ? "" : ", ") + d.name;
    for (const auto& item : list) {
      const std::string name = text(item, "drivers", "driver");
      if (std::none_of(model.drivers.begin(), model.drivers.end(),
                       [&](const Driver& d) { return d.name == name; }))
        fail(item, "drivers",
             "the file has no driver '" + name + "' (it has " +
                 (known.empty() ? std::string("none") : known) + ")");
      if (std::find(s.drivers.begin(), s.drivers.end(), name) != s.drivers.end())
        fail(item, "drivers", "driver '" + name + "' is listed twice");
      s.drivers.push_back(name);
    }
    if (const YAML::Node t = root["t_end"]) {
      const double value = number(t, "study", "t_end");
      if (!(value > 0.0) || !std::isfinite(value))
        fail(t, "study", "t_end must be a positive time (the file's time unit)");
      s.t_end = value * unit_system(model.units).time_si;
    }
  }

  // The file's value at the path, as a number (the nominal value of a tolerance).
  double nominal(const YAML::Node& item, const StudyParameter& p, const std::string& element,
                 const std::string& value) const {
    double v = 0.0;
    const auto [end, ec] = std::from_chars(value.data(), value.data() + value.size(), v);
    if (ec != std::errc() || end != value.data() + value.size())
      fail(item, element,
           "the file's value at '" + p.path + "' is '" + value +
               "', not a number: give the nominal value as 'mean'");
    return v;
  }

  static std::string folded(std::string name) {
    for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return name;
  }
  static bool is_column(const std::string& name) {
    const std::string f = folded(name);
    return f == "variant" || f == "status" || f == "message";
  }

  // The metric columns the study will have, from its first variant (the columns depend on the
  // mechanism: one per joint reaction, a transmission angle per four-bar loop): `best: metric`
  // must be one of them, and no parameter may share a name with one (one SQL column each).
  void check_metric_names(const YAML::Node& root, const Study& s) const;

  bool flag(const YAML::Node& node, const std::string& field) const {
    bool v = false;
    if (!node.IsScalar() || !YAML::convert<bool>::decode(node, v))
      fail(node, "metrics", "field '" + field + "' must be true or false");
    return v;
  }

  // metrics: {cycle: true, validate: true, assemble: true, deviation: [coupler.P]}: the blocks
  // listed true are computed (the others not); the deviation points must be points of moving
  // bodies of the mechanism file.
  StudyMetrics metrics(const YAML::Node& node) const {
    expect_keys(node, "metrics", {"cycle", "validate", "assemble", "deviation"});
    StudyMetrics m;
    m.cycle = node["cycle"] && flag(node["cycle"], "cycle");
    m.validate = node["validate"] && flag(node["validate"], "validate");
    m.assemble = node["assemble"] && flag(node["assemble"], "assemble");
    if (const YAML::Node d = node["deviation"]) {
      if (d.IsScalar()) {
        m.deviation.push_back(text(d, "metrics", "deviation"));
      } else if (d.IsSequence() && d.size() > 0) {
        for (const auto& p : d) m.deviation.push_back(text(p, "metrics", "deviation"));
      } else {
        fail(d, "metrics", "field 'deviation' must be a point body.point or a list of them");
      }
      std::set<std::string> seen;
      for (const std::string& p : m.deviation)
        if (!seen.insert(p).second) fail(d, "metrics", "deviation: point '" + p + "' listed twice");
      const Model model = parse_mechanism(mechanism_, mechanism_origin_, {});
      const TracePoints points = resolve_trace_points(model, m.deviation);
      if (points.status == TraceStatus::bad_request) {
        std::string message = points.message;
        if (message.rfind("--trace: ", 0) == 0) message = message.substr(9);
        fail(d, "metrics", "deviation: " + message + " in " + mechanism_origin_);
      }
    }
    if (!m.cycle && !m.validate && !m.assemble && m.deviation.empty())
      fail(node, "metrics",
           "no metric block is on: set cycle, validate or assemble true, or list deviation points");
    return m;
  }

  // objective: {minimize: EXPR} or {maximize: EXPR}; constraints: [{metric: EXPR, min: a},
  // {metric: EXPR, max: b}, {metric: EXPR, equal: c, tolerance: t}]; algorithm: cobyla | isres;
  // evaluations: N; tolerance: share of each variable's span.
  void goal(const YAML::Node& root, OptimizeGoal& g) const {
    const YAML::Node objective = require(root, "objective", "study");
    if (!objective.IsMap())
      fail(objective, "objective", "expected {minimize: METRIC} or {maximize: METRIC}");
    expect_keys(objective, "objective", {"minimize", "maximize"});
    if (objective.size() != 1) fail(objective, "objective", "give one of minimize, maximize");
    g.maximize = static_cast<bool>(objective["maximize"]);
    g.objective = text(objective[g.maximize ? "maximize" : "minimize"], "objective", "metric");
    if (const YAML::Node list = root["constraints"]) {
      if (!list.IsSequence())
        fail(list, "constraints", "expected a list of {metric: ..., min: | max: | equal: ...}");
      for (const auto& item : list) {
        const std::string element = "constraint " + std::to_string(g.constraints.size() + 1);
        if (!item.IsMap()) fail(item, element, "expected {metric: ..., min: | max: | equal: ...}");
        expect_keys(item, element, {"metric", "min", "max", "equal", "tolerance"});
        OptimizeConstraint c;
        c.text = text(require(item, "metric", element), element, "metric");
        int kinds = 0;
        for (const char* key : {"min", "max", "equal"}) kinds += item[key] ? 1 : 0;
        if (kinds != 1) fail(item, element, "give exactly one of min, max, equal");
        const char* key = item["min"] ? "min" : item["max"] ? "max" : "equal";
        c.kind = item["min"]   ? OptimizeConstraint::Kind::at_least
                 : item["max"] ? OptimizeConstraint::Kind::at_most
                               : OptimizeConstraint::Kind::equal;
        c.bound = number(item[key], element, key);
        if (item["tolerance"]) {
          if (c.kind != OptimizeConstraint::Kind::equal)
            fail(item["tolerance"], element, "'tolerance' belongs to an 'equal' constraint");
          c.tolerance = number(item["tolerance"], element, "tolerance");
          if (!(c.tolerance >= 0.0)) fail(item["tolerance"], element, "tolerance must be ≥ 0");
        } else if (c.kind == OptimizeConstraint::Kind::equal) {
          c.tolerance = 1e-4 * std::max(std::abs(c.bound), 1.0);
        }
        g.constraints.push_back(std::move(c));
      }
    }
    if (const YAML::Node a = root["algorithm"]) {
      const std::string name = text(a, "study", "algorithm");
      if (name == "cobyla")
        g.algorithm = OptimizeGoal::Algorithm::cobyla;
      else if (name == "isres")
        g.algorithm = OptimizeGoal::Algorithm::isres;
      else if (name == "multistart")
        g.algorithm = OptimizeGoal::Algorithm::multistart;
      else
        fail(a, "study",
             "algorithm must be 'cobyla' (local), 'isres' (global) or 'multistart' (COBYLA from "
             "several starts, in parallel), got '" +
                 name + "'");
    }
    if (const YAML::Node n = root["starts"]) {
      if (g.algorithm != OptimizeGoal::Algorithm::multistart)
        fail(n, "study", "'starts' belongs to algorithm: multistart");
      g.starts = integer(n, "study", "starts", 1, 10'000);
    }
    if (root["evaluations"])
      g.evaluations = integer(root["evaluations"], "study", "evaluations", 1, 1'000'000);
    if (const YAML::Node t = root["tolerance"]) {
      g.tolerance = number(t, "study", "tolerance");
      if (!(g.tolerance > 0.0 && g.tolerance < 1.0))
        fail(t, "study", "tolerance must be between 0 and 1 (a share of each variable's span)");
    }
  }

  // The objective and the constraints as the expression columns `objective`, `constraint.1`, …
  // after the file's own expressions (checked with them on the nominal design).
  void add_goal_expressions(const YAML::Node& root, Study& s) const {
    if (s.kind != StudyKind::optimize) return;
    s.metrics.expressions.push_back({"objective", s.goal.objective});
    goal_nodes_.push_back(root["objective"][s.goal.maximize ? "maximize" : "minimize"]);
    for (size_t k = 0; k < s.goal.constraints.size(); ++k) {
      s.metrics.expressions.push_back(
          {"constraint." + std::to_string(k + 1), s.goal.constraints[k].text});
      goal_nodes_.push_back(root["constraints"][k]["metric"]);
    }
  }

  // expressions: {swing: range(rocker_angle), error: range(rocker_angle) - 75}: named
  // expressions of the metric columns, in order (each may use the ones before it).
  std::vector<MetricExpression> expressions(const YAML::Node& node) const {
    if (!node.IsMap() || node.size() == 0)
      fail(node, "expressions", "expected a mapping of names to expressions (swing: range(x))");
    std::vector<MetricExpression> list;
    for (const auto& item : node) {
      const std::string name = text(item.first, "expressions", "name");
      const bool identifier =
          (std::isalpha(static_cast<unsigned char>(name[0])) != 0 || name[0] == '_') &&
          std::all_of(name.begin(), name.end(), [](char c) {
            return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_' || c == '.';
          });
      if (!identifier)
        fail(item.first, "expressions",
             "the name '" + name + "' must be letters, digits, '_' and '.', a letter first");
      list.push_back({name, text(item.second, "expression '" + name + "'", "expression")});
    }
    return list;
  }

  StudyParameter parameter(const YAML::Node& item, StudyKind kind) const {
    if (!item.IsMap()) fail(item, "parameters", "expected a mapping {path: ..., values: [...]}");
    expect_keys(item, "parameters",
                {"path", "name", "values", "range", "normal", "uniform", "bounds", "start"});
    StudyParameter p;
    p.path = text(require(item, "path", "parameters"), "parameters", "path");
    p.name = item["name"] ? text(item["name"], "parameters", "name") : p.path;
    const std::string element = "parameter '" + p.name + "'";
    const std::string nominal_text = file_text(item, p, element);
    check_file_number(item, p, element);
    if (kind == StudyKind::optimize) return bounded(item, std::move(p), element, nominal_text);
    int laws = 0;
    for (const char* key : {"values", "range", "normal", "uniform"}) laws += item[key] ? 1 : 0;
    if (laws != 1 || item["bounds"] || item["start"])
      fail(item, element,
           "give exactly one of values, range (grid), normal, uniform (monte-carlo)"
           " (bounds and start: an optimize study)");
    const bool grid_law = item["values"] || item["range"];
    if (grid_law != (kind == StudyKind::grid))
      fail(item, element,
           kind == StudyKind::grid ? "a grid study takes values or range"
                                   : "a monte-carlo study takes normal or uniform");
    if (const YAML::Node v = item["values"]) {
      if (!v.IsSequence() || v.size() == 0) fail(v, element, "values must be a list of numbers");
      for (const auto& x : v) p.values.push_back(number(x, element, "values"));
    } else if (const YAML::Node r = item["range"]) {
      expect_keys(r, element, {"from", "to", "step", "steps"});
      const double from = number(require(r, "from", element), element, "from");
      const double to = number(require(r, "to", element), element, "to");
      if (r["step"] && r["steps"]) fail(r, element, "give step or steps, not both");
      long count = 0;
      if (r["steps"]) {
        count = integer(r["steps"], element, "steps", 1, 1'000'000);
        for (long i = 0; i <= count; ++i)
          p.values.push_back(from + (to - from) * double(i) / double(count));
      } else {
        const double step = number(require(r, "step", element), element, "step");
        if (!(step > 0.0) || (to - from) / step > 1e6)
          fail(r["step"], element, "step must be positive and give at most 1e6 values");
        const long n = static_cast<long>(std::floor((to - from) / step * (1 + 1e-12)));
        if (n < 0) fail(r, element, "the range is empty (from > to)");
        for (long i = 0; i <= n; ++i) p.values.push_back(from + step * double(i));
      }
    } else {
      const bool normal = static_cast<bool>(item["normal"]);
      const YAML::Node law = normal ? item["normal"] : item["uniform"];
      const char* spread = normal ? "sigma" : "tolerance";
      expect_keys(law, element, {"mean", spread});
      p.law = normal ? StudyParameter::Law::normal : StudyParameter::Law::uniform;
      const double w = number(require(law, spread, element), element, spread);
      if (!(w >= 0.0)) fail(law[spread], element, std::string(spread) + " must be ≥ 0");
      (normal ? p.sigma : p.tolerance) = w;
      p.mean = law["mean"] ? number(law["mean"], element, "mean")
                           : nominal(item, p, element, nominal_text);
      check_law_range(law, p, element, normal);
    }
    if (!p.values.empty()) {
      const auto [lo, hi] = std::minmax_element(p.values.begin(), p.values.end());
      check_value(item[item["values"] ? "values" : "range"], p, element, *lo, "the smallest value");
      check_value(item[item["values"] ? "values" : "range"], p, element, *hi, "the largest value");
    }
    return p;
  }

  // An optimisation's design variable: bounds: [lower, upper], start (default: the file's value);
  // both ends and the start valid values of the file's field.
  StudyParameter bounded(const YAML::Node& item, StudyParameter p, const std::string& element,
                         const std::string& nominal_text) const {
    for (const char* key : {"values", "range", "normal", "uniform"})
      if (item[key]) fail(item[key], element, "an optimize study takes bounds: [lower, upper]");
    const YAML::Node b = require(item, "bounds", element);
    if (!b.IsSequence() || b.size() != 2) fail(b, element, "bounds must be [lower, upper]");
    p.law = StudyParameter::Law::bounds;
    p.lower = number(b[0], element, "bounds");
    p.upper = number(b[1], element, "bounds");
    if (!(p.lower < p.upper) || !std::isfinite(p.upper - p.lower))
      fail(b, element, "bounds must be [lower, upper] with lower < upper");
    p.mean = item["start"] ? number(item["start"], element, "start")
                           : nominal(item, p, element, nominal_text);
    if (p.mean < p.lower || p.mean > p.upper)
      fail(item["start"] ? item["start"] : b, element,
           "the start (" + value_text(p.mean) + ") is outside the bounds");
    check_value(b, p, element, p.lower, "the lower bound");
    check_value(b, p, element, p.upper, "the upper bound");
    check_value(item, p, element, p.mean, "the start");
    return p;
  }

  // The values a law draws lie in mean ± kLawReach spreads (a normal law beyond 10 σ: below
  // 1e-23 per draw; a uniform one within mean ± tolerance): they must be finite numbers there —
  // and the law's mean and both ends valid values of the file's field, checked by reading the
  // mechanism with them (the same limits as a number written in the file, docs/file-format.md).
  void check_law_range(const YAML::Node& law, const StudyParameter& p, const std::string& element,
                       bool normal) const {
    const double reach = normal ? 10.0 * p.sigma : p.tolerance;
    const double lo = p.mean - reach, hi = p.mean + reach;
    if (!std::isfinite(lo) || !std::isfinite(hi) || !std::isfinite(hi - lo))
      fail(law, element,
           std::string("mean ± ") + (normal ? "10 sigma" : "tolerance") +
               " must be finite numbers (the law draws its values there)");
    check_value(law, p, element, p.mean, "the mean");
    if (!normal) {
      check_value(law, p, element, lo, "mean − tolerance");
      check_value(law, p, element, hi, "mean + tolerance");
    }
  }

  // The field at the path must be read as a number: a text value there (a name, a description)
  // is refused, found by reading the mechanism with a word that no number field accepts.
  void check_file_number(const YAML::Node& item, const StudyParameter& p,
                         const std::string& element) const {
    try {
      (void)parse_mechanism(mechanism_, mechanism_origin_, {{p.path, "orthomech_not_a_number"}});
    } catch (const InputError&) {
      return;  // refused as a number field refuses a word
    }
    fail(item["path"], element,
         "path '" + p.path + "' in " + mechanism_origin_ +
             " is not a number (a word is accepted there): a study varies numbers");
  }

  // One value the parameter takes, read into the mechanism as a variant would be.
  void check_value(const YAML::Node& node, const StudyParameter& p, const std::string& element,
                   double v, const std::string& which) const {
    try {
      (void)parse_mechanism(mechanism_, mechanism_origin_, {{p.path, value_text(v)}});
    } catch (const InputError& e) {
      fail(node, element, which + " (" + value_text(v) + ") is not a valid value: " + e.message());
    }
  }
};

}  // namespace

namespace {

// A name of the form of a metric column (cycle_metrics, validate_metrics, assemble_metrics,
// deviation_metrics): only those can collide with one.
bool could_be_metric(const std::string& name) {
  if (name == "dead_points") return true;
  const auto ends_with = [&](const std::string& tail) {
    return name.size() >= tail.size() &&
           name.compare(name.size() - tail.size(), tail.size(), tail) == 0;
  };
  for (const char* head :
       {"drive.", "power.", "transmission.", "pressure.", "validate.", "assemble.", "deviation."})
    if (name.rfind(head, 0) == 0) return true;
  for (const std::string& tail : measure_metric_suffixes())
    if (ends_with(tail)) return true;
  return ends_with(".peak");
}

}  // namespace

void StudyReader::check_metric_names(const YAML::Node& root, const Study& s) const {
  const YAML::Node best = root["best"];
  const bool best_given = best && best["metric"];
  const bool collide = std::any_of(s.parameters.begin(), s.parameters.end(),
                                   [](const StudyParameter& p) { return could_be_metric(p.name); });
  const std::vector<MetricExpression>& expressions = s.metrics.expressions;
  if (!best_given && !collide && expressions.empty()) return;
  // The nominal design (the file unchanged) gives the metric columns of the study; its
  // expressions are evaluated here, each refused at its line when it cannot be.
  Study nominal = s;
  nominal.parameters.clear();
  nominal.metrics.expressions.clear();
  VariantResult r = evaluate_variant(mechanism_, mechanism_origin_, nominal, 0, {});
  if (r.metrics.empty()) return;  // no column known: the nominal has none to compare with
  // The file's units, for the expressions' numbers with a unit (the nominal read: it is valid).
  const UnitSystem units = unit_system(parse_mechanism(mechanism_, mechanism_origin_, {}).units);
  const YAML::Node listed = root["expressions"];
  for (size_t k = 0; k < expressions.size(); ++k) {
    const MetricExpression& e = expressions[k];
    for (const auto& [name, value] : r.metrics)
      if (folded(name) == folded(e.name))
        fail(listed, "expression '" + e.name + "'", "the name is that of a metric column");
    for (const StudyParameter& p : s.parameters)
      if (folded(p.name) == folded(e.name))
        fail(listed, "expression '" + e.name + "'", "the name is that of a parameter");
    if (is_column(e.name))
      fail(listed, "expression '" + e.name + "'", "the name is a column of the study's table");
    double v = 0.0;
    try {
      v = evaluate_metric_expression(e.text, r.metrics, &units);
    } catch (const std::invalid_argument& error) {
      YAML::Node at;
      const size_t own = expressions.size() - goal_nodes_.size();  // the file's expressions first
      if (k >= own) {
        at = goal_nodes_[k - own];
      } else {
        for (const auto& item : listed)
          if (item.first.Scalar() == e.name) at = item.second;
      }
      fail(
          at,
          k >= own ? (e.name == "objective" ? "objective" : e.name) : "expression '" + e.name + "'",
          error.what());
    }
    r.metrics.emplace_back(e.name, v);
  }
  std::string names;
  for (const auto& [name, value] : r.metrics) names += (names.empty() ? "" : ", ") + name;
  for (size_t j = 0; j < s.parameters.size(); ++j)
    for (const auto& [name, value] : r.metrics)
      if (folded(name) == folded(s.parameters[j].name))
        fail(root["parameters"][j], "parameter '" + s.parameters[j].name + "'",
             "the name is that of a metric column: give the parameter another name");
  if (best_given && std::none_of(r.metrics.begin(), r.metrics.end(),
                                 [&](const auto& m) { return m.first == s.best_metric; }))
    fail(best["metric"], "best",
         "unknown metric '" + s.best_metric + "' (the study's metrics: " + names + ")");
}

Study parse_study(const std::string& text, const std::string& origin, const std::string& mechanism,
                  const std::string& mechanism_origin) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw InputError({origin, e.mark.line + 1, e.mark.column + 1}, "YAML", e.msg);
  }
  if (!root.IsDefined() || root.IsNull())
    throw InputError({origin, 1, 1}, "study", "the study file is empty");
  detail::check_yaml_document(root, origin);
  try {
    return StudyReader(origin, mechanism, mechanism_origin).read(root);
  } catch (const YAML::Exception& e) {
    throw InputError(
        {origin, e.mark.is_null() ? 1 : e.mark.line + 1, e.mark.is_null() ? 1 : e.mark.column + 1},
        "YAML", e.msg);
  }
}

std::string study_identity(const std::string& text, const std::string& origin) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw InputError({origin, e.mark.line + 1, e.mark.column + 1}, "YAML", e.msg);
  }
  if (!root.IsMap() || !root["study"] || !root["study"].IsScalar()) return text;
  const std::string kind = root["study"].Scalar();
  const char* key = kind == "monte-carlo" ? "samples" : kind == "optimize" ? "evaluations" : "";
  if (*key == '\0' || !root[key] || !root[key].IsScalar()) return text;
  const YAML::Node samples = root[key];
  const std::string& value = samples.Scalar();
  const auto at = static_cast<size_t>(std::max(0, samples.Mark().pos));
  if (samples.Mark().pos < 0 || text.compare(at, value.size(), value) != 0) return text;
  std::string identity = text;
  identity.replace(at, value.size(), "N");
  return identity;
}

Study load_study(const std::string& path, const std::string& mechanism,
                 const std::string& mechanism_origin) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError({path, 0, 0}, "study", "cannot open the study file");
  std::ostringstream text;
  text << in.rdbuf();
  return parse_study(text.str(), path, mechanism, mechanism_origin);
}

}  // namespace orthomech
