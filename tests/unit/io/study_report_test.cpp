// The study report's pieces (io/study_report.hpp) without a browser (study_report_browser_test.cpp
// opens the page in Chromium): the histogram against counts made here with the bins' edges;
// Sturges' bin count; the sensitivity bar of an exactly linear metric y = 3 x₁ − 2 x₂ (its
// least-squares coefficients are 3 and −2, so the effect per standard deviation is 3 σ₁ and −2 σ₂,
// σ computed here); one point per variant with both values in each scatter panel; the shape errors;
// and the figures' files.
#include "orthomech/io/study_report.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <regex>
#include <stdexcept>
#include <string>
#include <vector>

namespace orthomech {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

long count(const std::string& text, const std::string& what) {
  long n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

double sample_sd(const std::vector<double>& v) {
  double mean = 0;
  for (const double x : v) mean += x;
  mean /= static_cast<double>(v.size());
  double ss = 0;
  for (const double x : v) ss += (x - mean) * (x - mean);
  return std::sqrt(ss / static_cast<double>(v.size() - 1));
}

TEST(StudyReport, HistogramCountsEveryValueInTheBinOfItsEdges) {
  std::vector<double> v;
  for (int k = 0; k < 97; ++k) v.push_back(std::sin(0.37 * k) * 5 + 0.01 * k);
  v.push_back(kNaN);  // left out
  const std::vector<HistogramBin> bins = histogram(v, 8);
  ASSERT_EQ(bins.size(), 8u);
  long total = 0;
  for (size_t b = 0; b < bins.size(); ++b) {
    long here = 0;
    for (const double x : v)
      if (std::isfinite(x) && x >= bins[b].low && (x < bins[b].high || b + 1 == bins.size()))
        ++here;
    EXPECT_EQ(bins[b].count, here) << "bin " << b;
    total += bins[b].count;
    if (b > 0) {
      EXPECT_DOUBLE_EQ(bins[b].low, bins[b - 1].high);
    }
  }
  EXPECT_EQ(total, 97);
  // Equal values: one bin with all of them; no value: no bin.
  const std::vector<HistogramBin> one = histogram({2.5, 2.5, 2.5}, 8);
  ASSERT_EQ(one.size(), 1u);
  EXPECT_EQ(one[0].count, 3);
  EXPECT_TRUE(histogram({kNaN}, 8).empty());
}

TEST(StudyReport, SturgesBins) {
  EXPECT_EQ(histogram_bins(0), 1);
  EXPECT_EQ(histogram_bins(1), 1);
  EXPECT_EQ(histogram_bins(2), 2);    // ⌈log₂ 2⌉ + 1
  EXPECT_EQ(histogram_bins(200), 9);  // ⌈7.64⌉ + 1
  EXPECT_EQ(histogram_bins(1L << 50), 40);
}

StudyReport linear_study() {
  StudyReport r;
  r.title = "t";
  r.kind = "monte-carlo";
  StudyReportColumn x1{"a", {}}, x2{"b", {}}, y{"y", {}};
  for (int k = 0; k < 30; ++k) {
    r.variants.push_back(k);
    x1.values.push_back(std::cos(1.3 * k));
    x2.values.push_back(0.5 * std::sin(0.7 * k));
    y.values.push_back(3 * x1.values.back() - 2 * x2.values.back());
  }
  y.values[4] = kNaN;  // a variant without the metric: no point in its panels
  r.parameters = {x1, x2};
  r.metrics = {y};
  StudyReportStatistics st;
  st.sensitivity = {StudyReportStatistics::Sensitivity{3, 2.9, 3.1},
                    StudyReportStatistics::Sensitivity{-2, -2.1, -1.9}};
  r.statistics = {st};
  return r;
}

TEST(StudyReport, SensitivityBarIsTheEffectOfOneStandardDeviation) {
  const StudyReport r = linear_study();
  const std::string html = study_report_html(r);
  const std::regex bar(R"re(class="bar" data-parameter="(\w+)" data-effect="([^"]+)")re");
  int bars = 0;
  for (std::sregex_iterator it(html.begin(), html.end(), bar), end; it != end; ++it) {
    const std::string p = (*it)[1];
    const double effect = std::stod((*it)[2]);
    const double expected =
        p == "a" ? 3 * sample_sd(r.parameters[0].values) : -2 * sample_sd(r.parameters[1].values);
    EXPECT_NEAR(effect, expected, 1e-14) << p;
    ++bars;
  }
  EXPECT_EQ(bars, 2);
}

TEST(StudyReport, EachPanelHasAPointPerVariantWithBothValues) {
  const StudyReport r = linear_study();
  const std::string html = study_report_html(r);
  EXPECT_EQ(count(html, "<svg xmlns=\"http://www.w3.org/2000/svg\" class=\"panel\""), 2);
  EXPECT_EQ(count(html, "<circle class=\"point"), 2 * 29);  // 30 variants, one without y
  EXPECT_EQ(count(html, "data-variant=\"4\""), 0);
  EXPECT_EQ(count(html, "<svg xmlns=\"http://www.w3.org/2000/svg\" class=\"histogram\""), 1);
  // No best variants (a Monte Carlo study): no table, no cycle.
  EXPECT_EQ(count(html, "id=\"best\""), 0);
}

TEST(StudyReport, ColumnsOfAnotherLengthAreRefused) {
  StudyReport r = linear_study();
  r.metrics[0].values.pop_back();
  EXPECT_THROW((void)study_report_html(r), std::invalid_argument);
  r = linear_study();
  r.statistics.clear();
  EXPECT_NO_THROW((void)study_report_html(r));
  r.statistics.resize(2);
  EXPECT_THROW((void)study_report_figures(r), std::invalid_argument);
}

TEST(StudyReport, FiguresAreStandaloneSvgFilesWithSafeNames) {
  StudyReport r = linear_study();
  r.metrics[0].name = "A.|F|.peak";
  const std::vector<StudyFigure> figures = study_report_figures(r);
  ASSERT_EQ(figures.size(), 3u);
  EXPECT_EQ(figures[0].file, "scatter.svg");
  EXPECT_EQ(figures[1].file, "histogram-A._F_.peak.svg");
  EXPECT_EQ(figures[2].file, "sensitivity-A._F_.peak.svg");
  for (const StudyFigure& f : figures) {
    EXPECT_EQ(f.svg.rfind("<?xml", 0), 0u) << f.file;
    EXPECT_EQ(count(f.svg, "<svg "), f.file == "scatter.svg" ? 3 : 1) << f.file;
    EXPECT_NE(f.svg.find("</svg>"), std::string::npos) << f.file;
  }
  // The scatter document holds each panel once.
  EXPECT_EQ(count(figures[0].svg, "<circle class=\"point"), 2 * 29);
}

}  // namespace
}  // namespace orthomech
