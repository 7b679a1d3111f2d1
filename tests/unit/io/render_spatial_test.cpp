// Pictures of spatial mechanisms (issue 13 item 1; io/render.hpp Projection, build_scene).
//
// Oracles: the projection of a known point in each named view is computed here by hand from the
// view's definition (which world axes point right and up); a numeric azimuth/elevation is checked
// against the viewer direction it names (u and v orthonormal and perpendicular to it, u
// horizontal, v upward). The PNG of mechanisms/rssr.yaml is read back with Cairo: every joint's
// marker (the revolute symbol) must sit at the pixel computed here from the RSSR's closed form
// (its comment block: crank angle θ, rocker angle φ), projected by hand and mapped by the
// documented transform (box of the projected joint points, margins, uniform scale, centred).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/io/render.hpp"
#include "support/cli_runner.hpp"
#include "support/png_image.hpp"

namespace orthomech {
namespace {

using test::CliResult;
using test::run_cli;

constexpr double kDeg = std::numbers::pi / 180.0;

// ---- the projection -----------------------------------------------------------------------------
TEST(SpatialView, NamedViewsProjectAKnownPointAsComputedByHand) {
  const Vec3 p(1.0, 2.0, 3.0);
  struct Case {
    const char* view;
    Vec2 expected;
  };
  const Case cases[] = {
      {"top", Vec2(1.0, 2.0)},    // x right, y up: the planar drawing
      {"front", Vec2(1.0, 3.0)},  // from −y: x right, z up
      {"side", Vec2(2.0, 3.0)},   // from +x: y right, z up
      // From (1, 1, 1): right = (−1, 1, 0)/√2, up = (−1, −1, 2)/√6.
      {"iso", Vec2((-1.0 + 2.0) / std::sqrt(2.0), (-1.0 - 2.0 + 6.0) / std::sqrt(6.0))},
  };
  for (const Case& c : cases) {
    const auto view = view_projection(c.view);
    ASSERT_TRUE(view.has_value()) << c.view;
    const Vec2 got = (*view)(p);
    EXPECT_NEAR(got.x(), c.expected.x(), 1e-15) << c.view;
    EXPECT_NEAR(got.y(), c.expected.y(), 1e-15) << c.view;
  }
  // The top view is exactly the identity of the planar drawing.
  EXPECT_TRUE(view_projection("top")->is_top());
  EXPECT_FALSE(view_projection("iso")->is_top());
}

// "AZ,EL": the viewer along w = (cos e cos a, cos e sin a, sin e); u, v orthonormal, ⟂ w, u
// horizontal, v with a non-negative z, and u × v = w (right-handed: the screen faces the viewer).
TEST(SpatialView, AzimuthElevationLooksFromTheNamedDirection) {
  for (const auto& [a, e] : {std::pair{30.0, 20.0}, std::pair{-120.0, 60.0},
                             std::pair{200.0, -15.0}, std::pair{0.0, 0.0}}) {
    char text[64];
    std::snprintf(text, sizeof text, "%g,%g", a, e);
    const auto view = view_projection(text);
    ASSERT_TRUE(view.has_value()) << text;
    const Vec3 w(std::cos(e * kDeg) * std::cos(a * kDeg), std::cos(e * kDeg) * std::sin(a * kDeg),
                 std::sin(e * kDeg));
    EXPECT_NEAR(view->u.norm(), 1.0, 1e-15) << text;
    EXPECT_NEAR(view->v.norm(), 1.0, 1e-15) << text;
    EXPECT_NEAR(view->u.dot(view->v), 0.0, 1e-15) << text;
    EXPECT_NEAR(view->u.dot(w), 0.0, 1e-15) << text;
    EXPECT_NEAR(view->v.dot(w), 0.0, 1e-15) << text;
    EXPECT_NEAR(view->u.z(), 0.0, 1e-15) << text;
    EXPECT_GE(view->v.z(), 0.0) << text;
    EXPECT_NEAR((view->toward_viewer() - w).norm(), 0.0, 1e-15) << text;
  }
  // The numbers of the named views give the named views.
  for (const auto& [name, numbers] :
       {std::pair{"top", "-90,90"}, std::pair{"front", "-90,0"}, std::pair{"side", "0,0"},
        std::pair{"iso", "45,35.264389682754654"}}) {
    const auto a = view_projection(name), b = view_projection(numbers);
    ASSERT_TRUE(a && b) << name;
    EXPECT_NEAR((a->u - b->u).norm(), 0.0, 1e-14) << name;
    EXPECT_NEAR((a->v - b->v).norm(), 0.0, 1e-14) << name;
  }
  for (const char* bad : {"persp", "", "30", "30,", ",20", "30,100", "a,b", "30,20,10", "ISO"})
    EXPECT_FALSE(view_projection(bad).has_value()) << bad;
}

TEST(SpatialView, PlanarMechanismsAreDrawnInTheTopViewOnly) {
  const Model planar = load_mechanism(test::bundled_file("crank-rocker"));
  EXPECT_TRUE(choose_view(planar, "").projection.has_value());
  EXPECT_TRUE(choose_view(planar, "top").projection.has_value());
  const ViewChoice iso = choose_view(planar, "iso");
  EXPECT_FALSE(iso.projection.has_value());
  EXPECT_NE(iso.message.find("--view"), std::string::npos) << iso.message;
  const Model spatial = load_mechanism(test::bundled_file("rssr"));
  const ViewChoice def = choose_view(spatial, "");
  ASSERT_TRUE(def.projection.has_value());
  EXPECT_NEAR((def.projection->u - view_projection("iso")->u).norm(), 0.0, 0.0) << "default iso";
  const ViewChoice unknown = choose_view(spatial, "oblique");
  EXPECT_FALSE(unknown.projection.has_value());
  EXPECT_NE(unknown.message.find("--view: unknown view 'oblique'"), std::string::npos);
  RenderOptions o;
  o.projection = *view_projection("iso");
  EXPECT_THROW((void)build_scene(planar, planar.design_q(), o), std::invalid_argument);
}

// ---- the RSSR's joints in the PNG
// ----------------------------------------------------------------- mechanisms/rssr.yaml (mm):
// crank r1 = 100 about z through A0 = 0, rocker r2 = 200 about x through B0 = (300, 0, 200); rocker
// angle φ from world y about x (the file's closed form, its values).
struct RssrPose {
  Vec3 A0, A, B, B0;
};
RssrPose rssr_at(double theta_deg, double phi_deg) {
  RssrPose p;
  p.A0 = Vec3(0.0, 0.0, 0.0);
  p.B0 = Vec3(300.0, 0.0, 200.0);
  p.A = 100.0 * Vec3(std::cos(theta_deg * kDeg), std::sin(theta_deg * kDeg), 0.0);
  p.B = p.B0 + 200.0 * Vec3(0.0, std::cos(phi_deg * kDeg), std::sin(phi_deg * kDeg));
  return p;
}

// The design position of the file: θ = 30°, φ = 158.12936317866155° (its comment block).
constexpr double kDesignTheta = 30.0, kDesignPhi = 158.12936317866155;

struct PngCase {
  const char* view;
  Vec3 right, up;  // the view's screen axes, by hand
};

class RenderRssr : public ::testing::TestWithParam<PngCase> {};

Rgba colour_at(const test::PngImage& png, const Vec2& p) {
  const int i = static_cast<int>(std::floor(p.x())), j = static_cast<int>(std::floor(p.y()));
  if (i < 0 || j < 0 || i >= png.width || j >= png.height) return Rgba{-1, -1, -1, -1};
  const uint32_t v = png.argb(i, j);
  return Rgba{((v >> 16) & 0xff) / 255.0, ((v >> 8) & 0xff) / 255.0, (v & 0xff) / 255.0,
              ((v >> 24) & 0xff) / 255.0};
}
bool same_colour(const Rgba& a, const Rgba& b) {
  constexpr double tol = 3.0 / 255.0;
  return std::abs(a.r - b.r) <= tol && std::abs(a.g - b.g) <= tol && std::abs(a.b - b.b) <= tol;
}

// Renders the RSSR with `extra` arguments in view c and checks every joint marker at the pixel
// of the closed-form pose (θ, φ) projected by hand.
void expect_rssr_joints_at(const PngCase& c, const std::vector<std::string>& extra,
                           double theta_deg, double phi_deg) {
  const test::TempDir dir("orthomech_spatial_render_");
  const std::string out = (dir.path / "rssr.png").string();
  std::vector<std::string> args = {"render", test::bundled_file("rssr"), "--view", c.view, "--out",
                                   out};
  args.insert(args.end(), extra.begin(), extra.end());
  const CliResult r = run_cli(args);
  ASSERT_EQ(r.status, 0) << r.err;
  const test::PngImage png = test::PngImage::from_file(out);
  ASSERT_EQ(png.width, 800);
  ASSERT_EQ(png.height, 600);
  // Project by hand (metres do not matter: the transform is scale-free), then the documented
  // transform: box of the projected joint points, area 720 × 480 px (margins 40, legend 40).
  const RssrPose pose = rssr_at(theta_deg, phi_deg);
  const Vec3 joints[] = {pose.A0, pose.A, pose.B, pose.B0};
  const char* names[] = {"A0", "A", "B", "B0"};
  std::vector<Vec2> flat;
  for (const Vec3& p : joints) flat.emplace_back(c.right.dot(p), c.up.dot(p));
  Vec2 lo = flat[0], hi = flat[0];
  for (const Vec2& f : flat) lo = lo.cwiseMin(f), hi = hi.cwiseMax(f);
  const double scale = std::min(720.0 / (hi.x() - lo.x()), 480.0 / (hi.y() - lo.y()));
  const Vec2 centre = 0.5 * (lo + hi), centre_px(400.0, 40.0 + 240.0);
  for (size_t k = 0; k < flat.size(); ++k) {
    const Vec2 px(centre_px.x() + scale * (flat[k].x() - centre.x()),
                  centre_px.y() - scale * (flat[k].y() - centre.y()));
    EXPECT_TRUE(same_colour(colour_at(png, px), kJointFill))
        << c.view << " joint " << names[k] << " centre (" << px.x() << ", " << px.y() << ")";
    for (const Vec2& d : {Vec2(1, 0), Vec2(-1, 0), Vec2(0, 1), Vec2(0, -1)})
      EXPECT_TRUE(same_colour(colour_at(png, px + kJointRadius * d), kJointInk))
          << c.view << " joint " << names[k] << " ring";
  }
}

TEST_P(RenderRssr, JointMarkersAtTheProjectedClosedFormPixels) {
  expect_rssr_joints_at(GetParam(), {}, kDesignTheta, kDesignPhi);
}

// --input locks the driver's spatial joint (assemble with a lock on the crank angle): the joints at
// the pixels of (M1) at θ = 90°, φ = 208.8717849220° (docs/spatial.md §4.1), on the file's branch;
// --position p30 locks the file's design position (θ = 30°).
TEST_P(RenderRssr, InputAndPositionDrawTheClosedFormPoseThere) {
  expect_rssr_joints_at(GetParam(), {"--input", "90deg"}, 90.0, 208.8717849220);
  expect_rssr_joints_at(GetParam(), {"--position", "p30"}, kDesignTheta, kDesignPhi);
}

INSTANTIATE_TEST_SUITE_P(Views, RenderRssr,
                         ::testing::Values(PngCase{"top", Vec3::UnitX(), Vec3::UnitY()},
                                           PngCase{"front", Vec3::UnitX(), Vec3::UnitZ()},
                                           PngCase{"side", Vec3::UnitY(), Vec3::UnitZ()},
                                           PngCase{"iso", Vec3(-1, 1, 0) / std::sqrt(2.0),
                                                   Vec3(-1, -1, 2) / std::sqrt(6.0)}),
                         [](const auto& param_info) { return std::string(param_info.param.view); });

// The scene of a spatial file has one marker per joint, the triad's three axes and, with a
// trace, the projected path (the trace's z matters: the front view shows it).
TEST(SpatialScene, MarkersTriadAndProjectedTrace) {
  const Model model = load_mechanism(test::bundled_file("rssr"));
  const PoseResult pose = assemble_pose(model, {});
  ASSERT_EQ(pose.status, PoseStatus::ok) << pose.message;
  const TraceResult traced = trace_points(model, {"rocker.B"}, pose.driver);
  ASSERT_EQ(traced.status, TraceStatus::completed) << traced.message;
  ASSERT_EQ(traced.traces.size(), 1u);
  const PointTrace& t = traced.traces[0];
  ASSERT_EQ(t.z.size(), t.path.size());
  for (size_t k = 0; k < t.path.size(); ++k) {
    // B stays on the rocker's circle: x = 300 mm, (y, z − 200) of radius 200 mm.
    EXPECT_NEAR(t.path[k].x(), 0.3, 1e-9);
    EXPECT_NEAR(std::hypot(t.path[k].y(), t.z[k] - 0.2), 0.2, 1e-9);
  }
  RenderOptions o;
  o.projection = *view_projection("side");
  o.traces = traced.traces;
  const Scene scene = build_scene(model, pose.q, o);
  int markers = 0;
  std::vector<std::string> triad;
  const Path* trace = nullptr;
  for (const Primitive& p : scene.primitives) {
    if (p.role == Role::spatial_joint) ++markers;
    if (p.role == Role::triad && std::holds_alternative<Text>(p.shape))
      triad.push_back(std::get<Text>(p.shape).text);
    if (p.role == Role::trace) trace = &std::get<Path>(p.shape);
  }
  EXPECT_EQ(markers, 4);
  EXPECT_EQ(triad, (std::vector<std::string>{"x", "y", "z"}));
  ASSERT_NE(trace, nullptr);
  ASSERT_EQ(trace->points.size(), t.path.size());
  for (size_t k = 0; k < t.path.size(); ++k) {  // side: (y, z)
    EXPECT_NEAR(trace->points[k].model.x(), t.path[k].y(), 1e-15);
    EXPECT_NEAR(trace->points[k].model.y(), t.z[k], 1e-15);
  }
}

}  // namespace
}  // namespace orthomech
