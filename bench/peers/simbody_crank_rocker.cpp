// The crank-rocker (mechanisms/crank-rocker.yaml) swinging under gravity, in Simbody: crank and
// coupler a chain of pin mobilizers from the ground pivot A0, the rocker a pin at B0, the loop
// closed at B by two Constraint::PointInPlane (the coupler's end B held on the planes x = c and
// y = 0 of the rocker's frame, whose intersection is the rocker's end: the point coincidence in
// the plane, two equations, none redundant, as in simbody_n_four_bar.cpp; a Constraint::Ball
// would add the equation along z, redundant in a planar mechanism). The mechanism in the x–y
// plane, pin axes +z (a positive angle turns +x towards +y), gravity −y: the plane of the
// mechanism file and of crank_rocker_reference.hpp (mujoco_crank_rocker.cpp's x–z plane, axes −y,
// gravity −z is the same model turned about x). Uniform rods of 1 kg per metre as in
// mujoco_crank_rocker.cpp: mass m, centre of mass at mid-length, m L²/12 about the centre across
// the rod, 1e-12 kg·m² along it. Every body frame sits at its pin at the design pose (crank 60°,
// open assembly), so the pin angles start at 0 and the crank angle is θ0 + q; released at rest.
// Integrated by one of Simbody's error-controlled integrators with its accuracy and constraint
// tolerance set to ACC. Prints one line: the setting, CPU time of the stepping per simulated
// second, |θ − θ_ref| of the crank angle at the time reached (rad, against
// crank_rocker_reference.hpp), the largest loop gap at B seen (m, sampled at the start and every
// 0.01 s), the number of steps, or where and why the integration stopped. CPU time is capped at
// CPU_CAP seconds.
//   usage: peer_simbody_crank_rocker rkm|cpodes ACC [T_END [CPU_CAP]]   (T_END 10 s, CPU_CAP 120)
// (rkf and rk3 are accepted too: simbody_support.hpp.)
#include <Simbody.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "crank_rocker_reference.hpp"
#include "simbody_support.hpp"

using namespace SimTK;

namespace {

// A uniform rod of mass m and length L along the body's x axis from its origin: mass properties
// about the origin.
MassProperties rod(double m, double L) {
  const Vec3 com(0.5 * L, 0, 0);
  const double J = m * L * L / 12.0, tiny = 1e-12;
  return MassProperties(m, com, Inertia(tiny, J, J).shiftFromMassCenter(com, m));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s rkm|cpodes ACC [T_END [CPU_CAP]]\n", argv[0]);
    return 2;
  }
  const std::string method = argv[1];
  const double accuracy = std::atof(argv[2]);
  const double t_end = argc > 3 ? std::atof(argv[3]) : 10.0;
  const double cap = argc > 4 ? std::atof(argv[4]) : 120.0;
  const orthomech::peers::CrankRocker cr;
  double t3 = 0.0, t4 = 0.0;  // coupler and rocker angles at the design pose
  cr.angles(cr.theta0, t3, t4);

  MultibodySystem system;
  SimbodyMatterSubsystem matter(system);
  GeneralForceSubsystem forces(system);
  Force::Gravity gravity(forces, matter, -YAxis, cr.g);
  MobilizedBody::Pin crank(matter.Ground(), Transform(Rotation(cr.theta0, ZAxis), Vec3(0)),
                           Body::Rigid(rod(cr.m2, cr.a)), Transform());
  MobilizedBody::Pin coupler(crank, Transform(Rotation(t3 - cr.theta0, ZAxis), Vec3(cr.a, 0, 0)),
                             Body::Rigid(rod(cr.m3, cr.b)), Transform());
  MobilizedBody::Pin rocker(matter.Ground(), Transform(Rotation(t4, ZAxis), Vec3(cr.d, 0, 0)),
                            Body::Rigid(rod(cr.m4, cr.c)), Transform());
  const Vec3 b_coupler(cr.b, 0, 0), b_rocker(cr.c, 0, 0);
  Constraint::PointInPlane(rocker, UnitVec3(XAxis), cr.c, coupler, b_coupler);
  Constraint::PointInPlane(rocker, UnitVec3(YAxis), 0.0, coupler, b_coupler);
  // The start: q = u = 0, the design pose at rest. TimeStepper::initialize (run_timed) projects
  // it onto the constraints and changes it only by round-off: the pose closes B to 7e-18 m (the
  // angles in closed form); after the projection |Δq| = 4e-16 rad, Δu = 0 (u = 0 satisfies the
  // velocity constraints exactly); system.project at 1e-14 leaves q unchanged (checked once, at
  // accuracies 1e-4 and 1e-10).
  State state = system.realizeTopology();
  system.realize(state, Stage::Velocity);

  const auto integ = orthomech::peers::make_integrator(system, method, accuracy);
  const auto gap = [&](const State& s) {
    return (coupler.findStationLocationInGround(s, b_coupler) -
            rocker.findStationLocationInGround(s, b_rocker))
        .norm();
  };
  const orthomech::peers::SimbodyRun run =
      orthomech::peers::run_timed(system, *integ, state, t_end, cap, gap);
  const double t = run.last.getTime();
  const double err = std::abs(cr.theta0 + crank.getAngle(run.last) - cr.crank_angle(t));
  std::printf(
      "simbody %s crank-rocker acc=%g %s t=%g cpu_per_s=%.4g err=%.2e gap=%.1e steps=%d%s\n",
      orthomech::peers::simbody_version().c_str(), accuracy, method.c_str(), t,
      run.cpu / std::max(t, 1e-12), err, run.max_gap, integ->getNumStepsTaken(),
      orthomech::peers::stop_note(run.stop).c_str());
  return 0;
}
