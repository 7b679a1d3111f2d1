#pragma once
// A synthesis task file (issue 50; docs/file-format.md, "Synthesis tasks"): what a designer
// wants of a planar four-bar — coupler poses (motion generation), coupler points (path
// generation) or input–output angle pairs (function generation) — with the requirements its
// candidates must meet and the mechanism each candidate is written as. Read once, validated,
// immutable; every mistake an InputError at its file:line with the element's name.
#include <optional>
#include <string>
#include <vector>

#include "orthomech/synthesis/four_bar.hpp"
#include "orthomech/synthesis/rssr.hpp"

namespace orthomech::synthesis {

enum class TaskKind { motion, path, function };
[[nodiscard]] const char* to_string(TaskKind kind) noexcept;

// A path task's timing (path_generation.hpp, PathTiming): the crank angles at the points given
// (from the ground line), given up to a free start, or free (matched in order).
enum class TaskTiming { prescribed, free_start, free };
[[nodiscard]] const char* to_string(TaskTiming timing) noexcept;

// A motion task's given pivots of one dyad (2–4 poses; docs/file-format.md, "Synthesis tasks"), in
// SI, world coordinates; a moving pivot where it is at the first pose. 2 poses: both (the fixed
// pivot a guess); 3 poses: exactly one; 4 poses: at most one.
struct TaskPivots {
  std::optional<Vec2> fixed_pivot;
  std::optional<Vec2> moving_pivot;
};

// The linkage a function or path task asks for (key `linkage`, default four-bar); motion tasks
// are four-bars. A slider-crank (four_bar.hpp, SliderCrank): function pairs are [crank angle
// from the slider line, slider position]; a path task's fixed_pivot is the crank pivot O, its
// ground_angle the slider line's angle γ and its crank angles are measured from that line.
// A spatial RSSR (rssr.hpp, `linkage: rssr`, function tasks): pairs are [φ, ψ], the input and
// output cranks' angles about the axes of `axes:`, each from its reference direction.
enum class TaskLinkage { four_bar, slider_crank, rssr };
[[nodiscard]] const char* to_string(TaskLinkage linkage) noexcept;

struct SynthesisTask {
  std::string file;  // where it was read from (messages)
  std::string name;
  TaskKind kind = TaskKind::motion;
  TaskLinkage linkage = TaskLinkage::four_bar;
  // The task's units, as a mechanism file's: the candidates are written in them. SI factors.
  std::string length_unit = "mm", angle_unit = "deg";
  double length_si = 1e-3, angle_si = 0.017453292519943295;
  // Targets, in SI (m, rad). motion: poses of the coupler frame; path: points; function: pairs.
  std::vector<Vec2> positions;  // motion and path: P_j
  std::vector<double> angles;   // motion: θ_j of the pose
  std::vector<double> inputs;   // function: φ_i; path (timed): φ_i from the ground line
  std::vector<double> outputs;  // function: ψ_i (four-bar) or the slider positions s_i (m)
  double ground = 0.0;          // function, four-bar: the ground length d (m)
  TaskTiming timing = TaskTiming::free;
  std::optional<Vec2> fixed_pivot;     // path: A0 given
  std::optional<double> ground_angle;  // path: θ_g given (rad)
  TaskPivots crank, follower;          // motion, 2–4 poses: the pivots given
  // function, RSSR: the revolute axes (SI, world) and the held design coordinates (L58).
  RevoluteAxis input_axis, output_axis;
  Vec3 held_a = Vec3::Zero(), held_b = Vec3::Zero();
  // Requirements of a candidate (every one is validated; these are checked besides).
  bool crank_rocker = false;                     // Grashof with the crank the shortest link
  double min_transmission = 0.5235987755982988;  // rad: the worst transmission angle allowed
  double tolerance = 0.0;  // m: how far from a target a candidate's point may be (0: automatic)
  // Search.
  unsigned long seed = 1;
  int starts = 200;
  // The mechanism a candidate is written as: link mass per length (kg/m), the driver's speed.
  double mass_per_length = 1.0;          // kg/m (1 g/mm, a 20 × 6 mm steel bar is 0.94)
  double speed = 6.283185307179586;      // rad/s (60 rpm)
  std::string rank_by = "transmission";  // or "error", "drive_torque", "pin_force"
};

// Reads a task from YAML text (`origin` names it in messages) or from a file. Throws InputError.
[[nodiscard]] SynthesisTask parse_synthesis_task(const std::string& text,
                                                 const std::string& origin);
[[nodiscard]] SynthesisTask load_synthesis_task(const std::string& path);

}  // namespace orthomech::synthesis
