// The N-four-bar (IFToMM A02, mechanisms/n-four-bar-*.yaml) in Simbody: links and couplers as a
// tree of pin mobilizers (rotation about z, the mechanism in the x–y plane, gravity −y), each
// loop closed by two Constraint::PointInPlane (the right end R of coupler k held on the planes
// x = 0 and y = 1 of link k + 1: the point coincidence in the plane, two equations, none
// redundant). Integrated by one of Simbody's error-controlled integrators with its accuracy and
// constraint tolerance set to ACC. Prints one line: N, the setting, CPU time per simulated second,
// |B0 − exact| at t_end (m; nfourbar_reference.hpp), the largest loop gap seen (sampled every
// 0.01 s), or where and why the integration stopped. CPU time is capped at CPU_CAP seconds.
// With `ball` the loops are closed by Constraint::Ball instead (three equations, the one along z
// redundant: Simbody's least-squares projection has to cope with it).
//   usage: peer_simbody_n_four_bar N T_END ACC rkm|rkf|rk3|cpodes [CPU_CAP [plane|ball]]
#include <Simbody.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <memory>
#include <string>
#include <vector>

#include "nfourbar_reference.hpp"

using namespace SimTK;

namespace {

double cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

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

  std::unique_ptr<Integrator> integ;
  if (method == "rkm")
    integ = std::make_unique<RungeKuttaMersonIntegrator>(system);
  else if (method == "rkf")
    integ = std::make_unique<RungeKuttaFeldbergIntegrator>(system);
  else if (method == "rk3")
    integ = std::make_unique<RungeKutta3Integrator>(system);
  else
    integ = std::make_unique<CPodesIntegrator>(system);
  integ->setAccuracy(accuracy);
  integ->setConstraintTolerance(accuracy);
  TimeStepper ts(system, *integ);
  ts.initialize(state);

  const auto gap = [&](const State& s) {
    double g = 0.0;
    for (int k = 0; k < N; ++k)
      g = std::max(g, (couplers[k].findStationLocationInGround(s, Vec3(1, 0, 0)) -
                       links[k + 1].findStationLocationInGround(s, Vec3(0, 1, 0)))
                          .norm());
    return g;
  };
  double max_gap = 0.0, cpu = 0.0;
  std::string stop;
  State last = ts.getState();  // the last state reached (after a failure: the one before it)
  const int samples = static_cast<int>(std::lround(t_end / 0.01));
  for (int i = 1; i <= samples && stop.empty(); ++i) {
    const double c0 = cpu_seconds();
    try {
      ts.stepTo(t_end * i / samples);
      last = ts.getState();
    } catch (const std::exception& e) {
      stop = std::string("integrator failure: ") + e.what();
    }
    cpu += cpu_seconds() - c0;
    system.realize(last, Stage::Position);
    max_gap = std::max(max_gap, gap(last));
    if (cpu > cap && stop.empty()) stop = "CPU cap reached";
  }
  const State& s = last;
  const double t = s.getTime();
  const Vec3 b0 = links[0].findStationLocationInGround(s, Vec3(0, 1, 0));
  const std::array<double, 2> ref = orthomech::peers::n_four_bar_b0(N, t);
  const double err = std::hypot(b0[0] - ref[0], b0[1] - ref[1]);
  // The exception's text: its last non-empty line (Simbody nests "thrown at FILE:LINE" blocks;
  // the innermost reason comes last); the whole text on stderr.
  std::string first;
  if (!stop.empty()) {
    std::fprintf(stderr, "%s\n", stop.c_str());
    size_t end = stop.find_last_not_of(" \n");
    const size_t begin = stop.rfind('\n', end);
    first = stop.substr(begin == std::string::npos ? 0 : begin + 1, end - begin);
    first = first.substr(first.find_first_not_of(' '));
    if (const size_t u = stop.find("Unable to"); u != std::string::npos)
      first = stop.substr(u, stop.find('\n', u) - u);  // "Unable to advance time past 2.68212."
    if (stop.rfind("integrator failure", 0) == 0) first = "integrator failure: " + first;
  }
  std::printf("simbody %s%s N=%d acc=%g %s t=%g cpu_per_s=%.4g err=%.2e gap=%.1e steps=%d%s%s\n",
              "3.7", ball ? " ball" : "", N, accuracy, method.c_str(), t, cpu / std::max(t, 1e-12),
              err, max_gap, integ->getNumStepsTaken(),
              stop.empty() ? "" : " STOP: ", first.c_str());
  return 0;
}
