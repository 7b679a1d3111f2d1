// `cycle` with an idle degree of freedom held at zero rate (issue 13 item 1; docs/spatial.md §4.1,
// §6.5): the RSSR of mechanisms/rssr.yaml with joint B spherical (an S–S coupler whose spin about
// AB moves no other body: DOF 2, one idle). Independent oracles:
//  - the universal-joint file (no idle spin) with the coupler's axial inertia J_a extrapolated to
//    zero: its drive and reactions are linear in J_a for the same motion (its kinematics do not
//    depend on inertia), so 2·X(J_a) − X(2 J_a) is X at J_a = 0, which is what the S–S coupler
//    with its spin held at zero gives (no axial term), whatever its own J_a;
//  - the closed form (M1) for the rocker angle;
//  - power balance: drive power = d/dt (T + V), from the bodies' data;
//  - the held spin: the coupler's body-x angular velocity (along AB) is 0; with its centre of
//    mass off AB the hold is vᵀM u = 0 for the spin v written in the test, u̇ equals central
//    differences of u over the time grid (the İ u term), and the holding torque equals Euler's
//    equation about AB written in the test.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numbers>
#include <string>

#include "orthomech/analysis/cycle.hpp"
#include "orthomech/analysis/mobility.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/model/spatial.hpp"
#include "orthomech/projection/workspace.hpp"
#include "support/cli_runner.hpp"
#include "support/fixtures.hpp"
#include "support/spatial_energy.hpp"
#include "support/spatial_oracles.hpp"

namespace orthomech {
namespace {

constexpr double kPi = std::numbers::pi;

using test::full_cycle;
using test::measure_index;

const Body& body(const Model& m, const char* name) {
  return m.bodies[static_cast<size_t>(m.find_body(name))];
}

// The bundled RSSR, joint B spherical (S–S coupler) if `spherical`, the coupler's axial (body x,
// along AB) inertia set to `axial` kg·m².
Model rssr(bool spherical, double axial) {
  Model m = test::load_bundled("rssr");
  if (spherical)
    std::get<SpatialJoint>(m.joints[static_cast<size_t>(m.find_joint("B"))].kind).type =
        SpatialJointType::spherical;
  m.bodies[static_cast<size_t>(m.find_body("coupler"))].spatial.inertia(0, 0) = axial;
  finalize_model(m);
  return m;
}

using test::rssr_rocker_angle;  // docs/spatial.md (M1), the file's branch

TEST(SpatialIdleCycle, SsCouplerIsDrivenWithItsSpinHeld) {
  const Model m = rssr(true, 1e-6);
  const Mobility mob = compute_mobility(m, test::assembled_q(m));
  ASSERT_EQ(mob.dof, 2);
  ASSERT_EQ(mob.idle.size(), 1u);
  // The shared idle motion: the coupler's spin about AB (its body x), at unit rate.
  const MatX V = idle_motions(m, test::assembled_q(m), idle_body_indices(m, mob));
  ASSERT_EQ(V.cols(), 1);
  const int c = body(m, "coupler").u_offset;
  EXPECT_NEAR(std::abs(V(c + 3, 0)), 1.0, 1e-12);
  EXPECT_NEAR(V.norm(), 1.0, 1e-12);  // com on AB: no translation
  const CycleResult r = full_cycle(m, 360);
  ASSERT_EQ(r.status, CycleStatus::completed) << r.message;
  ASSERT_EQ(r.points.size(), 360u);
  EXPECT_EQ(r.dof, 2);
  ASSERT_EQ(r.idle.size(), 1u);
  EXPECT_EQ(r.idle[0].body, "coupler");
  EXPECT_TRUE(r.dead_points.empty());
  EXPECT_TRUE(r.warnings.empty()) << r.warnings.front();
  const size_t crank = measure_index(m, "crank_angle"), rocker = measure_index(m, "rocker_angle");
  double drive_peak = 0.0, worst_angle = 0.0, worst_spin = 0.0, worst_spin_rate = 0.0;
  double wdot_peak = 0.0;
  for (const DrivenPointView& p : r.points) {
    drive_peak = std::max(drive_peak, std::abs(p.drive));
    worst_angle = std::max(
        worst_angle, std::abs(std::remainder(
                         p.measures[rocker] - rssr_rocker_angle(p.measures[crank]), 2 * kPi)));
    const Vec3 w = p.u.segment<3>(c + 3), wdot = p.udot.segment<3>(c + 3);
    worst_spin = std::max(worst_spin, std::abs(w.x()) / w.norm());
    worst_spin_rate = std::max(worst_spin_rate, std::abs(wdot.x()));
    wdot_peak = std::max(wdot_peak, wdot.norm());
  }
  EXPECT_LT(worst_angle, 1e-10);
  // The spin about AB is held at zero (the held row carries rounding of ~1e-12) and stays there
  // (İ u to ~1e-8; see the off-axis test).
  EXPECT_LT(worst_spin, 1e-11);
  EXPECT_LT(worst_spin_rate, 1e-7 * wdot_peak);
  EXPECT_LT(r.idle_hold_peak, 1e-10 * drive_peak);  // holding it takes no torque
}

TEST(SpatialIdleCycle, SsCouplerEqualsTheUniversalFileAtZeroAxialInertia) {
  constexpr double Ja = 1e-6;  // kg·m², the file's
  const CycleResult u1 = full_cycle(rssr(false, Ja), 120);
  const CycleResult u2 = full_cycle(rssr(false, 2 * Ja), 120);
  ASSERT_EQ(u1.status, CycleStatus::completed) << u1.message;
  ASSERT_EQ(u2.status, CycleStatus::completed) << u2.message;
  ASSERT_EQ(u1.components.size(), u2.components.size());
  // J_a matters in the universal file (its coupler spins): the comparison can fail.
  double drive_peak = 0.0, axial_effect = 0.0;
  for (size_t k = 0; k < u1.points.size(); ++k) {
    drive_peak = std::max(drive_peak, std::abs(u1.points[k].drive));
    axial_effect = std::max(axial_effect, std::abs(u1.points[k].drive - u2.points[k].drive));
  }
  EXPECT_GT(axial_effect, 1e-5 * drive_peak);
  for (const double axial : {Ja, 5 * Ja}) {  // the S–S result does not depend on J_a
    const Model m = rssr(true, axial);
    const size_t rocker = measure_index(m, "rocker_angle");
    const CycleResult s = full_cycle(m, 120);
    ASSERT_EQ(s.status, CycleStatus::completed) << s.message;
    ASSERT_EQ(s.points.size(), u1.points.size());
    ASSERT_EQ(s.components.size(), u1.components.size());
    double force_peak = 0.0, moment_peak = 0.0;
    for (const DrivenPointView& p : u1.points)
      for (size_t i = 0; i < u1.components.size(); ++i)
        (u1.components[i].unit == "N" ? force_peak : moment_peak) = std::max(
            u1.components[i].unit == "N" ? force_peak : moment_peak, std::abs(p.reactions[i]));
    for (size_t k = 0; k < s.points.size(); ++k) {
      const DrivenPointView a = u1.points[k], b = u2.points[k], p = s.points[k];
      ASSERT_NEAR(p.input, a.input, 1e-12);
      EXPECT_NEAR(p.measures[rocker], a.measures[rocker], 1e-11) << "rocker angle at " << p.input;
      EXPECT_NEAR(p.drive, 2 * a.drive - b.drive, 1e-10 * drive_peak) << "at " << p.input;
      for (size_t i = 0; i < s.components.size(); ++i) {
        ASSERT_EQ(s.components[i].name, u1.components[i].name);
        // World components (the joint frames of a spherical and a universal joint differ).
        if (!s.components[i].global) continue;
        const double scale = s.components[i].unit == "N" ? force_peak : moment_peak;
        EXPECT_NEAR(p.reactions[i], 2 * a.reactions[i] - b.reactions[i], 1e-9 * scale)
            << s.components[i].name << " at " << p.input << " (J_a " << axial << ")";
      }
    }
  }
}

TEST(SpatialIdleCycle, PowerBalanceWithTheSpinHeld) {
  const Model m = rssr(true, 1e-6);
  const CycleResult r = full_cycle(m, 180);
  ASSERT_EQ(r.status, CycleStatus::completed) << r.message;
  double scale = 0.0, worst = 0.0;
  for (const DrivenPointView& p : r.points) {
    const double drive_power = p.drive * p.input_rate;
    scale = std::max(scale, std::abs(drive_power));
    worst =
        std::max(worst, std::abs(drive_power - test::spatial_energy_rate(m, p, Vec3(0, 0, -9.81))));
  }
  EXPECT_GT(scale, 1.0);
  EXPECT_LT(worst, 1e-6 * scale);
  // By differences of the reported energies over the time grid (second order in the step).
  for (size_t k = 1; k + 1 < r.points.size(); ++k) {
    const DrivenPointView a = r.points[k - 1], b = r.points[k + 1], c = r.points[k];
    const double dE = (b.kinetic + b.potential - a.kinetic - a.potential) / (b.time - a.time);
    EXPECT_NEAR(dE, c.drive * c.input_rate, 1e-2 * scale) << "at " << c.input;
  }
}

// The coupler's centre of mass 30 mm off AB: its spin about AB is still idle kinematically, but
// the held row vᵀM depends on q (v has a translation R(e × (c − A)) that turns with the coupler),
// so İ u enters the accelerations, and holding the spin takes a torque (gravity and inertia about
// AB): reported, with a warning, and not as a joint reaction.
TEST(SpatialIdleCycle, OffAxisCouplerHoldsItsSpinWithTheRowsRate) {
  std::string text = test::read_text(test::bundled_file("rssr"));
  auto replace = [&text](const std::string& from, const std::string& to) {
    const size_t at = text.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    text.replace(at, from.size(), to);
  };
  replace("type: universal, connects: [coupler.B, rocker.B], axes: [[0, 0, 1], [0, 0, 1]]",
          "type: spherical, connects: [coupler.B, rocker.B]");
  replace("com: [210, 0, 0]", "com: [210, 30, 0]");
  const Model m = parse_mechanism(text, "rssr-off-axis.yaml");
  constexpr int kSteps = 360;
  const CycleResult r = full_cycle(m, kSteps);
  ASSERT_EQ(r.status, CycleStatus::completed) << r.message;
  ASSERT_EQ(r.idle.size(), 1u);
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("idle motion of 'coupler'"), std::string::npos) << r.warnings[0];
  const Body& cb = body(m, "coupler");
  const int c = cb.u_offset;
  // Joint A's point on the coupler (from its centre of mass, body frame).
  const auto& A = std::get<SpatialJoint>(m.joints[static_cast<size_t>(m.find_joint("A"))].kind);
  ASSERT_EQ(A.pj.body, m.find_body("coupler"));
  const Vec3 sA = A.pj.s;
  ASSERT_GT(sA.cross(Vec3::UnitX()).norm(), 0.029);  // the centre of mass is off AB
  const Vec3 g(0, 0, -9.81);
  double udot_peak = 0.0, hold_peak = 0.0, worst_fd = 0.0, worst_row = 0.0;
  double worst_spin_fd = 0.0;
  for (const DrivenPointView& p : r.points) udot_peak = std::max(udot_peak, p.udot.norm());
  for (size_t k = 0; k < r.points.size(); ++k) {
    const DrivenPointView p = r.points[k];
    const Mat3 R = spatial_frame(m, m.find_body("coupler"), p.q, nullptr).R;
    // The spin about AB at unit rate: ω = e_x (body), v = ω × (r_c − r_A) = R (e_x × −s_A).
    const Vec3 v_spin = R * Vec3::UnitX().cross(-sA);
    const Vec3 v = p.u.segment<3>(c), w = p.u.segment<3>(c + 3);
    const double row = cb.mass * v_spin.dot(v) + Vec3::UnitX().dot(cb.spatial.inertia * w);
    const double row_scale =
        cb.mass * v_spin.norm() * v.norm() + cb.spatial.inertia.norm() * w.norm();
    worst_row = std::max(worst_row, std::abs(row) / row_scale);
    // Euler's equation about AB: the torque that holds the spin, e · [(r_c − r_A) × m (a − g) +
    // R (J ω̇ + ω × J ω)] (the spherical joints exert no moment about the line through them).
    const Vec3 a = p.udot.segment<3>(c), wdot = p.udot.segment<3>(c + 3);
    const Vec3 e = R.col(0), rc_rA = -(R * sA);
    const double hold = e.dot(rc_rA.cross(cb.mass * (a - g)) +
                              R * (cb.spatial.inertia * wdot + w.cross(cb.spatial.inertia * w)));
    EXPECT_NEAR(std::abs(p.idle_hold), std::abs(hold), 1e-9 * (1.0 + std::abs(hold)));
    hold_peak = std::max(hold_peak, std::abs(hold));
    // u̇ against the derivative of the velocity field along the motion: the held trajectory has
    // q̇ = u(q) (constant speed: u depends on q only), so u̇ = lim (u(q ⊕ δu) − u(q ⊕ −δu)) / 2δ,
    // u(·) from compute_driven (whose velocities are checked against the row above). Off
    // f(q) = 0 by O(δ²) on both sides alike: the difference is second order in δ.
    if (k % 100 != 0) continue;
    VecX ud = VecX::Zero(m.n);
    constexpr double delta = 1e-5;  // s: 6e-5 rad of the crank
    for (const double sign : {1.0, -1.0}) {
      State st(m);
      st.q = p.q;
      integrate_positions(m, st.q, VecX(p.u), sign * delta);
      Workspace ws(m, r.rank);
      DrivenWorkspace dw(m, r.rank, {m.find_body("coupler")});
      DrivenPoint at;
      ASSERT_TRUE(compute_driven(m, m.drivers[0].joint, p.input_rate, 0.0, st, ws, dw, at));
      ud += sign * at.u / (2 * delta);
    }
    worst_fd = std::max(worst_fd, (ud - p.udot).cwiseAbs().maxCoeff());
    worst_spin_fd = std::max(worst_spin_fd, std::abs(ud(c + 3) - p.udot(c + 3)));
  }
  EXPECT_LT(worst_row, 1e-12);
  EXPECT_LT(worst_fd, 1e-6 * udot_peak) << worst_fd / udot_peak;
  EXPECT_LT(worst_spin_fd, 1e-6 * udot_peak) << worst_spin_fd / udot_peak;
  EXPECT_GT(hold_peak, 1e-3);  // N·m: far from idle dynamically
  EXPECT_NEAR(r.idle_hold_peak, hold_peak, 1e-9 * hold_peak);
}

// With the crank's joint cylindrical (it may also slide) the S–S RSSR has DOF 3: one idle, two
// to drive. The refusal counts them.
TEST(SpatialIdleCycle, RefusalCountsTheIdleDegreesOfFreedom) {
  Model m = rssr(true, 1e-6);
  std::get<SpatialJoint>(m.joints[static_cast<size_t>(m.find_joint("A0"))].kind).type =
      SpatialJointType::cylindrical;
  finalize_model(m);
  const CycleResult r = full_cycle(m, 36);
  EXPECT_EQ(r.status, CycleStatus::failed);
  EXPECT_EQ(r.dof, 3);
  ASSERT_EQ(r.idle.size(), 1u);
  EXPECT_EQ(r.message,
            "a single driver needs a mechanism with 1 DOF; this one has 3 (1 idle, held at zero "
            "rate: 2 to drive) (drive every degree of freedom: cycle --drivers A,B,…)");
}

TEST(SpatialIdleCycle, CliSaysTheIdleSpinIsHeld) {
  std::string text = test::read_text(test::bundled_file("rssr"));
  const std::string from =
      "type: universal, connects: [coupler.B, rocker.B], axes: [[0, 0, 1], [0, 0, 1]]";
  const size_t at = text.find(from);
  ASSERT_NE(at, std::string::npos);
  text.replace(at, from.size(), "type: spherical, connects: [coupler.B, rocker.B]");
  const test::TempDir dir("orthomech_idle_cycle_");
  const std::string file = (dir.path / "rssr-ss.yaml").string();
  { std::ofstream(file) << text; }
  const test::CliResult r = test::run_cli({"cycle", file, "--steps", "36", "-v"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("idle degrees of freedom held at zero rate"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("body 'coupler' (1 direction)"), std::string::npos) << r.err;
  EXPECT_NE(r.out.find("dead points     none"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("status          completed"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("mobility        DOF 2 (1 idle, held at zero rate), rank of E 16"),
            std::string::npos)
      << r.out;
}

}  // namespace
}  // namespace orthomech
