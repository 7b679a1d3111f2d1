#pragma once
// The process CPU clock the peer programs time their stepping with (mujoco_support.hpp,
// simbody_support.hpp).
#include <ctime>

namespace orthomech::peers {

inline double cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

}  // namespace orthomech::peers
