#include "orthomech/study/measure_metrics.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <variant>

#include "../io/expressions.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/io/units.hpp"
#include "orthomech/model/measures.hpp"

namespace orthomech {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The columns of one series: extremes (value and input), range, time ratio, RMS.
struct SeriesColumns {
  double min = kNaN, max = kNaN, min_at = kNaN, max_at = kNaN, time_ratio = kNaN, rms = kNaN;
};

// A series' columns NAME.min, …; when one of them is a column already (a measure named
// `transmission` beside the loops' transmission.min), the series' are measure.NAME.min, … .
void append(const std::string& series, const SeriesColumns& s, bool with_rms, MetricColumns& out) {
  const bool taken = std::any_of(out.begin(), out.end(), [&](const auto& column) {
    const std::string& c = column.first;
    return c.size() > series.size() && c.compare(0, series.size(), series) == 0 &&
           std::find(measure_metric_suffixes().begin(), measure_metric_suffixes().end(),
                     c.substr(series.size())) != measure_metric_suffixes().end();
  });
  const std::string name = taken ? "measure." + series : series;
  out.emplace_back(name + ".min", s.min);
  out.emplace_back(name + ".max", s.max);
  out.emplace_back(name + ".range", s.max - s.min);
  out.emplace_back(name + ".min_at", s.min_at);
  out.emplace_back(name + ".max_at", s.max_at);
  out.emplace_back(name + ".time_ratio", s.time_ratio);
  if (with_rms) out.emplace_back(name + ".rms", s.rms);
}

// A stroke's columns (already refined by compute_cycle_metrics), in the file's units.
SeriesColumns stroke_columns(const StrokeMetric& st, const OutputUnit& u, const OutputUnit& in) {
  SeriesColumns s;
  s.min = u.from_si(st.min.value);
  s.max = u.from_si(st.max.value);
  s.min_at = in.from_si(st.min.input);
  s.max_at = in.from_si(st.max.input);
  if (st.time_ratio) s.time_ratio = *st.time_ratio;
  return s;
}

// The characters of a column name (drive.peak, A.|F|.peak, crank.T.x): a name ends where they do.
bool name_char(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_' || c == '.' || c == '|';
}

bool is_function(const std::string& f) {
  const std::vector<std::string>& s = measure_metric_suffixes();
  return std::find(s.begin(), s.end(), "." + f) != s.end();
}

std::invalid_argument unknown_metric(const std::string& name, const MetricColumns& columns) {
  std::string list;
  for (const auto& [n, v] : columns) list += (list.empty() ? "" : ", ") + n;
  return std::invalid_argument("unknown metric '" + name + "' (the study's metrics: " + list + ")");
}

}  // namespace

const std::vector<std::string>& measure_metric_suffixes() {
  static const std::vector<std::string> s{".min",    ".max", ".range",     ".min_at",
                                          ".max_at", ".rms", ".time_ratio"};
  return s;
}

void measure_metrics(const Model& model, const CycleResult& c, const CycleMetrics& metrics,
                     int driver_joint, MetricColumns& out) {
  const UnitSystem U = unit_system(model.units);
  const bool angular =
      driver_joint >= 0 && joint_coordinate_kind(model.joints[static_cast<size_t>(driver_joint)]) ==
                               CoordinateKind::angle;
  const OutputUnit in = output_unit(angular ? Dimension::angle : Dimension::length, U);
  auto stroke_of = [&](const std::string& name) -> const StrokeMetric* {
    for (const StrokeMetric& st : metrics.strokes)
      if (st.name == name) return &st;
    return nullptr;
  };
  // The measures, each with its RMS (a stroke's extremes where it has one).
  for (size_t i = 0; i < model.measures.size(); ++i) {
    const Measure& m = model.measures[i];
    if (const auto* jc = std::get_if<JointCoordinate>(&m.kind))
      if (jc->joint == driver_joint && m.derivative == 0) continue;  // the input itself
    const OutputUnit u = output_unit(dimension_of(m.unit), U);
    SeriesColumns s;
    double squares = 0.0;
    long samples = 0;
    for (const DrivenPointView& p : c.points) {
      if (!measure_reported(model, p, i)) continue;
      const double y = u.from_si(p.measures[i]);
      if (samples == 0 || y < s.min) s.min = y, s.min_at = in.from_si(p.input);
      if (samples == 0 || y > s.max) s.max = y, s.max_at = in.from_si(p.input);
      squares += y * y;
      ++samples;
    }
    if (samples > 0) s.rms = std::sqrt(squares / static_cast<double>(samples));
    if (const StrokeMetric* st = stroke_of(m.name)) {
      const double rms = s.rms;
      s = stroke_columns(*st, u, in);
      s.rms = rms;
    }
    append(m.name, s, true, out);
  }
  // The strokes that are not measures: prismatic joints, tracer points.
  for (const StrokeMetric& st : metrics.strokes) {
    const bool measure = std::any_of(model.measures.begin(), model.measures.end(),
                                     [&](const Measure& m) { return m.name == st.name; });
    if (!measure)
      append(st.name, stroke_columns(st, output_unit(dimension_of(st.unit), U), in), false, out);
  }
}

double evaluate_metric_expression(const std::string& text, const MetricColumns& columns) {
  // The columns the text uses become the variables _c0, _c1, … of the file's arithmetic.
  std::vector<size_t> used;
  auto variable = [&](size_t column) {
    const auto it = std::find(used.begin(), used.end(), column);
    const size_t k = static_cast<size_t>(it - used.begin());
    if (it == used.end()) used.push_back(column);
    return "_c" + std::to_string(k);
  };
  auto column_of = [&](const std::string& name) -> std::optional<size_t> {
    for (size_t k = 0; k < columns.size(); ++k)
      if (columns[k].first == name) return k;
    return std::nullopt;
  };
  std::string rewritten;
  size_t i = 0;
  while (i < text.size()) {
    if (!name_char(text[i]) || (i > 0 && name_char(text[i - 1])) ||
        std::isdigit(static_cast<unsigned char>(text[i])) != 0) {
      rewritten += text[i++];
      continue;
    }
    size_t end = i;
    while (end < text.size() && name_char(text[end])) ++end;
    const std::string name = text.substr(i, end - i);
    // f(NAME): the column NAME.f.
    size_t open = end;
    while (open < text.size() && text[open] == ' ') ++open;
    if (open < text.size() && text[open] == '(' && is_function(name)) {
      size_t a = open + 1;
      while (a < text.size() && text[a] == ' ') ++a;
      size_t b = a;
      while (b < text.size() && name_char(text[b])) ++b;
      size_t close = b;
      while (close < text.size() && text[close] == ' ') ++close;
      const std::string argument = text.substr(a, b - a);
      if (b > a && close < text.size() && text[close] == ')') {
        std::optional<size_t> k = column_of(argument + "." + name);
        if (!k) k = column_of("measure." + argument + "." + name);
        if (k) {
          rewritten += variable(*k);
          i = close + 1;
          continue;
        }
        if (name != "min" && name != "max")
          throw std::invalid_argument("'" + name + "(" + argument + ")': '" + argument +
                                      "' is not a measure or stroke of the study (no column '" +
                                      argument + "." + name + "')");
      }
      rewritten += name;  // muparser's own min(a, b), max(a, b)
      i = end;
      continue;
    }
    if (const auto k = column_of(name)) {
      rewritten += variable(*k);
    } else if (name.find_first_of(".|") != std::string::npos) {
      throw unknown_metric(name, columns);
    } else {
      rewritten += name;  // a function or constant of the arithmetic, or an unknown name
    }
    i = end;
  }
  detail::Expressions e;
  for (size_t k = 0; k < used.size(); ++k)
    e.define("_c" + std::to_string(k), columns[used[k]].second);
  try {
    return e.evaluate(rewritten);
  } catch (const detail::UnknownName& u) {
    throw unknown_metric(u.name, columns);
  }
}

}  // namespace orthomech
