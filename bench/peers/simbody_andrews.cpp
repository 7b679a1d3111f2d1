// Andrews' squeezing mechanism (test-set problem `andrews`, IFToMM A03;
// mechanisms/andrews-squeezer.yaml) in Simbody, the model of mujoco_andrews.cpp: four chains of
// pin mobilizers from the ground — K1–K2 from O, K3 from B, K5–K4 and K7–K6 from A — with the
// loops closed at E by Constraint::PointInPlane pairs (K2's end E held on the planes x = E_x and
// y = E_y of K3's, K4's and K6's frames, whose intersection is that body's E: two equations per
// loop, six in all for the test set's six multipliers, none redundant; a Constraint::Ball would
// add three equations along z, redundant in the plane). The spring (c0 = 4530 N/m,
// l0 = 0.07785 m) is a Force::TwoPointLinearSpring from K3's point D to the ground point C (the
// force k (l − l0) along the line, the test set's and the MuJoCo tendon's), the drive torque
// mom = 0.033 N·m a Force::MobilityConstantForce on K1's pin. The plane is x–y, pin axes +z, no
// gravity (the test set has none). Every body frame sits at its parent pin at the published
// consistent angles of t = 0, so the pin angles start at 0 and the test set's angles are their
// t = 0 values plus the pin angles (Θ, Φ, Ω: the child's pin, relative to its parent, as in the
// test set). Masses, inertias (about the centre of mass, about z; J/2 about the in-plane axes as
// in the MuJoCo peer, which do not enter the planar motion) and centres of mass are the test
// set's. Integrated by one of Simbody's error-controlled integrators with its accuracy and
// constraint tolerance set to ACC. Prints one line: the setting, CPU time of the stepping per
// simulated second, the largest |angle − reference| over the seven angles at the time reached
// (rad, against the published PSIDE solution at t = 0.03 s, support/andrews_published.hpp; only
// meaningful when t = 0.03), the largest loop gap at E (m, sampled at the start and every
// 0.01 s), the number of steps, or where and why the integration stopped. CPU time is capped at
// CPU_CAP seconds.
//   usage: peer_simbody_andrews rkm|cpodes ACC [CPU_CAP]   (CPU_CAP 120 s)
// (rkf and rk3 are accepted too: simbody_support.hpp.)
#include <Simbody.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "simbody_support.hpp"
#include "support/andrews_published.hpp"

using namespace SimTK;

namespace {

namespace published = orthomech::test::andrews;

constexpr double kTEnd = 0.03;  // s: the test set's interval
constexpr double kTorque = 0.033;
constexpr double kStiffness = 4530.0, kFreeLength = 0.07785;

struct Link {
  double mass, inertia;  // kg, kg·m² about the centre of mass
  double cx, cy;         // centre of mass in the body frame (m)
};
// The test set's masses, inertias and centres of mass (body frames as in the mechanism file).
constexpr Link kK1{0.04325, 2.194e-6, 0.00092, 0.0};
constexpr Link kK2{0.00365, 4.410e-7, -0.0115, 0.0};
constexpr Link kK3{0.02373, 5.255e-6, 0.01043, -0.01874};
constexpr Link kK4{0.00706, 5.667e-7, 0.0, -0.00579};
constexpr Link kK5{0.07050, 1.169e-5, 0.02308, 0.00916};
constexpr Link kK6{0.00706, 5.667e-7, 0.00579, 0.0};
constexpr Link kK7{0.05498, 1.912e-5, 0.00449, -0.01228};

// A body at (px, py) of its parent's frame turned by `angle` about z, with its pin there.
MobilizedBody::Pin pin(MobilizedBody& parent, const Link& l, double px, double py, double angle) {
  const Vec3 com(l.cx, l.cy, 0);
  const double half = 0.5 * l.inertia;
  const Body::Rigid body(
      MassProperties(l.mass, com, Inertia(half, half, l.inertia).shiftFromMassCenter(com, l.mass)));
  return MobilizedBody::Pin(parent, Transform(Rotation(angle, ZAxis), Vec3(px, py, 0)), body,
                            Transform());
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s rkm|cpodes ACC [CPU_CAP]\n", argv[0]);
    return 2;
  }
  const std::string method = argv[1];
  const double accuracy = std::atof(argv[2]);
  const double cap = argc > 3 ? std::atof(argv[3]) : 120.0;
  const auto& a0 = published::kAnglesT0;  // β, Θ, γ, Φ, δ, Ω, ε at t = 0

  MultibodySystem system;
  SimbodyMatterSubsystem matter(system);
  GeneralForceSubsystem forces(system);
  MobilizedBody& ground = matter.updGround();
  MobilizedBody::Pin k1 = pin(ground, kK1, 0.0, 0.0, a0[0]);  // at O, angle β
  MobilizedBody::Pin k2 = pin(k1, kK2, 0.007, 0.0, a0[1]);    // at K1's P, Θ relative to K1
  MobilizedBody::Pin k3 = pin(ground, kK3, -0.03635, 0.03273, a0[2]);   // at B, angle γ
  MobilizedBody::Pin k5 = pin(ground, kK5, -0.06934, -0.00227, a0[4]);  // at A, angle δ
  MobilizedBody::Pin k4 = pin(k5, kK4, 0.04, 0.0, a0[3]);  // at K5's G, Φ relative to K5
  MobilizedBody::Pin k7 = pin(ground, kK7, -0.06934, -0.00227, a0[6]);  // at A, angle ε
  MobilizedBody::Pin k6 = pin(k7, kK6, 0.0, -0.04, a0[5]);  // at K7's H, Ω relative to K7
  // E on K2 and on the three bodies it closes the loops with.
  const Vec3 e2(-0.028, 0, 0);
  const std::array<MobilizedBody::Pin*, 3> closing{&k3, &k4, &k6};
  const std::array<Vec3, 3> e{Vec3(0, -0.035, 0), Vec3(0, -0.02, 0), Vec3(0.02, 0, 0)};
  for (size_t k = 0; k < 3; ++k) {
    Constraint::PointInPlane(*closing[k], UnitVec3(XAxis), e[k][0], k2, e2);
    Constraint::PointInPlane(*closing[k], UnitVec3(YAxis), e[k][1], k2, e2);
  }
  Force::TwoPointLinearSpring(forces, k3, Vec3(0.02, -0.018, 0), ground, Vec3(0.014, 0.072, 0),
                              kStiffness, kFreeLength);
  Force::MobilityConstantForce(forces, k1, kTorque);
  // The start: q = u = 0, the published consistent angles at rest (the test set's velocities at
  // t = 0 are 0). TimeStepper::initialize (run_timed) projects it onto the constraints and
  // changes it only by round-off: the published angles close the loops at E to 8e-18 m; after
  // the projection |Δq| = 5e-16 rad, Δu = 0 (u = 0 satisfies the velocity constraints exactly);
  // system.project at 1e-14 leaves q unchanged (checked once, RK-Merson and CPodes at accuracies
  // 1e-4 and 1e-10).
  State state = system.realizeTopology();
  system.realize(state, Stage::Velocity);

  const auto integ = orthomech::peers::make_integrator(system, method, accuracy);
  const auto gap = [&](const State& s) {
    const Vec3 p = k2.findStationLocationInGround(s, e2);
    double g = 0.0;
    for (size_t k = 0; k < 3; ++k)
      g = std::max(g, (p - closing[k]->findStationLocationInGround(s, e[k])).norm());
    return g;
  };
  const orthomech::peers::SimbodyRun run =
      orthomech::peers::run_timed(system, *integ, state, kTEnd, cap, gap);
  const State& s = run.last;
  // The test set's order β, Θ, γ, Φ, δ, Ω, ε: the pins K1, K2, K3, K4, K5, K6, K7.
  const std::array<const MobilizedBody::Pin*, 7> pins{&k1, &k2, &k3, &k4, &k5, &k6, &k7};
  double err = 0.0;
  for (size_t k = 0; k < 7; ++k)
    err = std::max(err, std::abs(a0[k] + pins[k]->getAngle(s) - published::kAnglesT003[k]));
  const double t = s.getTime();
  std::printf("simbody %s andrews acc=%g %s t=%g cpu_per_s=%.4g err=%.2e gap=%.1e steps=%d%s\n",
              orthomech::peers::simbody_version().c_str(), accuracy, method.c_str(), t,
              run.cpu / std::max(t, 1e-12), err, run.max_gap, integ->getNumStepsTaken(),
              orthomech::peers::stop_note(run.stop).c_str());
  return 0;
}
