#include "orthomech/study/measure_metrics.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <variant>

#include "../io/expressions.hpp"
#include "orthomech/analysis/multi_drive.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/io/units.hpp"
#include "orthomech/model/measures.hpp"

namespace orthomech {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

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

namespace {

// A number at text[k] and a base unit's name right after it (spaces between allowed): its value,
// the unit ("" none) and where it ends; nullopt when text[k] does not start a number.
struct Literal {
  double value = 0.0;
  std::string unit;
  size_t end = 0;
};
std::optional<Literal> literal(const std::string& text, size_t k) {
  const char* start = text.c_str() + k;
  char* stop = nullptr;
  Literal l;
  l.value = std::strtod(start, &stop);
  if (stop == start || !std::isfinite(l.value)) return std::nullopt;
  l.end = k + static_cast<size_t>(stop - start);
  size_t a = l.end;
  while (a < text.size() && text[a] == ' ') ++a;
  size_t b = a;
  while (b < text.size() && std::isalpha(static_cast<unsigned char>(text[b])) != 0) ++b;
  if (b > a && (b == text.size() || !name_char(text[b])) && base_unit(text.substr(a, b - a))) {
    l.unit = text.substr(a, b - a);
    l.end = b;
  }
  return l;
}

// The `at(` call at text[i] (i at the 'a'): its measure name and input (with its unit, if
// written), and where it ends (after the ')'); nullopt when text[i] does not start a call of `at`.
struct AtCall {
  std::string measure;
  double input = 0.0;
  std::string unit;
  size_t end = 0;
};
std::optional<AtCall> at_call(const std::string& text, size_t i) {
  if (text.compare(i, 2, "at") != 0 || (i > 0 && name_char(text[i - 1]))) return std::nullopt;
  size_t k = i + 2;
  while (k < text.size() && text[k] == ' ') ++k;
  if (k >= text.size() || text[k] != '(') return std::nullopt;
  const auto fail = [&](const std::string& why) {
    return std::invalid_argument("'" + text.substr(i) + "': at(MEASURE, INPUT) " + why);
  };
  ++k;
  while (k < text.size() && text[k] == ' ') ++k;
  const size_t a = k;
  while (k < text.size() && name_char(text[k])) ++k;
  AtCall call;
  call.measure = text.substr(a, k - a);
  while (k < text.size() && text[k] == ' ') ++k;
  if (call.measure.empty() || k >= text.size() || text[k] != ',')
    throw fail("needs a measure's name first");
  ++k;
  while (k < text.size() && text[k] == ' ') ++k;
  const std::optional<Literal> input = literal(text, k);
  if (!input)
    throw fail(
        "needs the input as a number (the driver's unit of the file, or with its unit: "
        "90deg, 20mm)");
  call.input = input->value;
  call.unit = input->unit;
  k = input->end;
  while (k < text.size() && text[k] == ' ') ++k;
  if (k >= text.size() || text[k] != ')') throw fail("needs ')' after the input");
  call.end = k + 1;
  return call;
}

std::string number_text(double v) {
  char buffer[32];
  const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, v);
  return std::string(buffer, ec == std::errc() ? end : buffer);
}

std::string at_column(const AtCall& call) {
  return call.measure + "@" + number_text(call.input) + call.unit;
}

// The cubic through four points (s_k, y_k) at s (Lagrange's form).
double cubic_at(const double* s, const double* y, double at) {
  double v = 0.0;
  for (int j = 0; j < 4; ++j) {
    double w = 1.0;
    for (int m = 0; m < 4; ++m)
      if (m != j) w *= (at - s[m]) / (s[j] - s[m]);
    v += w * y[j];
  }
  return v;
}

}  // namespace

std::vector<MeasureAt> measure_at_requests(const std::vector<MetricExpression>& expressions) {
  std::vector<MeasureAt> out;
  for (const MetricExpression& e : expressions)
    for (size_t i = 0; i < e.text.size(); ++i)
      if (const auto call = at_call(e.text, i)) {
        const std::string column = at_column(*call);
        if (std::none_of(out.begin(), out.end(),
                         [&](const MeasureAt& m) { return m.column == column; }))
          out.push_back({call->measure, call->input, call->unit, column});
        i = call->end - 1;
      }
  return out;
}

void measure_at_metrics(const Model& model, const CycleResult& c, int driver_joint,
                        const std::vector<MeasureAt>& requests, MetricColumns& out) {
  if (requests.empty()) return;
  const UnitSystem U = unit_system(model.units);
  const bool angular =
      driver_joint >= 0 && joint_coordinate_kind(model.joints[static_cast<size_t>(driver_joint)]) ==
                               CoordinateKind::angle;
  const OutputUnit in = output_unit(angular ? Dimension::angle : Dimension::length, U);
  for (const MeasureAt& request : requests) {
    const auto it = std::find_if(model.measures.begin(), model.measures.end(),
                                 [&](const Measure& m) { return m.name == request.measure; });
    if (it == model.measures.end()) continue;
    const auto i = static_cast<size_t>(it - model.measures.begin());
    const OutputUnit u = output_unit(dimension_of(it->unit), U);
    // The series in increasing input (a sweep may run backwards).
    std::vector<std::pair<double, double>> series;
    for (const DrivenPointView& p : c.points)
      if (measure_reported(model, p, i)) series.emplace_back(p.input, u.from_si(p.measures[i]));
    std::sort(series.begin(), series.end());
    // The input in SI: in the driver's unit of the file, or in the unit written (of its kind).
    const std::optional<BaseUnit> written =
        request.unit.empty() ? std::nullopt : base_unit(request.unit);
    const bool kind_matches =
        !written || written->dimension == (angular ? Dimension::angle : Dimension::length);
    double value = kNaN;
    if (series.size() >= 4 && kind_matches) {
      const double lo = series.front().first, hi = series.back().first;
      double s = request.input * (written ? written->si : in.si);
      if (angular) {  // up to whole turns into [lo, hi]
        const double turn = 2.0 * std::numbers::pi;
        s += turn * std::ceil((lo - s) / turn - 1e-12);
      }
      if (s >= lo - 1e-12 * (1.0 + std::abs(lo)) && s <= hi + 1e-12 * (1.0 + std::abs(hi))) {
        const auto above = std::lower_bound(series.begin(), series.end(), std::pair{s, -kInf});
        const auto k = static_cast<long>(above - series.begin());
        const long first = std::clamp(k - 2, 0L, static_cast<long>(series.size()) - 4);
        double xs[4], ys[4];
        for (int j = 0; j < 4; ++j) {
          xs[j] = series[static_cast<size_t>(first + j)].first;
          ys[j] = series[static_cast<size_t>(first + j)].second;
        }
        value = cubic_at(xs, ys, s);
      }
    }
    out.emplace_back(request.column, value);
  }
}

void multi_drive_measure_metrics(const Model& model, const MultiDriveResult& r,
                                 MetricColumns& out) {
  const UnitSystem U = unit_system(model.units);
  const OutputUnit time = output_unit(Dimension::time, U);
  for (size_t i = 0; i < model.measures.size(); ++i) {
    const OutputUnit u = output_unit(dimension_of(model.measures[i].unit), U);
    SeriesColumns s;
    double squares = 0.0;
    long samples = 0;
    for (const MultiDrivenPoint& p : r.points) {
      const double y = u.from_si(p.measures[i]);
      if (!std::isfinite(y)) continue;
      if (samples == 0 || y < s.min) s.min = y, s.min_at = time.from_si(p.time);
      if (samples == 0 || y > s.max) s.max = y, s.max_at = time.from_si(p.time);
      squares += y * y;
      ++samples;
    }
    if (samples > 0) s.rms = std::sqrt(squares / static_cast<double>(samples));
    append(model.measures[i].name, s, true, out);
  }
}

double evaluate_metric_expression(const std::string& text, const MetricColumns& columns,
                                  const UnitSystem* units) {
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
    // A number with a unit (75deg, 0.5 m): its value in the file's unit of that kind.
    if (std::isdigit(static_cast<unsigned char>(text[i])) != 0 &&
        (i == 0 || !name_char(text[i - 1]))) {
      const std::optional<Literal> l = literal(text, i);
      if (l && !l->unit.empty()) {
        if (!units)
          throw std::invalid_argument("'" + text.substr(i, l->end - i) +
                                      "': a unit needs the mechanism file's units");
        const BaseUnit u = *base_unit(l->unit);
        rewritten += '(';
        rewritten += number_text(output_unit(u.dimension, *units).from_si(l->value * u.si));
        rewritten += ')';
        i = l->end;
        continue;
      }
      if (l) {
        rewritten += text.substr(i, l->end - i);
        i = l->end;
        continue;
      }
    }
    if (!name_char(text[i]) || (i > 0 && name_char(text[i - 1])) ||
        std::isdigit(static_cast<unsigned char>(text[i])) != 0) {
      rewritten += text[i++];
      continue;
    }
    // at(NAME, X): the column NAME@X.
    if (const auto call = at_call(text, i)) {
      const std::string column = at_column(*call);
      const std::optional<size_t> k = column_of(column);
      if (!k)
        throw std::invalid_argument("'at(" + call->measure + ", ...)': '" + call->measure +
                                    "' is not a measure of the file (no column '" + column + "')");
      rewritten += variable(*k);
      i = call->end;
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
