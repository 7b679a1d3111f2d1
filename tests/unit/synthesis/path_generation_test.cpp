// Path generation (src/synthesis/path_generation.cpp, (L21)–(L24)).
// Oracles: targets sampled from the known crank-rocker of mechanisms/crank-rocker.yaml (a zero
// of the objective exists); every result's error recomputed by calc_position (circle
// intersection) through path_error; the published benchmark cases of issue 50 with their data
// (docs/synthesis.md, "Benchmark cases": sources and best published errors).
#include "orthomech/synthesis/path_generation.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <numbers>
#include <stdexcept>

namespace orthomech::synthesis {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

FourBar crank_rocker() {  // mechanisms/crank-rocker.yaml
  FourBar fb;
  fb.B0 = {70, 0};
  fb.a = 30;
  fb.b = 80;
  fb.c = 60;
  fb.coupler_point = {40, 20};
  return fb;
}

const std::vector<double> kRoundTripAngles{0, 50, 110, 170, 240, 310};  // deg

std::vector<Vec2> sampled_targets() {
  std::vector<Vec2> t;
  for (const double a : kRoundTripAngles) t.push_back(calc_position(crank_rocker(), a * kDeg).P);
  return t;
}

bool long_tests() { return std::getenv("ORTHOMECH_LONG_TESTS") != nullptr; }

// The result's error is the closed form's, and its linkage meets the requested type.
void expect_consistent(const PathSynthesisResult& r, const std::vector<Vec2>& targets) {
  EXPECT_DOUBLE_EQ(r.error, path_error(r.linkage, targets, r.crank_angles));
  EXPECT_TRUE(r.assembles);
}

TEST(PathGeneration, L21_TimedRoundTripFindsTheCrankRocker) {
  const std::vector<Vec2> targets = sampled_targets();
  PathSynthesisOptions o;
  for (const double a : kRoundTripAngles) o.crank_angles.push_back(a * kDeg);
  o.starts = 60;
  o.branch = 1;
  const PathSynthesisResult r = synthesize_path_generator(targets, o);
  ASSERT_EQ(r.status, SynthesisStatus::ok) << r.message;
  expect_consistent(r, targets);
  EXPECT_LE(r.max_distance, 1e-10);
  // 12 equations in 9 unknowns: the linkage itself comes back (to the polish's precision).
  const FourBar want = crank_rocker();
  EXPECT_NEAR((r.linkage.A0 - want.A0).norm(), 0.0, 1e-8);
  EXPECT_NEAR((r.linkage.B0 - want.B0).norm(), 0.0, 1e-8);
  EXPECT_NEAR(r.linkage.a, want.a, 1e-8);
  EXPECT_NEAR(r.linkage.b, want.b, 1e-8);
  EXPECT_NEAR(r.linkage.c, want.c, 1e-8);
  EXPECT_NEAR((r.linkage.coupler_point - want.coupler_point).norm(), 0.0, 1e-8);
}

TEST(PathGeneration, L24_FreeStartRecoversTheCrankOffset) {
  // The crank-rocker's points at θ = 40° + φ_i, given φ_i only: the start θ_0 = 40° is found.
  std::vector<Vec2> targets;
  PathSynthesisOptions o;
  o.timing = PathTiming::prescribed_free_start;
  for (const double a : kRoundTripAngles) {
    targets.push_back(calc_position(crank_rocker(), (a + 40.0) * kDeg).P);
    o.crank_angles.push_back(a * kDeg);
  }
  o.starts = 60;
  o.branch = 1;
  const PathSynthesisResult r = synthesize_path_generator(targets, o);
  ASSERT_EQ(r.status, SynthesisStatus::ok) << r.message;
  expect_consistent(r, targets);
  EXPECT_LE(r.max_distance, 1e-10);
  // θ_g + θ_0 is determined (the ground angle and the start trade off only through it).
  EXPECT_NEAR(std::remainder(r.crank_angles[0] - 40.0 * kDeg, 2 * std::numbers::pi), 0.0, 1e-8);
  EXPECT_NEAR(r.linkage.a, 30.0, 1e-8);
}

TEST(PathGeneration, L24_UntimedRoundTripPassesThroughThePoints) {
  // Untimed, 6 points: 15 unknowns for 12 equations, so some exact linkage exists (not
  // necessarily the crank-rocker): the stated bound is max distance ≤ 1e-8 (0.01 µm on 100 mm).
  const std::vector<Vec2> targets = sampled_targets();
  PathSynthesisOptions o;
  o.timing = PathTiming::free;
  o.starts = 40;
  o.branch = 1;
  o.turning = 1;
  const PathSynthesisResult r = synthesize_path_generator(targets, o);
  ASSERT_EQ(r.status, SynthesisStatus::ok) << r.message;
  expect_consistent(r, targets);
  EXPECT_LE(r.max_distance, 1e-8);
  // The timing is increasing within one turn.
  for (std::size_t i = 1; i < r.crank_angles.size(); ++i)
    EXPECT_GE(r.crank_angles[i], r.crank_angles[i - 1]);
  EXPECT_LE(r.crank_angles.back() - r.crank_angles.front(), 2 * std::numbers::pi + 1e-9);
}

TEST(PathGeneration, L22_CrankRockerRequirementIsMet) {
  const std::vector<Vec2> targets = sampled_targets();
  PathSynthesisOptions o;
  o.timing = PathTiming::free;
  o.require_crank_rocker = true;
  o.starts = 20;
  o.branch = 1;
  o.turning = 1;
  const PathSynthesisResult r = synthesize_path_generator(targets, o);
  ASSERT_EQ(r.status, SynthesisStatus::ok) << r.message;
  EXPECT_EQ(r.grashof, GrashofType::crank_rocker);
  EXPECT_LE(r.linkage.a, std::min({r.linkage.b, r.linkage.c, ground_length(r.linkage)}));
  expect_consistent(r, targets);
}

TEST(PathGeneration, DeterministicForASeed) {
  const std::vector<Vec2> targets = sampled_targets();
  PathSynthesisOptions o;
  o.timing = PathTiming::free;
  o.starts = 5;
  o.branch = 1;
  o.turning = 1;
  o.polished = 1;
  const PathSynthesisResult r1 = synthesize_path_generator(targets, o);
  const PathSynthesisResult r2 = synthesize_path_generator(targets, o);
  EXPECT_EQ(r1.error, r2.error);
  EXPECT_EQ(r1.evaluations, r2.evaluations);
  EXPECT_EQ(r1.linkage.a, r2.linkage.a);
  // The same on one thread and on three (the multistart's runs assembled in start order), for
  // the quasi-random and the nearest-point start.
  for (const PathStart start : {PathStart::quasi_random, PathStart::nearest_point}) {
    o.start = start;
    o.threads = 1;
    const PathSynthesisResult one = synthesize_path_generator(targets, o);
    o.threads = 3;
    const PathSynthesisResult three = synthesize_path_generator(targets, o);
    EXPECT_EQ(one.error, three.error);
    EXPECT_EQ(one.evaluations, three.evaluations);
    EXPECT_EQ(one.linkage.a, three.linkage.a);
    EXPECT_EQ(one.linkage.coupler_point, three.linkage.coupler_point);
  }
}

TEST(PathGeneration, L23_RestartsAreDeterministicAndNeverWorsen) {
  const std::vector<Vec2> targets = sampled_targets();
  PathSynthesisOptions o;
  o.timing = PathTiming::free;
  o.starts = 3;
  o.branch = 1;
  o.turning = 1;
  o.polished = 1;
  o.local_evaluations = 300;  // a poor start, so that the hops have something to do
  const PathSynthesisResult plain = synthesize_path_generator(targets, o);
  o.restarts = 10;
  const PathSynthesisResult r1 = synthesize_path_generator(targets, o);
  const PathSynthesisResult r2 = synthesize_path_generator(targets, o);
  EXPECT_EQ(r1.error, r2.error);
  EXPECT_EQ(r1.evaluations, r2.evaluations);
  EXPECT_GT(r1.evaluations, plain.evaluations);
  EXPECT_LE(r1.error, plain.error);
}

TEST(PathGeneration, WorldBoxBoundsTheResult) {
  // The crank-rocker's points in a box that excludes it (links ≤ 50 < b = 80): the result keeps
  // to the box.
  const std::vector<Vec2> targets = sampled_targets();
  PathSynthesisOptions o;
  for (const double a : kRoundTripAngles) o.crank_angles.push_back(a * kDeg);
  o.starts = 20;
  o.branch = 1;
  PathSynthesisOptions::WorldBox w;
  w.link_hi = 50.0;
  w.pivot_lo = w.coupler_lo = -50.0;
  w.pivot_hi = w.coupler_hi = 100.0;
  o.world_box = w;
  const PathSynthesisResult r = synthesize_path_generator(targets, o);
  expect_consistent(r, targets);
  for (const double v : {ground_length(r.linkage), r.linkage.a, r.linkage.b, r.linkage.c})
    EXPECT_LE(v, 50.0 + 1e-9);
  for (const double v : {r.linkage.A0.x(), r.linkage.A0.y(), r.linkage.coupler_point.x(),
                         r.linkage.coupler_point.y()}) {
    EXPECT_GE(v, -50.0 - 1e-9);
    EXPECT_LE(v, 100.0 + 1e-9);
  }
  EXPECT_GT(r.error, 1e-6);  // the exact linkage is outside
}

TEST(PathGeneration, MisuseThrows) {
  PathSynthesisOptions o;
  o.crank_angles = {0.0};
  EXPECT_THROW((void)synthesize_path_generator({Vec2(0, 0)}, o), std::invalid_argument);
  EXPECT_THROW((void)synthesize_path_generator({Vec2(0, 0), Vec2(1, 0)}, o),
               std::invalid_argument);  // one angle for two targets
  EXPECT_THROW((void)path_error(crank_rocker(), {Vec2(0, 0)}, {}), std::invalid_argument);
  PathSynthesisOptions bad;
  bad.crank_angles = {0.0, 1.0};
  bad.restarts = -1;
  EXPECT_THROW((void)synthesize_path_generator({Vec2(0, 0), Vec2(1, 0)}, bad),
               std::invalid_argument);
  bad.restarts = 0;
  bad.world_box = PathSynthesisOptions::WorldBox{};
  bad.world_box->link_lo = -1.0;
  EXPECT_THROW((void)synthesize_path_generator({Vec2(0, 0), Vec2(1, 0)}, bad),
               std::invalid_argument);
  EXPECT_EQ(path_error(crank_rocker(), {calc_position(crank_rocker(), 1.0).P}, {1.0}), 0.0);
}

// ---- benchmark cases of issue 50 (docs/synthesis.md, "Benchmark cases") --------------------
// Each bound is this implementation's result for the default seed (rounded up), so that a
// regression fails; the published best errors are in the doc table.

TEST(PathGenerationBenchmark, FivePointsPrescribedTimingFixedGround) {
  const std::vector<Vec2> targets{
      {3, 3}, {2.759, 3.363}, {2.372, 3.663}, {1.890, 3.862}, {1.355, 3.943}};
  PathSynthesisOptions o;
  o.crank_angles = {30 * kDeg, 45 * kDeg, 60 * kDeg, 75 * kDeg, 90 * kDeg};
  o.fixed_A0 = Vec2(0, 0);
  o.fixed_ground_angle = 0.0;
  const PathSynthesisResult r = synthesize_path_generator(targets, o);
  ASSERT_EQ(r.status, SynthesisStatus::ok) << r.message;
  expect_consistent(r, targets);
  EXPECT_LE(r.error, 7.5e-7);
  EXPECT_NEAR(r.linkage.A0.norm(), 0.0, 1e-12);
  EXPECT_NEAR(r.linkage.B0.y(), 0.0, 1e-12);
}

TEST(PathGenerationBenchmark, SixPointsOnAHalfCirclePrescribedTiming) {
  const std::vector<Vec2> targets{{0, 0},          {1.9098, 5.8779}, {6.9098, 9.5106},
                                  {13.09, 9.5106}, {18.09, 5.8779},  {20, 0}};
  PathSynthesisOptions o;
  for (int k = 1; k <= 6; ++k) o.crank_angles.push_back(30.0 * k * kDeg);  // from the ground line
  const PathSynthesisResult r = synthesize_path_generator(targets, o);
  ASSERT_EQ(r.status, SynthesisStatus::ok) << r.message;
  expect_consistent(r, targets);
  EXPECT_LE(r.error, 1.12);
}

TEST(PathGenerationBenchmark, SixCollinearPointsUntimedCrankRocker) {
  if (!long_tests()) GTEST_SKIP() << "set ORTHOMECH_LONG_TESTS=1 (about 8 s)";
  const std::vector<Vec2> targets{{20, 20}, {20, 25}, {20, 30}, {20, 35}, {20, 40}, {20, 45}};
  PathSynthesisOptions o;
  o.timing = PathTiming::free;
  o.require_crank_rocker = true;
  o.starts = 60;  // per branch and turning sense: 240 local runs
  const PathSynthesisResult r = synthesize_path_generator(targets, o);
  ASSERT_EQ(r.status, SynthesisStatus::ok) << r.message;
  expect_consistent(r, targets);
  EXPECT_EQ(r.grashof, GrashofType::crank_rocker);
  EXPECT_LE(r.error, 1e-20);
}

// ---- the remaining cases of issue 50 and the published linkages --------------------------------
// Published values: the result files of the repository github.com/sy-nguyen-van/
// DE_Jaya_Synthesis_Four_Bar_Mechanisms (the code of Nguyen-Van & Gwak, "A new study on
// optimization of four-bar mechanisms based on a hybrid-combined differential evolution and Jaya
// algorithm", Symmetry 14(2) 381, 2022, per its README): Case{2,3,4,5}/…/x_best_HCDJ_Case*.txt
// (the linkage) and Records_HCDJ_Case*.txt (its best error). Their variables x = (r1 ground, r2
// crank, r3 coupler, r4 follower, rcx, rcy, x0, y0, θ0, crank angles from the ground line); their
// loop root (−√ in the half-angle formula) is our branch +1. Each linkage is re-evaluated here by
// calc_position (path_error), independently of their code; the 8 printed digits reproduce the
// recorded error to 1e-5 relative.

const std::vector<Vec2> kClosedCurve18{
    {0.5, 1.1},  {0.4, 1.1}, {0.3, 1.1}, {0.2, 1.0},  {0.1, 0.9},  {0.05, 0.75},
    {0.02, 0.6}, {0.0, 0.5}, {0.0, 0.4}, {0.03, 0.3}, {0.1, 0.25}, {0.15, 0.2},
    {0.2, 0.3},  {0.3, 0.4}, {0.4, 0.5}, {0.5, 0.7},  {0.6, 0.9},  {0.6, 1.0}};
const std::vector<Vec2> kHalfCircle{{0, 0},          {1.9098, 5.8779}, {6.9098, 9.5106},
                                    {13.09, 9.5106}, {18.09, 5.8779},  {20, 0}};
const std::vector<Vec2> kEllipse{
    {20, 10},          {17.66, 15.142}, {11.736, 17.878}, {5, 16.928},     {0.60307, 12.736},
    {0.60307, 7.2638}, {5, 3.0718},     {11.736, 2.1215}, {17.66, 4.8577}, {20, 10}};

struct Published {
  FourBar linkage;
  std::vector<double> crank_angles;  // absolute
};

// x = (r1, r2, r3, r4, rcx, rcy, x0, y0, θ0), crank angles φ_i from the ground line.
Published from_nguyen_van(const std::vector<double>& x, const std::vector<double>& phi) {
  Published p;
  p.linkage.A0 = {x[6], x[7]};
  p.linkage.B0 = p.linkage.A0 + x[0] * Vec2(std::cos(x[8]), std::sin(x[8]));
  p.linkage.a = x[1];
  p.linkage.b = x[2];
  p.linkage.c = x[3];
  p.linkage.coupler_point = {x[4], x[5]};
  p.linkage.branch = 1;
  for (const double f : phi) p.crank_angles.push_back(x[8] + f);
  return p;
}

bool assembles_at(const FourBar& fb, const std::vector<double>& crank_angles) {
  return std::all_of(crank_angles.begin(), crank_angles.end(),
                     [&](double t) { return calc_position(fb, t).assembles; });
}

// The independent checks of a benchmark result: the error is the closed form's, the linkage
// assembles at every target by calc_position, and its Grashof type is classify_grashof's.
void expect_valid(const PathSynthesisResult& r, const std::vector<Vec2>& targets) {
  expect_consistent(r, targets);
  EXPECT_TRUE(assembles_at(r.linkage, r.crank_angles));
  EXPECT_EQ(r.grashof, classify_grashof(r.linkage));
}

// Every variable of the result inside a world box (the published bounds).
void expect_inside(const FourBar& fb, const PathSynthesisOptions::WorldBox& w) {
  constexpr double tol = 1e-9;
  for (const double v : {fb.A0.x(), fb.A0.y()}) {
    EXPECT_GE(v, w.pivot_lo - tol);
    EXPECT_LE(v, w.pivot_hi + tol);
  }
  for (const double v : {ground_length(fb), fb.a, fb.b, fb.c}) {
    EXPECT_GE(v, w.link_lo - tol);
    EXPECT_LE(v, w.link_hi + tol);
  }
  for (const double v : {fb.coupler_point.x(), fb.coupler_point.y()}) {
    EXPECT_GE(v, w.coupler_lo - tol);
    EXPECT_LE(v, w.coupler_hi + tol);
  }
}

PathSynthesisOptions::WorldBox world_box(double half) {
  PathSynthesisOptions::WorldBox w;
  w.pivot_lo = w.coupler_lo = -half;
  w.pivot_hi = w.coupler_hi = w.link_hi = half;
  w.link_lo = 0.0;
  return w;
}

// Published values (Records_HCDJ_Case*.txt, the best of their runs).
constexpr double kPublishedFivePoints = 1.9239227e-06;
constexpr double kPublishedClosedCurve18 = 1.6077817e-02;
constexpr double kPublishedHalfCircle = 1.2162122;   // their box: links [0, 50], the rest ±50
constexpr double kPublishedEllipse = 4.2014375e-04;  // their box: links [0, 80], the rest ±80

TEST(PathGenerationBenchmark, PublishedLinkagesReevaluated) {
  {  // five points: the ground fixed, θ = π/6 … π/2 (Case2: x = (r1, r2, r3, r4, rcx, rcy))
    const std::vector<Vec2> targets{
        {3, 3}, {2.759, 3.363}, {2.372, 3.663}, {1.890, 3.862}, {1.355, 3.943}};
    const Published p =
        from_nguyen_van({4.2930812, 1.9978324, 4.7374099, 2.9417301, 1.7074051, 1.6441696, 0, 0, 0},
                        {30 * kDeg, 45 * kDeg, 60 * kDeg, 75 * kDeg, 90 * kDeg});
    EXPECT_TRUE(assembles_at(p.linkage, p.crank_angles));
    EXPECT_NEAR(path_error(p.linkage, targets, p.crank_angles), kPublishedFivePoints,
                1e-5 * kPublishedFivePoints);
    EXPECT_EQ(classify_grashof(p.linkage), GrashofType::crank_rocker);
  }
  {  // eighteen points, θ_i = θ0 + x10 + (i − 1) 20°
    std::vector<double> phi;
    for (int i = 0; i < 18; ++i) phi.push_back(5.0644224 + i * 20.0 * kDeg);
    const Published p = from_nguyen_van({49.800886, 0.28817159, 48.476138, 1.633642, -23.41281,
                                         7.6644886, -14.836153, 20.140223, 2.5286091},
                                        phi);
    EXPECT_NEAR(path_error(p.linkage, kClosedCurve18, p.crank_angles), kPublishedClosedCurve18,
                1e-5 * kPublishedClosedCurve18);
    EXPECT_TRUE(assembles_at(p.linkage, p.crank_angles));
    EXPECT_EQ(classify_grashof(p.linkage), GrashofType::crank_rocker);
  }
  {  // half circle, θ = 30° … 180° from the ground line
    std::vector<double> phi;
    for (int k = 1; k <= 6; ++k) phi.push_back(30.0 * k * kDeg);
    const Published p = from_nguyen_van({49.99998, 1.3484315, 1.3484507, 50.0, 11.384434, 4.4424357,
                                         10.194752, -3.694134, 6.2158799},
                                        phi);
    EXPECT_NEAR(path_error(p.linkage, kHalfCircle, p.crank_angles), kPublishedHalfCircle,
                1e-5 * kPublishedHalfCircle);
    EXPECT_TRUE(assembles_at(p.linkage, p.crank_angles));
    // Their constraint is Grashof with the crank shortest; in the printed digits s + l exceeds
    // p + q by 8e-7 (1.3484315 + 50 vs 49.99998 + 1.3484507): not a crank-rocker.
    EXPECT_EQ(classify_grashof(p.linkage), GrashofType::triple_rocker);
  }
  {  // ellipse, free timing (their ten crank angles, a full turn from the first to the last)
    const Published p = from_nguyen_van({79.999856, 8.1232008, 50.870344, 42.360533, -10.853763,
                                         0.091433127, 7.5379031, -0.52254141, 4.0121195},
                                        {2.3428599, 3.0535127, 3.7417464, 4.4255457, 5.1086716,
                                         5.7983829, 0.21286893, 0.91658554, 1.6304135, 2.3428152});
    EXPECT_NEAR(path_error(p.linkage, kEllipse, p.crank_angles), kPublishedEllipse,
                1e-5 * kPublishedEllipse);
    EXPECT_TRUE(assembles_at(p.linkage, p.crank_angles));
    EXPECT_EQ(classify_grashof(p.linkage), GrashofType::crank_rocker);
  }
}

TEST(PathGenerationBenchmark, FivePointsBeatThePublishedError) {
  // The default search of FivePointsPrescribedTimingFixedGround (7.42e-7) against the record;
  // a box twice as large and 400 starts give the same optimum (docs/synthesis.md).
  const std::vector<Vec2> targets{
      {3, 3}, {2.759, 3.363}, {2.372, 3.663}, {1.890, 3.862}, {1.355, 3.943}};
  PathSynthesisOptions o;
  o.crank_angles = {30 * kDeg, 45 * kDeg, 60 * kDeg, 75 * kDeg, 90 * kDeg};
  o.fixed_A0 = Vec2(0, 0);
  o.fixed_ground_angle = 0.0;
  o.starts = long_tests() ? 200 : 40;
  const PathSynthesisResult r = synthesize_path_generator(targets, o);
  ASSERT_EQ(r.status, SynthesisStatus::ok) << r.message;
  expect_valid(r, targets);
  EXPECT_LE(r.error, kPublishedFivePoints);
  if (long_tests()) {
    EXPECT_LE(r.error, 7.42e-7);
  }
}

// Eighteen points, θ_i = θ_g + θ_0 ± (i − 1)·20°, crank-rocker (the crank turns 340° between
// the first and the last point). The box is the default one (A0 within ±4 spreads of the
// centroid, links ≤ 8 spreads = 3.0), inside the published [0, 50] / ±50.
PathSynthesisResult closed_curve_18(double sense, int starts) {
  PathSynthesisOptions o;
  o.timing = PathTiming::prescribed_free_start;
  for (int i = 0; i < 18; ++i) o.crank_angles.push_back(sense * 20.0 * i * kDeg);
  o.require_crank_rocker = true;
  o.starts = starts;
  return synthesize_path_generator(kClosedCurve18, o);
}

void expect_valid_closed_curve_18(const PathSynthesisResult& r, double sense) {
  ASSERT_EQ(r.status, SynthesisStatus::ok) << r.message;
  expect_valid(r, kClosedCurve18);
  EXPECT_EQ(classify_grashof(r.linkage), GrashofType::crank_rocker);
  EXPECT_TRUE(calc_crank_range(r.linkage).full_turn);
  for (std::size_t i = 0; i < r.crank_angles.size(); ++i)
    EXPECT_NEAR(r.crank_angles[i] - r.crank_angles[0], sense * 20.0 * kDeg * static_cast<double>(i),
                1e-12);
}

TEST(PathGenerationBenchmark, EighteenPointsFreeStartCrankRocker) {
  // Short: the counter-clockwise sense with 30 starts; long: both senses with 100 starts each.
  const int starts = long_tests() ? 100 : 30;
  const PathSynthesisResult ccw = closed_curve_18(1.0, starts);
  expect_valid_closed_curve_18(ccw, 1.0);
  EXPECT_LE(ccw.error, kPublishedClosedCurve18);
  if (!long_tests()) return;
  EXPECT_LE(ccw.error, 9.03e-3);
  const PathSynthesisResult cw = closed_curve_18(-1.0, starts);
  expect_valid_closed_curve_18(cw, -1.0);
  EXPECT_LE(cw.error, 1.79e-2);  // the clockwise sense fits worse
  EXPECT_LT(ccw.error, cw.error);
}

TEST(PathGenerationBenchmark, HalfCircleInThePublishedBounds) {
  if (!long_tests()) GTEST_SKIP() << "set ORTHOMECH_LONG_TESTS=1 (about 20 s)";
  PathSynthesisOptions o;
  for (int k = 1; k <= 6; ++k) o.crank_angles.push_back(30.0 * k * kDeg);
  // The literature's usual bounds: links [0, 60], A0 and the coupler point ±60.
  o.world_box = world_box(60.0);
  const PathSynthesisResult r60 = synthesize_path_generator(kHalfCircle, o);
  ASSERT_EQ(r60.status, SynthesisStatus::ok) << r60.message;
  expect_valid(r60, kHalfCircle);
  expect_inside(r60.linkage, *o.world_box);
  EXPECT_LE(r60.error, 1.153);
  EXPECT_LE(r60.error, kPublishedHalfCircle);
  // The published run's box (links [0, 50], the rest ±50): still below its 1.2162.
  o.world_box = world_box(50.0);
  const PathSynthesisResult r50 = synthesize_path_generator(kHalfCircle, o);
  ASSERT_EQ(r50.status, SynthesisStatus::ok) << r50.message;
  expect_valid(r50, kHalfCircle);
  expect_inside(r50.linkage, *o.world_box);
  EXPECT_LE(r50.error, 1.2083);
  EXPECT_LE(r50.error, kPublishedHalfCircle);
  // With the crank-rocker required (their constraint) in ±60: 1.159, a genuine crank-rocker.
  o.world_box = world_box(60.0);
  o.require_crank_rocker = true;
  const PathSynthesisResult rc = synthesize_path_generator(kHalfCircle, o);
  ASSERT_EQ(rc.status, SynthesisStatus::ok) << rc.message;
  expect_valid(rc, kHalfCircle);
  EXPECT_EQ(classify_grashof(rc.linkage), GrashofType::crank_rocker);
  EXPECT_LE(rc.error, 1.1591);
  EXPECT_LE(rc.error, kPublishedHalfCircle);
}

// Ten points on an ellipse, free timing, crank-rocker; the first and last targets coincide, so
// the crank turns once (the timing's total is at most one turn).
void expect_valid_ellipse(const PathSynthesisResult& r) {
  ASSERT_EQ(r.status, SynthesisStatus::ok) << r.message;
  expect_valid(r, kEllipse);
  EXPECT_EQ(classify_grashof(r.linkage), GrashofType::crank_rocker);
  EXPECT_TRUE(calc_crank_range(r.linkage).full_turn);
  const double sense = r.crank_angles.back() >= r.crank_angles.front() ? 1.0 : -1.0;
  for (std::size_t i = 1; i < r.crank_angles.size(); ++i)
    EXPECT_GE(sense * (r.crank_angles[i] - r.crank_angles[i - 1]), 0.0);
  EXPECT_LE(std::abs(r.crank_angles.back() - r.crank_angles.front()), 2 * std::numbers::pi + 1e-9);
}

TEST(PathGenerationBenchmark, TenPointsOnAnEllipseUntimed) {
  PathSynthesisOptions o;
  o.timing = PathTiming::free;
  o.require_crank_rocker = true;
  o.world_box = world_box(80.0);  // the published run's bounds
  o.start = PathStart::nearest_point;
  if (!long_tests()) {
    o.starts = 8;  // a short run: 4.549e-4 (not yet the published error)
    const PathSynthesisResult r = synthesize_path_generator(kEllipse, o);
    expect_valid_ellipse(r);
    expect_inside(r.linkage, *o.world_box);
    EXPECT_LE(r.error, 4.6e-4);
    return;
  }
  // The nearest-point start (L25) and curve-distance basin hopping
  // about the four best distinct candidates: 4.0991e-4 for seed 1, below the published 4.2014e-4
  // (their linkage, locally refined, 4.197e-4).
  o.starts = 20;  // curve-distance starts per branch
  o.restarts = 300;
  o.restart_step = 0.05;
  o.restart_candidates = 4;
  const PathSynthesisResult r = synthesize_path_generator(kEllipse, o);
  expect_valid_ellipse(r);
  expect_inside(r.linkage, *o.world_box);
  EXPECT_LE(r.error, 4.2e-4);
  EXPECT_LE(r.error, kPublishedEllipse);
  // A larger box (links up to 12 spreads = 109, outside the published bounds) gives 1.9e-4.
  PathSynthesisOptions big = o;
  big.start = PathStart::quasi_random;
  big.restart_candidates = 1;
  big.world_box.reset();
  big.max_link = big.max_coupler = 12.0;
  big.pivot_box = 6.0;
  big.starts = 100;
  big.polished = 8;
  big.restarts = 0;
  const PathSynthesisResult rb = synthesize_path_generator(kEllipse, big);
  expect_valid_ellipse(rb);
  EXPECT_LE(rb.error, 1.9e-4);
  EXPECT_LE(rb.error, kPublishedEllipse);
}

}  // namespace
}  // namespace orthomech::synthesis
