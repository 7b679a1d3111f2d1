#include "orthomech/io/report.hpp"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "orthomech/check.hpp"

namespace orthomech {

std::string escape_html(const std::string& s) {
  std::string out;
  out.reserve(s.size());
  for (const char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

namespace {

// JSON inside <script>: "</" written as "<\/" so that no "</script>" ends the element early.
std::string script_json(const nlohmann::json& j) {
  const std::string text = j.dump();
  std::string out;
  out.reserve(text.size());
  for (size_t i = 0; i < text.size(); ++i) {
    out += text[i];
    if (text[i] == '<' && i + 1 < text.size() && text[i + 1] == '/') out += '\\';
  }
  return out;
}

size_t count_frames(const std::string& svg) {
  size_t n = 0;
  for (size_t at = svg.find("<g id=\"frame-"); at != std::string::npos;
       at = svg.find("<g id=\"frame-", at + 1))
    ++n;
  return n;
}

// The SVG document without its XML declaration (inline in HTML).
std::string inline_svg(const std::string& svg) {
  const size_t start = svg.find("<svg");
  if (start == std::string::npos) throw std::invalid_argument("report: the animation is no SVG");
  return svg.substr(start);
}

constexpr const char* kStyle = R"(
body { font-family: "DejaVu Sans", sans-serif; margin: 16px; color: #222; }
h1 { font-size: 20px; margin: 0 0 12px 0; }
h2 { font-size: 16px; }
.row { display: flex; flex-wrap: wrap; gap: 16px; align-items: flex-start; }
#mechanism { display: inline-block; border: 1px solid #ccc; }
#mechanism svg { display: block; }
.controls { margin: 8px 0; display: flex; gap: 8px; align-items: center; font-size: 13px; }
#position { width: 480px; }
#play { width: 64px; }
pre { font-size: 12px; background: #f6f6f6; padding: 8px; overflow-x: auto; }
svg.plot { display: block; border: 1px solid #ddd; margin-bottom: 12px; background: #fff; }
svg.plot text { font-size: 11px; fill: #333; }
svg.plot .title { font-size: 13px; font-weight: bold; }
svg.plot .grid { stroke: #eee; }
svg.plot .cursor { stroke: #d00; stroke-width: 1.5; }
#tooltip { position: absolute; pointer-events: none; background: rgba(255, 255, 240, 0.95);
  border: 1px solid #888; padding: 4px 6px; font-size: 12px; white-space: pre; display: none; }
)";

// The page's script: plots, cursor, tooltip, slider and play button (report.hpp: the contract).
constexpr const char* kScript = R"JS(
(function () {
  'use strict';
  var data = JSON.parse(document.getElementById('report-data').textContent);
  var NS = 'http://www.w3.org/2000/svg';
  var n = data.input.length;
  var slider = document.getElementById('position');
  var play = document.getElementById('play');
  var readout = document.getElementById('readout');
  var tooltip = document.getElementById('tooltip');
  var mechanism = document.querySelector('#mechanism svg');
  // The frames are switched by this script: the standalone SVG's own (SMIL) timing goes.
  Array.prototype.slice.call(mechanism.querySelectorAll('animate')).forEach(function (a) {
    a.parentNode.removeChild(a);
  });
  var frames = Array.prototype.slice.call(mechanism.querySelectorAll('g[id^="frame-"]'));
  var colours = ['#1f5fbf', '#d2691e', '#2e8b57', '#8b3fbf', '#c0392b', '#16a085', '#7f8c8d',
                 '#b8860b'];
  var W = 520, H = 230, ML = 72, MR = 16, MT = 30, MB = 40;

  function fmt(v) {
    if (v === null || v === undefined) return 'not reported';
    var a = Math.abs(v);
    if (a !== 0 && (a < 1e-3 || a >= 1e6)) return v.toExponential(4);
    return String(+v.toPrecision(5));
  }
  function el(name, attrs, parent) {
    var e = document.createElementNS(NS, name);
    for (var k in attrs) e.setAttribute(k, attrs[k]);
    if (parent) parent.appendChild(e);
    return e;
  }
  // Round tick values covering [lo, hi], about `count` of them.
  function ticks(lo, hi, count) {
    var span = hi - lo;
    var step = Math.pow(10, Math.floor(Math.log10(span / count)));
    var err = count * step / span;
    if (err <= 0.15) step *= 10; else if (err <= 0.35) step *= 5; else if (err <= 0.75) step *= 2;
    var t = [];
    for (var v = Math.ceil(lo / step) * step; v <= hi + 1e-9 * step; v += step)
      t.push(Math.abs(v) < 1e-9 * step ? 0 : v);
    return t;
  }
  function range(values) {
    var lo = Infinity, hi = -Infinity;
    values.forEach(function (v) {
      if (v === null) return;
      lo = Math.min(lo, v);
      hi = Math.max(hi, v);
    });
    if (!(lo <= hi)) return [0, 1];
    if (lo === hi) {
      var d = lo === 0 ? 1 : 0.1 * Math.abs(lo);
      return [lo - d, hi + d];
    }
    return [lo, hi];
  }

  var xr = range(data.input);
  function makePlot(p) {
    var svg = el('svg', {'class': 'plot', id: 'plot-' + p.id, width: W, height: H,
                         viewBox: '0 0 ' + W + ' ' + H});
    var all = [];
    p.series.forEach(function (s) { all = all.concat(s.values); });
    var yr = range(all), pad = 0.05 * (yr[1] - yr[0]);
    var ylo = yr[0] - pad, yhi = yr[1] + pad;
    function X(v) { return ML + (v - xr[0]) / (xr[1] - xr[0]) * (W - ML - MR); }
    function Y(v) { return H - MB - (v - ylo) / (yhi - ylo) * (H - MT - MB); }
    ticks(xr[0], xr[1], 8).forEach(function (t) {
      el('line', {'class': 'grid', x1: X(t), x2: X(t), y1: MT, y2: H - MB}, svg);
      el('text', {x: X(t), y: H - MB + 14, 'text-anchor': 'middle'}, svg).textContent = fmt(t);
    });
    ticks(ylo, yhi, 5).forEach(function (t) {
      el('line', {'class': 'grid', x1: ML, x2: W - MR, y1: Y(t), y2: Y(t)}, svg);
      el('text', {x: ML - 4, y: Y(t) + 4, 'text-anchor': 'end'}, svg).textContent = fmt(t);
    });
    el('rect', {x: ML, y: MT, width: W - ML - MR, height: H - MT - MB, fill: 'none',
                stroke: '#999'}, svg);
    el('text', {'class': 'title', x: ML, y: 18}, svg).textContent =
        p.title + ' [' + p.unit + ']';
    el('text', {x: (ML + W - MR) / 2, y: H - 6, 'text-anchor': 'middle'}, svg).textContent =
        data.input_label;
    var legendX = W - MR;
    var markers = [];
    p.series.slice().reverse().forEach(function (s, r) {
      var c = colours[(p.series.length - 1 - r) % colours.length];
      var t = el('text', {x: legendX, y: 18, 'text-anchor': 'end', fill: c}, svg);
      t.textContent = s.name;
      t.style.fill = c;
      legendX -= 8 + 6.5 * s.name.length;
    });
    p.series.forEach(function (s, i) {
      var c = colours[i % colours.length], d = '', pen = false;
      s.values.forEach(function (v, k) {
        if (v === null) { pen = false; return; }
        d += (pen ? 'L' : 'M') + X(data.input[k]).toFixed(2) + ' ' + Y(v).toFixed(2);
        pen = true;
      });
      el('path', {'class': 'series', 'data-series': s.name, d: d, fill: 'none', stroke: c,
                  'stroke-width': 1.8}, svg);
      markers.push(el('circle', {r: 4, fill: c, visibility: 'hidden'}, svg));
    });
    var cursor = el('line', {'class': 'cursor', x1: 0, x2: 0, y1: MT, y2: H - MB}, svg);
    var overlay = el('rect', {x: ML, y: MT, width: W - ML - MR, height: H - MT - MB,
                              fill: 'transparent', 'pointer-events': 'all'}, svg);
    // Hover: the position whose plotted point is nearest the pointer, over every series.
    function nearest(evt) {
      var box = svg.getBoundingClientRect();
      var mx = evt.clientX - box.left, my = evt.clientY - box.top, best = 0, bestD = Infinity;
      p.series.forEach(function (s) {
        s.values.forEach(function (v, k) {
          if (v === null) return;
          var dx = X(data.input[k]) - mx, dy = Y(v) - my, d2 = dx * dx + dy * dy;
          if (d2 < bestD) { bestD = d2; best = k; }
        });
      });
      return best;
    }
    overlay.addEventListener('mousemove', function (evt) {
      var k = nearest(evt);
      var lines = [data.input_label + ' = ' + fmt(data.input[k])];
      p.series.forEach(function (s, i) {
        var v = s.values[k];
        lines.push(s.name + ' = ' + fmt(v) + (v === null ? '' : ' ' + p.unit));
        markers[i].setAttribute('visibility', v === null ? 'hidden' : 'visible');
        if (v !== null) {
          markers[i].setAttribute('cx', X(data.input[k]));
          markers[i].setAttribute('cy', Y(v));
        }
      });
      tooltip.textContent = lines.join('\n');
      tooltip.dataset.position = k;
      tooltip.style.display = 'block';
      tooltip.style.left = (evt.pageX + 14) + 'px';
      tooltip.style.top = (evt.pageY + 14) + 'px';
    });
    overlay.addEventListener('mouseleave', function () {
      tooltip.style.display = 'none';
      markers.forEach(function (m) { m.setAttribute('visibility', 'hidden'); });
    });
    overlay.addEventListener('click', function (evt) {
      setPlaying(false);
      show(nearest(evt));
    });
    document.getElementById('plots').appendChild(svg);
    return function (k) {
      var x = X(data.input[k]);
      cursor.setAttribute('x1', x);
      cursor.setAttribute('x2', x);
      cursor.dataset.position = k;
    };
  }
  var cursors = data.plots.map(makePlot);

  var current = 0, playing = false, last = null, interval = 1000 * data.duration / n;
  function show(k) {
    k = ((k % n) + n) % n;
    if (frames[current]) frames[current].setAttribute('display', 'none');
    if (frames[k]) frames[k].setAttribute('display', 'inline');
    current = k;
    slider.value = String(k);
    cursors.forEach(function (update) { update(k); });
    readout.textContent = 'position ' + (k + 1) + ' of ' + n + ', ' + data.input_label + ' = ' +
                          fmt(data.input[k]);
    document.body.dataset.position = k;
  }
  function tick(t) {
    if (!playing) return;
    if (last === null) last = t;
    var steps = Math.floor((t - last) / interval);
    if (steps > 0) {
      last += steps * interval;
      show(current + steps);
    }
    requestAnimationFrame(tick);
  }
  function setPlaying(on) {
    playing = on;
    play.textContent = on ? 'Pause' : 'Play';
    play.setAttribute('aria-pressed', on ? 'true' : 'false');
    if (on) {
      last = null;
      requestAnimationFrame(tick);
    }
  }
  slider.addEventListener('input', function () {
    setPlaying(false);
    show(parseInt(slider.value, 10));
  });
  play.addEventListener('click', function () { setPlaying(!playing); });
  frames.forEach(function (f, k) { f.setAttribute('display', k === 0 ? 'inline' : 'none'); });
  show(0);
  setPlaying(true);
  document.body.dataset.ready = 'yes';
})();
)JS";

}  // namespace

std::vector<std::size_t> picture_positions(std::size_t n) {
  std::vector<std::size_t> k;
  k.reserve(std::min(n, kMaxPictureFrames));
  if (n <= kMaxPictureFrames) {
    for (std::size_t i = 0; i < n; ++i) k.push_back(i);
    return k;
  }
  // m evenly spaced of the n: i_j = round(j (n − 1) / (m − 1)), strictly increasing as n > m.
  const std::size_t m = kMaxPictureFrames;
  for (std::size_t j = 0; j < m; ++j)
    k.push_back(static_cast<std::size_t>(std::llround(
        static_cast<double>(j) * static_cast<double>(n - 1) / static_cast<double>(m - 1))));
  return k;
}

std::string cycle_report_html(const CycleReport& report) {
  const size_t n = report.input.size();
  check_argument(n != 0, "cycle_report_html", "report.input", "must not be empty (no positions)");
  const std::vector<std::size_t> shown = picture_positions(n);
  check_argument(count_frames(report.animation) == shown.size(), "cycle_report_html",
                 "report.animation", "must have one frame per picture position");
  nlohmann::json data;
  std::vector<double> input;
  input.reserve(shown.size());
  for (const std::size_t k : shown) input.push_back(report.input[k]);
  data["input"] = input;
  data["input_label"] = report.input_label;
  data["duration"] = report.duration;
  nlohmann::json plots = nlohmann::json::array();
  for (const ReportPlot& p : report.plots) {
    nlohmann::json series = nlohmann::json::array();
    for (const ReportSeries& s : p.series) {
      check_argument(s.values.size() == n, "cycle_report_html", "report.plots",
                     "must have one value per position in every series");
      nlohmann::json values = nlohmann::json::array();
      for (const std::size_t k : shown)
        values.push_back(s.values[k] ? nlohmann::json(*s.values[k]) : nlohmann::json());
      series.push_back({{"name", s.name}, {"values", values}});
    }
    plots.push_back({{"id", p.id}, {"title", p.title}, {"unit", p.unit}, {"series", series}});
  }
  data["plots"] = plots;

  const std::string title = escape_html(report.title);
  std::string html;
  html.reserve(report.animation.size() + 64 * 1024);
  html += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>";
  html += title + " - orthomech cycle</title>\n";
  // First of all: collect script errors (the browser tests read them).
  html +=
      "<script>window.reportErrors = []; window.addEventListener('error', function (e) { "
      "window.reportErrors.push(String(e.message || e)); });</script>\n";
  html += "<style>" + std::string(kStyle) + "</style>\n</head>\n<body>\n";
  html += "<h1>" + title + "</h1>\n<div class=\"row\">\n<div>\n<div id=\"mechanism\">\n";
  html += inline_svg(report.animation);
  html += "</div>\n<div class=\"controls\"><button id=\"play\" type=\"button\">Play</button>";
  html += "<input id=\"position\" type=\"range\" min=\"0\" max=\"" + std::to_string(n - 1) +
          "\" step=\"1\" value=\"0\" aria-label=\"position\">";
  html += "<span id=\"readout\"></span></div>\n</div>\n<div id=\"plots\"></div>\n</div>\n";
  html += "<h2>Summary</h2>\n<pre id=\"summary\">" + escape_html(report.summary) + "</pre>\n";
  html += "<div id=\"tooltip\"></div>\n";
  html +=
      "<script type=\"application/json\" id=\"report-data\">" + script_json(data) + "</script>\n";
  html += "<script>" + std::string(kScript) + "</script>\n</body>\n</html>\n";
  return html;
}

}  // namespace orthomech
