#pragma once
// Drawing a mechanism at one position (issue 14, `orthomech render`): a Scene — a list of
// primitives in model coordinates — and the transform that maps it to pixels. Writing the image
// (SVG, PNG or PDF) goes through one Cairo drawing routine for all three surfaces
// (src/io/render.cpp); no Cairo type appears here.
//
// Coordinates. Every vertex of a primitive is a model point (world frame, SI metres) plus an
// offset in pixels (x right, y down), so that symbols (joint circles, slider blocks, ground
// hatching, labels) keep their size on screen whatever the scale. A vertex may instead be a
// pure screen position (the scale bar).
//
// The transform (ViewTransform, fit_view), documented in docs/cli.md:
//   box       = bounding box of the model parts of every vertex that is not a screen position
//               (plus ± the model radius of circles): body points, outline vertices, ground
//               points, joint and spring end points, guides, pitch circles;
//   area      = [margin, width − margin] × [margin, height − margin − legend] (pixels);
//   scale     = min(area width / box width, area height / box height) px per metre (one box
//               side may be zero; both zero: 1 px per length unit of the file);
//   pixel     = (cx_px + scale (x − cx), cy_px − scale (y − cy)) + offset_px,
//               with (cx, cy) the box centre and (cx_px, cy_px) the area centre.
// A pixel (i, j) of the PNG covers [i, i + 1) × [j, j + 1) in these coordinates (Cairo's
// convention). SVG uses the same numbers in px, PDF in pt.
//
// Spatial mechanisms (dimension 3) are drawn in an orthographic projection (Projection): a world
// point p is the model point (uᵀp, vᵀp) of the drawing above, u the screen's right and v its up
// direction; everything after that (fit_view, the transform, Cairo) is the planar drawing's. A
// planar mechanism is the special case of the view "top", u = x, v = y (the identity).
#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "orthomech/model/model.hpp"

namespace orthomech {

struct Rgba {
  double r = 0.0, g = 0.0, b = 0.0, a = 1.0;  // 0…1 each
};

// What a primitive depicts (tests and the SVG layer order use it).
enum class Role {
  body,
  ground,
  revolute,
  prismatic,
  pin_in_slot,
  gear,
  fixed,
  distance,
  spring_damper,
  point,
  trace,
  driver,
  label,
  scale_bar,
  spatial_joint,  // the marker of a spatial joint (the revolute symbol)
  axis,           // a spatial joint's axis (revolute, cylindrical, prismatic, screw, universal)
  triad,          // the ground frame's axes (spatial views)
};

// A model point plus a pixel offset (x right, y down), or a pure screen position.
struct Vertex {
  Vec2 model = Vec2::Zero();  // world frame, m
  Vec2 px = Vec2::Zero();     // offset in pixels
  bool screen = false;        // true: `px` is the absolute pixel position, `model` unused
};

struct Style {
  std::optional<Rgba> stroke;  // none: not stroked
  std::optional<Rgba> fill;    // none: not filled (closed paths only)
  double line_width = 1.0;     // px
  bool round = false;          // round caps and joins
};

struct Path {
  std::vector<Vertex> points;
  bool closed = false;
  Style style;
};
struct Circle {
  Vertex centre;
  double radius_px = 0.0;     // radius = radius_px + scale · radius_model
  double radius_model = 0.0;  // m
  Style style;
};
struct Text {
  Vertex at;  // left end of the base line
  std::string text;
  double size = 11.0;  // px
  Rgba colour;
};
using Shape = std::variant<Path, Circle, Text>;

struct Primitive {
  Role role = Role::body;
  std::string element;  // the body, joint, load or point it belongs to ("" for the scale bar)
  Shape shape;
};

struct ViewTransform {
  int width = 0, height = 0;      // px
  double scale = 1.0;             // px per metre
  Vec2 centre = Vec2::Zero();     // model box centre, m
  Vec2 centre_px = Vec2::Zero();  // drawing-area centre, px
  [[nodiscard]] Vec2 to_pixels(const Vertex& v) const {
    if (v.screen) return v.px;
    return Vec2(centre_px.x() + scale * (v.model.x() - centre.x()),
                centre_px.y() - scale * (v.model.y() - centre.y())) +
           v.px;
  }
};

// The path of a point over a cycle (`render --trace`).
struct PointTrace {
  std::string point;          // "body.point" as given
  std::vector<double> input;  // the driver's input at each position (rad or m)
  std::vector<Vec2> path;     // world x, y of the point at each position, m
  std::vector<double> z;      // spatial mechanisms: world z at each position, m (planar: empty)
  // The world position of point k (z = 0 when z is empty).
  [[nodiscard]] Vec3 at(size_t k) const {
    return Vec3(path[k].x(), path[k].y(), z.empty() ? 0.0 : z[k]);
  }
};

// ---- the view of a spatial mechanism ---------------------------------------------------------
// An orthographic projection onto the screen: u points right, v up (unit, orthogonal, world
// frame); w = u × v points from the mechanism toward the viewer. From an azimuth a and an
// elevation e (the viewer in the direction w = (cos e cos a, cos e sin a, sin e), z up):
//   u = (−sin a, cos a, 0),   v = w × u = (−sin e cos a, −sin e sin a, cos e)          (V1)
// The named views (docs/cli.md, "render --view"):
//   top   a = −90°, e = 90°:          u = x, v = y (the planar drawing's identity)
//   front a = −90°, e = 0:            u = x, v = z (the viewer on −y)
//   side  a = 0,    e = 0:            u = y, v = z (the viewer on +x)
//   iso   a = 45°,  e = asin(1/√3):   u = (−1, 1, 0)/√2, v = (−1, −1, 2)/√6 (the viewer on (1, 1,
//   1))
struct Projection {
  Vec3 u = Vec3::UnitX(), v = Vec3::UnitY();  // the top view
  [[nodiscard]] Vec2 operator()(const Vec3& p) const { return Vec2(u.dot(p), v.dot(p)); }
  [[nodiscard]] Vec3 toward_viewer() const { return u.cross(v); }
  [[nodiscard]] bool is_top() const { return u == Vec3::UnitX() && v == Vec3::UnitY(); }
};
// (V1) from an azimuth and an elevation in radians (the named views' exact vectors are those of
// view_projection, not these rounded ones).
[[nodiscard]] Projection projection_from(double azimuth, double elevation);
// "iso", "front", "top", "side" (exact vectors above), or "AZ,EL" in degrees (|EL| ≤ 90);
// nullopt for anything else.
[[nodiscard]] std::optional<Projection> view_projection(const std::string& view);
// The view of `render --view` and `cycle --view` for this model: "" is "iso" for a spatial
// mechanism and "top" for a planar one, which is drawn in its plane only. nullopt with the
// message (naming the option) for an unknown view or a planar mechanism in another view.
struct ViewChoice {
  std::optional<Projection> projection;
  std::string message;
};
[[nodiscard]] ViewChoice choose_view(const Model& model, const std::string& view);

// The look of a render (sizes in px).
struct RenderOptions {
  int width = 800, height = 600;      // image size, px (SVG px, PDF pt)
  bool labels = false;                // names of bodies, joints and points
  double margin = 40.0;               // px on every side, room for symbols and labels
  double legend = 40.0;               // px strip at the bottom for the scale bar
  int driver = -1;                    // joint index to mark as driven (−1: none)
  std::vector<PointTrace> traces;     // paths drawn (and fitted in the view) over the bodies
  std::optional<ViewTransform> view;  // this view instead of fit_view (frames of an animation)
  Projection projection;              // spatial mechanisms; a planar one is drawn in "top" only
};

// Revolute symbol: a filled circle of radius kJointRadius − kJointRing/2 in kJointFill with a ring
// of width kJointRing centred on radius kJointRadius in kJointInk (tests read these pixels).
inline constexpr double kJointRadius = 7.0;  // px
inline constexpr double kJointRing = 3.0;    // px
inline constexpr Rgba kJointFill{1.0, 0.85, 0.3, 1.0};
inline constexpr Rgba kJointInk{0.1, 0.1, 0.1, 1.0};
inline constexpr Rgba kBackground{1.0, 1.0, 1.0, 1.0};
// The first trace (--trace) is a round-capped kTraceWidth px line in this colour.
inline constexpr Rgba kFirstTraceColour{0.75, 0.0, 0.55, 1.0};
inline constexpr double kTraceWidth = 3.0;  // px

struct Scene {
  std::vector<Primitive> primitives;
  ViewTransform view;
  Rgba background = kBackground;
};

// The scene of `model` at positions q (size model.nq), fitted to the image (fit_view) with the
// scale bar in the file's length unit (model.units.length). Bodies from their outline, else a
// bar (two points) or the convex hull of three or more points; ground symbols with hatching at
// the ground points of joints and springs; a symbol per joint and spring-damper; the driver
// marked; labels if asked. A spatial mechanism in options.projection: each body as the segments
// between its joint points (a bar for two, the convex hull of the projected points for more; a
// disc at the centre of mass for none), ground supports at the ground's joint points, a marker
// per joint (the revolute symbol) with a short stroke along the projected axis of an axial joint,
// named points and traces projected, and the ground frame's axes as a triad in the legend strip
// (bottom right, screen positions: it does not move the view). Throws std::invalid_argument for a
// planar mechanism in any projection but "top".
[[nodiscard]] Scene build_scene(const Model& model, const VecX& q, const RenderOptions& options);

// The documented transform (above) for these primitives.
[[nodiscard]] ViewTransform fit_view(const std::vector<Primitive>& primitives,
                                     const RenderOptions& options, double fallback_scale);

enum class ImageFormat { svg, png, pdf };
// By the file name's extension (.svg, .png, .pdf, any case); nullopt for anything else.
[[nodiscard]] std::optional<ImageFormat> image_format_of(const std::string& path);

// The image as bytes (one Cairo drawing routine for every format). Throws std::runtime_error if
// Cairo reports an error.
[[nodiscard]] std::string draw_image(const Scene& scene, ImageFormat format);
// draw_image, then an atomic write to `path` (io/mechanism_writer.hpp). Throws
// std::runtime_error when the file cannot be written.
void write_image(const Scene& scene, ImageFormat format, const std::string& path);

// Frees the process-wide caches of Cairo and fontconfig (fonts loaded for text), which
// otherwise live until the process ends and which LeakSanitizer reports as leaks. Call it only
// when no drawing is in progress and no Scene is being drawn on another thread (the CLI calls it
// once, after writing the image); a later draw_image loads them again.
void release_render_caches();

// ---- the position to draw -------------------------------------------------------------------
struct RenderPose {
  std::string position;  // a design position of the file (its inputs are locked), or
  std::string input;     // a value of the driver's joint ("30deg", "12mm"; bare: file units)
};
enum class PoseStatus { ok, bad_request, cannot_assemble };
struct PoseResult {
  PoseStatus status = PoseStatus::cannot_assemble;
  std::string message;  // why not (bad_request: the option's problem; else the assembly's)
  VecX q;               // the assembled position (status ok)
  int driver = -1;      // joint index of the driver (model.analysis.driver, else the first)
};
// Assembles the mechanism where `pose` asks (analysis/assembly.hpp `assemble`, mass metric, from
// the design position, the inputs locked): the design position itself when both fields are
// empty. Numerical trouble is data (cannot_assemble), never an exception.
[[nodiscard]] PoseResult assemble_pose(const Model& model, const RenderPose& pose);

// ---- coupler curves ----------------------------------------------------------------------------
enum class TraceStatus {
  completed,    // the whole cycle
  partial,      // the sweep stopped early (a dead point): the paths up to there
  failed,       // the sweep failed (message says why); no paths
  bad_request,  // a point name is not "body.point" of a moving body
};
struct TraceResult {
  TraceStatus status = TraceStatus::failed;
  std::string message;
  std::vector<PointTrace> traces;
};
// The paths of the named points ("body.point"; "body.origin" is the body frame's origin) over
// the cycle of the driver (`cycle`'s sweep, analysis/cycle.hpp run_cycle: a full turn of a
// constant-speed revolute, one period of a harmonic law, from the design position, the file's
// `analysis: steps`). Numerical trouble is data, never an exception.
// The input range of the sweep (SI): none given, a revolute driver's full turn from the design
// position; a prismatic driver has no full turn and takes [start, end], else its joint's
// `limits:` (bad_request, the message naming render's --from/--to, when it has neither).
struct SweepRange {
  std::optional<double> start, end;
};
[[nodiscard]] TraceResult trace_points(const Model& model, const std::vector<std::string>& points,
                                       int driver, const SweepRange& range = {});
// The two steps of trace_points, for a caller that has the positions already (`cycle --trace`:
// the cycle's own positions). resolve_trace_points: the named points as PointRef (s from the
// centre of mass, label the name as given), or status bad_request with the message (traces
// empty). trace_paths: the world path of each point at the positions q (inputs alongside).
// Spatial mechanisms: spatial_points instead of points (and the traces' z filled).
struct TracePoints {
  TraceStatus status = TraceStatus::completed;  // completed or bad_request
  std::string message;
  std::vector<PointRef> points;                 // planar
  std::vector<SpatialPointRef> spatial_points;  // spatial
};
[[nodiscard]] TracePoints resolve_trace_points(const Model& model,
                                               const std::vector<std::string>& points);
[[nodiscard]] std::vector<PointTrace> trace_paths(const Model& model,
                                                  const std::vector<PointRef>& points,
                                                  const std::vector<VecX>& q,
                                                  const std::vector<double>& input);
[[nodiscard]] std::vector<PointTrace> trace_paths(const Model& model, const TracePoints& points,
                                                  const std::vector<VecX>& q,
                                                  const std::vector<double>& input);

// ---- animation -------------------------------------------------------------------------------
// The positions of the driver's cycle (run_cycle, as trace_points): q and the input at each.
struct CyclePositions {
  TraceStatus status = TraceStatus::failed;  // completed, partial or failed (message)
  std::string message;
  std::vector<VecX> q;
  std::vector<double> input;
};
[[nodiscard]] CyclePositions sweep_positions(const Model& model, int driver,
                                             const SweepRange& range = {});

// The one view of an animation: fit_view over the primitives of every frame (and the traces).
[[nodiscard]] ViewTransform animation_view(const Model& model, const std::vector<VecX>& frames,
                                           const RenderOptions& options);
// An SVG that plays by itself (SMIL): one frame per position, each a group `<g id="frame-K">`
// (K = 0, 1, …) shown during [K/N, (K+1)/N) of a loop of `duration` seconds, every frame drawn by
// draw_image in animation_view. The traces draw along: a trace with one point per frame shows its
// first K + 1 points in frame K (any other trace is whole in every frame). Element ids of each
// frame are prefixed `fK-` so that frames do not collide.
[[nodiscard]] std::string animated_svg(const Model& model, const std::vector<VecX>& frames,
                                       const RenderOptions& options, double duration);

}  // namespace orthomech
