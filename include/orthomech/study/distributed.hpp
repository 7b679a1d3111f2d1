#pragma once
// A design study shared among MPI ranks (docs/cli.md "sweep", "On a cluster"): rank 0 holds the
// results and hands out variant indices one at a time to the other ranks as they ask (dynamic load
// balancing); every other rank evaluates what it is given. The output is rank 0's, written exactly
// as by one process. Built with Open MPI when it is installed (ORTHOMECH_HAVE_MPI); otherwise
// mpi_launched() is false and nothing here is used.
#include <functional>
#include <string>
#include <vector>

#include "orthomech/process_share.hpp"
#include "orthomech/study/study.hpp"

namespace orthomech {

// This process was started by mpirun with two or more ranks, and this build has MPI.
[[nodiscard]] bool mpi_launched();

// MPI_Init on construction, MPI_Finalize on destruction; an MpiSession destroyed before
// finish() was called (an error on one rank) aborts every rank instead of leaving them waiting.
class MpiSession {
 public:
  MpiSession();
  ~MpiSession();
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;
  [[nodiscard]] int rank() const { return rank_; }
  [[nodiscard]] int size() const { return size_; }
  void finish() { finished_ = true; }

 private:
  int rank_ = 0, size_ = 1;
  bool finished_ = false;
};

// The ranks of the session as the processes of a shared search (process_share.hpp: each rank runs
// its share of a multistart's starts, then every rank holds every outcome: MPI_Allgatherv). Used
// by `synthesize` under mpirun.
[[nodiscard]] ProcessShare mpi_share(const MpiSession& session);

// Rank 0 tells every rank whether the study starts (`go`: its set-up succeeded) or not (an error,
// reported by rank 0 alone); every rank returns rank 0's answer.
bool broadcast_start(bool go);
// Rank 0: hands out the variants `next` gives (one index per call, −1 when there is none left;
// the indices are drawn as the ranks ask, so that none are held in memory) to the other ranks and
// calls `done` with each result (one at a time, any order); returns when every variant handed
// out is back and every rank is released. When `done` throws, no further variant is handed out,
// every rank is released and the exception is rethrown.
void coordinate_variants(const std::function<long()>& next,
                         const std::function<void(const VariantResult&)>& done);
// Every other rank: asks rank 0 for variants, evaluates them and sends the results back, until
// rank 0 has none left.
void serve_variants(const std::string& mechanism, const std::string& origin, const Study& study);

}  // namespace orthomech
