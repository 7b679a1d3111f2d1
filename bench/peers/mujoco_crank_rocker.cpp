// The crank-rocker (mechanisms/crank-rocker.yaml) swinging under gravity, in MuJoCo: crank and
// coupler a chain of hinges from the ground pivot A0, the rocker a hinge at B0, the loop closed
// by an `equality connect` at B (the coupler's end, on the rocker's end). The mechanism in the x–z
// plane, hinge axes −y (a positive angle turns +x towards +z, up), gravity −z; uniform rods of
// 1 kg per metre; released at rest at the file's design pose (crank 60°). Prints one line: the
// setting, CPU time per simulated second, |θ − θ_ref| of the crank angle at t_end (rad, against
// crank_rocker_reference.hpp) and the largest loop gap seen (m, sampled every 0.01 s and at the
// end).   usage: peer_mujoco_crank_rocker T_END DT euler|rk4 default|tight
// `tight` as in mujoco_n_four_bar.cpp: solref = (2 dt, 1), solimp = (0.9999, 0.9999, 0.001).
#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>

#include "crank_rocker_reference.hpp"
#include "mujoco_support.hpp"

namespace {

std::string model_xml(const orthomech::peers::CrankRocker& cr, double dt, bool rk4, bool tight) {
  double t3 = 0.0, t4 = 0.0;
  cr.angles(cr.theta0, t3, t4);
  std::ostringstream x;
  x.precision(17);
  const double tiny = 1e-12;                  // the rods' axial inertia
  const auto rod = [&](double m, double L) {  // inertial of a rod along local x from the origin
    const double J = m * L * L / 12.0;
    x << "<inertial pos='" << L / 2 << " 0 0' mass='" << m << "' diaginertia='" << tiny << " " << J
      << " " << J << "'/>";
  };
  x << "<mujoco model='crank-rocker'>\n  <compiler angle='radian'/>\n"
    << "  <option timestep='" << dt << "' integrator='" << (rk4 ? "RK4" : "Euler")
    << "' gravity='0 0 " << -cr.g << "'><flag contact='disable'/></option>\n  <worldbody>\n"
    << "    <body name='crank' pos='0 0 0' axisangle='0 -1 0 " << cr.theta0 << "'>\n"
    << "      <joint name='A0' type='hinge' axis='0 -1 0'/>\n      ";
  rod(cr.m2, cr.a);
  x << "\n      <body name='coupler' pos='" << cr.a << " 0 0' axisangle='0 -1 0 " << t3 - cr.theta0
    << "'>\n        <joint name='A' type='hinge' axis='0 -1 0'/>\n        ";
  rod(cr.m3, cr.b);
  x << "\n        <site name='Bc' pos='" << cr.b << " 0 0'/>\n      </body>\n    </body>\n"
    << "    <body name='rocker' pos='" << cr.d << " 0 0' axisangle='0 -1 0 " << t4 << "'>\n"
    << "      <joint name='B0' type='hinge' axis='0 -1 0'/>\n      ";
  rod(cr.m4, cr.c);
  x << "\n      <site name='Br' pos='" << cr.c << " 0 0'/>\n    </body>\n  </worldbody>\n"
    << "  <equality>\n    <connect body1='coupler' body2='rocker' anchor='" << cr.b << " 0 0'";
  if (tight) x << " solref='" << 2 * dt << " 1' solimp='0.9999 0.9999 0.001'";
  x << "/>\n  </equality>\n</mujoco>\n";
  return x.str();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 5) {
    std::fprintf(stderr, "usage: %s T_END DT euler|rk4 default|tight\n", argv[0]);
    return 2;
  }
  const double t_end = std::atof(argv[1]), dt = std::atof(argv[2]);
  const bool rk4 = std::string(argv[3]) == "rk4", tight = std::string(argv[4]) == "tight";
  const orthomech::peers::CrankRocker cr;
  mjModel* m = orthomech::peers::load_mjcf(model_xml(cr, dt, rk4, tight));
  if (!m) return 2;
  mjData* d = mj_makeData(m);
  mj_forward(m, d);
  const int bc = mj_name2id(m, mjOBJ_SITE, "Bc"), br = mj_name2id(m, mjOBJ_SITE, "Br");
  const int crank = m->jnt_qposadr[mj_name2id(m, mjOBJ_JOINT, "A0")];
  const auto gap = [&] {
    const double* p = d->site_xpos;
    return std::hypot(std::hypot(p[3 * bc] - p[3 * br], p[3 * bc + 1] - p[3 * br + 1]),
                      p[3 * bc + 2] - p[3 * br + 2]);
  };
  const auto [cpu, max_gap] = orthomech::peers::run_timed(m, d, t_end, dt, gap);
  const double err = std::abs(cr.theta0 + d->qpos[crank] - cr.crank_angle(t_end));
  std::printf("mujoco %s crank-rocker dt=%g %s %s t=%g cpu_per_s=%.4g err=%.2e gap=%.1e\n",
              mj_versionString(), dt, rk4 ? "rk4" : "euler", tight ? "tight" : "default", d->time,
              cpu / t_end, err, max_gap);
  mj_deleteData(d);
  mj_deleteModel(m);
  return 0;
}
