// Where a cycle starts (issue 11 item 1): `--from X` reaches X by continuation along the design
// position's branch, so that the sweep from X equals the full cycle at X (same assembly mode,
// every angle unwrapped continuously); the initial projection holds the driven joint at its drawn
// value and names the bodies it had to move.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

#include "orthomech/analysis/cycle.hpp"
#include "support/fixtures.hpp"

namespace orthomech {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;

// Both sweeps converge every position to a few ulps of its coordinates (the corrector's
// tolerance, 1e-14 relative); the same branch point reached along two paths agrees to that,
// amplified by the conditioning of the position problem (away from change points, < 1e3).
constexpr double kSamePosition = 1e-10;

// The first position of the sweep from X against the full cycle's position at X, for X every 10°
// around the turn. The full cycles (36 steps from the design input 60°) contain every X exactly.
// On the triple-crank the starts at 0° and 180° are change points: both sweeps take their values
// there from the branch (bridged), and agree.
TEST(CycleStart, FromXEqualsTheFullCycleAtX) {
  for (const char* name : {"crank-rocker", "triple-crank"}) {
    const Model model = test::load_bundled(name);
    CycleOptions full_options;
    full_options.driver = model.drivers.at(0);
    full_options.steps = 36;
    const CycleResult full = run_cycle(model, full_options);
    ASSERT_EQ(full.status, CycleStatus::completed) << name << ": " << full.message;
    for (int degrees = 0; degrees < 360; degrees += 10) {
      const double X = degrees * kDeg;
      CycleOptions o = full_options;
      o.use_start = true;
      o.start = X;
      const CycleResult r = run_cycle(model, o);
      ASSERT_EQ(r.status, CycleStatus::completed) << name << " " << degrees << ": " << r.message;
      ASSERT_FALSE(r.points.empty());
      const DrivenPointView first = r.points[0];
      if (std::string(name) == "triple-crank" && degrees % 180 == 0) {
        EXPECT_TRUE(first.singular) << degrees;
        EXPECT_GE(first.bridge, 0) << degrees;
      }
      // The full cycle's position whose input is X modulo a turn.
      long k = -1;
      for (size_t i = 0; i < full.points.size(); ++i)
        if (std::abs(std::remainder(full.points[i].input - X, 2.0 * kPi)) < 1e-9)
          k = static_cast<long>(i);
      ASSERT_GE(k, 0) << degrees;
      const DrivenPointView at = full.points[static_cast<size_t>(k)];
      EXPECT_NEAR(first.input, at.input, 1e-12) << name << " " << degrees;
      EXPECT_LE((first.q - at.q).cwiseAbs().maxCoeff(), kSamePosition) << name << " " << degrees;
      for (size_t m = 0; m < model.measures.size(); ++m)
        EXPECT_NEAR(first.measures[m], at.measures[m],
                    kSamePosition * (1.0 + std::abs(at.measures[m])))
            << name << " " << degrees << " " << model.measures[m].name;
      // And the sweep goes on as the full cycle does: its drive RMS over the same turn.
      const auto rs = summarize_cycle(r, reaction_magnitudes(r), "N*m");
      const auto fs = summarize_cycle(full, reaction_magnitudes(full), "N*m");
      EXPECT_NEAR(rs[0].rms, fs[0].rms, 1e-9 * fs[0].rms) << name << " " << degrees;
    }
  }
}

// A sketched design pose (coupler and rocker angles off by a few degrees, as a designer's
// drawing): the projection keeps the crank at its drawn 60° and closes the loop with the other
// bodies, in the drawn assembly mode; both moved bodies are named. Oracle: the crank-rocker's
// closed position at crank 60°, B the upper intersection of the circles of radius b = 80 mm about
// A = a(cos 60°, sin 60°) and c = 60 mm about B0 = (70, 0) mm.
TEST(CycleStart, TheDesignPositionKeepsTheDrivenJointAsDrawn) {
  Model model = test::load_bundled("crank-rocker");
  const int coupler = model.find_body("coupler"), rocker = model.find_body("rocker");
  model.bodies[static_cast<size_t>(coupler)].design_pose.z() += 2.0 * kDeg;
  model.bodies[static_cast<size_t>(rocker)].design_pose.z() -= 3.0 * kDeg;
  CycleOptions o;
  o.driver = model.drivers.at(0);
  o.steps = 36;
  const CycleResult r = run_cycle(model, o);
  ASSERT_EQ(r.status, CycleStatus::completed) << r.message;
  const DrivenPointView p = r.points[0];
  EXPECT_NEAR(p.input, 60.0 * kDeg, 1e-12);  // held at its drawn value
  // Closed form of B.
  const double a = 0.030, b = 0.080, c = 0.060, g = 0.070;
  const double Ax = a * std::cos(60.0 * kDeg), Ay = a * std::sin(60.0 * kDeg);
  const double dx = g - Ax, dy = -Ay, d = std::hypot(dx, dy);
  const double along = (b * b - c * c + d * d) / (2.0 * d),
               across = std::sqrt(b * b - along * along);
  const double ex = dx / d, ey = dy / d;
  const double Bx = Ax + along * ex - across * ey, By = Ay + along * ey + across * ex;
  const double coupler_angle = std::atan2(By - Ay, Bx - Ax);
  const double rocker_angle = std::atan2(By, Bx - g);
  const auto& q = p.q;
  EXPECT_NEAR(q(model.bodies[static_cast<size_t>(coupler)].q_offset + 2), coupler_angle, 1e-12);
  EXPECT_NEAR(q(model.bodies[static_cast<size_t>(rocker)].q_offset + 2), rocker_angle, 1e-12);
  // The two bodies that had to move are named, the crank is not.
  ASSERT_EQ(r.start_moves.size(), 2u);
  EXPECT_EQ(r.start_moves[0].body, "coupler");
  EXPECT_EQ(r.start_moves[1].body, "rocker");
  EXPECT_NEAR(r.start_moves[0].angle, 2.0 * kDeg, 1e-9);
  EXPECT_NEAR(r.start_moves[1].angle, 3.0 * kDeg, 1e-9);
  ASSERT_EQ(r.warnings.size(), 2u);
  EXPECT_NE(r.warnings[0].find("body 'coupler' moved by"), std::string::npos) << r.warnings[0];
  EXPECT_NE(r.warnings[0].find("2 deg"), std::string::npos) << r.warnings[0];
  // In the file's declared units: the same model declared in SI says radians (2° = 0.034907 rad).
  Model si = model;
  si.units = DeclaredUnits{};
  const CycleResult r_si = run_cycle(si, o);
  ASSERT_EQ(r_si.warnings.size(), 2u);
  EXPECT_NE(r_si.warnings[0].find("0.034907 rad"), std::string::npos) << r_si.warnings[0];
  EXPECT_EQ(r_si.warnings[0].find("deg"), std::string::npos) << r_si.warnings[0];
  // The file as drawn closes: nothing is said.
  const CycleResult clean = run_cycle(test::load_bundled("crank-rocker"), o);
  EXPECT_TRUE(clean.warnings.empty());
  EXPECT_TRUE(clean.start_moves.empty());
}

}  // namespace
}  // namespace orthomech
