#include "orthomech/io/render.hpp"

#include <cairo-pdf.h>
#include <cairo-svg.h>
#include <cairo.h>
#include <fontconfig/fontconfig.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <memory>
#include <numbers>
#include <stdexcept>

#include "orthomech/analysis/assembly.hpp"
#include "orthomech/analysis/cycle.hpp"
#include "orthomech/check.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/io/file_writer.hpp"
#include "orthomech/io/report.hpp"
#include "orthomech/io/units.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/model/spatial.hpp"
#include "shared_library.hpp"

namespace orthomech {

namespace {

constexpr double kPi = std::numbers::pi;

// ---- colours and sizes (px) --------------------------------------------------------------------
constexpr Rgba kInk{0.1, 0.1, 0.1, 1.0};
constexpr Rgba kGroundFill{0.85, 0.85, 0.85, 1.0};
constexpr Rgba kDriverRed{0.85, 0.1, 0.1, 1.0};
constexpr Rgba kSliderFill{0.82, 0.87, 0.95, 1.0};
constexpr Rgba kGearGreen{0.1, 0.55, 0.25, 1.0};
constexpr Rgba kSpringBlue{0.15, 0.35, 0.75, 1.0};
// Trace colours, cycled: saturated, unlike the pastel bodies.
constexpr Rgba kTrace[] = {
    {0.75, 0.0, 0.55, 1.0}, {0.0, 0.55, 0.6, 1.0}, {0.9, 0.45, 0.0, 1.0}, {0.35, 0.2, 0.8, 1.0}};
constexpr double kTraceWidth = 3.0;
// Body colours, cycled: pastel fills with a darker edge of the same hue.
constexpr Rgba kBodyFill[] = {{0.55, 0.68, 0.88, 0.6}, {0.62, 0.82, 0.62, 0.6},
                              {0.92, 0.66, 0.55, 0.6}, {0.78, 0.66, 0.88, 0.6},
                              {0.88, 0.80, 0.50, 0.6}, {0.55, 0.82, 0.82, 0.6}};
constexpr Rgba kBodyEdge[] = {{0.20, 0.30, 0.55, 1.0}, {0.20, 0.45, 0.20, 1.0},
                              {0.60, 0.30, 0.20, 1.0}, {0.40, 0.25, 0.55, 1.0},
                              {0.55, 0.45, 0.10, 1.0}, {0.15, 0.45, 0.45, 1.0}};
constexpr double kBarWidth = 10.0;        // a two-point body
constexpr double kGroundTriangle = 20.0;  // height of the pivot support
constexpr double kHatch = 6.0;            // length of a hatch stroke
constexpr double kSliderLength = 30.0, kSliderHeight = 16.0;
constexpr double kSlotWidth = 12.0;
constexpr double kPointRadius = 2.5;
constexpr double kDriverRadius = 15.0;
constexpr double kLabelSize = 11.0;
constexpr double kTriadLength = 25.0;  // px, an axis of the ground frame's triad
// Two drawn points closer than this (m) are the same place (a named point at a joint).
constexpr double kSamePlace = 1e-9;

Vertex at(const Vec2& model, const Vec2& px = Vec2::Zero()) { return Vertex{model, px, false}; }
Vertex screen(double x, double y) { return Vertex{Vec2::Zero(), Vec2(x, y), true}; }

// A model direction as a unit vector in pixel axes (y down), and a perpendicular to it.
Vec2 px_dir(const Vec2& d) {
  const double n = d.norm();
  return n > 0.0 ? Vec2(d.x() / n, -d.y() / n) : Vec2(1.0, 0.0);
}
Vec2 px_perp(const Vec2& d_px) { return Vec2(-d_px.y(), d_px.x()); }

Style stroke_only(const Rgba& c, double width, bool round = false) {
  Style s;
  s.stroke = c;
  s.line_width = width;
  s.round = round;
  return s;
}
Style filled(const Rgba& fill, const Rgba& edge, double width) {
  Style s;
  s.fill = fill;
  s.stroke = edge;
  s.line_width = width;
  return s;
}

// World position of a body-frame point p of body b at q: r_P = r_c + R(φ)(p − c), c the centre of
// mass in the body frame (the same map as PointRef's, whose s is measured from c).
Vec2 body_point(const Model& model, int b, const Vec2& p, const VecX& q) {
  const Body& body = model.bodies[static_cast<size_t>(b)];
  PointRef ref;
  ref.body = b;
  ref.s = p - body.com_local;
  return point_kinematics(model, ref, q, nullptr).r;
}
Vec2 world(const Model& model, const PointRef& p, const VecX& q) {
  return point_kinematics(model, p, q, nullptr).r;
}
// A body-frame direction in the world.
Vec2 world_direction(const Model& model, int b, const Vec2& d, const VecX& q) {
  if (b == kGround) return d;
  const Body& body = model.bodies[static_cast<size_t>(b)];
  if (body.kind != BodyKind::rigid) return d;
  return rotation(q(body.q_offset + 2)) * d;
}

// Convex hull (Andrew's monotone chain), counter-clockwise, without repeated points.
std::vector<Vec2> convex_hull(std::vector<Vec2> p) {
  std::sort(p.begin(), p.end(), [](const Vec2& a, const Vec2& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  if (p.size() < 3) return p;
  const auto cross = [](const Vec2& o, const Vec2& a, const Vec2& b) {
    return (a - o).x() * (b - o).y() - (a - o).y() * (b - o).x();
  };
  std::vector<Vec2> h(2 * p.size());
  size_t k = 0;
  for (const Vec2& pi : p) {
    while (k >= 2 && cross(h[k - 2], h[k - 1], pi) <= 0.0) --k;
    h[k++] = pi;
  }
  for (size_t i = p.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && cross(h[k - 2], h[k - 1], p[i]) <= 0.0) --k;
    h[k++] = p[i];
  }
  h.resize(k - 1);
  return h;
}

double length_unit_si(const std::string& name) {
  if (name == "mm") return 1e-3;
  if (name == "cm") return 1e-2;
  if (name == "in") return 0.0254;
  if (name == "ft") return 0.3048;
  return 1.0;  // "m"
}
double angle_unit_si(const std::string& name) { return name == "deg" ? kPi / 180.0 : 1.0; }

class SceneBuilder {
 public:
  SceneBuilder(const Model& model, const VecX& q, const RenderOptions& options)
      : model_(model), q_(q), options_(options), proj_(options.projection) {}

  Scene build() {
    const bool spatial = model_.dimension == 3;
    if (spatial) {
      build_spatial();
    } else {
      collect_ground_points();
      add_ground();
      for (size_t b = 0; b < model_.bodies.size(); ++b) add_body(static_cast<int>(b));
      for (const Load& l : model_.loads)
        if (const auto* s = std::get_if<SpringDamper>(&l.kind))
          add_spring(l.name, world(model_, s->pi, q_), world(model_, s->pj, q_), s->stiffness,
                     s->damping);
      add_traces();
      for (size_t j = 0; j < model_.joints.size(); ++j) add_joint(static_cast<int>(j));
      add_points();
    }
    if (options_.driver >= 0 && options_.driver < static_cast<int>(model_.joints.size()))
      add_driver(options_.driver);
    if (options_.labels) {
      if (spatial)
        add_spatial_labels();
      else
        add_labels();
    }
    Scene scene;
    const double unit = length_unit_si(model_.units.length);
    scene.view = options_.view ? *options_.view : fit_view(prims_, options_, 100.0 / unit);
    add_scale_bar(scene.view, unit);
    if (spatial) add_triad(scene.view);
    scene.primitives = std::move(prims_);
    return scene;
  }

 private:
  const Model& model_;
  const VecX& q_;
  const RenderOptions& options_;
  const Projection proj_;
  std::vector<Primitive> prims_;
  std::vector<std::pair<std::string, Vec2>> ground_points_;  // label, world
  std::vector<std::pair<std::string, Vec2>> joint_places_;   // joint name, world

  void add(Role role, const std::string& element, Shape shape) {
    prims_.push_back(Primitive{role, element, std::move(shape)});
  }

  // Ground points are those joints and springs attach to (the model keeps no other).
  void collect_ground_points() {
    auto take = [&](const PointRef& p) {
      if (p.body != kGround) return;
      for (const auto& g : ground_points_)
        if ((g.second - p.s).norm() <= kSamePlace) return;
      ground_points_.emplace_back(p.label, p.s);
    };
    for (const Joint& j : model_.joints)
      std::visit(
          [&](const auto& k) {
            if constexpr (requires { k.pi; } &&
                          !std::is_same_v<std::decay_t<decltype(k)>, SpatialJoint>) {
              take(k.pi);
              take(k.pj);
            }
          },
          j.kind);
    for (const Load& l : model_.loads)
      if (const auto* s = std::get_if<SpringDamper>(&l.kind)) {
        take(s->pi);
        take(s->pj);
      }
  }

  // A pivot support at each ground point: a triangle below it on a hatched base line.
  void add_ground() {
    const double h = kGroundTriangle, w = 0.8 * kGroundTriangle;
    for (const auto& [label, p] : ground_points_) {
      Path tri;
      tri.points = {at(p), at(p, Vec2(-w, h)), at(p, Vec2(w, h))};
      tri.closed = true;
      tri.style = filled(kGroundFill, kInk, 1.5);
      add(Role::ground, label, tri);
      Path base;
      base.points = {at(p, Vec2(-1.6 * w, h)), at(p, Vec2(1.6 * w, h))};
      base.style = stroke_only(kInk, 1.5);
      add(Role::ground, label, base);
      for (int k = 0; k < 5; ++k) {
        const double x = -1.6 * w + (k + 0.5) * (3.2 * w / 5.0);
        Path hatch;
        hatch.points = {at(p, Vec2(x + 0.5 * kHatch, h)),
                        at(p, Vec2(x - 0.5 * kHatch, h + kHatch))};
        hatch.style = stroke_only(kInk, 1.0);
        add(Role::ground, label, hatch);
      }
    }
  }

  // Hatching on one side of a ground guide from a to b (model points).
  void add_ground_hatch(const std::string& element, const Vec2& a, const Vec2& b) {
    const Vec2 d = px_dir(b - a), n = px_perp(d);
    constexpr int kStrokes = 9;
    for (int k = 0; k <= kStrokes; ++k) {
      const Vec2 p = a + (b - a) * (static_cast<double>(k) / kStrokes);
      Path hatch;
      hatch.points = {at(p, 3.0 * n), at(p, 3.0 * n + kHatch * (n - d) / std::sqrt(2.0))};
      hatch.style = stroke_only(kInk, 1.0);
      add(Role::ground, element, hatch);
    }
  }

  void add_body(int b) {
    const Body& body = model_.bodies[static_cast<size_t>(b)];
    const Rgba fill = kBodyFill[static_cast<size_t>(b) % std::size(kBodyFill)];
    const Rgba edge = kBodyEdge[static_cast<size_t>(b) % std::size(kBodyEdge)];
    std::vector<Vec2> pts;
    if (!body.outline.empty()) {
      // The outline as given: a filled polygon over three or more vertices (a last vertex that
      // repeats the first is dropped), else a bar.
      for (const Vec2& p : body.outline) pts.push_back(body_point(model_, b, p, q_));
      const bool closed = pts.size() >= 3 && (pts.front() - pts.back()).norm() <= kSamePlace;
      if (closed) pts.pop_back();
      Path path;
      for (const Vec2& p : pts) path.points.push_back(at(p));
      path.closed = closed || pts.size() >= 3;
      path.style = pts.size() >= 3 ? filled(fill, edge, 2.0) : stroke_only(edge, kBarWidth, true);
      path.style.round = true;
      add(Role::body, body.name, path);
      return;
    }
    for (const auto& [name, p] : body.points) {
      const Vec2 w = body_point(model_, b, p, q_);
      if (std::none_of(pts.begin(), pts.end(),
                       [&](const Vec2& x) { return (x - w).norm() <= kSamePlace; }))
        pts.push_back(w);
    }
    add_body_shape(b, pts, Vec2(q_(body.q_offset), q_(body.q_offset + 1)));
  }

  // The shape of body b over its distinct points (model coordinates, already projected for a
  // spatial body): a disc at its centre of mass for one point or none, a bar for two (or for
  // collinear points, between the extreme ones), else a plate over their convex hull.
  void add_body_shape(int b, std::vector<Vec2> pts, const Vec2& centre) {
    const Body& body = model_.bodies[static_cast<size_t>(b)];
    const Rgba fill = kBodyFill[static_cast<size_t>(b) % std::size(kBodyFill)];
    const Rgba edge = kBodyEdge[static_cast<size_t>(b) % std::size(kBodyEdge)];
    if (pts.size() <= 1) {
      // A particle or a body with one point: a disc at its centre of mass.
      Circle c;
      c.centre = at(centre);
      c.radius_px = 8.0;
      c.style = filled(fill, edge, 2.0);
      c.style.fill->a = 1.0;
      add(Role::body, body.name, c);
      return;
    }
    // Three or more collinear points have a hull of two: a bar between the extreme ones.
    if (pts.size() > 2 && convex_hull(pts).size() < 3) pts = convex_hull(pts);
    if (pts.size() == 2) {
      // A bar: a wide stroke with round caps, edged by a wider one underneath.
      Path under, over;
      under.points = over.points = {at(pts[0]), at(pts[1])};
      under.style = stroke_only(edge, kBarWidth + 3.0, true);
      Rgba solid = fill;
      solid.a = 1.0;
      over.style = stroke_only(solid, kBarWidth, true);
      add(Role::body, body.name, under);
      add(Role::body, body.name, over);
      return;
    }
    // A plate over three or more points: their convex hull.
    Path plate;
    for (const Vec2& p : convex_hull(pts)) plate.points.push_back(at(p));
    plate.closed = true;
    plate.style = filled(fill, edge, 2.0);
    plate.style.round = true;
    add(Role::body, body.name, plate);
  }

  void add_traces() {
    for (size_t k = 0; k < options_.traces.size(); ++k) {
      const PointTrace& t = options_.traces[k];
      Path path;
      if (model_.dimension == 3)
        for (size_t i = 0; i < t.path.size(); ++i) path.points.push_back(at(proj_(t.at(i))));
      else
        for (const Vec2& p : t.path) path.points.push_back(at(p));
      path.style = stroke_only(kTrace[k % std::size(kTrace)], kTraceWidth, true);
      add(Role::trace, t.point, path);
    }
  }

  void add_revolute_symbol(Role role, const std::string& name, const Vec2& p) {
    Circle c;
    c.centre = at(p);
    c.radius_px = kJointRadius;
    c.style = filled(kJointFill, kJointInk, kJointRing);
    add(role, name, c);
  }

  void add_joint(int j) {
    const Joint& joint = model_.joints[static_cast<size_t>(j)];
    std::visit(
        [&](const auto& k) {
          using K = std::decay_t<decltype(k)>;
          if constexpr (std::is_same_v<K, Revolute>) {
            const Vec2 p = world(model_, k.pi, q_);
            joint_places_.emplace_back(joint.name, p);
            add_revolute_symbol(Role::revolute, joint.name, p);
          } else if constexpr (std::is_same_v<K, Prismatic>) {
            add_prismatic(joint.name, k);
          } else if constexpr (std::is_same_v<K, PinInSlot>) {
            add_pin_in_slot(joint.name, k);
          } else if constexpr (std::is_same_v<K, GearPair>) {
            add_gear(joint.name, k);
          } else if constexpr (std::is_same_v<K, Fixed>) {
            const Vec2 p = world(model_, k.pi, q_);
            joint_places_.emplace_back(joint.name, p);
            Path sq;
            const double s = 5.0;
            sq.points = {at(p, Vec2(-s, -s)), at(p, Vec2(s, -s)), at(p, Vec2(s, s)),
                         at(p, Vec2(-s, s))};
            sq.closed = true;
            sq.style = filled(kInk, kInk, 1.0);
            add(Role::fixed, joint.name, sq);
          } else if constexpr (std::is_same_v<K, Distance>) {
            const Vec2 a = world(model_, k.pi, q_), b = world(model_, k.pj, q_);
            joint_places_.emplace_back(joint.name, 0.5 * (a + b));
            Path rod;
            rod.points = {at(a), at(b)};
            rod.style = stroke_only(kInk, 2.0, true);
            add(Role::distance, joint.name, rod);
            for (const Vec2& e : {a, b}) {
              Circle c;
              c.centre = at(e);
              c.radius_px = 4.0;
              c.style = filled(kBackground, kInk, 1.5);
              add(Role::distance, joint.name, c);
            }
          }
        },
        joint.kind);
  }

  // A guide along body i's axis through Pi and the point Pj on it (prismatic, pin-in-slot): Pj,
  // the world axis, and the span [a, b] of the axis line from Pi to Pj's foot.
  struct GuideSpan {
    Vec2 pj, axis, a, b;
  };
  template <class Kind>
  [[nodiscard]] GuideSpan guide_span(const Kind& k) const {
    const Vec2 pi = world(model_, k.pi, q_), pj = world(model_, k.pj, q_);
    const Vec2 axis = world_direction(model_, k.pi.body, k.axis_local, q_).normalized();
    const double t = axis.dot(pj - pi);
    return {pj, axis, pi + std::min(0.0, t) * axis, pi + std::max(0.0, t) * axis};
  }

  // Slider block on its guide: the guide is the line through Pi (body i) along the axis, drawn
  // over Pi and the block's place; the block is centred on Pj.
  void add_prismatic(const std::string& name, const Prismatic& k) {
    const auto [pj, axis, a, b] = guide_span(k);
    joint_places_.emplace_back(name, pj);
    const Vec2 d = px_dir(axis), n = px_perp(d);
    const double ext = 0.5 * kSliderLength + 12.0;
    Path guide;
    guide.points = {at(a, -ext * d), at(b, ext * d)};
    guide.style = stroke_only(kInk, 2.0);
    add(Role::prismatic, name, guide);
    if (k.pi.body == kGround) {
      // The guide's end points in the model, for the hatching (a little beyond the block's travel).
      add_ground_hatch(name, a, b);
      Path ends;
      ends.points = {at(a, -ext * d + 3.0 * n), at(a, -ext * d + (3.0 + kHatch) * n)};
      ends.style = stroke_only(kInk, 1.0);
      add(Role::ground, name, ends);
    }
    Path block;
    const Vec2 hl = 0.5 * kSliderLength * d, hw = 0.5 * kSliderHeight * n;
    block.points = {at(pj, -hl - hw), at(pj, hl - hw), at(pj, hl + hw), at(pj, -hl + hw)};
    block.closed = true;
    block.style = filled(kSliderFill, kInk, 2.0);
    add(Role::prismatic, name, block);
  }

  // The slot (a hollow stadium along the axis of body i through Pi) and the pin Pj in it.
  void add_pin_in_slot(const std::string& name, const PinInSlot& k) {
    const auto [pj, axis, a, b] = guide_span(k);
    joint_places_.emplace_back(name, pj);
    const Vec2 d = px_dir(axis);
    Path outer, inner;
    outer.points = inner.points = {at(a, -kSlotWidth * d), at(b, kSlotWidth * d)};
    outer.style = stroke_only(kInk, kSlotWidth + 3.0, true);
    inner.style = stroke_only(kBackground, kSlotWidth, true);
    add(Role::pin_in_slot, name, outer);
    add(Role::pin_in_slot, name, inner);
    Circle pin;
    pin.centre = at(pj);
    pin.radius_px = 0.5 * kSlotWidth - 1.5;
    pin.style = filled(kJointInk, kJointInk, 1.0);
    add(Role::pin_in_slot, name, pin);
  }

  // Pitch circles of a gear pair: the gear centres are the pivots of the gears on the carrier
  // (their revolute joints), the centre distance splits in the ratio |k| = r_i / r_j
  // (external gears for k < 0, internal for k > 0).
  void add_gear(const std::string& name, const GearPair& k) {
    auto pivot = [&](int body) -> std::optional<Vec2> {
      for (const Joint& j : model_.joints)
        if (const auto* r = std::get_if<Revolute>(&j.kind))
          if ((r->pi.body == body && r->pj.body == k.carrier) ||
              (r->pj.body == body && r->pi.body == k.carrier))
            return world(model_, r->pi, q_);
      return std::nullopt;
    };
    const auto ci = pivot(k.bi), cj = pivot(k.bj);
    if (!ci || !cj) return;  // no pivots on the carrier: nothing to place the circles on
    const double dist = (*cj - *ci).norm(), ratio = std::abs(k.ratio);
    double rj = 0.0;
    if (k.ratio < 0.0)
      rj = dist / (1.0 + ratio);
    else if (std::abs(1.0 - ratio) > 1e-12)
      rj = dist / std::abs(1.0 - ratio);
    const double ri = ratio * rj;
    joint_places_.emplace_back(name, *ci + (ri / std::max(dist, 1e-300)) * (*cj - *ci));
    for (const auto& [c, r] : {std::pair{*ci, ri}, std::pair{*cj, rj}}) {
      if (!(r > 0.0)) continue;
      Circle pitch;
      pitch.centre = at(c);
      pitch.radius_model = r;
      pitch.style = stroke_only(kGearGreen, 1.5);
      add(Role::gear, name, pitch);
    }
  }

  // A spring (zig-zag) and a dashpot side by side between the two points; only the spring when
  // there is no damping and only the dashpot when there is no stiffness.
  void add_spring(const std::string& name, const Vec2& a, const Vec2& b, double stiffness,
                  double damping) {
    const bool spring = stiffness != 0.0 || damping == 0.0, damper = damping != 0.0;
    const Vec2 d = px_dir(b - a), n = px_perp(d);
    const double side = spring && damper ? 9.0 : 0.0;
    auto lerp = [&](double t) { return a + t * (b - a); };
    const Style ink = stroke_only(kSpringBlue, 1.5);
    Path lead_a, lead_b;
    lead_a.points = {at(a), at(lerp(0.15))};
    lead_b.points = {at(lerp(0.85)), at(b)};
    lead_a.style = lead_b.style = ink;
    add(Role::spring_damper, name, lead_a);
    add(Role::spring_damper, name, lead_b);
    if (spring && damper) {
      for (double t : {0.15, 0.85}) {
        Path bar;
        bar.points = {at(lerp(t), -side * n), at(lerp(t), side * n)};
        bar.style = ink;
        add(Role::spring_damper, name, bar);
      }
    }
    if (spring) {
      Path zig;
      const Vec2 off = -side * n;
      zig.points.push_back(at(lerp(0.15), off));
      constexpr int kTeeth = 8;
      for (int k = 0; k < kTeeth; ++k) {
        const double t = 0.2 + 0.6 * (k + 0.5) / kTeeth;
        zig.points.push_back(at(lerp(t), off + (k % 2 == 0 ? 6.0 : -6.0) * n));
      }
      zig.points.push_back(at(lerp(0.85), off));
      zig.style = ink;
      add(Role::spring_damper, name, zig);
    }
    if (damper) {
      const Vec2 off = side * n;
      Path rod_a, cylinder, piston, rod_b;
      rod_a.points = {at(lerp(0.15), off), at(lerp(0.35), off)};
      cylinder.points = {at(lerp(0.65), off + 7.0 * n), at(lerp(0.35), off + 7.0 * n),
                         at(lerp(0.35), off - 7.0 * n), at(lerp(0.65), off - 7.0 * n)};
      piston.points = {at(lerp(0.55), off + 5.0 * n), at(lerp(0.55), off - 5.0 * n)};
      rod_b.points = {at(lerp(0.55), off), at(lerp(0.85), off)};
      rod_a.style = cylinder.style = rod_b.style = ink;
      piston.style = stroke_only(kSpringBlue, 3.0);
      for (Path* p : {&rod_a, &cylinder, &piston, &rod_b}) add(Role::spring_damper, name, *p);
    }
  }

  [[nodiscard]] bool at_joint(const Vec2& p) const {
    return std::any_of(joint_places_.begin(), joint_places_.end(),
                       [&](const auto& j) { return (j.second - p).norm() <= kSamePlace; });
  }

  // Named body points that are not at a joint (e.g. a coupler point): small dots.
  void add_points() {
    for (size_t b = 0; b < model_.bodies.size(); ++b) {
      const Body& body = model_.bodies[b];
      for (const auto& [name, p] : body.points) {
        const Vec2 w = body_point(model_, static_cast<int>(b), p, q_);
        if (at_joint(w)) continue;
        Circle c;
        c.centre = at(w);
        c.radius_px = kPointRadius;
        c.style = filled(kInk, kInk, 1.0);
        add(Role::point, body.name + "." + name, c);
      }
    }
  }

  // The driver: a curved arrow round a revolute joint, a double arrow along a prismatic one, a
  // ring otherwise.
  void add_driver(int j) {
    const Joint& joint = model_.joints[static_cast<size_t>(j)];
    const Style red = stroke_only(kDriverRed, 2.0, true);
    if (const auto* r = std::get_if<Revolute>(&joint.kind)) {
      const Vec2 c = world(model_, r->pi, q_);
      Path arc;
      constexpr int kSegments = 40;
      const double a0 = 0.25 * kPi, a1 = 1.75 * kPi;  // px angles, counter-clockwise on screen
      for (int k = 0; k <= kSegments; ++k) {
        const double t = a0 + (a1 - a0) * k / kSegments;
        arc.points.push_back(at(c, kDriverRadius * Vec2(std::cos(t), -std::sin(t))));
      }
      arc.style = red;
      add(Role::driver, joint.name, arc);
      // Arrow head at the end of the arc, along its tangent.
      const Vec2 tip = kDriverRadius * Vec2(std::cos(a1), -std::sin(a1));
      const Vec2 tangent(-std::sin(a1), -std::cos(a1));
      const Vec2 normal(std::cos(a1), -std::sin(a1));
      Path head;
      head.points = {at(c, tip - 7.0 * tangent + 4.0 * normal), at(c, tip),
                     at(c, tip - 7.0 * tangent - 4.0 * normal)};
      head.style = red;
      add(Role::driver, joint.name, head);
      return;
    }
    if (const auto* p = std::get_if<Prismatic>(&joint.kind)) {
      const Vec2 pj = world(model_, p->pj, q_);
      const Vec2 d = px_dir(world_direction(model_, p->pi.body, p->axis_local, q_));
      const Vec2 n = px_perp(d), o = -(0.5 * kSliderHeight + 8.0) * n;
      Path shaft;
      shaft.points = {at(pj, o - 20.0 * d), at(pj, o + 20.0 * d)};
      shaft.style = red;
      add(Role::driver, joint.name, shaft);
      for (double sgn : {-1.0, 1.0}) {
        Path head;
        const Vec2 tip = o + sgn * 20.0 * d;
        head.points = {at(pj, tip - sgn * 6.0 * d + 4.0 * n), at(pj, tip),
                       at(pj, tip - sgn * 6.0 * d - 4.0 * n)};
        head.style = red;
        add(Role::driver, joint.name, head);
      }
      return;
    }
    for (const auto& [name, place] : joint_places_)
      if (name == joint.name) {
        Circle ring;
        ring.centre = at(place);
        ring.radius_px = kDriverRadius;
        ring.style = stroke_only(kDriverRed, 2.0);
        add(Role::driver, joint.name, ring);
      }
  }

  void add_text(const std::string& element, const Vertex& v, const std::string& text) {
    add(Role::label, element, Text{v, text, kLabelSize, kInk});
  }

  void add_labels() {
    // Bodies: at the centroid of their drawn points, their name.
    for (size_t b = 0; b < model_.bodies.size(); ++b) {
      const Body& body = model_.bodies[b];
      Vec2 c = Vec2::Zero();
      int count = 0;
      for (const auto& [name, p] : body.points) {
        c += body_point(model_, static_cast<int>(b), p, q_);
        ++count;
      }
      if (count == 0)
        c = Vec2(q_(body.q_offset), q_(body.q_offset + 1));
      else
        c /= count;
      add_text(body.name, at(c, Vec2(4.0, 14.0)), body.name);
    }
    // Joints: beside their symbol.
    for (const auto& [name, p] : joint_places_)
      add_text(name, at(p, Vec2(kJointRadius + 3.0, -kJointRadius - 3.0)), name);
    // Points not at a joint: "body.point".
    for (size_t b = 0; b < model_.bodies.size(); ++b)
      for (const auto& [name, p] : model_.bodies[b].points) {
        const Vec2 w = body_point(model_, static_cast<int>(b), p, q_);
        if (at_joint(w)) continue;
        const std::string label = model_.bodies[b].name + "." + name;
        add_text(label, at(w, Vec2(5.0, -5.0)), label);
      }
  }

  // ---- spatial mechanisms: everything drawn through the projection proj_ -----------------------
  [[nodiscard]] Vec3 world3(int body, const Vec3& s) const {
    return spatial_point(spatial_frame(model_, body, q_, nullptr), s).r;
  }
  [[nodiscard]] Vec3 world3(const SpatialPointRef& p) const { return world3(p.body, p.s); }
  [[nodiscard]] Mat3 rotation3(int body) const {
    return spatial_frame(model_, body, q_, nullptr).R;
  }

  // Bodies (farther first: painter's order along the view direction), springs, traces, the joints
  // with their axes, the points not at a joint.
  void build_spatial() {
    // Every body's joint points (world), and the ground's.
    std::vector<std::vector<Vec3>> joint_points(model_.bodies.size());
    auto take = [&](const SpatialPointRef& p) {
      const Vec3 w = world3(p);
      if (p.body == kGround) {
        const Vec2 g = proj_(w);
        if (std::none_of(ground_points_.begin(), ground_points_.end(),
                         [&](const auto& x) { return (x.second - g).norm() <= kSamePlace; }))
          ground_points_.emplace_back(p.label, g);
        return;
      }
      auto& pts = joint_points[static_cast<size_t>(p.body)];
      if (std::none_of(pts.begin(), pts.end(),
                       [&](const Vec3& x) { return (x - w).norm() <= kSamePlace; }))
        pts.push_back(w);
    };
    for (const Joint& j : model_.joints)
      if (const auto* k = std::get_if<SpatialJoint>(&j.kind)) {
        take(k->pi);
        take(k->pj);
      }
    add_ground();
    const Vec3 w = proj_.toward_viewer();
    std::vector<int> order(model_.bodies.size());
    for (size_t b = 0; b < order.size(); ++b) order[b] = static_cast<int>(b);
    auto depth = [&](int b) {
      const Body& body = model_.bodies[static_cast<size_t>(b)];
      return body.kind == BodyKind::spatial ? w.dot(q_.segment<3>(body.q_offset)) : 0.0;
    };
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return depth(a) < depth(b); });
    for (const int b : order) add_spatial_body(b, joint_points[static_cast<size_t>(b)]);
    for (const Load& l : model_.loads)
      if (const auto* s = std::get_if<SpatialSpringDamper>(&l.kind))
        add_spring(l.name, proj_(world3(s->pi)), proj_(world3(s->pj)), s->stiffness, s->damping);
    add_traces();
    for (const Joint& j : model_.joints)
      if (const auto* k = std::get_if<SpatialJoint>(&j.kind)) add_spatial_joint(j.name, *k);
    add_spatial_points();
  }

  void add_spatial_body(int b, std::vector<Vec3> pts) {
    const Body& body = model_.bodies[static_cast<size_t>(b)];
    if (body.kind != BodyKind::spatial) return;
    const Vec3 com = q_.segment<3>(body.q_offset);
    // Fewer than two joint points: the named points and the centre of mass give the shape.
    if (pts.size() < 2) {
      for (const auto& [name, p] : body.spatial.points)
        pts.push_back(world3(b, p - body.spatial.com_local));
      pts.push_back(com);
    }
    std::vector<Vec2> flat;
    for (const Vec3& p : pts) {
      const Vec2 f = proj_(p);
      if (std::none_of(flat.begin(), flat.end(),
                       [&](const Vec2& x) { return (x - f).norm() <= kSamePlace; }))
        flat.push_back(f);
    }
    add_body_shape(b, std::move(flat), proj_(com));
  }

  // A stroke of ± kAxisLength px along the projection of the world direction d through p: long
  // when d lies in the screen plane, a dot when it points at the viewer.
  void add_axis_stroke(const std::string& name, const Vec2& p, const Vec3& d, const Rgba& colour) {
    constexpr double kAxisLength = 18.0;
    const Vec2 s = kAxisLength * Vec2(proj_.u.dot(d), -proj_.v.dot(d)) / std::max(d.norm(), 1e-300);
    Path axis;
    axis.points = {at(p, -s), at(p, s)};
    axis.style = stroke_only(colour, 2.5, true);
    add(Role::axis, name, axis);
  }

  void add_spatial_joint(const std::string& name, const SpatialJoint& k) {
    const Vec3 pi = world3(k.pi), pj = world3(k.pj);
    if (k.type == SpatialJointType::distance) {
      const Vec2 a = proj_(pi), b = proj_(pj);
      joint_places_.emplace_back(name, 0.5 * (a + b));
      Path rod;
      rod.points = {at(a), at(b)};
      rod.style = stroke_only(kInk, 2.0, true);
      add(Role::distance, name, rod);
      for (const Vec2& e : {a, b}) {
        Circle c;
        c.centre = at(e);
        c.radius_px = 4.0;
        c.style = filled(kBackground, kInk, 1.5);
        add(Role::distance, name, c);
      }
      return;
    }
    const Vec2 p = proj_(pi);
    joint_places_.emplace_back(name, p);
    const Mat3 Ri = rotation3(k.pi.body), Rj = rotation3(k.pj.body);
    switch (k.type) {
      case SpatialJointType::revolute:
      case SpatialJointType::cylindrical:
      case SpatialJointType::prismatic:
      case SpatialJointType::screw:
        add_axis_stroke(name, p, Ri * k.frame_i.col(2), kInk);
        break;
      case SpatialJointType::universal:  // pin 1 = f of frame_i, pin 2 = g of frame_j
        add_axis_stroke(name, p, Ri * k.frame_i.col(0), kInk);
        add_axis_stroke(name, p, Rj * k.frame_j.col(1), kInk);
        break;
      default:
        break;
    }
    Circle c;
    c.centre = at(p);
    c.radius_px = kJointRadius;
    c.style = filled(kJointFill, kJointInk, kJointRing);
    add(Role::spatial_joint, name, c);
  }

  // A named point p of spatial body b (body frame) on the screen.
  Vec2 projected_point(size_t b, const Vec3& p) const {
    const Body& body = model_.bodies[b];
    return proj_(world3(static_cast<int>(b), p - body.spatial.com_local));
  }

  void add_spatial_points() {
    for (size_t b = 0; b < model_.bodies.size(); ++b) {
      const Body& body = model_.bodies[b];
      if (body.kind != BodyKind::spatial) continue;
      for (const auto& [name, p] : body.spatial.points) {
        const Vec2 w = projected_point(b, p);
        if (at_joint(w)) continue;
        Circle c;
        c.centre = at(w);
        c.radius_px = kPointRadius;
        c.style = filled(kInk, kInk, 1.0);
        add(Role::point, body.name + "." + name, c);
      }
    }
  }

  void add_spatial_labels() {
    for (size_t b = 0; b < model_.bodies.size(); ++b) {
      const Body& body = model_.bodies[b];
      if (body.kind != BodyKind::spatial) continue;
      Vec2 c = proj_(q_.segment<3>(body.q_offset));
      if (!body.spatial.points.empty()) {
        c = Vec2::Zero();
        for (const auto& [name, p] : body.spatial.points) c += projected_point(b, p);
        c /= static_cast<double>(body.spatial.points.size());
      }
      add_text(body.name, at(c, Vec2(4.0, 14.0)), body.name);
    }
    for (const auto& [name, p] : joint_places_)
      add_text(name, at(p, Vec2(kJointRadius + 3.0, -kJointRadius - 3.0)), name);
    for (size_t b = 0; b < model_.bodies.size(); ++b) {
      const Body& body = model_.bodies[b];
      if (body.kind != BodyKind::spatial) continue;
      for (const auto& [name, p] : body.spatial.points) {
        const Vec2 w = projected_point(b, p);
        if (at_joint(w)) continue;
        const std::string label = body.name + "." + name;
        add_text(label, at(w, Vec2(5.0, -5.0)), label);
      }
    }
  }

  // The ground frame's axes x (red), y (green), z (blue), kTriadLength px where they lie in the
  // screen plane, bottom right in the legend strip (screen positions). An axis along the view
  // direction is a small circle: with a dot when it points at the viewer, a cross when away.
  void add_triad(const ViewTransform& view) {
    // The triad's extent right of and below its origin (tips, labels ~8 px high), then the origin
    // that puts its bottom right 4 px inside the image and half a margin from the right edge.
    Vec2 hi = Vec2::Zero();
    for (int a = 0; a < 3; ++a) {
      const Vec3 e = Vec3::Unit(a);
      const Vec2 d = kTriadLength * Vec2(proj_.u.dot(e), -proj_.v.dot(e));
      const Vec2 l = d.norm() < 4.0 ? Vec2(7.0, 12.0) : d + 9.0 * d.normalized() + Vec2(-3.5, 4.0);
      for (const Vec2& p : {d, l, Vec2(l.x() + 7.0, l.y() - 8.0)}) hi = hi.cwiseMax(p);
    }
    const Vec2 o(view.width - 0.5 * options_.margin - hi.x(), view.height - 4.0 - hi.y());
    const Rgba colours[] = {{0.8, 0.1, 0.1, 1.0}, {0.1, 0.55, 0.1, 1.0}, {0.1, 0.2, 0.8, 1.0}};
    const char* names[] = {"x", "y", "z"};
    const Vec3 w = proj_.toward_viewer();
    for (int a = 0; a < 3; ++a) {
      const Vec3 e = Vec3::Unit(a);
      const Vec2 d = kTriadLength * Vec2(proj_.u.dot(e), -proj_.v.dot(e));  // px, y down
      const Rgba& c = colours[a];
      if (d.norm() < 4.0) {
        Circle ring;
        ring.centre = screen(o.x(), o.y());
        ring.radius_px = 5.0;
        ring.style = stroke_only(c, 1.5);
        add(Role::triad, names[a], ring);
        if (w.dot(e) > 0.0) {
          Circle dot;
          dot.centre = screen(o.x(), o.y());
          dot.radius_px = 1.5;
          dot.style = filled(c, c, 1.0);
          add(Role::triad, names[a], dot);
        } else {
          for (const double sgn : {-1.0, 1.0}) {
            Path cross;
            cross.points = {screen(o.x() - 3.5, o.y() - 3.5 * sgn),
                            screen(o.x() + 3.5, o.y() + 3.5 * sgn)};
            cross.style = stroke_only(c, 1.5);
            add(Role::triad, names[a], cross);
          }
        }
        add(Role::triad, names[a],
            Text{screen(o.x() + 7.0, o.y() + 12.0), names[a], kLabelSize, c});
        continue;
      }
      Path shaft;
      shaft.points = {screen(o.x(), o.y()), screen(o.x() + d.x(), o.y() + d.y())};
      shaft.style = stroke_only(c, 2.0, true);
      add(Role::triad, names[a], shaft);
      const Vec2 t = d.normalized(), n(-t.y(), t.x());
      const Vec2 tip = o + d;
      Path head;
      head.points = {
          screen(tip.x() - 6.0 * t.x() + 3.5 * n.x(), tip.y() - 6.0 * t.y() + 3.5 * n.y()),
          screen(tip.x(), tip.y()),
          screen(tip.x() - 6.0 * t.x() - 3.5 * n.x(), tip.y() - 6.0 * t.y() - 3.5 * n.y())};
      head.style = stroke_only(c, 2.0, true);
      add(Role::triad, names[a], head);
      const Vec2 l = tip + 9.0 * t + Vec2(-3.5, 4.0);
      add(Role::triad, names[a], Text{screen(l.x(), l.y()), names[a], kLabelSize, c});
    }
  }

  // A bar of a round length (1, 2 or 5 × 10^k file units) near a quarter of the area's width,
  // bottom left, in the legend strip.
  void add_scale_bar(const ViewTransform& view, double unit_si) {
    const double area = view.width - 2.0 * options_.margin;
    const double target = 0.25 * area / (view.scale * unit_si);  // file units
    if (!(target > 0.0) || !std::isfinite(target)) return;
    const double decade = std::pow(10.0, std::floor(std::log10(target)));
    double len = decade;
    for (double m : {2.0, 5.0})
      if (m * decade <= target) len = m * decade;
    const double px = len * unit_si * view.scale;
    const double x0 = options_.margin, y = view.height - 0.5 * options_.legend;
    Path bar;
    bar.points = {screen(x0, y), screen(x0 + px, y)};
    bar.style = stroke_only(kInk, 2.0);
    add(Role::scale_bar, "", bar);
    for (double x : {x0, x0 + px}) {
      Path tick;
      tick.points = {screen(x, y - 5.0), screen(x, y + 5.0)};
      tick.style = stroke_only(kInk, 2.0);
      add(Role::scale_bar, "", tick);
    }
    char text[64];
    std::snprintf(text, sizeof text, "%g %s", len, model_.units.length.c_str());
    add(Role::scale_bar, "", Text{screen(x0 + px + 8.0, y + 4.0), text, kLabelSize, kInk});
  }
};

// Cairo's functions, from libcairo.so.2 opened at the first picture (io/shared_library.hpp): a
// command that draws nothing does not load Cairo and the 17 libraries it brings.
struct CairoApi {
  explicit CairoApi(const detail::SharedLibrary& lib)
      : arc(lib.function<decltype(::cairo_arc)>("cairo_arc")),
        close_path(lib.function<decltype(::cairo_close_path)>("cairo_close_path")),
        create(lib.function<decltype(::cairo_create)>("cairo_create")),
        debug_reset_static_data(lib.function<decltype(::cairo_debug_reset_static_data)>(
            "cairo_debug_reset_static_data")),
        destroy(lib.function<decltype(::cairo_destroy)>("cairo_destroy")),
        fill(lib.function<decltype(::cairo_fill)>("cairo_fill")),
        fill_preserve(lib.function<decltype(::cairo_fill_preserve)>("cairo_fill_preserve")),
        image_surface_create(
            lib.function<decltype(::cairo_image_surface_create)>("cairo_image_surface_create")),
        line_to(lib.function<decltype(::cairo_line_to)>("cairo_line_to")),
        move_to(lib.function<decltype(::cairo_move_to)>("cairo_move_to")),
        new_path(lib.function<decltype(::cairo_new_path)>("cairo_new_path")),
        new_sub_path(lib.function<decltype(::cairo_new_sub_path)>("cairo_new_sub_path")),
        paint(lib.function<decltype(::cairo_paint)>("cairo_paint")),
        pdf_surface_create_for_stream(lib.function<decltype(::cairo_pdf_surface_create_for_stream)>(
            "cairo_pdf_surface_create_for_stream")),
        select_font_face(
            lib.function<decltype(::cairo_select_font_face)>("cairo_select_font_face")),
        set_font_size(lib.function<decltype(::cairo_set_font_size)>("cairo_set_font_size")),
        set_line_cap(lib.function<decltype(::cairo_set_line_cap)>("cairo_set_line_cap")),
        set_line_join(lib.function<decltype(::cairo_set_line_join)>("cairo_set_line_join")),
        set_line_width(lib.function<decltype(::cairo_set_line_width)>("cairo_set_line_width")),
        set_source_rgba(lib.function<decltype(::cairo_set_source_rgba)>("cairo_set_source_rgba")),
        show_text(lib.function<decltype(::cairo_show_text)>("cairo_show_text")),
        status(lib.function<decltype(::cairo_status)>("cairo_status")),
        status_to_string(
            lib.function<decltype(::cairo_status_to_string)>("cairo_status_to_string")),
        stroke(lib.function<decltype(::cairo_stroke)>("cairo_stroke")),
        surface_destroy(lib.function<decltype(::cairo_surface_destroy)>("cairo_surface_destroy")),
        surface_finish(lib.function<decltype(::cairo_surface_finish)>("cairo_surface_finish")),
        surface_status(lib.function<decltype(::cairo_surface_status)>("cairo_surface_status")),
        surface_write_to_png_stream(lib.function<decltype(::cairo_surface_write_to_png_stream)>(
            "cairo_surface_write_to_png_stream")),
        svg_surface_create_for_stream(lib.function<decltype(::cairo_svg_surface_create_for_stream)>(
            "cairo_svg_surface_create_for_stream")),
        svg_surface_set_document_unit(lib.function<decltype(::cairo_svg_surface_set_document_unit)>(
            "cairo_svg_surface_set_document_unit")) {}
  decltype(&::cairo_arc) arc;
  decltype(&::cairo_close_path) close_path;
  decltype(&::cairo_create) create;
  decltype(&::cairo_debug_reset_static_data) debug_reset_static_data;
  decltype(&::cairo_destroy) destroy;
  decltype(&::cairo_fill) fill;
  decltype(&::cairo_fill_preserve) fill_preserve;
  decltype(&::cairo_image_surface_create) image_surface_create;
  decltype(&::cairo_line_to) line_to;
  decltype(&::cairo_move_to) move_to;
  decltype(&::cairo_new_path) new_path;
  decltype(&::cairo_new_sub_path) new_sub_path;
  decltype(&::cairo_paint) paint;
  decltype(&::cairo_pdf_surface_create_for_stream) pdf_surface_create_for_stream;
  decltype(&::cairo_select_font_face) select_font_face;
  decltype(&::cairo_set_font_size) set_font_size;
  decltype(&::cairo_set_line_cap) set_line_cap;
  decltype(&::cairo_set_line_join) set_line_join;
  decltype(&::cairo_set_line_width) set_line_width;
  decltype(&::cairo_set_source_rgba) set_source_rgba;
  decltype(&::cairo_show_text) show_text;
  decltype(&::cairo_status) status;
  decltype(&::cairo_status_to_string) status_to_string;
  decltype(&::cairo_stroke) stroke;
  decltype(&::cairo_surface_destroy) surface_destroy;
  decltype(&::cairo_surface_finish) surface_finish;
  decltype(&::cairo_surface_status) surface_status;
  decltype(&::cairo_surface_write_to_png_stream) surface_write_to_png_stream;
  decltype(&::cairo_svg_surface_create_for_stream) svg_surface_create_for_stream;
  decltype(&::cairo_svg_surface_set_document_unit) svg_surface_set_document_unit;
};

std::atomic<bool> cairo_loaded{false};

const CairoApi& cairo() {
  static const detail::SharedLibrary lib({"libcairo.so.2"}, false, "libcairo2");
  static const CairoApi api(lib);
  cairo_loaded = true;
  return api;
}

// ---- Cairo
// ---------------------------------------------------------------------------------------
struct SurfaceDeleter {
  void operator()(cairo_surface_t* s) const { cairo().surface_destroy(s); }
};
struct ContextDeleter {
  void operator()(cairo_t* c) const { cairo().destroy(c); }
};
using SurfacePtr = std::unique_ptr<cairo_surface_t, SurfaceDeleter>;
using ContextPtr = std::unique_ptr<cairo_t, ContextDeleter>;

cairo_status_t append_bytes(void* closure, const unsigned char* data, unsigned int length) {
  static_cast<std::string*>(closure)->append(reinterpret_cast<const char*>(data), length);
  return CAIRO_STATUS_SUCCESS;
}

void set_colour(cairo_t* cr, const Rgba& c) { cairo().set_source_rgba(cr, c.r, c.g, c.b, c.a); }

void fill_and_stroke(cairo_t* cr, const Style& style) {
  if (style.fill) {
    set_colour(cr, *style.fill);
    if (style.stroke)
      cairo().fill_preserve(cr);
    else
      cairo().fill(cr);
  }
  if (style.stroke) {
    set_colour(cr, *style.stroke);
    cairo().set_line_width(cr, style.line_width);
    cairo().set_line_cap(cr, style.round ? CAIRO_LINE_CAP_ROUND : CAIRO_LINE_CAP_BUTT);
    cairo().set_line_join(cr, style.round ? CAIRO_LINE_JOIN_ROUND : CAIRO_LINE_JOIN_MITER);
    cairo().stroke(cr);
  }
  cairo().new_path(cr);
}

// The one drawing routine of every surface.
void draw(cairo_t* cr, const Scene& scene) {
  set_colour(cr, scene.background);
  cairo().paint(cr);
  cairo().select_font_face(cr, "DejaVu Sans", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  const ViewTransform& view = scene.view;
  for (const Primitive& prim : scene.primitives) {
    std::visit(
        [&](const auto& s) {
          using S = std::decay_t<decltype(s)>;
          if constexpr (std::is_same_v<S, Path>) {
            if (s.points.empty()) return;
            for (size_t k = 0; k < s.points.size(); ++k) {
              const Vec2 p = view.to_pixels(s.points[k]);
              if (k == 0)
                cairo().move_to(cr, p.x(), p.y());
              else
                cairo().line_to(cr, p.x(), p.y());
            }
            if (s.closed) cairo().close_path(cr);
            Style style = s.style;
            if (!s.closed) style.fill.reset();
            fill_and_stroke(cr, style);
          } else if constexpr (std::is_same_v<S, Circle>) {
            const Vec2 c = view.to_pixels(s.centre);
            const double r = s.radius_px + view.scale * s.radius_model;
            cairo().new_sub_path(cr);
            cairo().arc(cr, c.x(), c.y(), r, 0.0, 2.0 * kPi);
            cairo().close_path(cr);
            fill_and_stroke(cr, s.style);
          } else {
            const Vec2 p = view.to_pixels(s.at);
            set_colour(cr, s.colour);
            cairo().set_font_size(cr, s.size);
            cairo().move_to(cr, p.x(), p.y());
            cairo().show_text(cr, s.text.c_str());
            cairo().new_path(cr);
          }
        },
        prim.shape);
  }
}

void check(cairo_status_t status, const char* what) {
  if (status != CAIRO_STATUS_SUCCESS)
    throw std::runtime_error(std::string("render: ") + what + ": " +
                             cairo().status_to_string(status));
}

}  // namespace

ViewTransform fit_view(const std::vector<Primitive>& primitives, const RenderOptions& options,
                       double fallback_scale) {
  // Bounding box of the model parts of every vertex (circles: ± their model radius).
  Vec2 lo = Vec2::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  auto take = [&](const Vertex& v, double r) {
    if (v.screen) return;
    lo = lo.cwiseMin(v.model - Vec2::Constant(r));
    hi = hi.cwiseMax(v.model + Vec2::Constant(r));
  };
  for (const Primitive& p : primitives) {
    if (const auto* path = std::get_if<Path>(&p.shape))
      for (const Vertex& v : path->points) take(v, 0.0);
    else if (const auto* c = std::get_if<Circle>(&p.shape))
      take(c->centre, c->radius_model);
  }
  ViewTransform view;
  view.width = options.width;
  view.height = options.height;
  const double area_w = options.width - 2.0 * options.margin;
  const double area_h = options.height - 2.0 * options.margin - options.legend;
  view.centre_px = Vec2(0.5 * options.width, options.margin + 0.5 * area_h);
  if (!(lo.x() <= hi.x())) {  // nothing to draw
    view.scale = fallback_scale;
    return view;
  }
  view.centre = 0.5 * (lo + hi);
  const Vec2 box = hi - lo;
  double scale = std::numeric_limits<double>::infinity();
  if (box.x() > 0.0) scale = std::min(scale, area_w / box.x());
  if (box.y() > 0.0) scale = std::min(scale, area_h / box.y());
  view.scale = std::isfinite(scale) ? scale : fallback_scale;
  return view;
}

Projection projection_from(double azimuth, double elevation) {
  // (V1): the viewer along w = (cos e cos a, cos e sin a, sin e); u horizontal, v = w × u.
  const double ca = std::cos(azimuth), sa = std::sin(azimuth);
  const double ce = std::cos(elevation), se = std::sin(elevation);
  Projection p;
  p.u = Vec3(-sa, ca, 0.0);
  p.v = Vec3(-se * ca, -se * sa, ce);
  return p;
}

std::optional<Projection> view_projection(const std::string& view) {
  // The named views with exact vectors (the top view is the identity of the planar drawing).
  Projection p;
  if (view == "top") return p;
  if (view == "front") {
    p.v = Vec3::UnitZ();
    return p;
  }
  if (view == "side") {
    p.u = Vec3::UnitY();
    p.v = Vec3::UnitZ();
    return p;
  }
  if (view == "iso") {
    p.u = Vec3(-1.0, 1.0, 0.0) / std::sqrt(2.0);
    p.v = Vec3(-1.0, -1.0, 2.0) / std::sqrt(6.0);
    return p;
  }
  // "AZ,EL" in degrees.
  const auto comma = view.find(',');
  if (comma == std::string::npos) return std::nullopt;
  auto number = [](const std::string& t) -> std::optional<double> {
    if (t.empty()) return std::nullopt;
    char* end = nullptr;
    const double v = std::strtod(t.c_str(), &end);
    if (end != t.c_str() + t.size() || !std::isfinite(v)) return std::nullopt;
    return v;
  };
  const auto az = number(view.substr(0, comma)), el = number(view.substr(comma + 1));
  if (!az || !el || std::abs(*el) > 90.0) return std::nullopt;
  return projection_from(*az * kPi / 180.0, *el * kPi / 180.0);
}

ViewChoice choose_view(const Model& model, const std::string& view) {
  ViewChoice choice;
  const std::string name = view.empty() ? (model.dimension == 3 ? "iso" : "top") : view;
  const std::optional<Projection> p = view_projection(name);
  if (!p) {
    choice.message = "--view: unknown view '" + view +
                     "' (use iso, front, top, side or AZIMUTH,ELEVATION in degrees, e.g. 30,20)";
    return choice;
  }
  if (model.dimension != 3 && !p->is_top()) {
    choice.message =
        "--view: a planar mechanism is drawn in its plane (the top view), not '" + view + "'";
    return choice;
  }
  choice.projection = p;
  return choice;
}

Scene build_scene(const Model& model, const VecX& q, const RenderOptions& options) {
  check_argument(q.size() == model.nq, "build_scene", "q", "must have model.nq coordinates");
  check_argument(model.dimension == 3 || options.projection.is_top(), "build_scene",
                 "options.projection", "must be the top view for a planar mechanism");
  check_argument(options.width > 0 && options.height > 0 &&
                     options.width - 2.0 * options.margin > 0.0 &&
                     options.height - 2.0 * options.margin - options.legend > 0.0,
                 "build_scene", "options", "makes the image smaller than its margins");
  return SceneBuilder(model, q, options).build();
}

std::optional<ImageFormat> image_format_of(const std::string& path) {
  const auto dot = path.find_last_of('.');
  const auto slash = path.find_last_of('/');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return std::nullopt;
  std::string ext = path.substr(dot + 1);
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext == "svg") return ImageFormat::svg;
  if (ext == "png") return ImageFormat::png;
  if (ext == "pdf") return ImageFormat::pdf;
  return std::nullopt;
}

std::string draw_image(const Scene& scene, ImageFormat format) {
  std::string bytes;
  const double w = scene.view.width, h = scene.view.height;
  SurfacePtr surface;
  switch (format) {
    case ImageFormat::png:
      surface.reset(
          cairo().image_surface_create(CAIRO_FORMAT_ARGB32, scene.view.width, scene.view.height));
      break;
    case ImageFormat::svg:
      surface.reset(cairo().svg_surface_create_for_stream(append_bytes, &bytes, w, h));
      cairo().svg_surface_set_document_unit(surface.get(), CAIRO_SVG_UNIT_PX);
      break;
    case ImageFormat::pdf:
      surface.reset(cairo().pdf_surface_create_for_stream(append_bytes, &bytes, w, h));
      break;
  }
  check(cairo().surface_status(surface.get()), "cannot create the surface");
  {
    const ContextPtr cr(cairo().create(surface.get()));
    draw(cr.get(), scene);
    check(cairo().status(cr.get()), "drawing failed");
  }
  if (format == ImageFormat::png)
    check(cairo().surface_write_to_png_stream(surface.get(), append_bytes, &bytes),
          "cannot encode the PNG");
  cairo().surface_finish(surface.get());
  check(cairo().surface_status(surface.get()), "cannot finish the image");
  return bytes;
}

void write_image(const Scene& scene, ImageFormat format, const std::string& path) {
  write_file(path, draw_image(scene, format));
}

void release_render_caches() {
  if (!cairo_loaded) return;  // nothing drawn: neither Cairo nor fontconfig was loaded
  cairo().debug_reset_static_data();
  static const detail::SharedLibrary fontconfig({"libfontconfig.so.1"}, false, "libfontconfig1");
  static auto* const fc_fini = fontconfig.function<decltype(::FcFini)>("FcFini");
  fc_fini();
}

TracePoints resolve_trace_points(const Model& model, const std::vector<std::string>& points) {
  TracePoints result;
  const bool spatial = model.dimension == 3;
  // The points: "body.point" of a moving body (PointRef: s from the centre of mass).
  for (const std::string& name : points) {
    const auto dot = name.find('.');
    const int b = dot == std::string::npos ? -2 : model.find_body(name.substr(0, dot));
    const std::string point = dot == std::string::npos ? "" : name.substr(dot + 1);
    if (b < 0) {
      result.status = TraceStatus::bad_request;
      result.message = "--trace: '" + name + "' is not body.point of a moving body";
      result.points.clear();
      return result;
    }
    const Body& body = model.bodies[static_cast<size_t>(b)];
    std::vector<std::string> names;
    if (spatial)
      for (const auto& p : body.spatial.points) names.push_back(p.first);
    else
      for (const auto& p : body.points) names.push_back(p.first);
    const auto it = std::find(names.begin(), names.end(), point);
    const auto index = static_cast<size_t>(it - names.begin());
    if (it == names.end() && point != "origin") {
      std::string known;
      for (const std::string& p : names) known += (known.empty() ? "" : ", ") + p;
      result.status = TraceStatus::bad_request;
      result.message = "--trace: body '" + body.name + "' has no point '" + point + "' (it has " +
                       (known.empty() ? std::string("origin") : known) + ")";
      result.points.clear();
      return result;
    }
    if (spatial) {
      SpatialPointRef ref;
      ref.body = b;
      ref.s = (it == names.end() ? Vec3::Zero() : body.spatial.points[index].second) -
              body.spatial.com_local;
      ref.label = name;
      result.spatial_points.push_back(ref);
      continue;
    }
    PointRef ref;
    ref.body = b;
    ref.s = (it == names.end() ? Vec2::Zero() : body.points[index].second) - body.com_local;
    ref.label = name;
    result.points.push_back(ref);
  }
  return result;
}

std::vector<PointTrace> trace_paths(const Model& model, const TracePoints& points,
                                    const std::vector<VecX>& q, const std::vector<double>& input) {
  std::vector<PointTrace> traces = trace_paths(model, points.points, q, input);
  for (const SpatialPointRef& ref : points.spatial_points) {
    PointTrace t;
    t.point = ref.label;
    t.input = input;
    t.path.reserve(q.size());
    t.z.reserve(q.size());
    for (const VecX& qk : q) {
      const Vec3 r = spatial_point(spatial_frame(model, ref.body, qk, nullptr), ref.s).r;
      t.path.emplace_back(r.x(), r.y());
      t.z.push_back(r.z());
    }
    traces.push_back(std::move(t));
  }
  return traces;
}

std::vector<PointTrace> trace_paths(const Model& model, const std::vector<PointRef>& points,
                                    const std::vector<VecX>& q, const std::vector<double>& input) {
  std::vector<PointTrace> traces;
  for (const PointRef& ref : points) {
    PointTrace t;
    t.point = ref.label;
    t.input = input;
    t.path.reserve(q.size());
    for (const VecX& qk : q) t.path.push_back(point_kinematics(model, ref, qk, nullptr).r);
    traces.push_back(std::move(t));
  }
  return traces;
}

TraceResult trace_points(const Model& model, const std::vector<std::string>& points, int driver,
                         const SweepRange& range) {
  TraceResult result;
  const TracePoints refs = resolve_trace_points(model, points);
  if (refs.status == TraceStatus::bad_request) {
    result.status = refs.status;
    result.message = refs.message;
    return result;
  }
  const CyclePositions sweep = sweep_positions(model, driver, range);
  if (sweep.status == TraceStatus::failed || sweep.status == TraceStatus::bad_request) {
    result.status = sweep.status;
    result.message = sweep.message;
    return result;
  }
  result.traces = trace_paths(model, refs, sweep.q, sweep.input);
  result.status = sweep.status;
  result.message = sweep.message;
  return result;
}

CyclePositions sweep_positions(const Model& model, int driver, const SweepRange& range) {
  CyclePositions result;
  const auto d = std::find_if(model.drivers.begin(), model.drivers.end(),
                              [&](const Driver& x) { return x.joint == driver; });
  if (d == model.drivers.end()) {
    result.status = TraceStatus::bad_request;
    result.message = "--trace and --animate need a driver and the file has none";
    return result;
  }
  CycleOptions options;
  options.driver = *d;
  options.steps = model.analysis.steps;
  // The range: as given; a prismatic driver without an end takes its joint's limits.
  const Joint& joint = model.joints[static_cast<size_t>(driver)];
  SweepRange r = range;
  if (!r.end && joint_coordinate_kind(joint) != CoordinateKind::angle) {
    if (!joint.limits) {
      result.status = TraceStatus::bad_request;
      result.message = "the prismatic driver '" + d->name + "' (joint '" + joint.name +
                       "') has no full turn to sweep: give its stroke with --from and --to, or "
                       "limits: on the joint";
      return result;
    }
    if (!r.start) r.start = (*joint.limits)(0);
    r.end = (*joint.limits)(1);
  }
  if (r.start) options.use_start = true, options.start = *r.start;
  if (r.end) options.full_cycle = false, options.end = *r.end;
  const CycleResult cycle = run_cycle(model, options);
  if (cycle.status == CycleStatus::failed || cycle.status == CycleStatus::invalid_request ||
      cycle.points.size() == 0) {
    result.status = TraceStatus::failed;
    result.message = "the cycle cannot be swept: " + cycle.message;
    return result;
  }
  for (const auto& p : cycle.points) {
    result.q.emplace_back(p.q);
    result.input.push_back(p.input);
  }
  result.status =
      cycle.status == CycleStatus::completed ? TraceStatus::completed : TraceStatus::partial;
  result.message = cycle.message;
  return result;
}

// Every `id="x"`, `href="#x"` and `url(#x)` of one frame's SVG prefixed with `prefix`.
static std::string prefix_ids(const std::string& svg, const std::string& prefix) {
  std::string out;
  out.reserve(svg.size() + svg.size() / 8);
  static const std::string keys[] = {"id=\"", "href=\"#", "url(#"};
  size_t i = 0;
  while (i < svg.size()) {
    bool matched = false;
    for (const std::string& k : keys)
      if (svg.compare(i, k.size(), k) == 0) {
        out += k + prefix;
        i += k.size();
        matched = true;
        break;
      }
    if (!matched) out += svg[i++];
  }
  return out;
}

ViewTransform animation_view(const Model& model, const std::vector<VecX>& frames,
                             const RenderOptions& options) {
  // Fitted to the primitives of every frame (each with the whole traces).
  std::vector<Primitive> all;
  for (const VecX& q : frames) {
    const Scene scene = build_scene(model, q, options);
    for (const Primitive& p : scene.primitives) all.push_back(p);
  }
  return fit_view(all, options, 100.0 / length_unit_si(model.units.length));
}

std::string animated_svg(const Model& model, const std::vector<VecX>& frames,
                         const RenderOptions& options, double duration) {
  check_argument(!frames.empty(), "animated_svg", "frames", "must not be empty");
  // At most kMaxPictureFrames frames (report.hpp picture_positions), the traces at the same
  // positions: a bounded picture whatever the number of positions.
  if (frames.size() > kMaxPictureFrames) {
    const std::vector<size_t> shown = picture_positions(frames.size());
    std::vector<VecX> kept;
    kept.reserve(shown.size());
    for (const size_t k : shown) kept.push_back(frames[k]);
    RenderOptions thinned = options;
    for (PointTrace& t : thinned.traces) {
      if (t.path.size() != frames.size()) continue;
      std::vector<Vec2> path;
      std::vector<double> z, input;
      for (const size_t k : shown) {
        path.push_back(t.path[k]);
        if (t.z.size() == frames.size()) z.push_back(t.z[k]);
        if (t.input.size() == frames.size()) input.push_back(t.input[k]);
      }
      t.path = std::move(path);
      t.z = std::move(z);
      t.input = std::move(input);
    }
    return animated_svg(model, kept, thinned, duration);
  }
  // One view for every frame.
  RenderOptions fixed = options;
  fixed.view = animation_view(model, frames, options);
  const size_t n = frames.size();
  char head[256];
  std::snprintf(head, sizeof head,
                "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<svg "
                "xmlns=\"http://www.w3.org/2000/svg\" xmlns:xlink=\"http://www.w3.org/1999/xlink\" "
                "width=\"%dpx\" height=\"%dpx\" viewBox=\"0 0 %d %d\" version=\"1.1\">\n",
                options.width, options.height, options.width, options.height);
  std::string out = head;
  for (size_t k = 0; k < n; ++k) {
    // The traces drawn along: up to this frame's position.
    for (size_t t = 0; t < fixed.traces.size(); ++t)
      if (options.traces[t].path.size() == n) {
        fixed.traces[t].path.assign(options.traces[t].path.begin(),
                                    options.traces[t].path.begin() + static_cast<long>(k) + 1);
        if (options.traces[t].z.size() == n)
          fixed.traces[t].z.assign(options.traces[t].z.begin(),
                                   options.traces[t].z.begin() + static_cast<long>(k) + 1);
      }
    const std::string svg = draw_image(build_scene(model, frames[k], fixed), ImageFormat::svg);
    // The frame's content: between the end of the <svg …> start tag and </svg>.
    const size_t open = svg.find("<svg");
    const size_t body = svg.find('>', open) + 1;
    const size_t close = svg.rfind("</svg>");
    const std::string id = "f" + std::to_string(k) + "-";
    // Shown during [k/n, (k+1)/n) of the loop (discrete key times; the first and last frames
    // have two key times only, so that they stay increasing).
    std::string values, times;
    const auto t = [&](size_t j) {
      char b[32];
      std::snprintf(b, sizeof b, "%.9g", static_cast<double>(j) / static_cast<double>(n));
      return std::string(b);
    };
    if (n == 1) {
      values = "inline", times = "0";
    } else if (k == 0) {
      values = "inline;none", times = "0;" + t(1);
    } else if (k + 1 == n) {
      values = "none;inline", times = "0;" + t(k);
    } else {
      values = "none;inline;none", times = "0;" + t(k) + ";" + t(k + 1);
    }
    char dur[32];
    std::snprintf(dur, sizeof dur, "%.9gs", duration);
    out += "<g id=\"frame-" + std::to_string(k) + "\" display=\"" + (k == 0 ? "inline" : "none") +
           "\">\n<animate attributeName=\"display\" calcMode=\"discrete\" "
           "repeatCount=\"indefinite\" dur=\"" +
           dur + "\" values=\"" + values + "\" keyTimes=\"" + times + "\"/>\n";
    out += prefix_ids(svg.substr(body, close - body), id);
    out += "</g>\n";
  }
  out += "</svg>\n";
  return out;
}

PoseResult assemble_pose(const Model& model, const RenderPose& pose) {
  PoseResult result;
  // The driver: the analysis' driver, else the first one.
  for (const Driver& d : model.drivers)
    if (d.name == model.analysis.driver) result.driver = d.joint;
  if (result.driver < 0 && !model.drivers.empty()) result.driver = model.drivers.front().joint;

  AssemblyOptions options;
  std::string where = "the design position";
  if (!pose.position.empty() && !pose.input.empty()) {
    result.status = PoseStatus::bad_request;
    result.message = "--position and --input are exclusive";
    return result;
  }
  if (!pose.position.empty()) {
    const auto it = std::find_if(model.design_positions.begin(), model.design_positions.end(),
                                 [&](const DesignPosition& p) { return p.name == pose.position; });
    if (it == model.design_positions.end()) {
      std::string known;
      for (const DesignPosition& p : model.design_positions)
        known += (known.empty() ? "" : ", ") + p.name;
      result.status = PoseStatus::bad_request;
      result.message = "design position '" + pose.position + "' is not defined" +
                       (known.empty() ? " (the file has none)" : " (the file has " + known + ")");
      return result;
    }
    for (const auto& [joint, value] : it->inputs) options.locks.push_back({joint, value});
    where = "design position '" + pose.position + "'";
  }
  if (!pose.input.empty()) {
    if (result.driver < 0) {
      result.status = PoseStatus::bad_request;
      result.message = "--input needs a driver and the file has none";
      return result;
    }
    const Joint& joint = model.joints[static_cast<size_t>(result.driver)];
    const bool angular = joint_coordinate_kind(joint) == CoordinateKind::angle;
    double value = 0.0;
    try {
      value = parse_position(
          pose.input, angular,
          angular ? angle_unit_si(model.units.angle) : length_unit_si(model.units.length));
    } catch (const std::invalid_argument& e) {
      result.status = PoseStatus::bad_request;
      result.message = std::string("--input: ") + e.what();
      return result;
    }
    options.locks.push_back({result.driver, value});
    where =
        "joint '" + joint.name + "' at " + format_input(value, angular, unit_system(model.units));
  }
  const AssemblyResult res = assemble(model, model.design_q(), options);
  if (res.status != AssemblyStatus::assembled && res.status != AssemblyStatus::unchanged) {
    result.status = PoseStatus::cannot_assemble;
    result.message = "cannot assemble " + where + ": " + res.message;
    result.q = res.q;
    return result;
  }
  result.status = PoseStatus::ok;
  result.q = res.q;
  return result;
}

}  // namespace orthomech
