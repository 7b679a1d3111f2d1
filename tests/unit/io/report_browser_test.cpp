// `cycle --report` and `cycle --animate` in a real browser (issue 14): headless Chromium driven
// over WebDriver (support/webdriver.hpp; Debian's chromium and chromium-driver, which
// scripts/setup installs — without them these tests fail saying so).
//
// The page (the slider-crank, 24 positions: crank 45° + 15° k) must run without script errors,
// have one animation frame per position, play by itself, and when the slider is moved with the
// keyboard to position k show exactly one frame, whose drawn crank (the revolute symbols of O and
// A, read back from the page's DOM) points at the k-th input angle of `cycle --json --positions`;
// hovering the drive curve shows the drive there. A screenshot of the mechanism at position k is
// compared with an independent drawing: Cairo's PNG of the mechanism assembled at that input
// (analysis/assembly, not the sweep's continuation) in the view fitted to every position — the
// same picture at a tolerance for antialiasing, and clearly different from another position's.
#include <cairo.h>
#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>
#include <thread>
#include <vector>

#include "orthomech/io/render.hpp"
#include "support/cli_runner.hpp"
#include "support/fixtures.hpp"
#include "support/png_image.hpp"
#include "support/webdriver.hpp"

namespace orthomech {
namespace {

using test::Browser;
using test::CliResult;
using test::run_cli;

constexpr int kSteps = 24;             // positions of the sweep in these tests (fast)
constexpr double kDesignCrank = 45.0;  // deg, mechanisms/slider-crank.yaml's design pose

struct Report {
  test::TempDir dir{"orthomech_report_"};
  std::string html;
  nlohmann::json cycle;  // cycle --json --positions of the same sweep
};
// The report of the slider-crank and the JSON of the same cycle.
void make_report(Report& report) {
  report.html = (report.dir.path / "report.html").string();
  const CliResult r =
      run_cli({"cycle", test::bundled_file("slider-crank"), "--steps", std::to_string(kSteps),
               "--report", report.html, "--json", "--positions"});
  ASSERT_EQ(r.status, 0) << r.err;
  report.cycle = nlohmann::json::parse(r.out);
  ASSERT_EQ(report.cycle["positions"], kSteps);
}

// Moves the slider to position k as a person would: focus it, Home, then k × ArrowRight.
void slide_to(Browser& browser, int k) {
  browser.execute("document.getElementById('position').focus();");
  nlohmann::json keys = nlohmann::json::array();
  auto press = [&](const char* key) {
    keys.push_back({{"type", "keyDown"}, {"value", key}});
    keys.push_back({{"type", "keyUp"}, {"value", key}});
  };
  press("\xEE\x80\x91");                              // U+E011 Home
  for (int i = 0; i < k; ++i) press("\xEE\x80\x94");  // U+E014 ArrowRight
  browser.actions(
      nlohmann::json::array({{{"type", "key"}, {"id", "keyboard"}, {"actions", keys}}}));
}

// Opens the report; fails the test (with the reason) when the browser or the page is not there.
void open_report(Browser& browser, const Report& report) {
  ASSERT_TRUE(browser.ok()) << browser.error;
  browser.navigate("file://" + report.html);
  ASSERT_TRUE(browser.wait_for("return document.body.dataset.ready === 'yes';", 10.0))
      << "the page's script did not finish: " << browser.execute("return window.reportErrors;");
}

// The shown frames' indices, and in the shown frame the centres of the revolute symbols (Cairo
// writes a circle of radius r about c as a path starting at c + (r, 0); the symbols are the
// paths filled with kJointFill, rgb(100%,85%,30%)), read from the page's DOM.
constexpr const char* kReadFrame = R"JS(
  var radius = arguments[0];
  var frames = document.querySelectorAll('#mechanism svg g[id^="frame-"]');
  var shown = [], joints = [];
  frames.forEach(function (f, k) {
    if (getComputedStyle(f).display === 'none') return;
    shown.push(k);
    f.querySelectorAll('path').forEach(function (p) {
      var style = p.getAttribute('style') || '';
      if (style.indexOf('fill:rgb(100%,85%,30%)') < 0) return;
      var m = /^\s*M\s*([-\d.e]+)\s+([-\d.e]+)/.exec(p.getAttribute('d'));
      if (m) joints.push([parseFloat(m[1]) - radius, parseFloat(m[2])]);
    });
  });
  return {shown: shown, joints: joints};
)JS";

// The angle (deg, in [0, 360)) of the drawn crank O → A (image y points down).
double drawn_crank(const nlohmann::json& joints) {
  const double dx = joints[1][0].get<double>() - joints[0][0].get<double>();
  const double dy = joints[1][1].get<double>() - joints[0][1].get<double>();
  double deg = std::atan2(-dy, dx) * 180.0 / std::numbers::pi;
  return deg < 0.0 ? deg + 360.0 : deg;
}
double wrap360(double deg) {
  const double w = std::fmod(deg, 360.0);
  return w < 0.0 ? w + 360.0 : w;
}
double angle_gap(double a, double b) {
  const double d = std::fmod(std::abs(a - b), 360.0);
  return std::min(d, 360.0 - d);
}

TEST(ReportBrowser, PlaysAndTheSliderPutsTheCrankAtEachInput) {
  Report report;
  ASSERT_NO_FATAL_FAILURE(make_report(report));
  Browser browser(1600, 1000);
  ASSERT_NO_FATAL_FAILURE(open_report(browser, report));
  EXPECT_EQ(browser.execute("return window.reportErrors;"), nlohmann::json::array());
  // Self-contained: the page loaded nothing besides itself.
  EXPECT_EQ(browser.execute("return performance.getEntriesByType('resource').map(function (e) { "
                            "return e.name; });"),
            nlohmann::json::array());
  const nlohmann::json log = browser.browser_log();
  ASSERT_TRUE(log.is_array()) << "no console log from chromedriver";
  for (const auto& entry : log) EXPECT_NE(entry.value("level", ""), "SEVERE") << entry.dump();

  // One frame per position, one shown at a time, and it plays by itself (4 s a loop: a frame
  // each 1/6 s).
  EXPECT_EQ(browser.execute(
                "return document.querySelectorAll('#mechanism svg g[id^=\"frame-\"]').length;"),
            kSteps);
  EXPECT_TRUE(browser.wait_for("return document.body.dataset.position !== '0';", 3.0))
      << "the animation does not play";

  // The slider stops it and shows position k: the crank at the k-th input, every plot's cursor
  // at k.
  for (const int k : {0, 1, 7, 13, 23}) {
    slide_to(browser, k);
    const nlohmann::json read = browser.execute(kReadFrame, {kJointRadius});
    ASSERT_EQ(read["shown"], nlohmann::json::array({k})) << "position " << k;
    ASSERT_EQ(read["joints"].size(), 3u) << "O, A, B";
    const double input = report.cycle["points"][k]["input"];
    EXPECT_NEAR(input, kDesignCrank + 15.0 * k, 1e-9);
    EXPECT_LT(angle_gap(drawn_crank(read["joints"]), wrap360(input)), 0.05)
        << "position " << k << ": crank drawn at " << drawn_crank(read["joints"]) << " deg";
    EXPECT_EQ(browser.execute("return Array.prototype.map.call(document.querySelectorAll("
                              "'svg.plot line.cursor'), function (c) { return "
                              "c.dataset.position; });"),
              nlohmann::json::array(
                  {std::to_string(k), std::to_string(k), std::to_string(k), std::to_string(k)}))
        << "drive, reaction forces, reaction moments, shaking force";
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(400));
  EXPECT_EQ(browser.execute("return document.body.dataset.position;"), "23") << "still paused";

  // Hovering the drive curve at position j shows the drive there.
  const int j = 9;
  const nlohmann::json vertex = browser.execute(R"JS(
      var d = document.querySelector('#plot-drive path.series').getAttribute('d');
      var v = d.split(/[ML]/).filter(function (s) { return s.length; })[arguments[0]];
      return v.trim().split(/\s+/).map(parseFloat);)JS",
                                                {j});
  // The vertex in the viewport (the plot's box; plots are drawn at 1 user unit per CSS px).
  const nlohmann::json box = browser.execute(
      "var b = document.getElementById('plot-drive').getBoundingClientRect(); return [b.left, "
      "b.top];");
  browser.actions(nlohmann::json::array(
      {{{"type", "pointer"},
        {"id", "mouse"},
        {"parameters", {{"pointerType", "mouse"}}},
        {"actions",
         {{{"type", "pointerMove"},
           {"duration", 0},
           {"origin", "viewport"},
           {"x", static_cast<int>(std::lround(box[0].get<double>() + vertex[0].get<double>()))},
           {"y",
            static_cast<int>(std::lround(box[1].get<double>() + vertex[1].get<double>()))}}}}}}));
  const nlohmann::json tip = browser.execute(
      "var t = document.getElementById('tooltip'); return {shown: t.style.display, position: "
      "t.dataset.position, text: t.textContent};");
  EXPECT_EQ(tip["shown"], "block");
  EXPECT_EQ(tip["position"], std::to_string(j));
  const std::string text = tip["text"];
  const auto at = text.find("drive = ");
  ASSERT_NE(at, std::string::npos) << text;
  const double shown = std::stod(text.substr(at + 8));
  const double drive = report.cycle["points"][j]["drive"];
  EXPECT_NEAR(shown, drive, 1e-4 * std::abs(drive)) << text;  // 5 significant digits
}

// ---- the screenshot -----------------------------------------------------------------------------
struct Image : test::PngImage {
  explicit Image(const std::string& png) : test::PngImage(from_bytes(png)) {}
  // 0–255 per channel (the images are opaque: premultiplied = plain).
  [[nodiscard]] std::array<int, 3> rgb(int i, int j) const {
    const uint32_t v = argb(i, j);
    return {static_cast<int>((v >> 16) & 0xff), static_cast<int>((v >> 8) & 0xff),
            static_cast<int>(v & 0xff)};
  }
};

// The fraction of pixels whose colour differs by more than `threshold` (0–255) in a channel.
double differing_fraction(const Image& a, const Image& b, int threshold) {
  long differ = 0;
  for (int j = 0; j < a.height; ++j)
    for (int i = 0; i < a.width; ++i) {
      const auto p = a.rgb(i, j), q = b.rgb(i, j);
      for (int c = 0; c < 3; ++c)
        if (std::abs(p[c] - q[c]) > threshold) {
          ++differ;
          break;
        }
    }
  return static_cast<double>(differ) / (static_cast<double>(a.width) * a.height);
}

// Cairo's drawing of the slider-crank at each of the positions' inputs, assembled there, in the
// one view fitted to all of them (as an animation's view is documented).
std::vector<std::string> reference_pngs() {
  const Model model = test::load_bundled("slider-crank");
  std::vector<VecX> q;
  int driver = -1;
  for (int k = 0; k < kSteps; ++k) {
    char input[32];
    std::snprintf(input, sizeof input, "%.12gdeg", kDesignCrank + 15.0 * k);
    const PoseResult pose = assemble_pose(model, RenderPose{"", input});
    EXPECT_EQ(pose.status, PoseStatus::ok) << pose.message;
    q.push_back(pose.q);
    driver = pose.driver;
  }
  RenderOptions options;
  options.driver = driver;
  options.view = animation_view(model, q, options);
  std::vector<std::string> pngs;
  for (const VecX& qk : q)
    pngs.push_back(draw_image(build_scene(model, qk, options), ImageFormat::png));
  release_render_caches();  // the sanitizer build checks leaks at exit
  return pngs;
}

TEST(ReportBrowser, ScreenshotOfAPositionMatchesCairosDrawingOfIt) {
  Report report;
  ASSERT_NO_FATAL_FAILURE(make_report(report));
  Browser browser(1600, 1000);
  ASSERT_NO_FATAL_FAILURE(open_report(browser, report));
  const std::vector<std::string> reference = reference_pngs();
  for (const int k : {5, 16}) {
    slide_to(browser, k);
    const Image shot(browser.screenshot(browser.element("#mechanism svg")));
    ASSERT_NE(shot.data, nullptr) << "the screenshot is no PNG";
    const Image same(reference[k]), other(reference[(k + 3) % kSteps]);
    ASSERT_EQ(shot.width, same.width);
    ASSERT_EQ(shot.height, same.height);
    // Two rasterisers (Skia, Cairo) differ by antialiasing on edges and by the text's hinting.
    const double mismatch = differing_fraction(shot, same, 64);
    const double wrong = differing_fraction(shot, other, 64);
    EXPECT_LT(mismatch, 0.005) << "position " << k;
    EXPECT_GT(wrong, std::max(0.01, 10.0 * mismatch))
        << "position " << k << " is like position " << (k + 3);
    std::printf("position %d: %.4f of the pixels differ from Cairo's, %.4f from position %d's\n", k,
                mismatch, wrong, (k + 3) % kSteps);
  }
}

// ---- the standalone animation -------------------------------------------------------------------
// `cycle --animate`: the SVG plays by itself (SMIL, no script): one frame per position, one shown
// at a time, and a different one a moment later.
TEST(AnimationBrowser, PlaysByItself) {
  test::TempDir dir("orthomech_animation_");
  const std::string svg = (dir.path / "cycle.svg").string();
  const CliResult r = run_cli({"cycle", test::bundled_file("slider-crank"), "--steps",
                               std::to_string(kSteps), "--animate", svg, "--duration", "2"});
  ASSERT_EQ(r.status, 0) << r.err;
  Browser browser(1000, 800);
  ASSERT_TRUE(browser.ok()) << browser.error;
  browser.navigate("file://" + svg);
  const std::string shown =
      "return Array.prototype.filter.call(document.querySelectorAll('g[id^=\"frame-\"]'), "
      "function (f) { return getComputedStyle(f).display !== 'none'; }).map(function (f) { "
      "return f.id; });";
  EXPECT_EQ(browser.execute("return document.querySelectorAll('g[id^=\"frame-\"]').length;"),
            kSteps);
  const nlohmann::json first = browser.execute(shown);
  ASSERT_EQ(first.size(), 1u) << first;
  EXPECT_TRUE(browser.wait_for(
      shown.substr(0, shown.size() - 1) + "[0] !== '" + first[0].get<std::string>() + "';", 2.0))
      << "the animation does not play";
  EXPECT_EQ(browser.execute(shown).size(), 1u);
}

}  // namespace
}  // namespace orthomech
