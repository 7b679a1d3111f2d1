#include "orthomech/study/study.hpp"

#include <omp.h>
#include <yaml-cpp/yaml.h>

#include <Eigen/LU>
#include <Eigen/QR>
#include <algorithm>
#include <boost/math/distributions/students_t.hpp>
#include <boost/random/mersenne_twister.hpp>
#include <boost/random/normal_distribution.hpp>
#include <boost/random/uniform_real_distribution.hpp>
#include <charconv>
#include <cmath>
#include <exception>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>
#include <variant>

#include "orthomech/analysis/cycle.hpp"
#include "orthomech/analysis/cycle_metrics.hpp"
#include "orthomech/error.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/io/units.hpp"

namespace orthomech {

namespace {

constexpr long kMaxVariants = 1'000'000'000;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// ---- reading the study file ---------------------------------------------------------------------
class StudyReader {
 public:
  StudyReader(std::string file, const std::string& mechanism, std::string mechanism_origin)
      : file_(std::move(file)),
        mechanism_(mechanism),
        mechanism_origin_(std::move(mechanism_origin)) {}

  Study read(const YAML::Node& root) {
    if (!root.IsMap()) fail(root, "study", "expected a mapping (study: grid, parameters: ...)");
    expect_keys(root, "study", {"study", "samples", "seed", "steps", "parameters", "best"});
    Study s;
    const YAML::Node kind = require(root, "study", "study");
    const std::string k = kind.IsScalar() ? kind.Scalar() : "";
    if (k == "grid")
      s.kind = StudyKind::grid;
    else if (k == "monte-carlo")
      s.kind = StudyKind::monte_carlo;
    else
      fail(kind, "study", "study must be 'grid' or 'monte-carlo', got '" + k + "'");
    if (s.kind == StudyKind::monte_carlo) {
      s.samples = integer(require(root, "samples", "study"), "study", "samples", 1, kMaxVariants);
      if (root["seed"])
        s.seed = static_cast<std::uint64_t>(integer(root["seed"], "study", "seed", 0, 1L << 62));
    } else if (root["samples"] || root["seed"]) {
      fail(root["samples"] ? root["samples"] : root["seed"], "study",
           "'samples' and 'seed' belong to a monte-carlo study");
    }
    if (root["steps"])
      s.steps = static_cast<int>(integer(root["steps"], "study", "steps", 2, kMaxCycleSteps));
    const YAML::Node params = require(root, "parameters", "study");
    if (!params.IsSequence() || params.size() == 0)
      fail(params, "parameters", "expected a list of parameters (- {path: ..., values: [...]})");
    std::set<std::string> names;
    for (const auto& item : params) {
      StudyParameter p = parameter(item, s.kind);
      if (!names.insert(p.name).second)
        fail(item, "parameter '" + p.name + "'", "the parameter is listed twice");
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
    return s;
  }

 private:
  std::string file_;
  const std::string& mechanism_;
  std::string mechanism_origin_;

  [[noreturn]] void fail(const YAML::Node& node, const std::string& element,
                         const std::string& message) const {
    const YAML::Mark m = node.Mark();
    throw InputError({file_, m.is_null() ? 1 : m.line + 1, m.is_null() ? 1 : m.column + 1}, element,
                     message);
  }
  void expect_keys(const YAML::Node& node, const std::string& element,
                   const std::vector<std::string>& allowed) const {
    if (!node.IsMap()) fail(node, element, "expected a mapping");
    for (const auto& kv : node) {
      const std::string key = kv.first.Scalar();
      if (std::find(allowed.begin(), allowed.end(), key) == allowed.end()) {
        std::string list;
        for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
        fail(kv.first, element, "unknown key '" + key + "' (allowed: " + list + ")");
      }
    }
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

  StudyParameter parameter(const YAML::Node& item, StudyKind kind) const {
    if (!item.IsMap()) fail(item, "parameters", "expected a mapping {path: ..., values: [...]}");
    expect_keys(item, "parameters", {"path", "name", "values", "range", "normal", "uniform"});
    StudyParameter p;
    p.path = text(require(item, "path", "parameters"), "parameters", "path");
    p.name = item["name"] ? text(item["name"], "parameters", "name") : p.path;
    const std::string element = "parameter '" + p.name + "'";
    const std::string nominal_text = file_text(item, p, element);
    int laws = 0;
    for (const char* key : {"values", "range", "normal", "uniform"}) laws += item[key] ? 1 : 0;
    if (laws != 1)
      fail(item, element,
           "give exactly one of values, range (grid), normal, uniform (monte-carlo)");
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
    }
    return p;
  }
};

std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

// ---- one variant's metrics ---------------------------------------------------------------------
const Driver* study_driver(const Model& model) {
  for (const Driver& d : model.drivers)
    if (d.name == model.analysis.driver) return &d;
  return model.drivers.empty() ? nullptr : &model.drivers.front();
}

// The cycle's summary in the file's units, named as in `cycle --json` (peaks.drive.max →
// drive.max; peaks."A.|F|".peak → A.|F|.peak; power.mean; the worst transmission angle of the
// four-bar loops, the worst pressure angle of the slider-crank loops; the dead points).
void cycle_metrics(const Model& model, const CycleResult& c, int driver_joint,
                   std::vector<std::pair<std::string, double>>& out) {
  const UnitSystem U = unit_system(model.units);
  const bool angular =
      std::holds_alternative<Revolute>(model.joints[static_cast<size_t>(driver_joint)].kind);
  const std::vector<ReactionMagnitude> magnitudes = reaction_magnitudes(c);
  const std::vector<SeriesSummary> summary = summarize_cycle(c, magnitudes, angular ? "N*m" : "N");
  for (const SeriesSummary& s : summary) {
    const OutputUnit u = output_unit(
        s.name == "drive" ? (angular ? Dimension::moment : Dimension::force) : dimension_of(s.unit),
        U);
    const auto value = [&](double v) { return s.samples > 0 ? u.from_si(v) : kNaN; };
    if (s.name == "drive") {
      out.emplace_back("drive.max", value(s.max.value));
      out.emplace_back("drive.min", value(s.min.value));
      out.emplace_back("drive.peak", value(s.peak));
      out.emplace_back("drive.rms", value(s.rms));
    } else {
      out.emplace_back(s.name + ".peak", value(s.peak));
    }
  }
  CycleMetricsOptions mo;
  mo.driver_joint = driver_joint;
  const CycleMetrics m = compute_cycle_metrics(model, c, mo);
  const OutputUnit power = output_unit(Dimension::power, U);
  out.emplace_back("power.mean", m.power.available ? power.from_si(m.power.mean) : kNaN);
  out.emplace_back("power.peak", m.power.available ? power.from_si(m.power.peak) : kNaN);
  const OutputUnit angle = output_unit(Dimension::angle, U);
  double transmission = kNaN, pressure = kNaN;
  for (const LoopAngleMetric& l : m.loops) {
    const double w = angle.from_si(l.worst.value);
    if (l.slider_crank)
      pressure = std::isnan(pressure) ? w : std::max(pressure, w);
    else
      transmission = std::isnan(transmission) ? w : std::min(transmission, w);
  }
  bool four_bar = false, slider = false;
  for (const LoopAngleMetric& l : m.loops) (l.slider_crank ? slider : four_bar) = true;
  if (four_bar) out.emplace_back("transmission.min", transmission);
  if (slider) out.emplace_back("pressure.max", pressure);
  out.emplace_back("dead_points", static_cast<double>(c.dead_points.size()));
}

}  // namespace

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
  try {
    return StudyReader(origin, mechanism, mechanism_origin).read(root);
  } catch (const YAML::Exception& e) {
    throw InputError(
        {origin, e.mark.is_null() ? 1 : e.mark.line + 1, e.mark.is_null() ? 1 : e.mark.column + 1},
        "YAML", e.msg);
  }
}

Study load_study(const std::string& path, const std::string& mechanism,
                 const std::string& mechanism_origin) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError({path, 0, 0}, "study", "cannot open the study file");
  std::ostringstream text;
  text << in.rdbuf();
  return parse_study(text.str(), path, mechanism, mechanism_origin);
}

long variant_count(const Study& study) {
  if (study.kind == StudyKind::monte_carlo) return study.samples;
  double count = 1.0;
  for (const StudyParameter& p : study.parameters) count *= static_cast<double>(p.values.size());
  return count > double(kMaxVariants) ? kMaxVariants + 1 : static_cast<long>(count);
}

std::vector<double> variant_values(const Study& study, long index) {
  std::vector<double> values(study.parameters.size());
  if (study.kind == StudyKind::grid) {
    long rest = index;
    for (size_t j = study.parameters.size(); j-- > 0;) {
      const auto& v = study.parameters[j].values;
      const long n = static_cast<long>(v.size());
      values[j] = v[static_cast<size_t>(rest % n)];
      rest /= n;
    }
    return values;
  }
  boost::random::mt19937_64 engine(
      splitmix64(study.seed ^ splitmix64(static_cast<std::uint64_t>(index))));
  for (size_t j = 0; j < study.parameters.size(); ++j) {
    const StudyParameter& p = study.parameters[j];
    if (p.law == StudyParameter::Law::normal) {
      values[j] = p.sigma > 0.0
                      ? boost::random::normal_distribution<double>(p.mean, p.sigma)(engine)
                      : p.mean;
    } else {
      values[j] = p.tolerance > 0.0 ? boost::random::uniform_real_distribution<double>(
                                          p.mean - p.tolerance, p.mean + p.tolerance)(engine)
                                    : p.mean;
    }
  }
  return values;
}

std::string value_text(double value) {
  char buffer[64];
  const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, value);
  return ec == std::errc() ? std::string(buffer, end) : std::string("nan");
}

VariantResult evaluate_variant(const std::string& mechanism, const std::string& origin,
                               const Study& study, long index, const std::vector<double>& values) {
  VariantResult r;
  r.index = index;
  r.values = values;
  try {
    std::vector<FileChange> changes;
    for (size_t j = 0; j < study.parameters.size(); ++j)
      changes.push_back({study.parameters[j].path, value_text(values[j])});
    Model model;
    try {
      model = parse_mechanism(mechanism, origin, changes);
    } catch (const InputError& e) {
      r.status = "invalid";
      r.message = e.what();
      return r;
    }
    const Driver* driver = study_driver(model);
    if (!driver) {
      r.status = "invalid";
      r.message = "the mechanism has no driver to sweep";
      return r;
    }
    CycleOptions co;
    co.driver = *driver;
    co.steps = study.steps > 0 ? study.steps : model.analysis.steps;
    const CycleResult c = run_cycle(model, co);
    r.status = c.status == CycleStatus::invalid_request ? "invalid" : to_string(c.status);
    r.message = c.message;
    if (!c.points.empty()) cycle_metrics(model, c, driver->joint, r.metrics);
  } catch (const std::exception& e) {
    r.status = "failed";
    r.message = std::string("internal error: ") + e.what();
    r.metrics.clear();
  }
  return r;
}

void run_variants(const std::string& mechanism, const std::string& origin, const Study& study,
                  const std::vector<long>& pending, int jobs,
                  const std::function<void(const VariantResult&)>& done) {
  std::exception_ptr failure;
  const long n = static_cast<long>(pending.size());
  const int threads = jobs > 0 ? jobs : omp_get_max_threads();  // 0: every core
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads) if (threads != 1)
  for (long k = 0; k < n; ++k) {
    bool stop = false;
#pragma omp critical(orthomech_study)
    stop = static_cast<bool>(failure);
    if (stop) continue;
    const long index = pending[static_cast<size_t>(k)];
    const VariantResult r =
        evaluate_variant(mechanism, origin, study, index, variant_values(study, index));
#pragma omp critical(orthomech_study)
    {
      if (!failure) {
        try {
          done(r);
        } catch (...) {
          failure = std::current_exception();
        }
      }
    }
  }
  if (failure) std::rethrow_exception(failure);
}

MetricStatistics metric_statistics(const std::string& name,
                                   const std::vector<std::vector<double>>& values,
                                   const std::vector<double>& metric) {
  MetricStatistics s;
  s.metric = name;
  std::vector<size_t> rows;
  for (size_t k = 0; k < metric.size(); ++k)
    if (!std::isnan(metric[k])) rows.push_back(k);
  s.n = static_cast<long>(rows.size());
  const size_t p = values.empty() ? 0 : values.front().size();
  s.sensitivity.assign(p, std::nullopt);
  if (rows.empty()) return s;
  std::vector<double> y;
  for (size_t k : rows) y.push_back(metric[k]);
  double sum = 0.0;
  for (double v : y) sum += v;
  s.mean = sum / double(y.size());
  double ss = 0.0;
  for (double v : y) ss += (v - s.mean) * (v - s.mean);
  s.stddev = y.size() > 1 ? std::sqrt(ss / double(y.size() - 1)) : 0.0;
  std::vector<double> sorted = y;
  std::sort(sorted.begin(), sorted.end());
  const auto quantile = [&](double q) {
    const double h = q * double(sorted.size() - 1);
    const size_t lo = static_cast<size_t>(std::floor(h));
    const size_t hi = std::min(lo + 1, sorted.size() - 1);
    return sorted[lo] + (h - double(lo)) * (sorted[hi] - sorted[lo]);
  };
  s.min = sorted.front();
  s.max = sorted.back();
  s.q05 = quantile(0.05);
  s.q50 = quantile(0.5);
  s.q95 = quantile(0.95);

  // The linear fit over the parameters that vary.
  std::vector<size_t> varying;
  for (size_t j = 0; j < p; ++j) {
    const double first = values[rows.front()][j];
    for (size_t k : rows)
      if (values[k][j] != first) {
        varying.push_back(j);
        break;
      }
  }
  const long n = s.n, m = static_cast<long>(varying.size());
  if (m == 0 || n <= m + 1 || s.min == s.max) return s;  // nothing to fit
  Eigen::MatrixXd X(n, m + 1);
  Eigen::VectorXd Y(n);
  for (long i = 0; i < n; ++i) {
    const size_t k = rows[static_cast<size_t>(i)];
    X(i, 0) = 1.0;
    for (long c = 0; c < m; ++c) X(i, c + 1) = values[k][varying[static_cast<size_t>(c)]];
    Y(i) = metric[k];
  }
  // Centre the columns (conditioning); the slopes are unchanged.
  for (long c = 1; c <= m; ++c) X.col(c).array() -= X.col(c).mean();
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(X);
  if (qr.rank() < m + 1) return s;
  const Eigen::VectorXd b = qr.solve(Y);
  const double rss = (Y - X * b).squaredNorm();
  const double dof = double(n - m - 1);
  const double sigma2 = rss / dof;
  const Eigen::MatrixXd cov = sigma2 * (X.transpose() * X).inverse();
  const double t = boost::math::quantile(boost::math::students_t_distribution<double>(dof), 0.975);
  for (long c = 0; c < m; ++c) {
    MetricStatistics::Sensitivity e;
    e.coefficient = b(c + 1);
    e.std_error = std::sqrt(std::max(0.0, cov(c + 1, c + 1)));
    e.low = e.coefficient - t * e.std_error;
    e.high = e.coefficient + t * e.std_error;
    s.sensitivity[varying[static_cast<size_t>(c)]] = e;
  }
  return s;
}

}  // namespace orthomech
