// The study report (io/study_report.hpp). Four steps: the scale of an axis (Axis: the data range
// with a margin, mapped onto pixels), the figures as SVG (scatter panels, histograms, sensitivity
// bars, cycle plots), the sections of the page that hold them, and the page.
#include "orthomech/io/study_report.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "orthomech/io/report.hpp"

namespace orthomech {

namespace {

std::string num(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.6g", v);
  return buffer;
}
// A data-* attribute's number: the shortest text that reads back to the same double.
std::string exact(double v) {
  char buffer[32];
  const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, v);
  return ec == std::errc() ? std::string(buffer, end) : std::string("nan");
}
// SVG coordinates: two decimals are enough at these sizes.
std::string px(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.2f", v);
  return buffer;
}
std::string attr(const std::string& s) {
  std::string out(1, '"');
  out += escape_html(s);
  out += '"';
  return out;
}

// ---- 1. Axes ------------------------------------------------------------------------------------

// The finite range of values, widened by 5 % each side (a unit either side when they are equal)
// and mapped onto [p0, p1] pixels.
struct Axis {
  double lo = 0.0, hi = 1.0, p0 = 0.0, p1 = 1.0;
  [[nodiscard]] double at(double v) const { return p0 + (v - lo) / (hi - lo) * (p1 - p0); }
};
Axis axis_of(const std::vector<double>& values, double p0, double p1) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const double v : values)
    if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
  if (!(lo <= hi)) lo = 0.0, hi = 1.0;
  const double pad = hi > lo ? 0.05 * (hi - lo) : std::max(1.0, std::abs(lo)) * 0.05;
  return {lo - pad, hi + pad, p0, p1};
}

std::string svg_open(const std::string& cls, double w, double h, const std::string& data) {
  return "<svg xmlns=\"http://www.w3.org/2000/svg\" class=\"" + cls + "\" width=\"" + px(w) +
         "\" height=\"" + px(h) + "\" viewBox=\"0 0 " + px(w) + " " + px(h) + "\"" + data +
         " font-family=\"sans-serif\" font-size=\"10\">";
}
std::string text_at(double x, double y, const std::string& s, const std::string& anchor) {
  return "<text x=\"" + px(x) + "\" y=\"" + px(y) + "\" text-anchor=\"" + anchor + "\">" +
         escape_html(s) + "</text>";
}
// The frame of a plot area and its axis ends labelled.
std::string frame(const Axis& x, const Axis& y) {
  const double left = x.p0, right = x.p1, top = y.p1, bottom = y.p0;
  std::string s = "<rect x=\"" + px(left) + "\" y=\"" + px(top) + "\" width=\"" + px(right - left) +
                  "\" height=\"" + px(bottom - top) + "\" fill=\"none\" stroke=\"#888\"/>";
  s += text_at(left, bottom + 12, num(x.lo), "start") +
       text_at(right, bottom + 12, num(x.hi), "end");
  s += text_at(left - 3, bottom, num(y.lo), "end") + text_at(left - 3, top + 8, num(y.hi), "end");
  return s;
}

// ---- 2. Figures ---------------------------------------------------------------------------------

constexpr double kPanelW = 220, kPanelH = 160, kLeft = 52, kBottom = 28, kTop = 18;

std::string scatter_panel(const StudyReport& r, size_t p, size_t m) {
  const StudyReportColumn& xs = r.parameters[p];
  const StudyReportColumn& ys = r.metrics[m];
  const Axis x = axis_of(xs.values, kLeft, kPanelW - 8);
  const Axis y = axis_of(ys.values, kPanelH - kBottom, kTop);
  std::string s = svg_open("panel", kPanelW, kPanelH,
                           " data-parameter=" + attr(xs.name) + " data-metric=" + attr(ys.name));
  s += frame(x, y);
  s += text_at(0.5 * (x.p0 + x.p1), kPanelH - 4, xs.name, "middle");
  s += text_at(x.p0, 11, ys.name, "start");
  for (size_t k = 0; k < r.variants.size(); ++k) {
    const double a = xs.values[k], b = ys.values[k];
    if (!std::isfinite(a) || !std::isfinite(b)) continue;
    const bool best = std::find(r.best.begin(), r.best.end(), r.variants[k]) != r.best.end();
    s += "<circle class=\"point" + std::string(best ? " best" : "") + "\" data-variant=\"" +
         std::to_string(r.variants[k]) + "\" cx=\"" + px(x.at(a)) + "\" cy=\"" + px(y.at(b)) +
         "\" r=\"" + (best ? "3.5" : "2.2") + "\"><title>variant " + std::to_string(r.variants[k]) +
         ": " + escape_html(xs.name) + " = " + num(a) + ", " + escape_html(ys.name) + " = " +
         num(b) + "</title></circle>";
  }
  return s + "</svg>";
}

std::string histogram_svg(const StudyReport& r, size_t m) {
  const StudyReportColumn& ys = r.metrics[m];
  long n = 0;
  for (const double v : ys.values) n += std::isfinite(v) ? 1 : 0;
  const std::vector<HistogramBin> bins = histogram(ys.values, histogram_bins(n));
  std::string s = svg_open("histogram", kPanelW + 40, kPanelH, " data-metric=" + attr(ys.name));
  if (bins.empty()) return s + text_at(kLeft, 40, ys.name + ": no values", "start") + "</svg>";
  long most = 1;
  for (const HistogramBin& b : bins) most = std::max(most, b.count);
  const Axis x{bins.front().low,
               bins.back().high > bins.front().low ? bins.back().high : bins.front().low + 1, kLeft,
               kPanelW + 32};
  const Axis y{0.0, static_cast<double>(most), kPanelH - kBottom, kTop};
  s += frame(x, y);
  s += text_at(x.p0, 11, ys.name + " (" + std::to_string(n) + " values)", "start");
  for (const HistogramBin& b : bins) {
    const double x0 = x.at(b.low), x1 = std::max(x.at(b.high), x0 + 1.0);
    s += "<rect class=\"bin\" data-count=\"" + std::to_string(b.count) + "\" data-low=\"" +
         exact(b.low) + "\" data-high=\"" + exact(b.high) + "\" x=\"" + px(x0) + "\" y=\"" +
         px(y.at(static_cast<double>(b.count))) + "\" width=\"" + px(x1 - x0) + "\" height=\"" +
         px(y.p0 - y.at(static_cast<double>(b.count))) +
         "\" fill=\"#7aa6d6\" stroke=\"#fff\" stroke-width=\"0.5\"><title>" + num(b.low) + " … " +
         num(b.high) + ": " + std::to_string(b.count) + "</title></rect>";
  }
  if (!r.statistics.empty()) {
    const StudyReportStatistics& st = r.statistics[m];
    const std::pair<const char*, double> q[] = {{"q05", st.q05}, {"q50", st.q50}, {"q95", st.q95}};
    for (const auto& [name, v] : q) {
      const double at = x.at(v);
      s += "<line class=\"quantile\" data-quantile=\"" + std::string(name) + "\" data-value=\"" +
           exact(v) + "\" x1=\"" + px(at) + "\" x2=\"" + px(at) + "\" y1=\"" + px(y.p1) +
           "\" y2=\"" + px(y.p0) + "\" stroke=\"#c33\" stroke-dasharray=\"3 2\"/>" +
           text_at(at, y.p1 - 2, name, "middle");
    }
  }
  return s + "</svg>";
}

// The bars of one metric: per parameter that varies, its effect over the study — the
// coefficient times the parameter's spread (the sample standard deviation of its values: the
// metric's change for one standard deviation of the parameter), with the 95 % interval scaled
// alike.
double spread(const std::vector<double>& v) {
  double mean = 0.0;
  long n = 0;
  for (const double x : v)
    if (std::isfinite(x)) mean += x, ++n;
  if (n < 2) return 0.0;
  mean /= static_cast<double>(n);
  double ss = 0.0;
  for (const double x : v)
    if (std::isfinite(x)) ss += (x - mean) * (x - mean);
  return std::sqrt(ss / static_cast<double>(n - 1));
}

std::string sensitivity_svg(const StudyReport& r, size_t m) {
  const StudyReportStatistics& st = r.statistics[m];
  struct Bar {
    std::string parameter;
    double effect, low, high;
  };
  std::vector<Bar> bars;
  for (size_t p = 0; p < st.sensitivity.size() && p < r.parameters.size(); ++p)
    if (st.sensitivity[p]) {
      const double sd = spread(r.parameters[p].values);
      bars.push_back({r.parameters[p].name, st.sensitivity[p]->coefficient * sd,
                      st.sensitivity[p]->low * sd, st.sensitivity[p]->high * sd});
    }
  const double row = 18,
               h = kTop + row * static_cast<double>(std::max<size_t>(bars.size(), 1)) + kBottom;
  std::string s =
      svg_open("sensitivity", kPanelW + 80, h, " data-metric=" + attr(r.metrics[m].name));
  s += text_at(4, 11, r.metrics[m].name + " per standard deviation of each parameter", "start");
  if (bars.empty()) return s + text_at(4, kTop + 12, "no parameter varies", "start") + "</svg>";
  std::vector<double> ends{0.0};
  for (const Bar& b : bars) ends.insert(ends.end(), {b.low, b.high, b.effect});
  const Axis x = axis_of(ends, 90, kPanelW + 72);
  const double zero = x.at(0.0);
  s += "<line x1=\"" + px(zero) + "\" x2=\"" + px(zero) + "\" y1=\"" + px(kTop) + "\" y2=\"" +
       px(h - kBottom) + "\" stroke=\"#888\"/>";
  s += text_at(x.p0, h - kBottom + 12, num(x.lo), "start") +
       text_at(x.p1, h - kBottom + 12, num(x.hi), "end");
  for (size_t k = 0; k < bars.size(); ++k) {
    const Bar& b = bars[k];
    const double y = kTop + row * static_cast<double>(k);
    const double a = std::min(zero, x.at(b.effect)), w = std::abs(x.at(b.effect) - zero);
    s += text_at(86, y + 12, b.parameter, "end");
    s += "<rect class=\"bar\" data-parameter=" + attr(b.parameter) + " data-effect=\"" +
         exact(b.effect) + "\" x=\"" + px(a) + "\" y=\"" + px(y + 3) + "\" width=\"" + px(w) +
         "\" height=\"" + px(row - 6) + "\" fill=\"#d6a77a\"><title>" + escape_html(b.parameter) +
         ": " + num(b.effect) + " [" + num(b.low) + ", " + num(b.high) + "]</title></rect>";
    s += "<line x1=\"" + px(x.at(b.low)) + "\" x2=\"" + px(x.at(b.high)) + "\" y1=\"" +
         px(y + 0.5 * row) + "\" y2=\"" + px(y + 0.5 * row) + "\" stroke=\"#333\"/>";
  }
  return s + "</svg>";
}

// One series of a variant's cycle against the input.
std::string cycle_plot(const VariantCycle& c, const VariantCycle::Series& series) {
  const Axis x = axis_of(c.input, kLeft, 2 * kPanelW - 8);
  const Axis y = axis_of(series.values, kPanelH - kBottom, kTop);
  std::string s = svg_open("cycle-plot", 2 * kPanelW, kPanelH, " data-name=" + attr(series.name));
  s += frame(x, y);
  s += text_at(x.p0, 11, series.name + " [" + series.unit + "]", "start");
  s += text_at(0.5 * (x.p0 + x.p1), kPanelH - 4, c.input_label, "middle");
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const double v : series.values)
    if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
  s += "<polyline class=\"series\" data-name=" + attr(series.name) + " data-min=\"" + exact(lo) +
       "\" data-max=\"" + exact(hi) +
       "\" fill=\"none\" stroke=\"#1f5fa8\" stroke-width=\"1.2\" points=\"";
  for (size_t k = 0; k < c.input.size() && k < series.values.size(); ++k)
    if (std::isfinite(series.values[k]))
      s += px(x.at(c.input[k])) + "," + px(y.at(series.values[k])) + " ";
  return s + "\"/></svg>";
}

std::string convergence_plot(const StudyReport& r) {
  // The objective's axis spans the feasible evaluations (an infeasible one next to a dead point
  // can be orders of magnitude off); infeasible ones outside it are not drawn, but counted.
  std::vector<double> n, y;
  for (const ConvergencePoint& c : r.convergence) {
    n.push_back(static_cast<double>(c.evaluation));
    if (c.feasible) y.push_back(c.objective);
    y.push_back(c.best);
  }
  if (std::none_of(y.begin(), y.end(), [](double v) { return std::isfinite(v); }))
    for (const ConvergencePoint& c : r.convergence) y.push_back(c.objective);
  const double w = 2 * kPanelW + 40, h = kPanelH + 40;
  const Axis x = axis_of(n, kLeft, w - 8), v = axis_of(y, h - kBottom, kTop);
  std::string s = svg_open("convergence", w, h, "");
  s += frame(x, v);
  long outside = 0;
  for (const ConvergencePoint& c : r.convergence)
    if (std::isfinite(c.objective) && (c.objective < v.lo || c.objective > v.hi)) ++outside;
  s +=
      text_at(x.p0, 11,
              r.objective + " per evaluation (open: infeasible" +
                  (outside > 0 ? "; " + std::to_string(outside) + " off the axis" : std::string()) +
                  "); line: the best feasible",
              "start");
  s += text_at(0.5 * (x.p0 + x.p1), h - 4, "evaluation", "middle");
  for (const ConvergencePoint& c : r.convergence)
    if (std::isfinite(c.objective) && c.objective >= v.lo && c.objective <= v.hi)
      s += "<circle class=\"evaluation\" data-evaluation=\"" + std::to_string(c.evaluation) +
           "\" data-objective=\"" + exact(c.objective) + "\" data-feasible=\"" +
           (c.feasible ? "yes" : "no") + "\" cx=\"" + px(x.at(static_cast<double>(c.evaluation))) +
           "\" cy=\"" + px(v.at(c.objective)) + "\" r=\"2.5\" fill=\"" +
           (c.feasible ? "#1f5fa8" : "none") + "\" stroke=\"" + (c.feasible ? "none" : "#999") +
           "\"><title>evaluation " + std::to_string(c.evaluation) + ": " + num(c.objective) +
           (c.feasible ? "" : " (infeasible)") + "</title></circle>";
  // The best so far as a step line from its first feasible evaluation.
  std::string points;
  bool started = false;
  double last = std::numeric_limits<double>::quiet_NaN();
  for (const ConvergencePoint& c : r.convergence) {
    if (!std::isfinite(c.best)) continue;
    const double at = x.at(static_cast<double>(c.evaluation));
    if (started) points += px(at) + "," + px(v.at(last)) + " ";
    points += px(at) + "," + px(v.at(c.best)) + " ";
    started = true;
    last = c.best;
  }
  return s + "<polyline class=\"best\" data-final=\"" + exact(last) +
         "\" fill=\"none\" stroke=\"#d62728\" stroke-width=\"1.5\" points=\"" + points +
         "\"/></svg>";
}

// ---- 3. Sections --------------------------------------------------------------------------------

void check_shape(const StudyReport& r) {
  for (const auto* columns : {&r.parameters, &r.metrics})
    for (const StudyReportColumn& c : *columns)
      if (c.values.size() != r.variants.size())
        throw std::invalid_argument("study report: column '" + c.name + "' has " +
                                    std::to_string(c.values.size()) + " values for " +
                                    std::to_string(r.variants.size()) + " variants");
  if (!r.statistics.empty() && r.statistics.size() != r.metrics.size())
    throw std::invalid_argument("study report: statistics for " +
                                std::to_string(r.statistics.size()) + " of " +
                                std::to_string(r.metrics.size()) + " metrics");
}

std::string scatter_section(const StudyReport& r) {
  std::string s = "<h2>Parameters against metrics</h2>\n<div id=\"scatter\">\n";
  for (size_t m = 0; m < r.metrics.size(); ++m) {
    s += "<div class=\"row\">";
    for (size_t p = 0; p < r.parameters.size(); ++p) s += scatter_panel(r, p, m);
    s += "</div>\n";
  }
  return s + "</div>\n";
}

std::string histogram_section(const StudyReport& r) {
  std::string s = "<h2>Distributions</h2>\n<div id=\"histograms\" class=\"row\">\n";
  for (size_t m = 0; m < r.metrics.size(); ++m) s += histogram_svg(r, m) + "\n";
  return s + "</div>\n";
}

std::string sensitivity_section(const StudyReport& r) {
  if (r.statistics.empty()) return "";
  std::string s = "<h2>Sensitivities</h2>\n<div id=\"sensitivities\" class=\"row\">\n";
  for (size_t m = 0; m < r.metrics.size(); ++m) s += sensitivity_svg(r, m) + "\n";
  return s + "</div>\n";
}

std::string convergence_section(const StudyReport& r) {
  if (r.convergence.empty()) return "";
  return "<h2>Convergence</h2>\n<div class=\"row\">" + convergence_plot(r) + "</div>\n";
}

std::string best_section(const StudyReport& r) {
  if (r.best.empty()) return "";
  std::string s = "<h2>Best variants" +
                  (r.best_metric.empty() ? "" : " by " + escape_html(r.best_metric)) +
                  "</h2>\n<table id=\"best\"><tr><th>variant</th>";
  for (const StudyReportColumn& c : r.parameters) s += "<th>" + escape_html(c.name) + "</th>";
  for (const StudyReportColumn& c : r.metrics) s += "<th>" + escape_html(c.name) + "</th>";
  s += "</tr>\n";
  for (const long v : r.best) {
    const auto it = std::find(r.variants.begin(), r.variants.end(), v);
    if (it == r.variants.end()) continue;
    const auto k = static_cast<size_t>(it - r.variants.begin());
    s += "<tr class=\"variant\" data-variant=\"" + std::to_string(v) + "\"><td>" +
         std::to_string(v) + "</td>";
    for (const auto* columns : {&r.parameters, &r.metrics})
      for (const StudyReportColumn& c : *columns) s += "<td>" + num(c.values[k]) + "</td>";
    s += "</tr>\n";
  }
  s += "</table>\n<p class=\"hint\">Click a variant (a row, or a large point of the scatter "
       "plots) for its cycle.</p>\n";
  for (const VariantCycle& c : r.cycles) {
    s += "<div class=\"cycle\" data-variant=\"" + std::to_string(c.variant) +
         "\" style=\"display: none\"><h3>variant " + std::to_string(c.variant) + ": its cycle (" +
         std::to_string(c.input.size()) + " positions)</h3><div class=\"row\">";
    for (const VariantCycle::Series& series : c.series) s += cycle_plot(c, series);
    s += "</div></div>\n";
  }
  return s;
}

constexpr const char* kStyle =
    "body{font-family:sans-serif;margin:1em 2em;color:#222}"
    ".row{display:flex;flex-wrap:wrap;gap:6px;margin-bottom:6px}"
    "pre{background:#f6f6f6;padding:8px;overflow-x:auto}"
    "circle.point{fill:#1f5fa8;fill-opacity:.55}circle.best{fill:#d62728;fill-opacity:.9;"
    "cursor:pointer}table{border-collapse:collapse}td,th{border:1px solid #ccc;padding:2px 6px;"
    "font-size:12px}tr.variant{cursor:pointer}tr.variant:hover,tr.shown{background:#fde9c8}"
    ".hint{color:#666;font-size:12px}";

// Clicking a best variant's row or point shows its cycle.
constexpr const char* kScript =
    "(function(){function show(v){document.querySelectorAll('div.cycle').forEach(function(d){"
    "d.style.display=d.dataset.variant===v?'block':'none';});"
    "document.querySelectorAll('tr.variant').forEach(function(t){"
    "t.classList.toggle('shown',t.dataset.variant===v);});}"
    "document.querySelectorAll('tr.variant, circle.best').forEach(function(e){"
    "e.addEventListener('click',function(){show(e.dataset.variant);});});"
    "window.showVariant=show;document.body.dataset.ready='yes';})();";

// The metrics a report shows by default: the best metric, the expressions, then those that vary
// over the rows (a constant column says nothing in a scatter plot) — the strokes and the worst
// loop angles first — kDefaultReportMetrics in all.
std::vector<std::string> default_report_metrics(const Study& study, const StudyDatabase& db,
                                                const std::vector<StudyDatabase::Row>& rows) {
  std::vector<std::string> chosen;
  const auto& names = db.metrics();
  const auto add = [&](const std::string& name) {
    if (chosen.size() < kDefaultReportMetrics &&
        std::find(names.begin(), names.end(), name) != names.end() &&
        std::find(chosen.begin(), chosen.end(), name) == chosen.end())
      chosen.push_back(name);
  };
  if (!study.best_metric.empty()) add(study.best_metric);
  // The expressions (an optimize goal's objective and constraints among them), except one that is
  // a column by another name (`constraint.1` of `{metric: transmission.min}`): that column.
  for (const MetricExpression& e : study.metrics.expressions)
    add(std::find(names.begin(), names.end(), e.text) != names.end() ? e.text : e.name);
  const auto varies = [&](size_t m) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const double v : summarized_metric(rows, m, db.metrics()[m]))
      if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
    return hi > lo;
  };
  // The strokes (M.range) and the worst loop angles before the other columns.
  const auto first = [](const std::string& name) {
    const std::string range = ".range";
    return name == "transmission.min" || name == "pressure.max" ||
           (name.size() > range.size() &&
            name.compare(name.size() - range.size(), range.size(), range) == 0);
  };
  for (const bool pass : {true, false})
    for (size_t m = 0; m < db.metrics().size(); ++m)
      if (first(db.metrics()[m]) == pass && varies(m)) add(db.metrics()[m]);
  return chosen;
}

}  // namespace

std::vector<double> summarized_metric(const std::vector<StudyDatabase::Row>& rows, size_t metric,
                                      const std::string& name) {
  const bool check = name.rfind("validate.", 0) == 0 || name.rfind("assemble.", 0) == 0;
  std::vector<double> y;
  y.reserve(rows.size());
  for (const auto& r : rows)
    y.push_back(r.status == "completed" || check ? r.metrics[metric]
                                                 : std::numeric_limits<double>::quiet_NaN());
  return y;
}

std::vector<const StudyDatabase::Row*> best_rows(const std::vector<StudyDatabase::Row>& rows,
                                                 size_t metric, bool largest, long count) {
  std::vector<const StudyDatabase::Row*> ranked;
  for (const auto& r : rows)
    if (r.status == "completed" && !std::isnan(r.metrics[metric])) ranked.push_back(&r);
  std::stable_sort(ranked.begin(), ranked.end(), [&](const auto* a, const auto* b) {
    return largest ? a->metrics[metric] > b->metrics[metric]
                   : a->metrics[metric] < b->metrics[metric];
  });
  if (static_cast<long>(ranked.size()) > std::max(0L, count))
    ranked.resize(static_cast<size_t>(std::max(0L, count)));
  return ranked;
}

StudyReport study_report_of(const Study& study, const StudyDatabase& db,
                            const std::string& mechanism, const std::string& origin,
                            const StudyReportRequest& request) {
  const std::vector<StudyDatabase::Row> rows = db.rows();
  StudyReport r;
  r.title = request.title;
  r.summary = request.summary;
  r.kind = study.kind == StudyKind::grid          ? "grid"
           : study.kind == StudyKind::monte_carlo ? "monte-carlo"
                                                  : "optimize";
  for (const auto& row : rows) r.variants.push_back(row.index);
  for (size_t p = 0; p < db.parameters().size(); ++p) {
    r.parameters.push_back({db.parameters()[p], {}});
    for (const auto& row : rows) r.parameters.back().values.push_back(row.values[p]);
  }
  const std::vector<std::string> shown =
      request.metrics.empty() ? default_report_metrics(study, db, rows) : request.metrics;
  std::vector<std::vector<double>> values;
  values.reserve(rows.size());
  for (const auto& row : rows) values.push_back(row.values);
  for (const std::string& name : shown) {
    const auto& names = db.metrics();
    const auto it = std::find(names.begin(), names.end(), name);
    if (it == names.end()) {
      std::string list;
      for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
      throw std::invalid_argument("unknown metric '" + name + "' (the study's metrics: " + list +
                                  ")");
    }
    const auto m = static_cast<size_t>(it - names.begin());
    r.metrics.push_back({name, summarized_metric(rows, m, name)});
    if (study.kind == StudyKind::monte_carlo) {
      const MetricStatistics s = metric_statistics(name, values, r.metrics.back().values);
      StudyReportStatistics st{s.q05, s.q50, s.q95, {}};
      for (const auto& sens : s.sensitivity)
        st.sensitivity.push_back(sens ? std::optional<StudyReportStatistics::Sensitivity>(
                                            {sens->coefficient, sens->low, sens->high})
                                      : std::nullopt);
      r.statistics.push_back(st);
    }
  }
  r.convergence = request.convergence;
  r.objective = request.objective;
  const auto& names = db.metrics();
  const auto best = std::find(names.begin(), names.end(), study.best_metric);
  if (!request.best.empty()) {  // a search's, as given
    r.best_metric = "objective";
    for (const long v : request.best) {
      const auto row = std::find_if(rows.begin(), rows.end(),
                                    [&](const StudyDatabase::Row& w) { return w.index == v; });
      if (row == rows.end()) continue;
      r.best.push_back(v);
      if (static_cast<long>(r.cycles.size()) < request.cycles)
        r.cycles.push_back(variant_cycle(mechanism, origin, study, v, row->values));
    }
  } else if (study.kind == StudyKind::grid && best != names.end()) {
    r.best_metric = study.best_metric;
    for (const auto* row : best_rows(rows, static_cast<size_t>(best - names.begin()),
                                     study.best_largest, study.best_count)) {
      r.best.push_back(row->index);
      if (static_cast<long>(r.cycles.size()) < request.cycles)
        r.cycles.push_back(variant_cycle(mechanism, origin, study, row->index, row->values));
    }
  }
  return r;
}

std::string convergence_svg(const StudyReport& report) {
  return "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n" + convergence_plot(report) + "\n";
}

int histogram_bins(long n) {
  if (n <= 1) return 1;
  return std::clamp(static_cast<int>(std::ceil(std::log2(static_cast<double>(n)))) + 1, 1, 40);
}

std::vector<HistogramBin> histogram(const std::vector<double>& values, int bins) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const double v : values)
    if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
  if (!(lo <= hi)) return {};
  if (hi == lo) bins = 1;
  bins = std::max(1, bins);
  std::vector<HistogramBin> out(static_cast<size_t>(bins));
  const double width = (hi - lo) / bins;
  for (int b = 0; b < bins; ++b) {
    out[static_cast<size_t>(b)].low = lo + width * b;
    out[static_cast<size_t>(b)].high = b + 1 == bins ? hi : lo + width * (b + 1);
  }
  for (const double v : values) {
    if (!std::isfinite(v)) continue;
    const int b = width > 0.0 ? std::min(bins - 1, static_cast<int>((v - lo) / width)) : 0;
    ++out[static_cast<size_t>(b)].count;
  }
  return out;
}

std::string study_report_html(const StudyReport& r) {
  check_shape(r);
  std::string html =
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>" +
      escape_html(r.title) + "</title>\n";
  html +=
      "<script>window.reportErrors = []; window.addEventListener('error', function (e) { "
      "window.reportErrors.push(String(e.message || e)); });</script>\n";
  html += "<style>" + std::string(kStyle) + "</style>\n</head>\n<body>\n";
  html += "<h1>" + escape_html(r.title) + "</h1>\n<p>" + escape_html(r.kind) + " study, " +
          std::to_string(r.variants.size()) + " variants shown (metrics in the file's units)</p>\n";
  html += "<details><summary>the summary</summary><pre id=\"summary\">" + escape_html(r.summary) +
          "</pre></details>\n";
  html += convergence_section(r) + best_section(r) + scatter_section(r) + histogram_section(r) +
          sensitivity_section(r);
  html += "<script>" + std::string(kScript) + "</script>\n</body>\n</html>\n";
  return html;
}

std::vector<StudyFigure> study_report_figures(const StudyReport& r) {
  check_shape(r);
  const auto file_name = [](const std::string& prefix, const std::string& metric) {
    std::string name = prefix;
    for (const char c : metric)
      name += std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '.' || c == '_' || c == '-'
                  ? c
                  : '_';
    return name + ".svg";
  };
  const std::string xml = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  std::vector<StudyFigure> out;
  // The scatter matrix as one document: the panels side by side, a row per metric.
  const double w = kPanelW * static_cast<double>(r.parameters.size());
  const double h = kPanelH * static_cast<double>(r.metrics.size());
  std::string scatter = xml + svg_open("scatter-matrix", std::max(w, 1.0), std::max(h, 1.0), "");
  for (size_t m = 0; m < r.metrics.size(); ++m)
    for (size_t p = 0; p < r.parameters.size(); ++p)
      scatter += "<g transform=\"translate(" + px(kPanelW * static_cast<double>(p)) + "," +
                 px(kPanelH * static_cast<double>(m)) + ")\">" + scatter_panel(r, p, m) + "</g>";
  out.push_back({"scatter.svg", scatter + "</svg>\n"});
  if (!r.convergence.empty()) out.push_back({"convergence.svg", convergence_svg(r)});
  for (size_t m = 0; m < r.metrics.size(); ++m) {
    out.push_back({file_name("histogram-", r.metrics[m].name), xml + histogram_svg(r, m) + "\n"});
    if (!r.statistics.empty())
      out.push_back(
          {file_name("sensitivity-", r.metrics[m].name), xml + sensitivity_svg(r, m) + "\n"});
  }
  return out;
}

}  // namespace orthomech
