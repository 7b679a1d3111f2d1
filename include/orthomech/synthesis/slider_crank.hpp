#pragma once
// Synthesis of planar slider-cranks (issue 50; docs/synthesis.md, "Slider-crank synthesis",
// (L40)–(L49)): function generation (crank angle → slider position) exactly through 3 precision
// pairs or by linear least squares through more, and path generation of a coupler point by the
// global search of path_generation.hpp (multistart BOBYQA + Levenberg–Marquardt polish).
//
// Sign convention (SliderCrank of four_bar.hpp). Function generation: crank pivot O = (0, 0),
// slider line along +x (γ = 0) at the offset e (the line y = e), input angle φ from the slider
// line (+x), counter-clockwise; slider position s along +x from the foot (0, e). The loop closure
// |B − A| = l with A = r (cos φ, sin φ), B = (s, e):
//   (s − r cos φ)² + (e − r sin φ)² = l²,                                               (L40)
// is linear in K = (K1, K2, K3) = (r, e·r, r² + e² − l²):
//   2 s cos φ · K1 + 2 sin φ · K2 − K3 = s².                                             (L41)
// A negative solved K1 is a crank pointing the other way: the linkage then has r = |K1| and the
// input offset π (crank angle θ = φ + input_offset); e = K2 / K1 either way.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "orthomech/synthesis/four_bar.hpp"
#include "orthomech/synthesis/path_generation.hpp"

namespace orthomech::synthesis {

struct SliderPair {
  double phi = 0.0;  // input (crank) angle φ from the slider line, rad
  double s = 0.0;    // slider position along the line from the foot of O, length
};

struct SliderFunctionResult {
  SynthesisStatus status = SynthesisStatus::no_linkage;
  std::string message;
  SliderCrank linkage;        // O = (0, 0), line along x (γ = 0), branch chosen from the data
  double input_offset = 0.0;  // crank angle θ = φ + input_offset (0 or π)
  Eigen::Vector3d K = Eigen::Vector3d::Zero();  // (K1, K2, K3) of (L41), signed
  // Largest |s_linkage(φ_i) − s_i| over the pairs (the pairs' length unit), the slider position
  // of the linkage computed by calc_position ((L8)), not by (L41).
  double max_position_error = 0.0;
};

// Exact synthesis through 3 precision pairs (L42) or linear least squares through more (L43);
// the lengths (L44) and the branch (L45). Throws std::invalid_argument for fewer than 3 pairs or
// a non-finite value.
[[nodiscard]] SliderFunctionResult synthesize_slider_function_generator(
    const std::vector<SliderPair>& pairs);

// Path generation of a slider-crank's coupler point (L46)–(L49): the targets, the timing
// (options.timing, options.crank_angles as φ_i from the slider line), the branch (options.branch)
// and the search (options.starts, seed, local_evaluations, polished, penalty_weight, the
// normalised box pivot_box, min_link, max_link, max_coupler) as for a four-bar; fixed_A0 fixes
// the crank pivot O, fixed_ground_angle the slider line's angle γ. Not used here: world_box,
// start (always the quasi-random design), restarts. require_crank_rocker asks for a crank that
// turns fully (r + |e| < l).
struct SliderPathResult {
  SynthesisStatus status = SynthesisStatus::no_linkage;
  std::string message;
  SliderCrank linkage;
  std::vector<double> crank_angles;  // absolute θ_i at the targets
  double error = 0.0;                // Σ |P(θ_i) − T_i|² by calc_position
  double max_distance = 0.0;         // max_i |P(θ_i) − T_i|
  bool assembles = false;            // at every θ_i
  int evaluations = 0;
};
// Throws std::invalid_argument as synthesize_path_generator does.
[[nodiscard]] SliderPathResult synthesize_slider_path_generator(
    const std::vector<Vec2>& targets, const PathSynthesisOptions& options);

// Whether the crank of a slider-crank turns fully: r + |e| < l (the loop closes at every θ).
[[nodiscard]] bool crank_turns_fully(const SliderCrank& linkage) noexcept;

}  // namespace orthomech::synthesis
