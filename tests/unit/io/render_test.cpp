// `orthomech render` (issue 14; io/render.hpp, cli/render.cpp).
//
// Oracle of the drawing: the crank-rocker (30/80/60 mm on a 70 mm ground, coupler point P =
// [40, 20] in the coupler frame, open assembly) is solved here in closed form at crank 0° and 90°
// (circle–circle intersection), mapped to pixels by the transform documented in io/render.hpp and
// docs/cli.md (box of the drawn model points, margins, uniform scale, centred), and the PNG that
// the command wrote is read back with Cairo: at every joint's pixel the centre must have the
// revolute symbol's fill and the ring its ink. SVG output is parsed as XML (expat) and its
// revolute symbols counted against the revolute joints of the file; PDF output starts with %PDF.
// Errors: unknown image type, unknown design position (exit 2), an input that cannot assemble
// (exit 3, with the reason), no file left behind.
#include "orthomech/io/render.hpp"

#include <cairo.h>
#include <expat.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "orthomech/io/mechanism_file.hpp"
#include "support/cli_runner.hpp"
#include "support/fixtures.hpp"
#include "support/png_image.hpp"
#include "support/zoo.hpp"

namespace orthomech {
namespace {

namespace fs = std::filesystem;
using test::CliResult;
using test::run_cli;

std::string bundled(const std::string& name) { return test::bundled_file(name); }

// A fresh output directory (test::TempDir), removed at the end of the test.
struct TempDir : test::TempDir {
  TempDir() : test::TempDir("orthomech_render_") {}
};

// ---- the crank-rocker in closed form (mm), independent of the library ------------------------
struct FourBarPose {
  Vec2 A0, B0, A, B, P;
};
// Links of mechanisms/crank-rocker.yaml (its comment block): ground d, crank a, coupler b, rocker
// c.
constexpr double kGroundLength = 70.0, kCrank = 30.0, kCoupler = 80.0, kRocker = 60.0;
const Vec2 kCouplerPoint(40.0, 20.0);  // P in the coupler frame (x from A to B)

// B is the intersection of the circles |B − A| = b and |B − B0| = c on the open circuit (B to the
// left of the line A → B0, as in the file's design pose).
FourBarPose crank_rocker_at(double crank_deg) {
  FourBarPose p;
  p.A0 = Vec2(0.0, 0.0);
  p.B0 = Vec2(kGroundLength, 0.0);
  const double t = crank_deg * std::numbers::pi / 180.0;
  p.A = kCrank * Vec2(std::cos(t), std::sin(t));
  const Vec2 AB0 = p.B0 - p.A;
  const double e = AB0.norm();
  // Along A → B0 the foot of B lies at x = (b² − c² + e²) / (2e); B is h to the left of it.
  const double x = (kCoupler * kCoupler - kRocker * kRocker + e * e) / (2.0 * e);
  const double h = std::sqrt(kCoupler * kCoupler - x * x);
  const Vec2 u = AB0 / e, left(-u.y(), u.x());
  p.B = p.A + x * u + h * left;
  const Vec2 ex = (p.B - p.A) / kCoupler, ey(-ex.y(), ex.x());
  p.P = p.A + kCouplerPoint.x() * ex + kCouplerPoint.y() * ey;
  return p;
}

// The documented transform (docs/cli.md, "render"): the box of the drawn model points (here the
// five points; the coupler outline is A–P–B), the drawing area inside the margins and above the
// legend strip, one scale, centred. Works in mm: the pixels do not depend on the length unit.
struct ExpectedView {
  double scale;  // px per mm
  Vec2 centre, centre_px;
  [[nodiscard]] Vec2 pixel(const Vec2& p) const {
    return Vec2(centre_px.x() + scale * (p.x() - centre.x()),
                centre_px.y() - scale * (p.y() - centre.y()));
  }
};
// The documented transform for a model bounding box [lo, hi] on a width × height image.
ExpectedView expected_view(const Vec2& lo, const Vec2& hi, int width, int height) {
  const RenderOptions defaults;  // the documented margins: 40 px, legend 40 px
  const double area_w = width - 2.0 * defaults.margin;
  const double area_h = height - 2.0 * defaults.margin - defaults.legend;
  ExpectedView v;
  v.scale = std::min(area_w / (hi.x() - lo.x()), area_h / (hi.y() - lo.y()));
  v.centre = 0.5 * (lo + hi);
  v.centre_px = Vec2(0.5 * width, defaults.margin + 0.5 * area_h);
  return v;
}
ExpectedView expected_view(const FourBarPose& p, int width, int height) {
  Vec2 lo = p.A0, hi = p.A0;
  for (const Vec2& v : {p.B0, p.A, p.B, p.P}) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  return expected_view(lo, hi, width, height);
}

// ---- reading a PNG back with Cairo -------------------------------------------------------------
struct Png : test::PngImage {
  explicit Png(const std::string& path) : test::PngImage(from_file(path)) {}
  // Colour of the pixel containing the point (x, y) (pixel (i, j) covers [i, i+1) × [j, j+1)),
  // 0…1; the image is opaque, so Cairo's premultiplied ARGB32 is the colour itself.
  [[nodiscard]] Rgba at(const Vec2& p) const {
    const int i = static_cast<int>(std::floor(p.x())), j = static_cast<int>(std::floor(p.y()));
    if (i < 0 || j < 0 || i >= width || j >= height) return Rgba{-1, -1, -1, -1};
    const uint32_t v = argb(i, j);
    return Rgba{((v >> 16) & 0xff) / 255.0, ((v >> 8) & 0xff) / 255.0, (v & 0xff) / 255.0,
                ((v >> 24) & 0xff) / 255.0};
  }
};

// 8-bit quantisation of the colour (1/255) plus a margin for antialiasing leaking into a pixel
// that lies wholly inside the shape: 3/255.
constexpr double kColourTolerance = 3.0 / 255.0;
bool same_colour(const Rgba& a, const Rgba& b) {
  return std::abs(a.r - b.r) <= kColourTolerance && std::abs(a.g - b.g) <= kColourTolerance &&
         std::abs(a.b - b.b) <= kColourTolerance && std::abs(a.a - b.a) <= kColourTolerance;
}
std::string str(const Rgba& c) {
  char s[80];
  std::snprintf(s, sizeof s, "rgba(%.3f, %.3f, %.3f, %.3f)", c.r, c.g, c.b, c.a);
  return s;
}

// The revolute symbol at pixel c: fill at the centre (the filled disc reaches kJointRadius −
// kJointRing/2 = 5.5 px, so every pixel within 1.2 px of the centre is wholly inside it) and ink
// on the ring, sampled in four directions at kJointRadius (the ring spans ±1.5 px around it, so
// the sampled pixel, within 0.71 px of the sample point, is wholly on the ring). A joint drawn
// more than about 1.5 px from c fails one of the ring samples.
void expect_joint_at(const Png& png, const Vec2& c, const std::string& name) {
  EXPECT_TRUE(same_colour(png.at(c), kJointFill)) << "joint " << name << " centre pixel (" << c.x()
                                                  << ", " << c.y() << ") is " << str(png.at(c));
  for (const Vec2& d : {Vec2(1, 0), Vec2(-1, 0), Vec2(0, 1), Vec2(0, -1)}) {
    const Vec2 p = c + kJointRadius * d;
    EXPECT_TRUE(same_colour(png.at(p), kJointInk)) << "joint " << name << " ring pixel (" << p.x()
                                                   << ", " << p.y() << ") is " << str(png.at(p));
  }
}

class RenderCrankRocker : public ::testing::TestWithParam<double> {};

TEST_P(RenderCrankRocker, PngJointsAtTheClosedFormPixels) {
  const double crank = GetParam();
  TempDir dir;
  const std::string out = (dir.path / "crank-rocker.png").string();
  // A bare --input number is in the file's angle unit (deg).
  const CliResult r =
      run_cli({"render", bundled("crank-rocker"), "--input", std::to_string(crank), "--out", out});
  ASSERT_EQ(r.status, 0) << r.err;
  const Png png(out);
  ASSERT_NE(png.data, nullptr) << "cannot read " << out;
  ASSERT_EQ(png.width, 800);
  ASSERT_EQ(png.height, 600);
  const FourBarPose pose = crank_rocker_at(crank);
  const ExpectedView view = expected_view(pose, 800, 600);
  expect_joint_at(png, view.pixel(pose.A0), "A0");
  expect_joint_at(png, view.pixel(pose.A), "A");
  expect_joint_at(png, view.pixel(pose.B), "B");
  expect_joint_at(png, view.pixel(pose.B0), "B0");
  // And the coupler point P (not a joint) is a dark dot, not a joint symbol.
  EXPECT_FALSE(same_colour(png.at(view.pixel(pose.P)), kJointFill));
}

INSTANTIATE_TEST_SUITE_P(CrankAngles, RenderCrankRocker, ::testing::Values(0.0, 90.0));

// The same through a design position: p2 locks the crank at 150°.
TEST(Render, PngAtADesignPosition) {
  TempDir dir;
  const std::string out = (dir.path / "p2.png").string();
  const CliResult r =
      run_cli({"render", bundled("crank-rocker"), "--position", "p2", "--out", out});
  ASSERT_EQ(r.status, 0) << r.err;
  const Png png(out);
  ASSERT_NE(png.data, nullptr);
  const FourBarPose pose = crank_rocker_at(150.0);
  const ExpectedView view = expected_view(pose, 800, 600);
  expect_joint_at(png, view.pixel(pose.A), "A");
  expect_joint_at(png, view.pixel(pose.B), "B");
}

// The library's transform is the documented one (the same box, scale and centre as above; the
// model is in metres, the closed form in mm).
TEST(Render, SceneTransformIsTheDocumentedOne) {
  const Model model = test::load_bundled("crank-rocker");
  const PoseResult pose = assemble_pose(model, RenderPose{"", "90deg"});
  ASSERT_EQ(pose.status, PoseStatus::ok) << pose.message;
  RenderOptions options;
  options.driver = pose.driver;
  const Scene scene = build_scene(model, pose.q, options);
  const ExpectedView expected = expected_view(crank_rocker_at(90.0), 800, 600);
  constexpr double kRelative = 1e-9;  // the closed form and the assembly agree to ~1e-12 mm
  EXPECT_NEAR(scene.view.scale * 1e-3, expected.scale, kRelative * expected.scale);
  EXPECT_NEAR(scene.view.centre.x() * 1e3, expected.centre.x(), 1e-6);
  EXPECT_NEAR(scene.view.centre.y() * 1e3, expected.centre.y(), 1e-6);
  int revolutes = 0, drivers = 0;
  for (const Primitive& p : scene.primitives) {
    revolutes += p.role == Role::revolute;
    drivers += p.role == Role::driver && p.element == "A0";
  }
  EXPECT_EQ(revolutes, 4);
  EXPECT_GT(drivers, 0) << "the driven joint A0 is marked";
}

// Every joint, load and body kind (tests/support/zoo.hpp, drawn at its unassembled design q):
// a symbol of each kind, and every format draws it.
TEST(Render, ZooHasASymbolOfEveryKindInEveryFormat) {
  const Model model = parse_mechanism(test::kZooYaml, "zoo");
  RenderOptions options;
  options.labels = true;
  options.driver = model.find_joint("J8");  // a prismatic driver: the double arrow
  const Scene scene = build_scene(model, model.design_q(), options);
  std::map<Role, int> count;
  for (const Primitive& p : scene.primitives) ++count[p.role];
  EXPECT_EQ(count[Role::revolute], 2);  // J1, J7
  EXPECT_GT(count[Role::prismatic], 0);
  EXPECT_GT(count[Role::pin_in_slot], 0);
  EXPECT_GT(count[Role::fixed], 0);
  EXPECT_GT(count[Role::distance], 0);
  EXPECT_GT(count[Role::spring_damper], 0);
  EXPECT_GT(count[Role::ground], 0);
  EXPECT_GT(count[Role::driver], 0);
  EXPECT_GT(count[Role::label], 0);
  EXPECT_GT(count[Role::scale_bar], 0);
  EXPECT_EQ(count[Role::body], 6);  // a: plate (3 points); b, c: bars (2 primitives each); p: disc
  for (const ImageFormat f : {ImageFormat::svg, ImageFormat::png, ImageFormat::pdf})
    EXPECT_GT(draw_image(scene, f).size(), 100u);
  release_render_caches();  // the sanitizer build checks leaks at exit
  EXPECT_GT(draw_image(scene, ImageFormat::png).size(), 100u) << "drawing again after a release";
  release_render_caches();
}

// Three collinear points (the triple crank's coupler: pins at 0, 100, 200 mm on its x axis) make
// a bar between the extreme ones, not a flat plate.
TEST(Render, CollinearPointsMakeABar) {
  const Model model = test::load_bundled("triple-crank");
  const Scene scene = build_scene(model, model.design_q(), RenderOptions{});
  int paths = 0;
  for (const Primitive& p : scene.primitives)
    if (p.role == Role::body && p.element == "coupler") {
      const auto* path = std::get_if<Path>(&p.shape);
      ASSERT_NE(path, nullptr);
      ASSERT_EQ(path->points.size(), 2u);
      EXPECT_NEAR((path->points[0].model - path->points[1].model).norm(), 0.2, 1e-12);  // m
      ++paths;
    }
  EXPECT_EQ(paths, 2);  // the bar and its edge
}

// Pitch circles of a gear pair on the ground: pivots 90 mm apart. Rolling without slip gives
// r1 ω1 = −r2 ω2 for external gears (k = ω2/ω1 = −r1/r2) and r1 ω1 = r2 ω2 for internal ones
// (k = r1/r2), with r1 + r2 (external) or r2 − r1 (internal, gear 2 the ring) equal to the
// centre distance.
TEST(Render, GearPitchCirclesRollOnEachOther) {
  for (const double k : {-2.0, 0.25}) {
    const std::string text = R"(orthomech: 1
name: gears
units: {length: mm}
ground:
  points: {O1: [0, 0], O2: [90, 0]}
bodies:
  - {name: g1, mass: 1, inertia: 1, pose: [0, 0, 0], points: {O: [0, 0]}}
  - {name: g2, mass: 1, inertia: 1, pose: [90, 0, 0], points: {O: [0, 0]}}
joints:
  - {name: P1, type: revolute, connects: [ground.O1, g1.O]}
  - {name: P2, type: revolute, connects: [ground.O2, g2.O]}
  - {name: mesh, type: gear, bodies: [g1, g2], ratio: )" +
                             std::to_string(k) + "}\n";
    const Model model = parse_mechanism(text, "gears");
    const Scene scene = build_scene(model, model.design_q(), RenderOptions{});
    std::vector<std::pair<Vec2, double>> circles;  // centre (mm), radius (mm)
    for (const Primitive& p : scene.primitives)
      if (p.role == Role::gear)
        if (const auto* c = std::get_if<Circle>(&p.shape))
          circles.emplace_back(c->centre.model * 1e3, c->radius_model * 1e3);
    ASSERT_EQ(circles.size(), 2u) << "k = " << k;
    constexpr double kTol = 1e-9;  // mm: a division and a product
    const double r1 = circles[0].second, r2 = circles[1].second;
    EXPECT_NEAR((circles[0].first - Vec2(0, 0)).norm(), 0.0, kTol);
    EXPECT_NEAR((circles[1].first - Vec2(90, 0)).norm(), 0.0, kTol);
    EXPECT_NEAR(r1 / r2, std::abs(k), kTol);
    EXPECT_NEAR(k < 0 ? r1 + r2 : r2 - r1, 90.0, kTol) << "k = " << k;
  }
}

// ---- SVG parsed as XML -------------------------------------------------------------------------
struct SvgCount {
  int elements = 0;
  int joint_fills = 0;  // <path> elements filled with the revolute symbol's colour
  bool svg_root = false;
};

// "fill:rgb(100%,85%,30%)" or "stroke:rgb(…)" (Cairo's SVG style syntax) → the colour, if present.
std::optional<Rgba> style_colour(const std::string& style, const std::string& property) {
  const std::string key = property + ":rgb(";
  const auto k = style.find(key);
  if (k == std::string::npos || (k > 0 && style[k - 1] != ';')) return std::nullopt;
  Rgba c;
  if (std::sscanf(style.c_str() + k + key.size(), "%lf%%,%lf%%,%lf%%)", &c.r, &c.g, &c.b) != 3)
    return std::nullopt;
  c.r /= 100.0;
  c.g /= 100.0;
  c.b /= 100.0;
  return c;
}
std::optional<Rgba> style_fill(const std::string& style) { return style_colour(style, "fill"); }

void XMLCALL start_element(void* data, const XML_Char* name, const XML_Char** attributes) {
  auto* count = static_cast<SvgCount*>(data);
  if (count->elements++ == 0) count->svg_root = std::string(name) == "svg";
  if (std::string(name) != "path") return;
  for (int k = 0; attributes[k]; k += 2)
    if (std::string(attributes[k]) == "style")
      if (const auto fill = style_fill(attributes[k + 1])) {
        Rgba f = *fill;
        f.a = 1.0;
        count->joint_fills += same_colour(f, kJointFill);
      }
}
void XMLCALL end_element(void*, const XML_Char*) {}

SvgCount parse_svg(const std::string& text, std::string& error) {
  SvgCount count;
  std::unique_ptr<std::remove_pointer_t<XML_Parser>, decltype(&XML_ParserFree)> parser(
      XML_ParserCreate(nullptr), XML_ParserFree);
  XML_SetUserData(parser.get(), &count);
  XML_SetElementHandler(parser.get(), start_element, end_element);
  if (XML_Parse(parser.get(), text.data(), static_cast<int>(text.size()), 1) != XML_STATUS_OK)
    error = XML_ErrorString(XML_GetErrorCode(parser.get()));
  return count;
}

// The expected number of revolute symbols is the number of revolute joints in each file's
// comment block: crank-rocker 4, Andrews' squeezer 10, slider-crank 3 (+ the prismatic slide).
TEST(Render, SvgIsXmlWithOneSymbolPerRevolute) {
  TempDir dir;
  for (const auto& [name, revolutes] : std::vector<std::pair<std::string, int>>{
           {"crank-rocker", 4}, {"andrews-squeezer", 10}, {"slider-crank", 3}}) {
    const std::string out = (dir.path / (name + ".svg")).string();
    const CliResult r = run_cli({"render", bundled(name), "--labels", "--out", out});
    ASSERT_EQ(r.status, 0) << name << ": " << r.err;
    std::string error;
    const SvgCount count = parse_svg(test::read_text(out), error);
    EXPECT_EQ(error, "") << name << ": not well-formed XML";
    EXPECT_TRUE(count.svg_root) << name;
    EXPECT_EQ(count.joint_fills, revolutes) << name;
  }
}

TEST(Render, PdfStartsWithItsSignature) {
  TempDir dir;
  const std::string out = (dir.path / "slider-crank.PDF").string();  // the extension in any case
  const CliResult r = run_cli({"render", bundled("slider-crank"), "--out", out});
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string text = test::read_text(out);
  EXPECT_EQ(text.substr(0, 5), "%PDF-");
  EXPECT_NE(text.find("%%EOF"), std::string::npos);
}

// ---- coupler curves (--trace) ------------------------------------------------------------------
// The traced path of the coupler point is the closed-form coupler curve at each input of the
// sweep (the sweep's positions are solved to ~1e-12 m).
constexpr double kTraceTolerance = 1e-9;  // m

TEST(RenderTrace, CouplerPointPathIsTheClosedFormCurve) {
  const Model model = test::load_bundled("crank-rocker");
  const PoseResult pose = assemble_pose(model, RenderPose{});
  ASSERT_EQ(pose.status, PoseStatus::ok);
  const TraceResult traced = trace_points(model, {"coupler.P", "crank.A"}, pose.driver);
  ASSERT_EQ(traced.status, TraceStatus::completed) << traced.message;
  ASSERT_EQ(traced.traces.size(), 2u);
  const PointTrace& p = traced.traces[0];
  ASSERT_GE(p.path.size(), 360u);  // analysis: steps 360, a full turn
  for (size_t k = 0; k < p.path.size(); ++k) {
    const FourBarPose closed = crank_rocker_at(p.input[k] * 180.0 / std::numbers::pi);
    EXPECT_LT((p.path[k] - 1e-3 * closed.P).norm(), kTraceTolerance) << "input " << p.input[k];
    EXPECT_LT((traced.traces[1].path[k] - 1e-3 * closed.A).norm(), kTraceTolerance);
  }
  const TraceResult bad = trace_points(model, {"coupler.Q"}, pose.driver);
  EXPECT_EQ(bad.status, TraceStatus::bad_request);
  EXPECT_EQ(bad.message, "--trace: body 'coupler' has no point 'Q' (it has A, B, P)");
}

// The PNG of `render --trace coupler.P` has the trace's colour on the closed-form curve, the view
// fitted to the curve as well (the documented box includes the traced paths).
TEST(RenderTrace, PngShowsTheCurveAtItsClosedFormPixels) {
  TempDir dir;
  const std::string out = (dir.path / "trace.png").string();
  const CliResult r =
      run_cli({"render", bundled("crank-rocker"), "--trace", "coupler.P", "--out", out});
  ASSERT_EQ(r.status, 0) << r.err;
  const Png png(out);
  ASSERT_NE(png.data, nullptr);
  // The box: the design position (crank 60°) and the curve sampled finely (1°: the drawn chords
  // of 360 steps deviate from the curve by < 0.01 mm, far below a pixel).
  FourBarPose box = crank_rocker_at(60.0);
  Vec2 lo = box.P, hi = box.P;
  for (int deg = 0; deg < 360; ++deg) {
    const Vec2 P = crank_rocker_at(deg).P;
    lo = lo.cwiseMin(P);
    hi = hi.cwiseMax(P);
  }
  for (const Vec2& v : {box.A0, box.B0, box.A, box.B}) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  const ExpectedView view = expected_view(lo, hi, 800, 600);
  int checked = 0;
  for (int deg = 0; deg < 360; deg += 15) {
    const Vec2 c = view.pixel(crank_rocker_at(deg).P);
    // Skip samples near what is drawn over the trace (joints, the point dot, labels: none).
    bool covered = false;
    for (const Vec2& j : {box.A0, box.B0, box.A, box.B, box.P})
      covered = covered || (view.pixel(j) - c).norm() < 3.0 * kJointRadius;
    if (covered) continue;
    ++checked;
    EXPECT_TRUE(same_colour(png.at(c), kFirstTraceColour))
        << "crank " << deg << " deg: pixel (" << c.x() << ", " << c.y() << ") is "
        << str(png.at(c));
  }
  EXPECT_GE(checked, 12);
}

// Driven from the rocker at constant speed the crank-rocker stops at a dead point (crank and
// coupler collinear, its comment block): the picture is drawn with the traces up to there, exit 1.
TEST(RenderTrace, SweepStoppedAtADeadPointDrawsThePartAndExitsOne) {
  TempDir dir;
  std::string text = test::read_text(bundled("crank-rocker"));
  const std::string from = "{name: motor, joint: A0, speed: 300 rpm}";
  ASSERT_NE(text.find(from), std::string::npos);
  text.replace(text.find(from), from.size(), "{name: motor, joint: B0, speed: 10 rpm}");
  const fs::path file = dir.path / "rocker-driven.yaml";
  std::ofstream(file) << text;
  const std::string out = (dir.path / "x.png").string();
  const CliResult r = run_cli({"render", file.string(), "--trace", "coupler.P", "--out", out});
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_NE(r.err.find("the traces stop where the sweep stopped"), std::string::npos) << r.err;
  EXPECT_TRUE(fs::exists(out));
}

TEST(RenderTrace, UnknownPointIsBadInput) {
  TempDir dir;
  const std::string out = (dir.path / "x.svg").string();
  const CliResult r =
      run_cli({"render", bundled("crank-rocker"), "--trace", "coupler", "--out", out});
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--trace: 'coupler' is not body.point of a moving body"), std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(out));
}

// ---- animation (--animate) ---------------------------------------------------------------------
// Frames of the animated SVG: groups frame-K; in each, the revolute symbols' paths in joint order
// (A0, A, B, B0). Cairo writes a circle of radius r about c starting at c + (r, 0): "M x y C …".
struct AnimationFrames {
  std::vector<std::vector<Vec2>> joints;  // per frame, the centres of the revolute symbols
  std::vector<std::vector<Vec2>> trace;   // per frame, the vertices of the first trace's path
  int animates = 0;                       // <animate> elements
  int depth = 0, frame_depth = -1;
};
void XMLCALL animation_start(void* data, const XML_Char* name, const XML_Char** attributes) {
  auto* f = static_cast<AnimationFrames*>(data);
  ++f->depth;
  const std::string element = name;
  std::string id, style, d;
  for (int k = 0; attributes[k]; k += 2) {
    const std::string key = attributes[k];
    if (key == "id") id = attributes[k + 1];
    if (key == "style") style = attributes[k + 1];
    if (key == "d") d = attributes[k + 1];
  }
  if (element == "g" && id.rfind("frame-", 0) == 0) {
    EXPECT_EQ(id, "frame-" + std::to_string(f->joints.size()));
    f->joints.emplace_back();
    f->trace.emplace_back();
    f->frame_depth = f->depth;
  }
  if (element == "animate") ++f->animates;
  if (element == "path" && f->frame_depth > 0) {
    const auto fill = style_fill(style);
    if (fill && same_colour(Rgba{fill->r, fill->g, fill->b, 1.0}, kJointFill)) {
      double x = 0.0, y = 0.0;
      EXPECT_EQ(std::sscanf(d.c_str(), "M %lf %lf", &x, &y), 2) << d;
      f->joints.back().emplace_back(x - kJointRadius, y);
    }
    // The first trace: "M x y L x y …" stroked in its colour.
    const auto stroke = style_colour(style, "stroke");
    if (stroke && same_colour(Rgba{stroke->r, stroke->g, stroke->b, 1.0}, kFirstTraceColour)) {
      std::istringstream in(d);
      std::string op;
      double x = 0.0, y = 0.0;
      while (in >> op >> x >> y) f->trace.back().emplace_back(x, y);
    }
  }
}
void XMLCALL animation_end(void* data, const XML_Char*) {
  auto* f = static_cast<AnimationFrames*>(data);
  if (f->depth == f->frame_depth) f->frame_depth = -1;
  --f->depth;
}

// One frame per position of the cycle (analysis: steps 360, from the design crank angle 60° in
// 1° steps: the sweep of a constant-speed crank), and in frame k every joint at the closed-form
// position of crank 60° + k°, through the documented transform fitted to all frames.
TEST(RenderAnimation, OneFramePerPositionWithTheJointsAtTheClosedForm) {
  TempDir dir;
  const std::string out = (dir.path / "anim.svg").string();
  const CliResult r = run_cli({"render", bundled("crank-rocker"), "--animate", "--out", out});
  ASSERT_EQ(r.status, 0) << r.err;
  AnimationFrames frames;
  std::unique_ptr<std::remove_pointer_t<XML_Parser>, decltype(&XML_ParserFree)> parser(
      XML_ParserCreate(nullptr), XML_ParserFree);
  XML_SetUserData(parser.get(), &frames);
  XML_SetElementHandler(parser.get(), animation_start, animation_end);
  const std::string text = test::read_text(out);
  ASSERT_EQ(XML_Parse(parser.get(), text.data(), static_cast<int>(text.size()), 1), XML_STATUS_OK)
      << XML_ErrorString(XML_GetErrorCode(parser.get()));
  const CliResult png =
      run_cli({"render", bundled("crank-rocker"), "--animate", "--out", out + ".png"});
  EXPECT_EQ(png.status, 2);
  EXPECT_NE(png.err.find("--animate writes an SVG"), std::string::npos) << png.err;
  constexpr int kSteps = 360;  // analysis: steps of the file
  ASSERT_EQ(static_cast<int>(frames.joints.size()), kSteps);
  EXPECT_EQ(frames.animates, kSteps);
  // The view: the box of every frame's points (the design crank 60° + k°, k = 0 … 359).
  Vec2 lo = Vec2::Constant(1e300), hi = -lo;
  for (int k = 0; k < kSteps; ++k) {
    const FourBarPose p = crank_rocker_at(60.0 + k);
    for (const Vec2& v : {p.A0, p.B0, p.A, p.B, p.P}) {
      lo = lo.cwiseMin(v);
      hi = hi.cwiseMax(v);
    }
  }
  const ExpectedView view = expected_view(lo, hi, 800, 600);
  constexpr double kSvgPrecision = 0.01;  // px: Cairo writes coordinates to 1/256 px
  for (int k = 0; k < kSteps; ++k) {
    const FourBarPose p = crank_rocker_at(60.0 + k);
    ASSERT_EQ(frames.joints[k].size(), 4u) << "frame " << k;
    const Vec2 expected[] = {p.A0, p.A, p.B, p.B0};
    for (int j = 0; j < 4; ++j)
      EXPECT_LT((frames.joints[k][j] - view.pixel(expected[j])).norm(), kSvgPrecision)
          << "frame " << k << " joint " << j;
  }
}

AnimationFrames parse_animation(const std::string& text) {
  AnimationFrames frames;
  std::unique_ptr<std::remove_pointer_t<XML_Parser>, decltype(&XML_ParserFree)> parser(
      XML_ParserCreate(nullptr), XML_ParserFree);
  XML_SetUserData(parser.get(), &frames);
  XML_SetElementHandler(parser.get(), animation_start, animation_end);
  EXPECT_EQ(XML_Parse(parser.get(), text.data(), static_cast<int>(text.size()), 1), XML_STATUS_OK)
      << XML_ErrorString(XML_GetErrorCode(parser.get()));
  return frames;
}

// ---- cycle --trace, --animate ------------------------------------------------------------------
// `cycle --trace`: the path of the coupler point P and the crank pin A over the cycle's own
// positions, in the JSON ("traces") and in cycle.csv ("trace coupler.P.x [mm]"), is the
// closed-form position at each input of the sweep, in the file's units (mm, the input in deg).
constexpr double kTraceToleranceMm = 1e-6;  // the positions are solved to ~1e-12 m

TEST(CycleTrace, JsonAndCsvHoldTheClosedFormPaths) {
  TempDir dir;
  const CliResult r = run_cli({"cycle", bundled("crank-rocker"), "--trace", "coupler.P", "--trace",
                               "crank.A", "--json", "--out", dir.path.string()});
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  const size_t n = j.at("positions");
  ASSERT_EQ(n, 360u);  // analysis: steps 360
  ASSERT_EQ(j.at("traces").size(), 2u);
  for (size_t t = 0; t < 2; ++t) {
    const nlohmann::json& trace = j["traces"][t];
    EXPECT_EQ(trace.at("point"), t == 0 ? "coupler.P" : "crank.A");
    EXPECT_EQ(trace.at("unit"), "mm");
    ASSERT_EQ(trace.at("x").size(), n);
    for (size_t k = 0; k < n; ++k) {
      const double input = trace["input"][k];
      EXPECT_NEAR(input, 60.0 + static_cast<double>(k), 1e-9);  // from the design crank 60°
      const FourBarPose closed = crank_rocker_at(input);
      const Vec2 expected = t == 0 ? closed.P : closed.A;
      EXPECT_NEAR(trace["x"][k].get<double>(), expected.x(), kTraceToleranceMm) << k;
      EXPECT_NEAR(trace["y"][k].get<double>(), expected.y(), kTraceToleranceMm) << k;
    }
  }
  // cycle.csv: the same path in the columns named after the point.
  std::istringstream csv(test::read_text(dir.path / "cycle.csv"));
  std::string line;
  ASSERT_TRUE(std::getline(csv, line));
  std::vector<std::string> header;
  for (std::istringstream h(line); std::getline(h, line, ',');) header.push_back(line);
  const auto column = [&](const std::string& name) {
    const auto it = std::find(header.begin(), header.end(), name);
    EXPECT_NE(it, header.end()) << name;
    return static_cast<size_t>(it - header.begin());
  };
  const size_t input = column("input [deg]"), px = column("trace coupler.P.x [mm]"),
               py = column("trace coupler.P.y [mm]");
  size_t rows = 0;
  while (std::getline(csv, line)) {
    std::vector<std::string> cells;
    for (std::istringstream c(line); std::getline(c, line, ',');) cells.push_back(line);
    ASSERT_GT(cells.size(), std::max({input, px, py}));
    const FourBarPose closed = crank_rocker_at(std::stod(cells[input]));
    EXPECT_NEAR(std::stod(cells[px]), closed.P.x(), kTraceToleranceMm) << "row " << rows;
    EXPECT_NEAR(std::stod(cells[py]), closed.P.y(), kTraceToleranceMm) << "row " << rows;
    ++rows;
  }
  EXPECT_EQ(rows, n);
  // The text summary names the trace's extent; --units si gives metres.
  const CliResult si = run_cli(
      {"cycle", bundled("crank-rocker"), "--trace", "coupler.P", "--json", "--units", "si"});
  ASSERT_EQ(si.status, 0) << si.err;
  const nlohmann::json js = nlohmann::json::parse(si.out);
  EXPECT_EQ(js["traces"][0]["unit"], "m");
  EXPECT_NEAR(js["traces"][0]["x"][0].get<double>(), 1e-3 * crank_rocker_at(60.0).P.x(), 1e-9);
}

TEST(CycleTrace, UnknownPointIsBadInput) {
  const CliResult r = run_cli({"cycle", bundled("crank-rocker"), "--trace", "coupler.Q"});
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--trace: body 'coupler' has no point 'Q' (it has A, B, P)"),
            std::string::npos)
      << r.err;
  EXPECT_TRUE(r.out.empty());
}

// `cycle --animate`: one frame per position of the cycle (--steps 36: crank 60° + 10° k), the
// joints of frame k at the closed form through the view fitted to every frame, and the trace
// drawn along: in frame k the coupler point's path has k + 1 vertices, the last at P(60° + 10° k).
TEST(CycleAnimate, OneFramePerPositionWithTheTraceDrawingAlong) {
  TempDir dir;
  const std::string out = (dir.path / "cycle.svg").string();
  constexpr int kSteps = 36;
  const CliResult r = run_cli({"cycle", bundled("crank-rocker"), "--steps", std::to_string(kSteps),
                               "--trace", "coupler.P", "--animate", out});
  ASSERT_EQ(r.status, 0) << r.err;
  const AnimationFrames frames = parse_animation(test::read_text(out));
  ASSERT_EQ(static_cast<int>(frames.joints.size()), kSteps);
  EXPECT_EQ(frames.animates, kSteps);
  Vec2 lo = Vec2::Constant(1e300), hi = -lo;
  for (int k = 0; k < kSteps; ++k) {
    const FourBarPose p = crank_rocker_at(60.0 + 10.0 * k);
    for (const Vec2& v : {p.A0, p.B0, p.A, p.B, p.P}) {
      lo = lo.cwiseMin(v);
      hi = hi.cwiseMax(v);
    }
  }
  const ExpectedView view = expected_view(lo, hi, 800, 600);
  constexpr double kSvgPrecision = 0.01;  // px
  for (int k = 0; k < kSteps; ++k) {
    const FourBarPose p = crank_rocker_at(60.0 + 10.0 * k);
    ASSERT_EQ(frames.joints[k].size(), 4u) << "frame " << k;
    const Vec2 expected[] = {p.A0, p.A, p.B, p.B0};
    for (int j = 0; j < 4; ++j)
      EXPECT_LT((frames.joints[k][j] - view.pixel(expected[j])).norm(), kSvgPrecision)
          << "frame " << k << " joint " << j;
    if (k == 0) continue;  // one vertex: nothing to stroke
    ASSERT_EQ(static_cast<int>(frames.trace[k].size()), k + 1) << "frame " << k;
    EXPECT_LT((frames.trace[k].back() - view.pixel(p.P)).norm(), kSvgPrecision) << "frame " << k;
    EXPECT_LT((frames.trace[k].front() - view.pixel(crank_rocker_at(60.0).P)).norm(),
              kSvgPrecision);
  }
  // Not an SVG: exit 2, nothing written.
  const CliResult png = run_cli({"cycle", bundled("crank-rocker"), "--animate", out + ".png"});
  EXPECT_EQ(png.status, 2);
  EXPECT_FALSE(fs::exists(out + ".png"));
}

// A sweep that stops at a dead point (the double-rocker driven from a rocker, its README): the
// animation has the positions up to there, one frame each, and the exit status is cycle's (1).
TEST(CycleAnimate, SweepStoppedAtADeadPointAnimatesThePositionsBefore) {
  TempDir dir;
  const std::string out = (dir.path / "dead.svg").string();
  const CliResult r =
      run_cli({"cycle", bundled("double-rocker"), "--speed", "10rpm", "--animate", out, "--json"});
  EXPECT_EQ(r.status, 1) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["status"], "stopped_at_dead_point");
  const AnimationFrames frames = parse_animation(test::read_text(out));
  EXPECT_GT(frames.joints.size(), 10u);
  EXPECT_EQ(frames.joints.size(), j["positions"].get<size_t>());
}

}  // namespace
}  // namespace orthomech
