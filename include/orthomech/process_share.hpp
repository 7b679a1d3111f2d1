#pragma once
// Processes sharing one search (docs/cli.md "synthesize", "Every core, and a cluster").
#include <functional>
#include <vector>

namespace orthomech {

// How the independent runs of a search (the starts of a multistart) are shared among processes,
// e.g. MPI ranks (study/distributed.hpp, mpi_share): this process runs the items k with
// k mod size = rank; `gather` takes this process's records (in its items' order) and returns
// every process's, rank by rank, rank r contributing counts[r] numbers. Every process then holds
// every record, so the result is the one process's. The default: one process.
struct ProcessShare {
  int rank = 0, size = 1;
  std::function<std::vector<double>(const std::vector<double>& mine,
                                    const std::vector<int>& counts)>
      gather;
  [[nodiscard]] bool shared() const { return size > 1 && gather; }
};

}  // namespace orthomech
