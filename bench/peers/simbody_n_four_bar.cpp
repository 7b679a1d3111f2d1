// The N-four-bar (IFToMM A02, mechanisms/n-four-bar-*.yaml) in Simbody: links and couplers as a
// tree of pin mobilizers (rotation about z, the mechanism in the x–y plane, gravity −y), each
// loop closed by two Constraint::PointInPlane (the right end R of coupler k held on the planes
// x = 0 and y = 1 of link k + 1: the point coincidence in the plane, two equations, none
// redundant). Integrated by one of Simbody's error-controlled integrators with its accuracy and
// constraint tolerance set to ACC. Prints one line: N, the setting, CPU time per simulated second,
// |B0 − exact| at t_end (m; nfourbar_reference.hpp), the largest loop gap seen (sampled at the
// start and every 0.01 s), or where and why the integration stopped. CPU time is capped at
// CPU_CAP seconds. The timed loop, the integrators and the stop note: simbody_support.hpp.
// With `ball` the loops are closed by Constraint::Ball instead (three equations, the one along z
// redundant: Simbody's least-squares projection has to cope with it).
//   usage: peer_simbody_n_four_bar N T_END ACC rkm|rkf|rk3|cpodes [CPU_CAP [plane|ball]]
#include <Simbody.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "nfourbar_reference.hpp"
#include "simbody_support.hpp"

using namespace SimTK;

namespace {

// A uniform rod of 1 kg, 1 m along `axis` from the body origin: mass properties about the origin.
MassProperties rod(const Vec3& axis) {
  const Vec3 com = 0.5 * axis;
  const double I = 1.0 / 12.0, tiny = 1e-9;
  const Inertia central(axis[0] != 0 ? tiny : I, axis[1] != 0 ? tiny : I, I);
  return MassProperties(1.0, com, central.shiftFromMassCenter(com, 1.0));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 5) {
    std::fprintf(stderr, "usage: %s N T_END ACC rkm|rkf|rk3|cpodes [CPU_CAP [plane|ball]]\n",
                 argv[0]);
    return 2;
  }
  const int N = std::atoi(argv[1]);
  const double t_end = std::atof(argv[2]), accuracy = std::atof(argv[3]);
  const std::string method = argv[4];
  const double cap = argc > 5 ? std::atof(argv[5]) : 120.0;
  const bool ball = argc > 6 && std::string(argv[6]) == "ball";

  MultibodySystem system;
  SimbodyMatterSubsystem matter(system);
  GeneralForceSubsystem forces(system);
  Force::Gravity gravity(forces, matter, -YAxis, 9.81);
  const Body::Rigid link_body(rod(Vec3(0, 1, 0))), coupler_body(rod(Vec3(1, 0, 0)));
  std::vector<MobilizedBody::Pin> links, couplers;
  for (int k = 0; k <= N; ++k) {
    links.emplace_back(matter.Ground(), Transform(Vec3(k, 0, 0)), link_body, Transform());
    if (k < N)
      couplers.emplace_back(links.back(), Transform(Vec3(0, 1, 0)), coupler_body, Transform());
  }
  for (int k = 0; k < N; ++k) {
    if (ball) {
      Constraint::Ball(couplers[k], Vec3(1, 0, 0), links[k + 1], Vec3(0, 1, 0));
    } else {
      Constraint::PointInPlane(links[k + 1], UnitVec3(XAxis), 0.0, couplers[k], Vec3(1, 0, 0));
      Constraint::PointInPlane(links[k + 1], UnitVec3(YAxis), 1.0, couplers[k], Vec3(1, 0, 0));
    }
  }
  State state = system.realizeTopology();
  // The benchmark's initial velocity: every link at −1 rad/s about z (B0 moves at x' = 1 m/s),
  // every coupler at +1 relative to its link (it translates).
  for (auto& l : links) l.setRate(state, -1.0);
  for (auto& c : couplers) c.setRate(state, 1.0);
  system.realize(state, Stage::Velocity);

  const auto integ = orthomech::peers::make_integrator(system, method, accuracy);
  const auto gap = [&](const State& s) {
    double g = 0.0;
    for (int k = 0; k < N; ++k)
      g = std::max(g, (couplers[k].findStationLocationInGround(s, Vec3(1, 0, 0)) -
                       links[k + 1].findStationLocationInGround(s, Vec3(0, 1, 0)))
                          .norm());
    return g;
  };
  const orthomech::peers::SimbodyRun run =
      orthomech::peers::run_timed(system, *integ, state, t_end, cap, gap);
  const State& s = run.last;
  const double t = s.getTime();
  const Vec3 b0 = links[0].findStationLocationInGround(s, Vec3(0, 1, 0));
  const std::array<double, 2> ref = orthomech::peers::n_four_bar_b0(N, t);
  const double err = std::hypot(b0[0] - ref[0], b0[1] - ref[1]);
  std::printf("simbody %s%s N=%d acc=%g %s t=%g cpu_per_s=%.4g err=%.2e gap=%.1e steps=%d%s\n",
              orthomech::peers::simbody_version().c_str(), ball ? " ball" : "", N, accuracy,
              method.c_str(), t, run.cpu / std::max(t, 1e-12), err, run.max_gap,
              integ->getNumStepsTaken(), orthomech::peers::stop_note(run.stop).c_str());
  return 0;
}
