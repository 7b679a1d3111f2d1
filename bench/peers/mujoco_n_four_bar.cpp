// The N-four-bar (IFToMM A02, mechanisms/n-four-bar-*.yaml) in MuJoCo: the links and couplers as a
// tree of hinges (axis y, the mechanism in the x–z plane, gravity −z), each loop closed by an
// `equality connect` between the right end R of coupler k and the top B of link k + 1. Prints one
// line: N, the setting, CPU time per simulated second, |B0 − exact| at t_end (m, the exact
// one-DOF reduction, nfourbar_reference.hpp) and the largest loop gap seen (m, sampled every
// 0.01 s and at the end).
//   usage: peer_mujoco_n_four_bar N T_END DT euler|rk4 default|tight
// `tight`: solref = (2 dt, 1) (the stiffest time constant MuJoCo takes, critical damping),
// solimp = (0.9999, 0.9999, 0.001): the constraint as hard as MuJoCo's soft model allows.
#include <mujoco/mujoco.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>

#include "mujoco_support.hpp"
#include "nfourbar_reference.hpp"

namespace {

std::string model_xml(int N, double dt, bool rk4, bool tight) {
  std::ostringstream x;
  x.precision(17);
  const double I = 1.0 / 12.0, tiny = 1e-9;  // rod 1 m, 1 kg about its centre; the axial axis
  x << "<mujoco model='n-four-bar'>\n"
    << "  <option timestep='" << dt << "' integrator='" << (rk4 ? "RK4" : "Euler")
    << "' gravity='0 0 -9.81'><flag contact='disable'/></option>\n"
    // Room for every constraint row (3 per connect): MuJoCo's default njmax (1000) would drop
    // the rows beyond it from N = 334 on, with only a warning.
    << "  <size njmax='" << 3 * N + 100 << "'/>\n  <worldbody>\n";
  for (int k = 0; k <= N; ++k) {
    x << "    <body name='link" << k << "' pos='" << k << " 0 0'>\n"
      << "      <joint name='O" << k << "' type='hinge' axis='0 1 0'/>\n"
      << "      <inertial pos='0 0 0.5' mass='1' diaginertia='" << I << " " << I << " " << tiny
      << "'/>\n"
      << "      <site name='B" << k << "' pos='0 0 1'/>\n";
    if (k < N)
      x << "      <body name='coupler" << k << "' pos='0 0 1'>\n"
        << "        <joint name='L" << k << "' type='hinge' axis='0 1 0'/>\n"
        << "        <inertial pos='0.5 0 0' mass='1' diaginertia='" << tiny << " " << I << " " << I
        << "'/>\n"
        << "        <site name='R" << k << "' pos='1 0 0'/>\n      </body>\n";
    x << "    </body>\n";
  }
  x << "  </worldbody>\n  <equality>\n";
  for (int k = 0; k < N; ++k) {
    x << "    <connect body1='coupler" << k << "' body2='link" << k + 1 << "' anchor='1 0 0'";
    if (tight) x << " solref='" << 2 * dt << " 1' solimp='0.9999 0.9999 0.001'";
    x << "/>\n";
  }
  x << "  </equality>\n</mujoco>\n";
  return x.str();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 6) {
    std::fprintf(stderr, "usage: %s N T_END DT euler|rk4 default|tight\n", argv[0]);
    return 2;
  }
  const int N = std::atoi(argv[1]);
  const double t_end = std::atof(argv[2]), dt = std::atof(argv[3]);
  const bool rk4 = std::string(argv[4]) == "rk4", tight = std::string(argv[5]) == "tight";
  mjModel* m = orthomech::peers::load_mjcf(model_xml(N, dt, rk4, tight));
  if (!m) return 2;
  mjData* d = mj_makeData(m);
  // The benchmark's initial velocity: every link at φ̇ = +1 about y (B0 moves at x' = 1 m/s),
  // every coupler at −1 relative to its link (it translates).
  for (int j = 0; j < m->njnt; ++j)
    d->qvel[m->jnt_dofadr[j]] = mj_id2name(m, mjOBJ_JOINT, j)[0] == 'O' ? 1.0 : -1.0;
  mj_forward(m, d);
  int site_b0 = mj_name2id(m, mjOBJ_SITE, "B0");
  const auto gap = [&] {
    double g = 0.0;
    for (int k = 0; k < N; ++k) {
      const int r = mj_name2id(m, mjOBJ_SITE, ("R" + std::to_string(k)).c_str());
      const int b = mj_name2id(m, mjOBJ_SITE, ("B" + std::to_string(k + 1)).c_str());
      g = std::fmax(g, std::hypot(std::hypot(d->site_xpos[3 * r] - d->site_xpos[3 * b],
                                             d->site_xpos[3 * r + 1] - d->site_xpos[3 * b + 1]),
                                  d->site_xpos[3 * r + 2] - d->site_xpos[3 * b + 2]));
    }
    return g;
  };
  const auto [cpu, max_gap] = orthomech::peers::run_timed(m, d, t_end, dt, gap);
  const std::array<double, 2> ref = orthomech::peers::n_four_bar_b0(N, t_end);
  const double err =
      std::hypot(d->site_xpos[3 * site_b0] - ref[0], d->site_xpos[3 * site_b0 + 2] - ref[1]);
  std::printf("mujoco %s N=%d dt=%g %s %s t=%g cpu_per_s=%.4g err=%.2e gap=%.1e\n",
              mj_versionString(), N, dt, rk4 ? "rk4" : "euler", tight ? "tight" : "default",
              d->time, cpu / t_end, err, max_gap);
  mj_deleteData(d);
  mj_deleteModel(m);
  return 0;
}
