// `synthesize --report FILE.html` (io/synthesis_output.hpp): the candidates drawn over the targets.
// Three steps: the sketch of a candidate in model coordinates (sketch), the view that fits it
// (fit), and the SVG of the sketch in that view (svg_of); the page puts the table above.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <sstream>
#include <vector>

#include "orthomech/io/report.hpp"
#include "orthomech/io/synthesis_output.hpp"

namespace orthomech {

namespace {

using synthesis::FourBar;
using synthesis::FourBarPosition;
using synthesis::SliderCrank;
using synthesis::SliderCrankPosition;
using synthesis::SynthesisCandidate;
using synthesis::SynthesisResult;
using synthesis::SynthesisTask;
using synthesis::TaskKind;
using synthesis::Vec2;

constexpr double kPi = std::numbers::pi;
constexpr double kWidth = 480, kHeight = 360, kMargin = 24;

// ---- 1. The sketch (task length units) ----------------------------------------------------------

struct Target {
  Vec2 at;
  bool has_angle = false;  // a pose: an arrow along its x axis
  double angle = 0.0;
};

struct Sketch {
  std::vector<Target> targets;
  std::vector<std::vector<Vec2>> curve;  // pieces where the linkage assembles
  // The linkage at the first target (none when it does not assemble there).
  std::vector<std::array<Vec2, 2>> links, ground;  // segments: bodies; ground line / slider guide
  std::vector<Vec2> pivots, joints;
};

// The curve's crank angles: every degree of the motion and the targets' own angles.
std::vector<double> curve_angles(const SynthesisCandidate& c) {
  const double from = c.cycle ? c.cycle->from : c.crank_angles.front();
  const double to = c.cycle ? c.cycle->to : c.crank_angles.back();
  const int steps = std::max(2, static_cast<int>(std::ceil(std::abs(to - from) / (kPi / 180))));
  std::vector<double> angles;
  for (int k = 0; k <= steps; ++k) angles.push_back(from + (to - from) * k / steps);
  angles.insert(angles.end(), c.crank_angles.begin(), c.crank_angles.end());
  if (to >= from)
    std::sort(angles.begin(), angles.end());
  else
    std::sort(angles.begin(), angles.end(), std::greater<>());
  return angles;
}

// One closed-form position of either linkage: whether it assembles, its traced point (the
// coupler point; a function task's output pin B) and its joints.
struct Placed {
  bool assembles = false;
  Vec2 traced, A, B, P;
};
// A spatial RSSR is drawn in the isometric view of its world frame (x to the lower right, y to
// the lower left, z up): (x, y, z) ↦ ((x − y) cos 30°, z − (x + y) sin 30°).
Vec2 isometric(const synthesis::Vec3& p) {
  return {(p.x() - p.y()) * std::cos(kPi / 6), p.z() - (p.x() + p.y()) * 0.5};
}

Placed place(const synthesis::Linkage& linkage, double theta, bool function) {
  Placed out;
  if (const auto* r = std::get_if<synthesis::Rssr>(&linkage)) {
    const synthesis::RssrPosition p = calc_position(*r, theta);
    const Vec2 A = isometric(p.A), B = isometric(p.B);
    return {p.assembles, B, A, B, B};
  }
  if (const auto* fb = std::get_if<FourBar>(&linkage)) {
    const FourBarPosition p = calc_position(*fb, theta);
    out = {p.assembles, p.P, p.A, p.B, p.P};
  } else {
    const SliderCrankPosition p = calc_position(std::get<SliderCrank>(linkage), theta);
    out = {p.assembles, p.P, p.A, p.B, p.P};
  }
  if (function) out.traced = out.B;
  return out;
}

// The target points: a path's points, a motion's poses, a function's output pin at the asked
// output (the follower's pin at angle ψ + offset; the slider's pin at s on its line).
std::vector<Target> targets(const SynthesisTask& task, const SynthesisCandidate& c) {
  const double L = task.length_si;
  std::vector<Target> out;
  for (size_t j = 0; j < c.crank_angles.size(); ++j) {
    if (task.kind != TaskKind::function) {
      out.push_back({task.positions[j] / L, task.kind == TaskKind::motion,
                     task.kind == TaskKind::motion ? task.angles[j] : 0.0});
    } else if (const auto* r = std::get_if<synthesis::Rssr>(&c.linkage)) {
      out.push_back({isometric(output_pin(*r, task.outputs[j])) / L});
    } else if (const auto* fb = std::get_if<FourBar>(&c.linkage)) {
      const double psi = task.outputs[j] + c.output_offset;
      out.push_back({(fb->B0 + fb->c * Vec2(std::cos(psi), std::sin(psi))) / L});
    } else {
      const auto& sc = std::get<SliderCrank>(c.linkage);
      const Vec2 t(std::cos(sc.line_angle), std::sin(sc.line_angle)), n(-t.y(), t.x());
      out.push_back({(sc.O + sc.offset * n + task.outputs[j] * t) / L});
    }
  }
  return out;
}

Sketch sketch(const SynthesisTask& task, const SynthesisCandidate& c) {
  const double L = task.length_si;
  const bool function = task.kind == TaskKind::function;
  Sketch s;
  s.targets = targets(task, c);
  std::vector<Vec2> piece, pins;  // pins: the output pin B over the motion (a slider's stroke)
  for (const double theta : curve_angles(c)) {
    const Placed p = place(c.linkage, theta, function);
    if (!p.assembles) {
      if (piece.size() > 1) s.curve.push_back(piece);
      piece.clear();
      continue;
    }
    piece.emplace_back(p.traced / L);
    pins.emplace_back(p.B / L);
  }
  if (piece.size() > 1) s.curve.push_back(piece);
  const Placed p0 = place(c.linkage, c.crank_angles.front(), function);
  if (!p0.assembles) return s;
  const Vec2 A = p0.A / L, B = p0.B / L, P = p0.P / L;
  s.joints = {A, B};
  if (const auto* r = std::get_if<synthesis::Rssr>(&c.linkage)) {  // the axes as dashed lines
    const Vec2 P1 = isometric(r->input.point) / L, P2 = isometric(r->output.point) / L;
    const double reach = std::max({r->a.norm(), r->b.norm(), r->coupler}) / L;
    s.links = {{P1, A}, {A, B}, {P2, B}};
    for (const synthesis::RevoluteAxis* ax : {&r->input, &r->output}) {
      const synthesis::Vec3 u = ax->direction.normalized() * (0.5 * reach * L);
      s.ground.push_back({isometric(ax->point - u) / L, isometric(ax->point + u) / L});
    }
    s.pivots = {P1, P2};
  } else if (const auto* fb = std::get_if<FourBar>(&c.linkage)) {
    const Vec2 A0 = fb->A0 / L, B0 = fb->B0 / L;
    s.links = {{A0, A}, {A, B}, {B0, B}, {A, P}, {B, P}};
    s.ground = {{A0, B0}};
    s.pivots = {A0, B0};
  } else {  // the guide over the stroke, the slider block at B
    const auto& sc = std::get<SliderCrank>(c.linkage);
    const Vec2 O = sc.O / L, t(std::cos(sc.line_angle), std::sin(sc.line_angle));
    double lo = 0.0, hi = 0.0;
    for (const Vec2& b : pins) lo = std::min(lo, (b - B).dot(t)), hi = std::max(hi, (b - B).dot(t));
    const double margin = 0.1 * std::max(hi - lo, sc.l / L);
    s.links = {{O, A}, {A, B}, {A, P}, {B, P}};
    s.ground = {{B + (lo - margin) * t, B + (hi + margin) * t}};
    s.pivots = {O, B};
  }
  return s;
}

// ---- 2. The view ----------------------------------------------------------------------------

struct View {
  double scale = 1.0, x0 = 0.0, y0 = 0.0;  // pixel = (x0 + s x, y0 − s y)
  double arrow = 1.0;                      // a pose arrow's length (model units)
  [[nodiscard]] double px(const Vec2& p) const { return x0 + scale * p.x(); }
  [[nodiscard]] double py(const Vec2& p) const { return y0 - scale * p.y(); }
};

View fit(const Sketch& s) {
  Vec2 lo = Vec2::Constant(1e300), hi = Vec2::Constant(-1e300);
  const auto add = [&](const Vec2& p) { lo = lo.cwiseMin(p), hi = hi.cwiseMax(p); };
  for (const Target& t : s.targets) add(t.at);
  for (const auto& piece : s.curve)
    for (const Vec2& p : piece) add(p);
  for (const auto& seg : s.links) add(seg[0]), add(seg[1]);
  for (const auto& seg : s.ground) add(seg[0]), add(seg[1]);
  const Vec2 size = (hi - lo).cwiseMax(1e-9);
  View v;
  v.scale = std::min((kWidth - 2 * kMargin) / size.x(), (kHeight - 2 * kMargin) / size.y());
  const Vec2 mid = (lo + hi) / 2;
  v.x0 = kWidth / 2 - v.scale * mid.x();
  v.y0 = kHeight / 2 + v.scale * mid.y();
  v.arrow = 0.06 * size.maxCoeff();
  return v;
}

// ---- 3. The SVG -------------------------------------------------------------------------------

std::string num(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3f", v);
  return b;
}

void line(std::ostringstream& out, const View& v, const Vec2& a, const Vec2& b, const char* cls) {
  out << "<line class=\"" << cls << "\" x1=\"" << num(v.px(a)) << "\" y1=\"" << num(v.py(a))
      << "\" x2=\"" << num(v.px(b)) << "\" y2=\"" << num(v.py(b)) << "\"/>\n";
}

std::string svg_of(const Sketch& s, const View& v, const SynthesisCandidate& c) {
  std::ostringstream out;
  char view[96];
  std::snprintf(view, sizeof view, "%.17g %.17g %.17g", v.scale, v.x0, v.y0);
  out << "<svg class=\"candidate\" data-name=\"" << escape_html(c.name) << "\" data-view=\"" << view
      << "\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" << kWidth << "\" height=\"" << kHeight
      << "\" viewBox=\"0 0 " << kWidth << ' ' << kHeight << "\">\n";
  for (const auto& piece : s.curve) {
    out << "<polyline class=\"curve\" points=\"";
    for (const Vec2& p : piece) out << num(v.px(p)) << ',' << num(v.py(p)) << ' ';
    out << "\"/>\n";
  }
  for (const auto& seg : s.ground) line(out, v, seg[0], seg[1], "ground");
  for (const auto& seg : s.links) line(out, v, seg[0], seg[1], "link");
  for (const Vec2& p : s.pivots)
    out << "<rect class=\"pivot\" x=\"" << num(v.px(p) - 5) << "\" y=\"" << num(v.py(p) - 5)
        << "\" width=\"10\" height=\"10\"/>\n";
  for (const Vec2& p : s.joints)
    out << "<circle class=\"joint\" cx=\"" << num(v.px(p)) << "\" cy=\"" << num(v.py(p))
        << "\" r=\"3.5\"/>\n";
  for (const Target& t : s.targets) {
    out << "<circle class=\"target\" cx=\"" << num(v.px(t.at)) << "\" cy=\"" << num(v.py(t.at))
        << "\" r=\"5\"/>\n";
    if (t.has_angle)
      line(out, v, t.at, t.at + v.arrow * Vec2(std::cos(t.angle), std::sin(t.angle)), "pose");
  }
  out << "</svg>\n";
  return out.str();
}

std::string caption(const SynthesisTask& task, const SynthesisCandidate& c) {
  std::ostringstream out;
  out << "<figcaption><b>" << escape_html(c.name) << "</b> — " << escape_html(c.method);
  if (c.cycle) {
    char b[160];
    std::snprintf(b, sizeof b, "; peak drive %.4g N*%s, largest pin force %.4g N (%s)",
                  c.cycle->peak_drive / task.length_si, task.length_unit.c_str(),
                  c.cycle->peak_pin_force, c.cycle->peak_pin.c_str());
    out << escape_html(b);
  }
  for (const std::string& why : c.rejections)
    out << "<br><span class=\"why\">rejected: " << escape_html(why) << "</span>";
  out << "</figcaption>\n";
  return out.str();
}

}  // namespace

std::string synthesis_report_html(const SynthesisTask& task, const SynthesisResult& result) {
  std::ostringstream out;
  out << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>"
      << escape_html(task.name) << " — orthomech synthesize</title>\n<style>\n"
      << "body{font-family:sans-serif;margin:1.5em}pre{background:#f4f4f4;padding:.8em}\n"
      << "figure{display:inline-block;margin:.5em;vertical-align:top;max-width:480px}\n"
      << "svg.candidate{border:1px solid #ccc;background:#fff}\n"
      << ".curve{fill:none;stroke:#bf008c;stroke-width:2}.link{stroke:#333;stroke-width:3}\n"
      << ".ground{stroke:#999;stroke-width:1;stroke-dasharray:4 3}.pivot{fill:#666}\n"
      << ".joint{fill:#fff;stroke:#333;stroke-width:1.5}\n"
      << ".target{fill:none;stroke:#0060c0;stroke-width:2}.pose{stroke:#0060c0;stroke-width:2}\n"
      << ".rejected svg{opacity:.55}.why{color:#a00}\n</style>\n</head>\n<body>\n<h1>"
      << escape_html(task.name) << "</h1>\n<pre id=\"summary\">"
      << escape_html(synthesis_text(task, result)) << "</pre>\n";
  out << "<p>Targets: blue circles (a pose with its x axis). Each candidate: the linkage at the "
         "first target, and the path of its "
      << (task.kind == TaskKind::function ? "output pin B" : "coupler point P")
      << " over its motion (magenta)."
      << (task.linkage == synthesis::TaskLinkage::rssr
              ? " A spatial RSSR is drawn in the isometric view of its world frame (x to the "
                "lower right, y to the lower left, z up), its revolute axes dashed."
              : "")
      << "</p>\n";
  for (const auto* list : {&result.accepted, &result.rejected}) {
    out << "<h2>" << (list == &result.accepted ? "Accepted" : "Rejected") << " (" << list->size()
        << ")</h2>\n";
    for (const SynthesisCandidate& c : *list) {
      const Sketch s = sketch(task, c);
      out << "<figure class=\"" << (c.accepted() ? "accepted" : "rejected") << "\">\n"
          << svg_of(s, fit(s), c) << caption(task, c) << "</figure>\n";
    }
  }
  out << "</body>\n</html>\n";
  return out.str();
}

}  // namespace orthomech
