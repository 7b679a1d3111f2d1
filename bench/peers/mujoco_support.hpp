#pragma once
// What the MuJoCo peers share: the process CPU clock, and a model loaded from MJCF text (MuJoCo
// 2.2 reads models from files only: the text goes through a temporary file).
#include <mujoco/mujoco.h>
#include <unistd.h>

#include <cstdio>
#include <ctime>
#include <fstream>
#include <string>

namespace orthomech::peers {

inline double cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

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

}  // namespace orthomech::peers
