#pragma once
// Path generation of planar four-bars by global optimisation (issue 50, item 4;
// docs/synthesis.md, "Path generation", (L21)–(L24)).
//
// The coupler point P(θ) of calc_position (four_bar.hpp) should pass through target points T_i.
// Objective (L21): F = Σ_i |P(θ_i) − T_i|² + w Σ (penalties)², the penalties being the loop's
// closure deficit at each θ_i (its slack below a margin of 1e-5 spreads), the Grashof crank-rocker
// violation when required, and the timing's excess over one turn (untimed). The reported `error` is
// the first sum alone (the squared distances, the measure of the published benchmarks), in the
// targets' units squared. Variables: A0, the ground angle θ_g and length d (so B0 = A0 + d (cos
// θ_g, sin θ_g)), a, b, c, the coupler point (p, q) and the timing: θ_i = θ_g + φ_i with φ_i given
// (timed, angles relative to the ground line), θ_g + θ_0 + φ_i (timed with a free start θ_0), or
// θ_0 + s Σ_{k≤i} δ_k with δ_k ≥ 0 (untimed: a free start and non-negative increments, s = ±1 the
// turning sense). Search: multistart BOBYQA over a seeded quasi-random design (NLopt through the
// private adapter) from every branch (and turning sense) asked for, then a Levenberg–Marquardt
// polish of the best runs on the residual vector of F, and optionally rounds of basin hopping
// from the best point (L23). Deterministic for a given seed.
#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "orthomech/process_share.hpp"
#include "orthomech/synthesis/four_bar.hpp"

namespace orthomech::synthesis {

enum class PathTiming {
  prescribed,             // θ_i = θ_g + φ_i
  prescribed_free_start,  // θ_i = θ_g + θ_0 + φ_i
  free,                   // θ_i = θ_0 + s Σ_{k≤i} δ_k, δ_k ≥ 0, in the targets' order
};

// How the multistart search of a free timing starts (L25). The quasi-random design is the
// default: the nearest-point start wins on the ten-point ellipse (4.10e-4 against 4.65e-4) but
// loses on the six collinear points (4.0e-6 against an exact 4e-28), docs/synthesis.md.
enum class PathStart {
  quasi_random,  // the quasi-random design over every variable, the increments in [0, 2π/(N − 1)]
  nearest_point,  // free timing: fit the curve distance first, time from the nearest points
};

struct PathSynthesisOptions {
  PathTiming timing = PathTiming::prescribed;
  std::vector<double> crank_angles;  // φ_i (timed), one per target
  // A fixed ground: A0 and θ_g given (the 5-point benchmark: A0 at the origin, ground along x).
  std::optional<Vec2> fixed_A0;
  std::optional<double> fixed_ground_angle;
  bool require_crank_rocker = false;  // Grashof with the crank the shortest link (L22)
  int branch = 0;                     // ±1: that branch only; 0: both
  int turning = 0;                    // untimed: ±1 that sense only; 0: both
  // The search box, in units of the targets' RMS distance from their centroid, about it.
  double pivot_box = 4.0;  // |A0 − centroid| per coordinate
  double max_link = 8.0;   // d, a, b, c ∈ [min_link, max_link]
  double min_link = 0.02;
  double max_coupler = 8.0;  // |p|, |q|
  // A box in the targets' units instead (the published benchmarks' variable bounds): when set,
  // it replaces pivot_box, max_link, max_coupler (and min_link, apart from a floor of 1e-6
  // spreads that keeps the links positive).
  struct WorldBox {
    double pivot_lo = -60.0, pivot_hi = 60.0;      // each coordinate of A0
    double link_lo = 0.0, link_hi = 60.0;          // d, a, b, c
    double coupler_lo = -60.0, coupler_hi = 60.0;  // p, q
  };
  std::optional<WorldBox> world_box;
  PathStart start = PathStart::quasi_random;
  // Quasi-random starts per branch and turning sense (nearest_point: curve-distance starts per
  // branch, each then continued in every turning sense whose timing stays within one turn).
  int starts = 200;
  unsigned long long seed = 1;
  // Threads of the multistart (OpenMP; 0: every core). The result does not depend on it
  // (solvers::minimize_multistart assembles the runs in start order).
  int threads = 0;
  // Processes (MPI ranks) sharing the multistart's starts (process_share.hpp; the result is the
  // one process's).
  ProcessShare share;
  int local_evaluations = 3000;  // BOBYQA budget per start
  int polished = 8;              // the best runs polished by Levenberg–Marquardt
  // The restart policy (basin hopping) after the polish: `restarts` rounds, each a local run
  // (BOBYQA + polish) from the best point moved by up to ±restart_step of the box per variable,
  // kept when it is better. 0: none.
  int restarts = 0;
  double restart_step = 0.02;
  // The rounds are shared out among the best `restart_candidates` distinct polished points (1:
  // the best point alone), each hopping from its own start with its own random stream.
  int restart_candidates = 1;
  double penalty_weight = 1e6;  // w of (L21)
};

struct PathSynthesisResult {
  SynthesisStatus status = SynthesisStatus::no_linkage;
  std::string message;
  FourBar linkage;
  std::vector<double> crank_angles;  // absolute θ_i at the targets
  double error = 0.0;                // Σ |P(θ_i) − T_i|² by calc_position
  double max_distance = 0.0;         // max_i |P(θ_i) − T_i|
  bool assembles = false;            // at every θ_i
  GrashofType grashof = GrashofType::triple_rocker;
  int evaluations = 0;
};

// Throws std::invalid_argument for fewer than 2 targets, crank_angles of the wrong size for a
// timed problem, or an empty or inverted box.
[[nodiscard]] PathSynthesisResult synthesize_path_generator(const std::vector<Vec2>& targets,
                                                            const PathSynthesisOptions& options);

// The error of (L21) of a given linkage at given absolute crank angles (the oracle of the
// benchmark table: calc_position alone).
[[nodiscard]] double path_error(const FourBar& linkage, const std::vector<Vec2>& targets,
                                const std::vector<double>& crank_angles);

}  // namespace orthomech::synthesis
