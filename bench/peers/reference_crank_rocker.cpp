// Prints the crank angle (rad) of the crank-rocker swinging under gravity at t
// (crank_rocker_reference.hpp), for run_peers.py's orthomech rows.
//   usage: peer_reference_crank_rocker T
#include <cstdio>
#include <cstdlib>

#include "crank_rocker_reference.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s T\n", argv[0]);
    return 2;
  }
  std::printf("%.17g\n", orthomech::peers::CrankRocker{}.crank_angle(std::atof(argv[1])));
  return 0;
}
