// Prints B0 = (x, y) of the N-four-bar's exact one-DOF reduction at t (nfourbar_reference.hpp), for
// run_peers.py's orthomech rows.   usage: peer_reference_n_four_bar N T
#include <cstdio>
#include <cstdlib>

#include "nfourbar_reference.hpp"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: %s N T\n", argv[0]);
    return 2;
  }
  const auto b0 = orthomech::peers::n_four_bar_b0(std::atoi(argv[1]), std::atof(argv[2]));
  std::printf("%.17g %.17g\n", b0[0], b0[1]);
  return 0;
}
