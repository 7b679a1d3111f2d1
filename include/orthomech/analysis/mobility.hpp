#pragma once
// Mobility (issue 2 §4): n, n_c, rank of E at a position, DOF = n − rank (eq. (25) with the
// rank in place of n_c), the Grübler–Kutzbach count n − n_c, and the redundant constraint
// equations named by joint and component, from the rank-revealing factorisation of the chart
// selector (scaled QR with column pivoting; tolerance ChartOptions::rank_tolerance).
// Large models (n ≥ kSparseMobilityFrom) use a sparse QR of the same scaled matrix instead
// (Eigen's SparseQR, COLAMD column ordering): the same rank and DOF; the redundant set it names
// is a valid one (the other rows have full rank) but may differ from the dense choice
// (docs/theory.md, "Rank and redundancy"; docs/performance.md, "Mobility of large models").
#include <string>
#include <vector>

#include "orthomech/model/free_system.hpp"  // inverse_mass_diagonal
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
  bool sparse = false;  // rank revealed by the sparse QR (RankMethod::sparse)
  // The dense QR's chart at q (rows, dependent and independent components, row scales): the one
  // ChartEngine::select chooses from the same Eᵀ, A and options, which simulate's start reuses
  // instead of a second QR. Empty on the sparse path.
  Chart chart;
  // Idle degrees of freedom (docs/spatial.md §4.1, §6.5): a body held by two or more joints that
  // can move while every other body is at rest, e.g. a coupler between two spherical joints
  // spinning about the line through them. Each counts in `dof`.
  struct Idle {
    std::string body;
    int count = 0;  // independent directions of that body's own motion
  };
  std::vector<Idle> idle;
};

// How the rank of E is revealed: `automatic` is `dense` below kSparseMobilityFrom velocities and
// `sparse` from there on (models given by functions, Model::general, stay dense).
enum class RankMethod { automatic, dense, sparse };
inline constexpr int kSparseMobilityFrom = 600;

[[nodiscard]] Mobility compute_mobility(const Model& model, const VecX& q,
                                        const ChartOptions& options = {},
                                        RankMethod method = RankMethod::automatic);

// The indices (Model::bodies) of the bodies of m.idle.
[[nodiscard]] std::vector<int> idle_body_indices(const Model& model, const Mobility& m);

// The own motions of the bodies `idle` at q (docs/spatial.md §4.1, §6.5): for each, a basis of the
// null space of Eᵀ restricted to its columns (scaled by √A_kk, rows normalised, as the rank test
// of compute_mobility), every other body at rest. One column (size n) per motion, scaled to a
// unit angular rate (1 rad/s; a motion without rotation: unit speed). n × 0 without idle bodies.
[[nodiscard]] MatX idle_motions(const Model& model, const VecX& q, const std::vector<int>& idle);

// Rows that hold those motions at zero rate, mass-orthogonally: for every motion v of
// idle_motions, the row vᵀM normalised. I u = 0 makes u M-orthogonal to the idle motions (the
// admissible velocity of least kinetic energy among u + span(v)). Used by validate (tangent,
// corrector, singularity measures) and by cycle (velocities, accelerations, positions).
// 0 × n without idle bodies. `motions`, if given: the motions v (idle_motions), row k's in
// column k.
[[nodiscard]] MatX idle_rows(const Model& model, const VecX& q, const std::vector<int>& idle,
                             MatX* motions = nullptr);

}  // namespace orthomech
