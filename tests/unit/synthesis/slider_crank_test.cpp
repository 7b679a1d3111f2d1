// Slider-crank synthesis (src/synthesis/slider_crank.cpp, docs/synthesis.md (L40)–(L49)).
// Oracles: the closed-form slider position of four_bar.cpp (calc_position, (L8)), which never
// uses the linear form (L41): pairs and coupler points are sampled from a known slider-crank with
// it and the synthesised one is checked with it; an independent least-squares solve (the normal
// equations, written here) for inconsistent data; a candidate's mechanism file read back and
// validated (run_synthesis, parse_mechanism, validate_design_positions).
#include "orthomech/synthesis/slider_crank.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <stdexcept>
#include <string>
#include <variant>

#include "orthomech/analysis/validate.hpp"
#include "orthomech/error.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/synthesis/function_generation.hpp"
#include "orthomech/synthesis/synthesize.hpp"

namespace orthomech::synthesis {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;
// Recovered lengths of 10–90 mm links from a well-conditioned 3 × 3 solve (≈ 1e-14 relative).
constexpr double kLength = 1e-10;
// Slider positions of ~100 mm reproduced by the closed form: a few ulps of 100.
constexpr double kPosition = 1e-12;

SliderCrank known() {  // r = 25, l = 90, e = 10 mm, line along x, crank pivot at the origin
  SliderCrank sc;
  sc.r = 25;
  sc.l = 90;
  sc.offset = 10;
  return sc;
}

std::vector<SliderPair> sample(const SliderCrank& sc, const std::vector<double>& phis) {
  std::vector<SliderPair> pairs;
  for (const double phi : phis) pairs.push_back({phi, calc_position(sc, phi).s});
  return pairs;
}

void expect_same_linkage(const SliderCrank& got, const SliderCrank& want) {
  EXPECT_NEAR(got.r, want.r, kLength);
  EXPECT_NEAR(got.l, want.l, kLength);
  EXPECT_NEAR(got.offset, want.offset, kLength);
  EXPECT_EQ(got.branch, want.branch);
}

// The largest |s(θ_i) − s_i| of a result, by calc_position in the test.
double max_position_error(const SliderFunctionResult& r, const std::vector<SliderPair>& pairs) {
  double worst = 0.0;
  for (const SliderPair& pr : pairs)
    worst = std::max(worst, std::abs(calc_position(r.linkage, pr.phi + r.input_offset).s - pr.s));
  return worst;
}

TEST(SliderCrankFunction, L42_ThreePairsRoundTrip) {
  for (const int branch : {1, -1}) {
    SliderCrank sc = known();
    sc.branch = branch;
    const auto pairs = sample(sc, {20 * kDeg, 75 * kDeg, 140 * kDeg});
    const SliderFunctionResult r = synthesize_slider_function_generator(pairs);
    ASSERT_EQ(r.status, SynthesisStatus::ok) << r.message;
    expect_same_linkage(r.linkage, sc);
    EXPECT_EQ(r.input_offset, 0.0);
    EXPECT_LE(r.max_position_error, kPosition);
    EXPECT_LE(max_position_error(r, pairs), kPosition);
    // The same linkage away from the precision pairs too (the whole turn: r + |e| < l).
    for (int k = 0; k < 36; ++k)
      EXPECT_NEAR(calc_position(r.linkage, k * 10 * kDeg).s, calc_position(sc, k * 10 * kDeg).s,
                  kPosition);
  }
}

// Angles measured from the other end of the line (φ + π): K1 = −r, the input offset π (L44).
TEST(SliderCrankFunction, L44_NegativeK1IsTheCrankTurnedHalfAround) {
  const auto base = sample(known(), {20 * kDeg, 75 * kDeg, 140 * kDeg});
  std::vector<SliderPair> pairs;
  for (const SliderPair& pr : base) pairs.push_back({pr.phi - kPi, pr.s});
  const SliderFunctionResult r = synthesize_slider_function_generator(pairs);
  ASSERT_EQ(r.status, SynthesisStatus::ok) << r.message;
  EXPECT_NEAR(r.K(0), -25.0, kLength);
  EXPECT_EQ(r.input_offset, kPi);
  expect_same_linkage(r.linkage, known());
  EXPECT_LE(max_position_error(r, pairs), kPosition);
}

// Ten Chebyshev-spaced pairs (L13) of the same linkage: consistent data, the least-squares
// solution is the exact one.
TEST(SliderCrankFunction, L43_LeastSquaresOnConsistentDataIsExact) {
  const std::vector<double> phis = chebyshev_spacing(10, 0.0, 150 * kDeg);
  const auto pairs = sample(known(), phis);
  const SliderFunctionResult r = synthesize_slider_function_generator(pairs);
  ASSERT_EQ(r.status, SynthesisStatus::ok) << r.message;
  expect_same_linkage(r.linkage, known());
  EXPECT_LE(r.max_position_error, kPosition);
}

// A law no slider-crank meets exactly, s = 80 + 15 sin 2φ on [0°, 150°] at ten Chebyshev points:
// K equals the normal equations' solution MᵀM K = Mᵀ b solved here, the lengths follow from it by
// (L44), the reported error is the closed form's (here: s = r cos θ ± √(l² − (e − r sin θ)²)
// written out), and l² is the mean squared crank-pin–slider distance of the data (the
// least-squares K3 is an intercept), which is why l² > 0 for every real data set.
TEST(SliderCrankFunction, L43_LeastSquaresMatchesTheNormalEquations) {
  std::vector<SliderPair> pairs;
  for (const double phi : chebyshev_spacing(10, 0.0, 150 * kDeg))
    pairs.push_back({phi, 80.0 + 15.0 * std::sin(2.0 * phi)});
  const SliderFunctionResult r = synthesize_slider_function_generator(pairs);
  ASSERT_EQ(r.status, SynthesisStatus::ok) << r.message;
  // The independent solve.
  Eigen::Matrix3d N = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  for (const SliderPair& pr : pairs) {
    const Eigen::Vector3d row(2.0 * pr.s * std::cos(pr.phi), 2.0 * std::sin(pr.phi), -1.0);
    N += row * row.transpose();
    rhs += row * (pr.s * pr.s);
  }
  const Eigen::Vector3d K = N.ldlt().solve(rhs);
  EXPECT_LE((r.K - K).norm(), 1e-9 * K.norm());
  const double rr = std::abs(K(0)), e = K(1) / K(0), l2 = K(0) * K(0) + e * e - K(2);
  EXPECT_NEAR(r.linkage.r, rr, 1e-9 * rr);
  EXPECT_NEAR(r.linkage.offset, e, 1e-9 * std::abs(e));
  EXPECT_NEAR(r.linkage.l * r.linkage.l, l2, 1e-9 * l2);
  double mean_d2 = 0.0;
  for (const SliderPair& pr : pairs) {
    const double u = K(0) * std::cos(pr.phi), v = K(0) * std::sin(pr.phi);
    mean_d2 += ((pr.s - u) * (pr.s - u) + (e - v) * (e - v)) / static_cast<double>(pairs.size());
  }
  EXPECT_NEAR(l2, mean_d2, 1e-9 * l2);
  // The error of the branch that fits better, by the closed form written here.
  const double theta_offset = K(0) < 0.0 ? kPi : 0.0;
  double worst[2] = {0.0, 0.0};
  for (const SliderPair& pr : pairs)
    for (int b = 0; b < 2; ++b) {
      const double th = pr.phi + theta_offset;
      const double root = std::sqrt(l2 - std::pow(e - rr * std::sin(th), 2));
      worst[b] = std::max(worst[b], std::abs(rr * std::cos(th) + (b == 0 ? root : -root) - pr.s));
    }
  EXPECT_NEAR(r.max_position_error, std::min(worst[0], worst[1]), 1e-9);
  EXPECT_GT(r.max_position_error, 0.1);  // the law is not met exactly
}

// Three pairs of the known linkage, one of them on the other branch: (L41) holds at all three,
// so the linkage is recovered, but no branch meets them all.
TEST(SliderCrankFunction, L45_PairsOnBothBranchesAreABranchDefect) {
  SliderCrank other = known();
  other.branch = -1;
  auto pairs = sample(known(), {20 * kDeg, 75 * kDeg});
  pairs.push_back({140 * kDeg, calc_position(other, 140 * kDeg).s});
  const SliderFunctionResult r = synthesize_slider_function_generator(pairs);
  EXPECT_EQ(r.status, SynthesisStatus::branch_defect);
  EXPECT_NE(r.message.find("branches"), std::string::npos) << r.message;
  EXPECT_NEAR(r.linkage.r, 25.0, kLength);
  EXPECT_NEAR(r.linkage.l, 90.0, kLength);
}

// No linkage, with the reason: a slider at rest (s constant: K1 = r = 0) and pairs that do not
// determine K (all at one crank angle). A real coupler l² ≤ 0 cannot arise from real data (see
// L43_LeastSquaresMatchesTheNormalEquations: l² is a mean of squares); the refusal stays as a
// guard against round-off.
TEST(SliderCrankFunction, L44_NoLinkageSaysWhy) {
  const SliderFunctionResult at_rest =
      synthesize_slider_function_generator({{0.1, 50.0}, {0.7, 50.0}, {1.5, 50.0}, {2.0, 50.0}});
  EXPECT_EQ(at_rest.status, SynthesisStatus::no_linkage);
  EXPECT_NE(at_rest.message.find("crank would have no length"), std::string::npos)
      << at_rest.message;
  const SliderFunctionResult one_angle =
      synthesize_slider_function_generator({{0.3, 40.0}, {0.3, 40.0}, {0.3, 40.0}});
  EXPECT_EQ(one_angle.status, SynthesisStatus::no_linkage);
  EXPECT_NE(one_angle.message.find("rank-deficient"), std::string::npos) << one_angle.message;
  EXPECT_THROW((void)synthesize_slider_function_generator({{0.1, 50.0}, {0.7, 60.0}}),
               std::invalid_argument);
}

// Path generation (L46)–(L49): six coupler points of a known offset slider-crank, timed (crank
// angles from the slider line given), everything else free: recovered to 1e-10 mm.
TEST(SliderCrankPath, L46_TimedCouplerPathRoundTrip) {
  SliderCrank sc = known();
  sc.O = Vec2(10, -5);
  sc.line_angle = 15 * kDeg;
  sc.coupler_point = Vec2(30, 15);
  std::vector<double> phis;
  std::vector<Vec2> targets;
  for (int k = 0; k < 6; ++k) {
    phis.push_back(k * 50 * kDeg);
    targets.push_back(calc_position(sc, sc.line_angle + phis.back()).P);
  }
  PathSynthesisOptions o;
  o.timing = PathTiming::prescribed;
  o.crank_angles = phis;
  o.branch = 1;
  o.starts = 8;
  const SliderPathResult r = synthesize_slider_path_generator(targets, o);
  ASSERT_EQ(r.status, SynthesisStatus::ok) << r.message;
  EXPECT_LE(r.max_distance, 1e-10);
  // The distances again, by calc_position here.
  double worst = 0.0;
  for (size_t i = 0; i < targets.size(); ++i)
    worst = std::max(worst, (calc_position(r.linkage, r.crank_angles[i]).P - targets[i]).norm());
  EXPECT_LE(worst, 1e-10);
}

// The same points with the crank angles known up to a common start (L47): θ_i = γ + θ_0 + φ_i,
// the angles given 40° short of the truth.
TEST(SliderCrankPath, L47_FreeStartRecoversTheCrankOffset) {
  SliderCrank sc = known();
  sc.O = Vec2(10, -5);
  sc.line_angle = 15 * kDeg;
  sc.coupler_point = Vec2(30, 15);
  std::vector<double> phis;
  std::vector<Vec2> targets;
  for (int k = 0; k < 6; ++k) {
    targets.push_back(calc_position(sc, sc.line_angle + k * 50 * kDeg).P);
    phis.push_back(k * 50 * kDeg - 40 * kDeg);
  }
  PathSynthesisOptions o;
  o.timing = PathTiming::prescribed_free_start;
  o.crank_angles = phis;
  o.branch = 1;
  o.starts = 8;
  const SliderPathResult r = synthesize_slider_path_generator(targets, o);
  ASSERT_EQ(r.status, SynthesisStatus::ok) << r.message;
  double worst = 0.0;
  for (size_t i = 0; i < targets.size(); ++i)
    worst = std::max(worst, (calc_position(r.linkage, r.crank_angles[i]).P - targets[i]).norm());
  EXPECT_LE(worst, 1e-10);
  EXPECT_NEAR(r.max_distance, worst, 1e-15);
}

// (L46)–(L47) with free timing: points of a known slider-crank's coupler curve at uneven crank
// steps (timing free: only their order is given). The search's crank angles are checked here by
// the closed form: the coupler point passes through every target, in order (the angles monotone
// within one turn), and the reported distance is the worst miss.
TEST(SliderCrankPath, L47_FreeTimingPassesThroughThePointsInOrder) {
  SliderCrank sc = known();
  sc.coupler_point = Vec2(30, 15);
  std::vector<Vec2> targets;
  for (const double phi : {0.0, 35.0, 90.0, 160.0, 210.0, 300.0})
    targets.push_back(calc_position(sc, sc.line_angle + phi * kDeg).P);
  PathSynthesisOptions o;
  o.timing = PathTiming::free;
  o.branch = 1;
  o.starts = 16;
  const SliderPathResult r = synthesize_slider_path_generator(targets, o);
  ASSERT_NE(r.status, SynthesisStatus::no_linkage) << r.message;
  ASSERT_EQ(r.crank_angles.size(), targets.size());
  double worst = 0.0;
  for (size_t i = 0; i < targets.size(); ++i) {
    const SliderCrankPosition p = calc_position(r.linkage, r.crank_angles[i]);
    ASSERT_TRUE(p.assembles) << i;
    worst = std::max(worst, (p.P - targets[i]).norm());
  }
  // Six points and free timing leave the fit exact (measured 1.4e-14 with 16 starts).
  EXPECT_LE(worst, 1e-10);
  EXPECT_NEAR(r.max_distance, worst, 1e-12);
  const double sense = r.crank_angles.back() > r.crank_angles.front() ? 1.0 : -1.0;
  for (size_t i = 1; i < targets.size(); ++i)
    EXPECT_GT(sense * (r.crank_angles[i] - r.crank_angles[i - 1]), 0.0) << i;
  EXPECT_LT(std::abs(r.crank_angles.back() - r.crank_angles.front()), 2 * std::numbers::pi);
}

// ---- the pipeline (run_synthesis, synthesize.cpp) ----------------------------------------------

constexpr double kMm = 1e-3;

// Every accepted candidate's file, read back here, passes validate (its own assembly solve, the
// targets as design positions) and meets each target within 1e-9 m.
void expect_files_validate(const SynthesisResult& r, const SynthesisTask& task) {
  ValidateOptions vo;
  vo.min_transmission = task.min_transmission;
  for (const SynthesisCandidate& c : r.accepted) {
    const Model model = parse_mechanism(c.file_text, c.name + ".yaml");
    const ValidationReport report = validate_design_positions(model, vo);
    EXPECT_TRUE(report.pass()) << c.name;
    ASSERT_EQ(report.positions.size(), c.crank_angles.size());
    for (const PositionReport& p : report.positions) {
      ASSERT_TRUE(p.target_error.has_value()) << p.name;
      EXPECT_LE(*p.target_error, 1e-9) << p.name;
      EXPECT_EQ(p.slider_cranks.size(), 1u) << p.name;  // validate saw the slider-crank loop
    }
  }
}

// The task text of three precision pairs of the known linkage (mm, deg), the slider positions by
// calc_position printed with every digit.
std::string slider_function_task() {
  std::string text =
      "orthomech-synthesis: 1\nname: slider\ntask: function\nlinkage: slider-crank\npairs:\n";
  for (const double deg : {20.0, 75.0, 140.0}) {
    char row[96];
    std::snprintf(row, sizeof row, "  - [%.17g, %.17g]\n", deg,
                  calc_position(known(), deg * kDeg).s);
    text += row;
  }
  return text;
}

TEST(SliderCrankSynthesize, FunctionTaskGivesBackTheSliderCrankAndItsFileValidates) {
  const SynthesisTask task = parse_synthesis_task(slider_function_task(), "slider.yaml");
  EXPECT_EQ(task.linkage, TaskLinkage::slider_crank);
  const SynthesisResult r = run_synthesis(task);
  ASSERT_EQ(r.accepted.size(), 1u) << r.message;
  const SynthesisCandidate& c = r.accepted[0];
  ASSERT_TRUE(std::holds_alternative<SliderCrank>(c.linkage));
  const SliderCrank& sc = std::get<SliderCrank>(c.linkage);
  EXPECT_NEAR(sc.r, 25 * kMm, 1e-10 * kMm);
  EXPECT_NEAR(sc.l, 90 * kMm, 1e-10 * kMm);
  EXPECT_NEAR(sc.offset, 10 * kMm, 1e-10 * kMm);
  EXPECT_LE(c.max_distance, 1e-9);
  // The worst transmission angle over 20°–140°: π/2 − the largest pressure angle, which is at
  // 90° (the crank pin farthest from the line): sin α = (r − e) / l.
  EXPECT_NEAR(c.worst_transmission, kPi / 2 - std::asin(15.0 / 90.0), 1e-12);
  expect_files_validate(r, task);
}

TEST(SliderCrankSynthesize, TheExampleTaskIsTheSameSliderCrank) {
  const SynthesisTask task =
      load_synthesis_task(std::string(ORTHOMECH_SOURCE_DIR) + "/examples/synthesis-slider.yaml");
  const SynthesisResult r = run_synthesis(task);
  ASSERT_EQ(r.accepted.size(), 1u) << r.message;
  const SliderCrank& sc = std::get<SliderCrank>(r.accepted[0].linkage);
  // The example's positions are rounded to 1e-12 mm.
  EXPECT_NEAR(sc.r, 25 * kMm, 1e-9 * kMm);
  EXPECT_NEAR(sc.l, 90 * kMm, 1e-9 * kMm);
  EXPECT_NEAR(sc.offset, 10 * kMm, 1e-9 * kMm);
}

// A timed path task: four coupler points of the known slider-crank (line at 15°, pivot O at
// (10, −5) mm, P = (30, 15) mm on the rod) at crank angles from the line.
TEST(SliderCrankSynthesize, PathTaskFindsASliderCrankThroughThePoints) {
  SliderCrank sc = known();
  sc.O = Vec2(10, -5);
  sc.line_angle = 15 * kDeg;
  sc.coupler_point = Vec2(30, 15);
  std::string text =
      "orthomech-synthesis: 1\ntask: path\nlinkage: slider-crank\ntiming: prescribed\n"
      "search: {seed: 1, starts: 6}\npoints:\n";
  std::string angles = "crank_angles: [";
  for (int k = 0; k < 6; ++k) {
    const Vec2 P = calc_position(sc, sc.line_angle + k * 50 * kDeg).P;
    char row[96];
    std::snprintf(row, sizeof row, "  - [%.17g, %.17g]\n", P.x(), P.y());
    text += row;
    angles += std::to_string(k * 50) + (k < 5 ? ", " : "]\n");
  }
  const SynthesisTask task = parse_synthesis_task(text + angles, "path.yaml");
  const SynthesisResult r = run_synthesis(task);
  ASSERT_FALSE(r.accepted.empty()) << r.message;
  for (const SynthesisCandidate& c : r.accepted)
    EXPECT_TRUE(std::holds_alternative<SliderCrank>(c.linkage)) << c.name;
  EXPECT_LE(r.accepted.front().max_distance, 1e-10 * kMm);
  expect_files_validate(r, task);
}

// The key's refusals, at the element.
TEST(SliderCrankTask, KeyErrorsNameTheElement) {
  const auto message = [](const std::string& text) {
    try {
      (void)parse_synthesis_task(text, "t.yaml");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string head = "orthomech-synthesis: 1\ntask: function\n";
  EXPECT_NE(message(head + "linkage: crank-slider\npairs: [[0, 1], [1, 2], [2, 3]]\n")
                .find("unknown linkage 'crank-slider'"),
            std::string::npos);
  EXPECT_NE(message(head + "linkage: slider-crank\nground: 70\npairs: [[0, 1], [1, 2], [2, 3]]\n")
                .find("takes no `ground`"),
            std::string::npos);
  EXPECT_NE(message(head + "linkage: slider-crank\npairs: [[0, 1], [1, 2], [2, 3]]\n"
                           "require: {crank_rocker: true}\n")
                .find("four-bar requirement"),
            std::string::npos);
  EXPECT_NE(message("orthomech-synthesis: 1\ntask: motion\nlinkage: slider-crank\n"
                    "poses: [[0, 0, 0], [1, 0, 0], [2, 0, 0]]\n")
                .find("four-bars only"),
            std::string::npos);
  EXPECT_NE(
      message(head + "linkage: slider-crank\npairs: [[0, 1], [1, 2], [2, 3]]\n").find("no error"),
      std::string::npos);
}

}  // namespace
}  // namespace orthomech::synthesis
