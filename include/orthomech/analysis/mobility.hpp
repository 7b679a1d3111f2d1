#pragma once
// Mobility (issue 2 §4): n, n_c, rank of E at a position, DOF = n − rank (eq. (25) with the
// rank in place of n_c), the Grübler–Kutzbach count n − n_c, and the redundant constraint
// equations named by joint and component, from the rank-revealing factorisation of the chart
// selector (scaled QR with column pivoting; tolerance ChartOptions::rank_tolerance).
#include <string>
#include <vector>

#include "orthomech/model/model.hpp"
#include "orthomech/projection/chart.hpp"

namespace orthomech {

struct Mobility {
  int nq = 0, n = 0, nc = 0;
  int rank = 0;
  int dof = 0;      // n − rank
  int grubler = 0;  // n − n_c: the Grübler–Kutzbach count for these bodies and joints
  std::vector<int> redundant_rows;     // constraint rows found dependent
  std::vector<std::string> redundant;  // "joint 'D', y"
  double smallest_pivot = 0.0;         // smallest kept |R_kk|/|R_11| (distance from a rank drop)
  double largest_dropped = 0.0;        // largest dropped |R_kk|/|R_11| (0 if none)
  double tolerance = 0.0;
  // Idle degrees of freedom (spatial.md §4.1, §6.5): a body held by two or more joints that can
  // move while every other body is at rest, e.g. a coupler between two spherical joints spinning
  // about the line through them. Each counts in `dof`.
  struct Idle {
    std::string body;
    int count = 0;  // independent directions of that body's own motion
  };
  std::vector<Idle> idle;
};

[[nodiscard]] Mobility compute_mobility(const Model& model, const VecX& q,
                                        const ChartOptions& options = {});

}  // namespace orthomech
