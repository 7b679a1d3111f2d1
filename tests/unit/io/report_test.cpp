// `cycle --report FILE.html` (issue 14; io/report.hpp) without a browser: the page is one
// self-contained file (nothing it would fetch: no src, no link, no URL but the SVG namespaces),
// with one animation frame per position and the plotted drive and reaction magnitudes equal to
// `cycle --json --positions` of the same sweep, in the same units. The page running in a browser:
// tests/unit/io/report_browser_test.cpp.
#include "orthomech/io/report.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "support/cli_runner.hpp"

namespace orthomech {
namespace {

using test::CliResult;
using test::run_cli;

size_t count(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

TEST(CycleReport, OneSelfContainedPageWithThePlottedValuesOfTheCycle) {
  test::TempDir dir("orthomech_report_");
  const std::string html = (dir.path / "report.html").string();
  constexpr int kSteps = 12;
  const CliResult r = run_cli({"cycle", test::bundled_file("slider-crank"), "--steps",
                               std::to_string(kSteps), "--report", html, "--json", "--positions"});
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json cycle = nlohmann::json::parse(r.out);
  const std::string page = test::read_text(html);
  ASSERT_FALSE(page.empty());
  // Nothing to fetch.
  EXPECT_EQ(count(page, " src="), 0u);
  EXPECT_EQ(count(page, "<link"), 0u);
  EXPECT_EQ(count(page, "@import"), 0u);
  EXPECT_EQ(count(page, "http"), count(page, "http://www.w3.org/2000/svg") +
                                     count(page, "http://www.w3.org/1999/xlink"));
  EXPECT_EQ(count(page, "<g id=\"frame-"), static_cast<size_t>(kSteps));
  // The summary is the terminal's, as is.
  const CliResult text =
      run_cli({"cycle", test::bundled_file("slider-crank"), "--steps", std::to_string(kSteps)});
  ASSERT_EQ(text.status, 0);
  const std::string pre = "<pre id=\"summary\">";
  const size_t from = page.find(pre), to = page.find("</pre>", from);
  ASSERT_NE(from, std::string::npos);
  std::string summary = page.substr(from + pre.size(), to - from - pre.size());
  for (const auto& [entity, c] : {std::pair<std::string, std::string>{"&lt;", "<"},
                                  {"&gt;", ">"},
                                  {"&quot;", "\""},
                                  {"&amp;", "&"}})
    for (size_t at = summary.find(entity); at != std::string::npos;
         at = summary.find(entity, at + 1))
      summary.replace(at, entity.size(), c);
  EXPECT_EQ(summary, text.out);
  // The plotted data.
  const std::string open = "<script type=\"application/json\" id=\"report-data\">";
  const size_t begin = page.find(open);
  ASSERT_NE(begin, std::string::npos);
  const size_t end = page.find("</script>", begin);
  const nlohmann::json data =
      nlohmann::json::parse(page.substr(begin + open.size(), end - begin - open.size()));
  ASSERT_EQ(data["input"].size(), static_cast<size_t>(kSteps));
  EXPECT_EQ(data["input_label"], "input [deg]");
  const nlohmann::json& points = cycle["points"];
  ASSERT_EQ(data["plots"].size(), 4u) << "drive, reaction forces, the slide's moment, shaking";
  EXPECT_EQ(data["plots"][2]["series"][0]["name"], "slide.|M|");
  EXPECT_EQ(data["plots"][2]["unit"], "N*mm");
  EXPECT_EQ(data["plots"][0]["unit"], cycle["driver"]["drive_unit"]);
  for (int k = 0; k < kSteps; ++k) {
    const double input = points[k]["input"], drive = points[k]["drive"];
    EXPECT_NEAR(data["input"][k].get<double>(), input, 1e-9);
    EXPECT_NEAR(data["plots"][0]["series"][0]["values"][k].get<double>(), drive,
                1e-12 * (1.0 + std::abs(drive)));
  }
  // A reaction magnitude: |F| of joint A from its components.
  const nlohmann::json& forces = data["plots"][1];
  EXPECT_EQ(forces["unit"], "N");
  bool found = false;
  for (const nlohmann::json& s : forces["series"]) {
    if (s["name"] != "A.|F|") continue;
    found = true;
    for (int k = 0; k < kSteps; ++k) {
      const double fx = points[k]["reactions"]["A.Fx"], fy = points[k]["reactions"]["A.Fy"];
      EXPECT_NEAR(s["values"][k].get<double>(), std::hypot(fx, fy), 1e-9 * std::hypot(fx, fy));
    }
  }
  EXPECT_TRUE(found);
  // The shaking force: x, y and |F_s|, whose largest value is the JSON peak.
  const nlohmann::json& shaking = data["plots"][3];
  EXPECT_EQ(shaking["unit"], "N");
  ASSERT_EQ(shaking["series"].size(), 3u);
  EXPECT_EQ(shaking["series"][2]["name"], "|F_s|");
  double peak = 0.0;
  for (int k = 0; k < kSteps; ++k) {
    const double x = shaking["series"][0]["values"][k], y = shaking["series"][1]["values"][k];
    const double m = shaking["series"][2]["values"][k];
    EXPECT_NEAR(m, std::hypot(x, y), 1e-12 * m);
    peak = std::max(peak, m);
  }
  const double json_peak = cycle["peaks"]["shaking force"]["peak"];
  EXPECT_NEAR(peak, json_peak, 1e-9 * json_peak);
}

TEST(CycleReport, UnwritableFileIsBadInputWithNothingOnStdout) {
  const CliResult r = run_cli({"cycle", test::bundled_file("slider-crank"), "--steps", "6",
                               "--report", "/nonexistent/dir/report.html"});
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--report"), std::string::npos) << r.err;
  EXPECT_TRUE(r.out.empty());
}

TEST(CycleReport, PicturePositionsAreEvenlySpacedWithBothEnds) {
  // All of them up to the limit; beyond it kMaxPictureFrames, strictly increasing, the first and
  // the last position included, and no gap larger than ceil((n − 1) / (m − 1)) positions.
  EXPECT_EQ(picture_positions(5), (std::vector<std::size_t>{0, 1, 2, 3, 4}));
  EXPECT_EQ(picture_positions(kMaxPictureFrames).size(), kMaxPictureFrames);
  for (const std::size_t n : {std::size_t{1001}, std::size_t{3600}, std::size_t{100001}}) {
    const auto k = picture_positions(n);
    ASSERT_EQ(k.size(), kMaxPictureFrames);
    EXPECT_EQ(k.front(), 0u);
    EXPECT_EQ(k.back(), n - 1);
    const std::size_t gap = (n - 1 + kMaxPictureFrames - 2) / (kMaxPictureFrames - 1);
    for (std::size_t j = 1; j < k.size(); ++j) {
      EXPECT_GT(k[j], k[j - 1]);
      EXPECT_LE(k[j] - k[j - 1], gap);
    }
  }
}

}  // namespace
}  // namespace orthomech
