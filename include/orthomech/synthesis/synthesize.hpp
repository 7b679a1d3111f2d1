#pragma once
// A synthesis task from its targets to validated, ranked candidates (issue 50; docs/cli.md,
// "synthesize"). The one algorithm behind `orthomech synthesize`:
//   1. the generator of the task's kind: Burmester motion generation (motion_generation.hpp),
//      path generation by global search (path_generation.hpp), Freudenstein function generation
//      (function_generation.hpp); for `linkage: slider-crank` the slider-crank's function and
//      path generation (slider_crank.hpp); for `linkage: rssr` the spatial RSSR function
//      generator (rssr.hpp);
//   2. each linkage written as a mechanism file (the format every command reads; an RSSR as a
//      spatial file), with one design position per target (its crank angle, the target point
//      and, for a pose, the coupler's angle);
//   3. that file read back and validated as `validate` does (analysis/validate.hpp: assembly at
//      every target, the target met, circuit, branch and order defects, transmission angle,
//      singular positions), plus the task's own requirements (Grashof crank-rocker) and the
//      worst transmission angle over the motion through the targets (the closed form of
//      four_bar.hpp, every degree of crank);
//   4. the file through `cycle` (analysis/cycle.hpp) over the motion it is built for (a full
//      turn of a crank that turns fully, else the crank from the first target to the last) at
//      the task's speed: the peak drive torque and the largest pin force; a run that does not
//      complete is a rejection too;
//   5. a candidate that fails anything is rejected with its reasons, never returned as a
//      solution; the others are ranked (worst transmission angle, largest first; the distance
//      to the targets, the peak drive torque or the peak pin force, smallest first).
// Results are data: nothing here throws for a numerical outcome.
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "orthomech/process_share.hpp"
#include "orthomech/synthesis/four_bar.hpp"
#include "orthomech/synthesis/rssr.hpp"
#include "orthomech/synthesis/task.hpp"

namespace orthomech::synthesis {

// What `cycle` computes on a candidate's file (step 4), in SI.
struct CandidateCycle {
  double from = 0.0, to = 0.0;  // the crank's motion (rad); a full turn: to = from + 2π
  int positions = 0;            // of the run (360 steps)
  double peak_drive = 0.0;      // N·m: the largest |drive torque|
  double peak_pin_force = 0.0;  // N: the largest joint force magnitude |F| over the joints
  std::string peak_pin;         // the joint it acts in
};

// A candidate's linkage: a four-bar, a slider-crank (task key `linkage: slider-crank`) or a spatial
// RSSR (`linkage: rssr`).
using Linkage = std::variant<FourBar, SliderCrank, Rssr>;

struct SynthesisCandidate {
  std::string name;    // "candidate-1" … in rank order (accepted), "rejected-1" … (rejected)
  std::string method;  // e.g. "Burmester points 1 and 3", "path search, branch +1"
  Linkage linkage;
  std::vector<double> crank_angles;  // rad at the targets, in the targets' order, unwrapped
  double max_distance = 0.0;         // m: largest distance of the coupler point (function: of
                                     // the follower pin, the slider pin or the RSSR's rocker
                                     // pin B) from its target
  double max_angle_error = 0.0;      // rad: motion: the coupler's angle; function: the output's
  double output_offset = 0.0;        // function: the follower's world angle is ψ + this
  GrashofType grashof = GrashofType::triple_rocker;  // four-bars only
  double worst_transmission = 0.0;  // rad: min over the motion of min(μ, π − μ) (a slider-crank:
                                    // μ = π/2 − the pressure angle; an RSSR: μ = asin of the
                                    // transmission index, rssr.hpp)
  std::optional<CandidateCycle> cycle;  // of an accepted candidate (step 4)
  std::vector<std::string> rejections;  // empty: accepted
  std::string file_text;                // the mechanism file (YAML)
  size_t task = 0;                      // internal: which generator output it is
  [[nodiscard]] bool accepted() const { return rejections.empty(); }
};

struct SynthesisResult {
  TaskKind kind = TaskKind::motion;
  SynthesisStatus status = SynthesisStatus::no_linkage;  // of the generator
  std::string message;                                   // the generator's, or why none
  double tolerance = 0.0;                    // m: the distance to a target a candidate may have
  std::vector<SynthesisCandidate> accepted;  // ranked
  std::vector<SynthesisCandidate> rejected;
};

// How the task is run (not what it asks): the threads of the global searches (path generation's
// multistart; 0: every core) and the processes sharing their starts (`mpirun`). The result does
// not depend on them.
struct SynthesisRunOptions {
  int threads = 0;
  ProcessShare share;  // processes (MPI ranks) sharing the global searches' starts
};

[[nodiscard]] SynthesisResult run_synthesis(const SynthesisTask& task,
                                            const SynthesisRunOptions& run = {});

// The mechanism file of a four-bar at the crank angles of its targets (exposed for tests).
[[nodiscard]] std::string four_bar_file(const SynthesisTask& task, const FourBar& linkage,
                                        const std::vector<double>& crank_angles, double tolerance,
                                        const std::string& name);
// The mechanism file of a slider-crank (crank, rod, slider on a prismatic joint) at the crank
// angles of its targets (exposed for tests).
[[nodiscard]] std::string slider_crank_file(const SynthesisTask& task, const SliderCrank& linkage,
                                            const std::vector<double>& crank_angles,
                                            double tolerance, const std::string& name);

}  // namespace orthomech::synthesis
