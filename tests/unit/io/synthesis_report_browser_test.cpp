// `synthesize --report` in a real browser (issue 50), as the cycle report is checked in
// report_browser_test.cpp: headless Chromium over WebDriver (support/webdriver.hpp; scripts/setup
// installs chromium and chromium-driver).
//
// The five-pose task of the README's tour: the page opens without console errors; it has one
// drawing per candidate, in the order of `synthesize --json`, each captioned with its name; the
// summary is the terminal's table; and in every drawing Chromium lays each target circle out at
// the pixel that the drawing's data-view gives for the task's pose (read here from the task file
// by the library's reader), to 0.01 px of the rendered page.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>

#include "orthomech/synthesis/task.hpp"
#include "support/cli_runner.hpp"
#include "support/webdriver.hpp"

namespace orthomech {
namespace {

using test::Browser;
using test::run_cli;

// Per drawing: its name, data-view, and the rendered centres of its target circles relative to
// the drawing's viewport (its box inside the CSS border; the SVG's width equals its viewBox's,
// so a user unit is a CSS px).
constexpr const char* kReadDrawings = R"JS(
  var out = [];
  document.querySelectorAll('svg.candidate').forEach(function (svg) {
    var box = svg.getBoundingClientRect();
    var targets = [];
    svg.querySelectorAll('circle.target').forEach(function (c) {
      var r = c.getBoundingClientRect();
      targets.push([r.left + r.width / 2 - box.left - svg.clientLeft,
                    r.top + r.height / 2 - box.top - svg.clientTop]);
    });
    var caption = svg.parentNode.querySelector('figcaption');
    out.push({name: svg.dataset.name, view: svg.dataset.view, targets: targets,
              caption: caption ? caption.textContent : ''});
  });
  return {drawings: out, summary: document.getElementById('summary').textContent};
)JS";

TEST(SynthesisReportBrowser, TargetsAreLaidOutWhereTheDrawingsViewPutsThem) {
  const test::TempDir dir("orthomech_synthesis_report_");
  const std::string task_file =
      std::string(ORTHOMECH_SOURCE_DIR) + "/examples/synthesis-motion.yaml";
  const std::string html = (dir.path / "report.html").string();
  const auto r = run_cli({"synthesize", task_file, "--report", html, "--json"});
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json result = nlohmann::json::parse(r.out);
  const auto text = run_cli({"synthesize", task_file});
  ASSERT_EQ(text.status, 0) << text.err;
  const synthesis::SynthesisTask task = synthesis::load_synthesis_task(task_file);

  Browser browser(1400, 1000);
  ASSERT_TRUE(browser.ok()) << browser.error;
  browser.navigate("file://" + html);
  ASSERT_TRUE(browser.wait_for("return document.readyState === 'complete';", 10.0));
  const nlohmann::json log = browser.browser_log();
  ASSERT_TRUE(log.is_array()) << "no console log from chromedriver";
  for (const auto& entry : log) EXPECT_NE(entry.value("level", ""), "SEVERE") << entry.dump();

  const nlohmann::json page = browser.execute(kReadDrawings);
  EXPECT_EQ(page["summary"].get<std::string>(), text.out);
  const nlohmann::json& drawings = page["drawings"];
  ASSERT_EQ(drawings.size(), result["accepted"].size() + result["rejected"].size());
  size_t k = 0;
  for (const char* list : {"accepted", "rejected"})
    for (const auto& c : result[list]) {
      const nlohmann::json& d = drawings[k++];
      EXPECT_EQ(d["name"], c["name"]);
      EXPECT_NE(d["caption"].get<std::string>().find(c["name"].get<std::string>()),
                std::string::npos);
      double s = 0, x0 = 0, y0 = 0;
      std::sscanf(d["view"].get<std::string>().c_str(), "%lf %lf %lf", &s, &x0, &y0);
      ASSERT_EQ(d["targets"].size(), task.positions.size()) << d["name"];
      for (size_t j = 0; j < task.positions.size(); ++j) {
        const double x = task.positions[j].x() / task.length_si;
        const double y = task.positions[j].y() / task.length_si;
        EXPECT_NEAR(d["targets"][j][0].get<double>(), x0 + s * x, 0.01) << d["name"] << " " << j;
        EXPECT_NEAR(d["targets"][j][1].get<double>(), y0 - s * y, 0.01) << d["name"] << " " << j;
      }
    }
}

}  // namespace
}  // namespace orthomech
