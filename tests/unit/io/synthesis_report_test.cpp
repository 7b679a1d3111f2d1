// The synthesis report page (io/synthesis_output.hpp, synthesis_report_html): read through its
// contract (svg.candidate with data-view "s x0 y0", circle.target, polyline.curve), every target
// is drawn at its place and the drawn curve of the candidate passes through it; the function
// task's targets are the follower pin at the asked output angles, by the closed form here.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "orthomech/io/synthesis_output.hpp"

namespace orthomech {
namespace {

using synthesis::Vec2;

struct Drawing {
  std::string name;
  double scale = 0, x0 = 0, y0 = 0;
  std::vector<Vec2> targets;  // pixels
  std::vector<Vec2> curve;    // pixels, every piece
};

std::vector<Drawing> drawings(const std::string& html) {
  std::vector<Drawing> out;
  const std::regex svg(R"re(<svg class="candidate" data-name="([^"]*)" data-view="([^"]*)")re");
  const std::regex circle(R"re(<circle class="target" cx="([^"]*)" cy="([^"]*)")re");
  const std::regex poly(R"re(<polyline class="curve" points="([^"]*)")re");
  std::smatch m;
  std::string rest = html;
  while (std::regex_search(rest, m, svg)) {
    Drawing d;
    d.name = m[1];
    std::istringstream(m[2].str()) >> d.scale >> d.x0 >> d.y0;
    const std::string tail = m.suffix();
    const std::string body = tail.substr(0, tail.find("</svg>"));
    for (auto it = std::sregex_iterator(body.begin(), body.end(), circle);
         it != std::sregex_iterator(); ++it)
      d.targets.emplace_back(std::stod((*it)[1]), std::stod((*it)[2]));
    for (auto it = std::sregex_iterator(body.begin(), body.end(), poly);
         it != std::sregex_iterator(); ++it) {
      std::istringstream pts((*it)[1].str());
      double x = 0, y = 0;
      char comma = 0;
      while (pts >> x >> comma >> y) d.curve.emplace_back(x, y);
    }
    out.push_back(d);
    rest = tail;
  }
  return out;
}

// The pixel of a model point (task length units) by the page's stated view.
Vec2 pixel(const Drawing& d, const Vec2& p) {
  return {d.x0 + d.scale * p.x(), d.y0 - d.scale * p.y()};
}

double nearest(const std::vector<Vec2>& curve, const Vec2& p) {
  double best = 1e300;
  for (const Vec2& c : curve) best = std::min(best, (c - p).norm());
  return best;
}

TEST(SynthesisReport, TargetsAtTheirPlaceAndTheCurveThroughThem) {
  const synthesis::SynthesisTask task = synthesis::load_synthesis_task(
      std::string(ORTHOMECH_SOURCE_DIR) + "/examples/synthesis-motion.yaml");
  const synthesis::SynthesisResult r = synthesis::run_synthesis(task);
  ASSERT_FALSE(r.accepted.empty());
  const std::vector<Drawing> d = drawings(synthesis_report_html(task, r));
  ASSERT_EQ(d.size(), r.accepted.size() + r.rejected.size());
  EXPECT_EQ(d[0].name, r.accepted[0].name);
  ASSERT_EQ(d[0].targets.size(), task.positions.size());
  ASSERT_GT(d[0].curve.size(), 360u);
  for (size_t j = 0; j < task.positions.size(); ++j) {
    const Vec2 at = pixel(d[0], task.positions[j] / task.length_si);
    EXPECT_LT((d[0].targets[j] - at).norm(), 1e-3) << j;  // pixels are written to 1e-3
    EXPECT_LT(nearest(d[0].curve, at), 2e-3) << j;
  }
}

// Function generation: the targets are B = B0 + c (cos ψ, sin ψ) at the asked output angles
// (mechanisms/crank-rocker.yaml: B0 = (70, 0), c = 60), and the drawn path of B meets them.
TEST(SynthesisReport, FunctionTargetsAreTheFollowerPinAtTheOutputAngles) {
  const synthesis::SynthesisTask task = synthesis::parse_synthesis_task(
      "orthomech-synthesis: 1\ntask: function\nground: 70\n"
      "pairs: [[60, 71.797553609615], [150, 115.823166144399], [270, 132.362157995438]]\n",
      "fn.yaml");
  const synthesis::SynthesisResult r = synthesis::run_synthesis(task);
  ASSERT_EQ(r.accepted.size(), 1u);
  const std::vector<Drawing> d = drawings(synthesis_report_html(task, r));
  ASSERT_EQ(d.size(), 1u);
  ASSERT_EQ(d[0].targets.size(), 3u);
  constexpr double kDeg = std::numbers::pi / 180;
  const double psi[] = {71.797553609615, 115.823166144399, 132.362157995438};
  for (int j = 0; j < 3; ++j) {
    const Vec2 B = Vec2(70, 0) + 60 * Vec2(std::cos(psi[j] * kDeg), std::sin(psi[j] * kDeg));
    EXPECT_LT((d[0].targets[j] - pixel(d[0], B)).norm(), 1e-3) << j;
    EXPECT_LT(nearest(d[0].curve, pixel(d[0], B)), 2e-3) << j;
  }
}

// A spatial RSSR is drawn in the isometric view (x, y, z) ↦ ((x − y) cos 30°, z − (x + y)/2): the
// targets are the rocker's pin B = P2 + E2 Rz(ψ) b at the asked outputs, computed here for the
// example's axes (output about world x through (300, 50, 200) mm, angle from world y: E2 Rz(ψ)
// (200, 0, 0) = 200 (0, cos ψ, sin ψ)), and the drawn path of B meets them.
TEST(SynthesisReport, RssrTargetsAreTheRockerPinInTheIsometricView) {
  const synthesis::SynthesisTask task = synthesis::load_synthesis_task(
      std::string(ORTHOMECH_SOURCE_DIR) + "/examples/synthesis-rssr.yaml");
  const synthesis::SynthesisResult r = synthesis::run_synthesis(task);
  ASSERT_EQ(r.accepted.size(), 1u) << r.message;
  const std::vector<Drawing> d = drawings(synthesis_report_html(task, r));
  ASSERT_EQ(d.size(), 1u);
  ASSERT_EQ(d[0].targets.size(), task.outputs.size());
  for (size_t j = 0; j < task.outputs.size(); ++j) {
    const double psi = task.outputs[j];
    const double x = 300, y = 50 + 200 * std::cos(psi), z = 200 + 200 * std::sin(psi);
    const Vec2 iso((x - y) * std::cos(std::numbers::pi / 6), z - (x + y) / 2);
    EXPECT_LT((d[0].targets[j] - pixel(d[0], iso)).norm(), 1e-3) << j;
    EXPECT_LT(nearest(d[0].curve, pixel(d[0], iso)), 2e-3) << j;
  }
}

}  // namespace
}  // namespace orthomech
