// `sweep --report` in a real browser (issue 51 item 5), as the cycle report is checked in
// report_browser_test.cpp: headless Chromium over WebDriver (support/webdriver.hpp; scripts/setup
// installs chromium and chromium-driver). Oracles are the study's own files (variants.csv,
// summary.json) and `cycle` run on a best variant through the command line:
//   - grid: every scatter panel has one point per variant, laid out by Chromium in the order of
//     the variant's parameter (x) and metric (y) values read from variants.csv; the best table is
//     summary.json's; a real mouse click on a best variant shows its cycle, and that cycle's drive
//     spans `cycle FILE --set …`'s drive minimum and maximum with one point per position;
//   - Monte Carlo: each histogram's bins count the CSV's values between their edges; each
//     quantile line is summary.json's quantile, drawn inside the bar of the bin that holds it;
//     each sensitivity bar is summary.json's coefficient times the parameter's standard deviation
//     over the CSV.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "support/cli_runner.hpp"
#include "support/webdriver.hpp"

namespace orthomech {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using test::Browser;
using test::run_cli;

// variants.csv as columns by name (empty cells NaN; status and message kept as NaN).
std::map<std::string, std::vector<double>> read_columns(const fs::path& csv) {
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);
  std::vector<std::string> names;
  for (std::stringstream h(line); std::getline(h, line, ',');) names.push_back(line);
  std::map<std::string, std::vector<double>> columns;
  for (std::string row; std::getline(in, row);) {
    std::stringstream cells(row);
    std::string cell;
    for (const std::string& name : names) {
      if (!std::getline(cells, cell, ',')) cell.clear();
      double v = std::nan("");
      try {
        size_t used = 0;
        v = std::stod(cell, &used);
        if (used != cell.size()) v = std::nan("");
      } catch (const std::exception&) {
      }
      columns[name].push_back(v);
    }
  }
  return columns;
}

void open_page(Browser& browser, const std::string& html) {
  ASSERT_TRUE(browser.ok()) << browser.error;
  browser.navigate("file://" + html);
  ASSERT_TRUE(browser.wait_for("return document.body.dataset.ready === 'yes';", 10.0))
      << "the page's script did not finish: " << browser.execute("return window.reportErrors;");
  EXPECT_EQ(browser.execute("return window.reportErrors;"), json::array());
  const json log = browser.browser_log();
  ASSERT_TRUE(log.is_array()) << "no console log from chromedriver";
  for (const auto& entry : log) EXPECT_NE(entry.value("level", ""), "SEVERE") << entry.dump();
}

// Per scatter panel: its parameter, metric and the rendered centres of its points by variant.
constexpr const char* kReadPanels = R"JS(
  var out = [];
  document.querySelectorAll('#scatter svg.panel').forEach(function (svg) {
    var points = [];
    svg.querySelectorAll('circle.point').forEach(function (c) {
      var r = c.getBoundingClientRect();
      points.push({variant: Number(c.dataset.variant), x: r.left + r.width / 2,
                   y: r.top + r.height / 2, best: c.classList.contains('best')});
    });
    out.push({parameter: svg.dataset.parameter, metric: svg.dataset.metric, points: points});
  });
  return out;
)JS";

TEST(StudyReportBrowser, GridScatterBestVariantsAndTheirCycles) {
  const test::TempDir dir("orthomech_study_report_");
  const std::string study = std::string(ORTHOMECH_SOURCE_DIR) + "/examples/grid-study.yaml";
  const std::string html = (dir.path / "report.html").string();
  const std::string out = (dir.path / "grid").string();
  const auto r = run_cli({"sweep", test::bundled_file("crank-rocker"), "--study", study, "--out",
                          out, "--report", html, "--figures", (dir.path / "figures").string()});
  ASSERT_EQ(r.status, 0) << r.err;
  const auto csv = read_columns(fs::path(out) / "variants.csv");
  const json summary = json::parse(test::read_text(fs::path(out) / "summary.json"));
  const size_t variants = csv.at("variant").size();
  ASSERT_EQ(variants, 15u);
  EXPECT_TRUE(fs::exists(dir.path / "figures" / "scatter.svg"));
  EXPECT_TRUE(fs::exists(dir.path / "figures" / "histogram-drive.peak.svg"));

  Browser browser(1400, 1000);
  open_page(browser, html);
  const json panels = browser.execute(kReadPanels);
  ASSERT_EQ(panels.size(), 2u * 8u);  // crank, coupler × the 8 metrics shown by default
  for (const auto& panel : panels) {
    const std::vector<double>& x = csv.at(panel["parameter"].get<std::string>());
    const std::vector<double>& y = csv.at(panel["metric"].get<std::string>());
    const json& points = panel["points"];
    ASSERT_EQ(points.size(), variants) << panel["metric"];
    // Chromium's layout keeps the data's order: a larger value is further right (x) or up (y),
    // an equal one at the same place (to rounding of the drawn centres, 0.01 px).
    for (const auto& a : points)
      for (const auto& b : points) {
        const auto i = static_cast<size_t>(a["variant"].get<long>());
        const auto j = static_cast<size_t>(b["variant"].get<long>());
        const double dx = a["x"].get<double>() - b["x"].get<double>();
        const double dy = a["y"].get<double>() - b["y"].get<double>();
        if (x[i] > x[j]) {
          EXPECT_GT(dx, 0.0) << panel["parameter"] << " " << i << " " << j;
        }
        if (x[i] == x[j]) {
          EXPECT_NEAR(dx, 0.0, 0.01);
        }
        if (y[i] > y[j]) {
          EXPECT_LT(dy, 0.0) << panel["metric"] << " " << i << " " << j;
        }
      }
  }
  // The best table is the summary's, best first.
  const json rows = browser.execute(
      "return Array.from(document.querySelectorAll('#best tr.variant')).map("
      "function (t) { return Number(t.dataset.variant); });");
  const json& best = summary["best"]["variants"];
  ASSERT_EQ(rows.size(), best.size());
  for (size_t k = 0; k < best.size(); ++k) EXPECT_EQ(rows[k], best[k]["variant"]);

  // A real click on the second best row shows its cycle alone.
  const long chosen = best[1]["variant"];
  const json row =
      browser.element("#best tr.variant[data-variant=\"" + std::to_string(chosen) + "\"] td");
  browser.actions(json::array(
      {{{"type", "pointer"},
        {"id", "mouse"},
        {"parameters", {{"pointerType", "mouse"}}},
        {"actions",
         {{{"type", "pointerMove"}, {"duration", 0}, {"origin", row}, {"x", 0}, {"y", 0}},
          {{"type", "pointerDown"}, {"button", 0}},
          {{"type", "pointerUp"}, {"button", 0}}}}}}));
  const json shown = browser.execute(
      "return Array.from(document.querySelectorAll('div.cycle')).filter(function (d) {"
      " return getComputedStyle(d).display !== 'none'; }).map(function (d) {"
      " var p = d.querySelector('polyline.series[data-name=\"drive\"]');"
      " return {variant: Number(d.dataset.variant), min: Number(p.dataset.min),"
      " max: Number(p.dataset.max), points: p.points.numberOfItems}; });");
  ASSERT_EQ(shown.size(), 1u) << shown.dump();
  EXPECT_EQ(shown[0]["variant"].get<long>(), chosen);
  // `cycle` on that variant through the command line.
  const auto cyc = run_cli({"cycle", test::bundled_file("crank-rocker"), "--set",
                            "bodies.crank.points.A.0=" + best[1]["crank"].dump(), "--set",
                            "bodies.coupler.points.B.0=" + best[1]["coupler"].dump(), "--json"});
  ASSERT_EQ(cyc.status, 0) << cyc.err;
  const json c = json::parse(cyc.out);
  EXPECT_EQ(shown[0]["points"].get<long>(), c["positions"].get<long>());
  const double lo = c["peaks"]["drive"]["min"]["value"], hi = c["peaks"]["drive"]["max"]["value"];
  EXPECT_NEAR(shown[0]["min"].get<double>(), lo, 1e-9 * std::abs(lo));
  EXPECT_NEAR(shown[0]["max"].get<double>(), hi, 1e-9 * std::abs(hi));
}

double sample_sd(const std::vector<double>& v) {
  double mean = 0;
  for (const double x : v) mean += x;
  mean /= static_cast<double>(v.size());
  double ss = 0;
  for (const double x : v) ss += (x - mean) * (x - mean);
  return std::sqrt(ss / static_cast<double>(v.size() - 1));
}

TEST(StudyReportBrowser, MonteCarloHistogramsQuantilesAndSensitivities) {
  const test::TempDir dir("orthomech_study_report_");
  const std::string study = (dir.path / "mc.yaml").string();
  std::ofstream(study) << "study: monte-carlo\nsamples: 60\nseed: 11\nsteps: 72\nparameters:\n"
                          "  - {name: crank, path: bodies.crank.points.A.0, normal: {sigma: 0.2}}\n"
                          "  - {name: rocker, path: bodies.rocker.points.B.0, uniform: "
                          "{tolerance: 0.3}}\n";
  const std::string html = (dir.path / "report.html").string();
  const std::string out = (dir.path / "mc").string();
  const auto r =
      run_cli({"sweep", test::bundled_file("crank-rocker"), "--study", study, "--out", out,
               "--report", html, "--report-metrics", "drive.peak,rocker_angle.range"});
  ASSERT_EQ(r.status, 0) << r.err;
  const auto csv = read_columns(fs::path(out) / "variants.csv");
  const json summary = json::parse(test::read_text(fs::path(out) / "summary.json"));

  Browser browser(1400, 1000);
  open_page(browser, html);
  const json page = browser.execute(R"JS(
    var out = {};
    document.querySelectorAll('svg.histogram').forEach(function (svg) {
      var bins = [], quantiles = [];
      svg.querySelectorAll('rect.bin').forEach(function (b) {
        var r = b.getBoundingClientRect();
        bins.push({count: Number(b.dataset.count), low: Number(b.dataset.low),
                   high: Number(b.dataset.high), left: r.left, right: r.right});
      });
      svg.querySelectorAll('line.quantile').forEach(function (l) {
        var r = l.getBoundingClientRect();
        quantiles.push({name: l.dataset.quantile, value: Number(l.dataset.value),
                        x: r.left + r.width / 2});
      });
      out[svg.dataset.metric] = {bins: bins, quantiles: quantiles, bars: {}};
    });
    document.querySelectorAll('svg.sensitivity').forEach(function (svg) {
      svg.querySelectorAll('rect.bar').forEach(function (b) {
        out[svg.dataset.metric].bars[b.dataset.parameter] = Number(b.dataset.effect);
      });
    });
    return out;
  )JS");
  ASSERT_EQ(page.size(), 2u) << page.dump();
  for (const auto& m : summary["metrics"]) {
    const std::string name = m["metric"];
    if (!page.contains(name)) continue;
    const json& h = page[name];
    const std::vector<double>& values = csv.at(name);
    long total = 0;
    for (size_t b = 0; b < h["bins"].size(); ++b) {
      const json& bin = h["bins"][b];
      const bool last = b + 1 == h["bins"].size();
      long here = 0;
      for (const double v : values)
        if (v >= bin["low"].get<double>() && (v < bin["high"].get<double>() || last)) ++here;
      EXPECT_EQ(bin["count"].get<long>(), here) << name << " bin " << b;
      total += here;
    }
    EXPECT_EQ(total, m["n"].get<long>()) << name;
    ASSERT_EQ(h["quantiles"].size(), 3u) << name;
    for (const auto& q : h["quantiles"]) {
      const double v = m[q["name"].get<std::string>()];
      EXPECT_NEAR(q["value"].get<double>(), v, 1e-12 * std::abs(v)) << name << " " << q["name"];
      for (const auto& bin : h["bins"])
        if (v > bin["low"].get<double>() && v < bin["high"].get<double>()) {
          EXPECT_GE(q["x"].get<double>(), bin["left"].get<double>() - 0.01) << name;
          EXPECT_LE(q["x"].get<double>(), bin["right"].get<double>() + 0.01) << name;
        }
    }
    for (const std::string parameter : {"crank", "rocker"}) {
      const double effect =
          m["sensitivity"][parameter]["coefficient"].get<double>() * sample_sd(csv.at(parameter));
      EXPECT_NEAR(h["bars"][parameter].get<double>(), effect, 1e-9 * std::abs(effect))
          << name << " / " << parameter;
    }
  }
}

// An unknown --report-metrics name is refused before any variant is computed.
TEST(StudyReportBrowser, AnUnknownReportMetricIsExit2) {
  const test::TempDir dir("orthomech_study_report_");
  const std::string study = std::string(ORTHOMECH_SOURCE_DIR) + "/examples/grid-study.yaml";
  const auto r = run_cli({"sweep", test::bundled_file("crank-rocker"), "--study", study, "--out",
                          (dir.path / "g").string(), "--report", (dir.path / "r.html").string(),
                          "--report-metrics", "drive.peek"});
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("unknown metric 'drive.peek'"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir.path / "g" / "study.sqlite"));
}

}  // namespace
}  // namespace orthomech
