// Andrews' squeezing mechanism (test-set problem `andrews`, IFToMM A03;
// mechanisms/andrews-squeezer.yaml) in MuJoCo: four hinge chains from the ground — K1–K2 from O,
// K3 from B, K5–K4 and K7–K6 from A — with the loops closed by three `equality connect`s at E
// (K2's end on K3's, K4's and K6's), the spring (c0 = 4530 N/m, l0 = 0.07785 m) a spatial tendon
// from K3's point D to the ground point C, the drive torque mom = 0.033 N·m applied to K1's hinge
// (qfrc_applied). The plane is x–y, hinge axes +z, no gravity (the test set has none). Every body
// frame sits at its parent hinge at the published consistent angles of t = 0, so the hinge
// angles start at 0 and the test set's angles are their t = 0 values plus the hinge angles
// (Θ, Φ, Ω: the child's hinge, relative to its parent, as in the test set). Data: the test set's
// (as in the mechanism file). Prints one line: the setting, CPU time of the stepping loop per
// simulated second, the largest |angle − reference| over the seven angles at t = 0.03 s (rad,
// against the published PSIDE solution, support/andrews_published.hpp) and the largest loop gap
// at E (m, sampled every 0.01 s and at the end).
//   usage: peer_mujoco_andrews DT euler|rk4 default|tight
// `tight` as in mujoco_n_four_bar.cpp: solref = (2 dt, 1), solimp = (0.9999, 0.9999, 0.001).
#include <mujoco/mujoco.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>

#include "mujoco_support.hpp"
#include "support/andrews_published.hpp"

namespace {

namespace published = orthomech::test::andrews;

constexpr double kTEnd = 0.03;  // s: the test set's interval
constexpr double kTorque = 0.033;

struct Link {
  const char* name;
  double mass, inertia;  // kg, kg·m² about the centre of mass
  double cx, cy;         // centre of mass in the body frame (m)
};
// The test set's masses, inertias and centres of mass (body frames as in the mechanism file).
constexpr Link kK1{"K1", 0.04325, 2.194e-6, 0.00092, 0.0};
constexpr Link kK2{"K2", 0.00365, 4.410e-7, -0.0115, 0.0};
constexpr Link kK3{"K3", 0.02373, 5.255e-6, 0.01043, -0.01874};
constexpr Link kK4{"K4", 0.00706, 5.667e-7, 0.0, -0.00579};
constexpr Link kK5{"K5", 0.07050, 1.169e-5, 0.02308, 0.00916};
constexpr Link kK6{"K6", 0.00706, 5.667e-7, 0.00579, 0.0};
constexpr Link kK7{"K7", 0.05498, 1.912e-5, 0.00449, -0.01228};

// A body at (x, y) of its parent frame turned by `angle` about z, with its hinge there.
void open_body(std::ostringstream& x, const Link& l, double px, double py, double angle) {
  // About the in-plane axes: J/2 each, a plate's (MuJoCo asks A + B ≥ C); the hinges turn only
  // about z, so these do not enter the motion.
  const double half = 0.5 * l.inertia;
  x << "<body name='" << l.name << "' pos='" << px << " " << py << " 0' axisangle='0 0 1 " << angle
    << "'>\n<joint name='" << l.name << "' type='hinge' axis='0 0 1'/>\n"
    << "<inertial pos='" << l.cx << " " << l.cy << " 0' mass='" << l.mass << "' diaginertia='"
    << half << " " << half << " " << l.inertia << "'/>\n";
}

std::string model_xml(double dt, bool rk4, bool tight) {
  const auto& a0 = published::kAnglesT0;  // β, Θ, γ, Φ, δ, Ω, ε at t = 0
  std::ostringstream x;
  x.precision(17);
  x << "<mujoco model='andrews'>\n<compiler angle='radian'/>\n<option timestep='" << dt
    << "' integrator='" << (rk4 ? "RK4" : "Euler")
    << "' gravity='0 0 0'><flag contact='disable'/></option>\n<worldbody>\n"
    << "<site name='C' pos='0.014 0.072 0'/>\n";
  open_body(x, kK1, 0.0, 0.0, a0[0]);    // at O, angle β
  open_body(x, kK2, 0.007, 0.0, a0[1]);  // at K1's P, angle Θ relative to K1
  x << "<site name='E2' pos='-0.028 0 0'/>\n</body>\n</body>\n";
  open_body(x, kK3, -0.03635, 0.03273, a0[2]);  // at B, angle γ
  x << "<site name='E3' pos='0 -0.035 0'/>\n<site name='D' pos='0.02 -0.018 0'/>\n</body>\n";
  open_body(x, kK5, -0.06934, -0.00227, a0[4]);  // at A, angle δ
  open_body(x, kK4, 0.04, 0.0, a0[3]);           // at K5's G, angle Φ relative to K5
  x << "<site name='E4' pos='0 -0.02 0'/>\n</body>\n</body>\n";
  open_body(x, kK7, -0.06934, -0.00227, a0[6]);  // at A, angle ε
  open_body(x, kK6, 0.0, -0.04, a0[5]);          // at K7's H, angle Ω relative to K7
  x << "<site name='E6' pos='0.02 0 0'/>\n</body>\n</body>\n</worldbody>\n<equality>\n";
  for (const char* other : {"K3", "K4", "K6"}) {
    x << "<connect body1='K2' body2='" << other << "' anchor='-0.028 0 0'";
    if (tight) x << " solref='" << 2 * dt << " 1' solimp='0.9999 0.9999 0.001'";
    x << "/>\n";
  }
  x << "</equality>\n<tendon><spatial stiffness='4530' springlength='0.07785'>"
    << "<site site='D'/><site site='C'/></spatial></tendon>\n</mujoco>\n";
  return x.str();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: %s DT euler|rk4 default|tight\n", argv[0]);
    return 2;
  }
  const double dt = std::atof(argv[1]);
  const bool rk4 = std::string(argv[2]) == "rk4", tight = std::string(argv[3]) == "tight";
  mjModel* m = orthomech::peers::load_mjcf(model_xml(dt, rk4, tight));
  if (!m) return 2;
  mjData* d = mj_makeData(m);
  // The test set's order β, Θ, γ, Φ, δ, Ω, ε: the hinges K1, K2, K3, K4, K5, K6, K7.
  std::array<int, 7> adr{};
  for (int k = 0; k < 7; ++k) {
    const std::string name = "K" + std::to_string(k + 1);
    adr[static_cast<size_t>(k)] = m->jnt_qposadr[mj_name2id(m, mjOBJ_JOINT, name.c_str())];
  }
  d->qfrc_applied[m->jnt_dofadr[mj_name2id(m, mjOBJ_JOINT, "K1")]] = kTorque;  // kept by mj_step
  mj_forward(m, d);
  std::array<int, 4> e{};
  for (int k = 0; k < 4; ++k) {
    const std::string name = std::string("E") + "2346"[k];
    e[static_cast<size_t>(k)] = mj_name2id(m, mjOBJ_SITE, name.c_str());
  }
  const auto gap = [&] {
    const double* p = d->site_xpos;
    double g = 0.0;
    for (int k = 1; k < 4; ++k) {
      const int a = 3 * e[0], b = 3 * e[static_cast<size_t>(k)];
      g = std::max(g,
                   std::hypot(std::hypot(p[a] - p[b], p[a + 1] - p[b + 1]), p[a + 2] - p[b + 2]));
    }
    return g;
  };
  const auto [cpu, max_gap] = orthomech::peers::run_timed(m, d, kTEnd, dt, gap);
  double err = 0.0;
  for (size_t k = 0; k < 7; ++k)
    err = std::max(err,
                   std::abs(published::kAnglesT0[k] + d->qpos[adr[k]] - published::kAnglesT003[k]));
  std::printf("mujoco %s andrews dt=%g %s %s t=%g cpu_per_s=%.4g err=%.2e gap=%.1e\n",
              mj_versionString(), dt, rk4 ? "rk4" : "euler", tight ? "tight" : "default", d->time,
              cpu / kTEnd, err, max_gap);
  mj_deleteData(d);
  mj_deleteModel(m);
  return 0;
}
