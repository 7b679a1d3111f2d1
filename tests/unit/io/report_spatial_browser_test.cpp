// `cycle --report` of a spatial mechanism in a real browser (issue 13 item 1), as the planar
// report is checked in report_browser_test.cpp: headless Chromium over WebDriver
// (support/webdriver.hpp; scripts/setup installs chromium and chromium-driver).
//
// The RSSR's report (24 positions, drawn in the top view): the page runs without script errors,
// has one frame per position, plays by itself, and when the slider is moved to position k shows
// exactly frame k, whose crank A0 → A (the first two joint markers, read from the DOM) points at
// the k-th input of `cycle --json`; the reaction plots include the moments |M| of the spatial
// joints (a spatial revolute carries moments, a planar pin does not).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>

#include "orthomech/io/render.hpp"
#include "support/cli_runner.hpp"
#include "support/webdriver.hpp"

namespace orthomech {
namespace {

using test::Browser;
using test::CliResult;
using test::run_cli;

constexpr int kSteps = 24;

// The shown frames and, in them, the centres of the joint markers (paths filled with kJointFill,
// rgb(100%,85%,30%); Cairo starts a circle of radius r about c at c + (r, 0)).
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

TEST(SpatialReportBrowser, OpensPlaysAndTheSliderPutsTheCrankAtEachInput) {
  const test::TempDir dir("orthomech_spatial_report_");
  const std::string html = (dir.path / "rssr.html").string();
  const CliResult r =
      run_cli({"cycle", test::bundled_file("rssr"), "--steps", std::to_string(kSteps), "--report",
               html, "--view", "top", "--trace", "coupler.B", "--json", "--positions"});
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json cycle = nlohmann::json::parse(r.out);
  ASSERT_EQ(cycle["positions"], kSteps);

  Browser browser(1600, 1000);
  ASSERT_TRUE(browser.ok()) << browser.error;
  browser.navigate("file://" + html);
  ASSERT_TRUE(browser.wait_for("return document.body.dataset.ready === 'yes';", 10.0))
      << "the page's script did not finish: " << browser.execute("return window.reportErrors;");
  EXPECT_EQ(browser.execute("return window.reportErrors;"), nlohmann::json::array());
  const nlohmann::json log = browser.browser_log();
  ASSERT_TRUE(log.is_array()) << "no console log from chromedriver";
  for (const auto& entry : log) EXPECT_NE(entry.value("level", ""), "SEVERE") << entry.dump();
  EXPECT_EQ(browser.execute(
                "return document.querySelectorAll('#mechanism svg g[id^=\"frame-\"]').length;"),
            kSteps);
  EXPECT_TRUE(browser.wait_for("return document.body.dataset.position !== '0';", 3.0))
      << "the animation does not play";

  // The moments of the spatial joints are plotted.
  const nlohmann::json moments = browser.execute(
      "return Array.prototype.map.call(document.querySelectorAll('#plot-moments path.series'), "
      "function (p) { return p.dataset.series; });");
  for (const char* m : {"A0.|M|", "B.|M|", "B0.|M|"})
    EXPECT_NE(std::find(moments.begin(), moments.end(), m), moments.end()) << m << " " << moments;

  for (const int k : {0, 5, 17}) {
    browser.execute("document.getElementById('position').focus();");
    nlohmann::json keys = nlohmann::json::array();
    auto press = [&](const char* key) {
      keys.push_back({{"type", "keyDown"}, {"value", key}});
      keys.push_back({{"type", "keyUp"}, {"value", key}});
    };
    press("\xEE\x80\x91");                              // Home
    for (int i = 0; i < k; ++i) press("\xEE\x80\x94");  // ArrowRight
    browser.actions(
        nlohmann::json::array({{{"type", "key"}, {"id", "keyboard"}, {"actions", keys}}}));
    const nlohmann::json read = browser.execute(kReadFrame, {kJointRadius});
    ASSERT_EQ(read["shown"], nlohmann::json::array({k})) << "position " << k;
    ASSERT_EQ(read["joints"].size(), 4u) << "A0, A, B, B0";
    // Top view: the crank's drawn angle (image y down) is the input θ.
    const double dx = read["joints"][1][0].get<double>() - read["joints"][0][0].get<double>();
    const double dy = read["joints"][1][1].get<double>() - read["joints"][0][1].get<double>();
    const double drawn = std::atan2(-dy, dx) * 180.0 / std::numbers::pi;
    const double input = cycle["points"][k]["input"];
    const double gap = std::fmod(std::abs(drawn - input) + 720.0, 360.0);
    EXPECT_LT(std::min(gap, 360.0 - gap), 0.1) << "position " << k << ": drawn " << drawn;
  }
}

}  // namespace
}  // namespace orthomech
