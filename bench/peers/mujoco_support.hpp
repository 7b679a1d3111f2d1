#pragma once
// What the MuJoCo peers share: the process CPU clock (cpu_clock.hpp), a model loaded from MJCF
// text (MuJoCo 2.2 reads models from files only: the text goes through a temporary file), and the
// timed stepping loop with its loop-gap samples.
#include <mujoco/mujoco.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include "cpu_clock.hpp"

namespace orthomech::peers {

// The model, or nullptr after printing MuJoCo's error on stderr.
inline mjModel* load_mjcf(const std::string& xml) {
  char path[] = "/tmp/peer_mujoco_XXXXXX.xml";
  const int fd = mkstemps(path, 4);
  if (fd < 0) return nullptr;
  close(fd);
  std::ofstream(path) << xml;
  char error[1000] = "";
  mjModel* m = mj_loadXML(path, nullptr, error, sizeof error);
  std::remove(path);
  if (!m) std::fprintf(stderr, "MuJoCo: %s\n", error);
  return m;
}

// What a timed run measured: CPU seconds of the stepping loop and the largest loop gap seen.
struct TimedRun {
  double cpu = 0.0;
  double max_gap = 0.0;
};

// Steps d to t_end in steps of dt, timed on the process CPU clock. gap() (the loop-closure gap
// at the sites, m) is sampled before the first step, every 0.01 s of simulated time (at a step's
// start, < 1 % of the steps) and at t_end after mj_forward (kinematics at t_end); the samples
// are inside the timed loop.
template <class Gap>
TimedRun run_timed(const mjModel* m, mjData* d, double t_end, double dt, const Gap& gap) {
  const long steps = std::lround(t_end / dt);
  const long sample = std::max(1L, std::lround(0.01 / dt));
  TimedRun run;
  run.max_gap = gap();
  const double c0 = cpu_seconds();
  for (long i = 0; i < steps; ++i) {
    mj_step(m, d);
    if (i % sample == 0) run.max_gap = std::fmax(run.max_gap, gap());
  }
  run.cpu = cpu_seconds() - c0;
  mj_forward(m, d);
  run.max_gap = std::fmax(run.max_gap, gap());
  return run;
}

}  // namespace orthomech::peers
