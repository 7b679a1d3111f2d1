#pragma once
// Function generation of planar four-bars by Freudenstein's equation [Freudenstein 1955]
// (issue 50, item 2; docs/synthesis.md, "Function generation", (L9)–(L13)).
//
// Sign convention. A0 = (0, 0), B0 = (d, 0); input (crank) angle φ and output (follower) angle
// ψ both measured counter-clockwise from the ground line's +x direction. The loop closure
// |B − A| = b with A = a(cos φ, sin φ), B = (d + c cos ψ, c sin ψ) reads
//   K1 cos φ − K2 cos ψ + K3 = cos(φ − ψ),                                               (L9)
//   K1 = −d / c,  K2 = −d / a,  K3 = (a² − b² + c² + d²) / (2ac).                         (L10)
// Freudenstein measures both angles from the other end of the ground line (φ → π − φ,
// ψ → π − ψ), which makes his K1 = d/c, K2 = d/a positive; the equation is the same.
// A negative solved a (or c) is a crank (follower) pointing the other way: the returned
// linkage then has the length |a| and the input offset π (crank angle = φ + input_offset).
#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "orthomech/synthesis/four_bar.hpp"

namespace orthomech::synthesis {

struct AnglePair {
  double phi = 0.0;  // input angle φ
  double psi = 0.0;  // output angle ψ
};

struct FunctionSynthesisResult {
  SynthesisStatus status = SynthesisStatus::no_linkage;
  std::string message;
  FourBar linkage;             // A0 = (0, 0), B0 = (d, 0), branch chosen from the data
  double input_offset = 0.0;   // crank angle θ = φ + input_offset (0 or π)
  double output_offset = 0.0;  // follower angle = ψ + output_offset (0 or π)
  Eigen::Vector3d K = Eigen::Vector3d::Zero();  // (K1, K2, K3) of (L9)
  // Largest |ψ_linkage(φ_i) − ψ_i| over the pairs (radians, wrapped to (−π, π]), the output
  // angle of the linkage computed by calc_position (circle intersection), not by (L9).
  double max_output_error = 0.0;
};

// Exact synthesis through 3 precision pairs (L11) or least squares through more (L12).
// Throws std::invalid_argument for fewer than 3 pairs or d ≤ 0.
[[nodiscard]] FunctionSynthesisResult synthesize_function_generator(
    const std::vector<AnglePair>& pairs, double ground_length);

// Chebyshev spacing of n precision points on [x0, x1] (L13):
//   x_j = (x0 + x1)/2 − (x1 − x0)/2 · cos((2j − 1)π / (2n)),  j = 1 … n.
[[nodiscard]] std::vector<double> chebyshev_spacing(int n, double x0, double x1);

// The linear map of a law y = f(x), x ∈ [x0, x1], to angles: φ = φ_start + (x − x0)/(x1 − x0)·Δφ,
// ψ = ψ_start + (f(x) − f(x0))/(f(x1) − f(x0))·Δψ, at the given x values.
struct AngleMap {
  double x0 = 0.0, x1 = 1.0;
  double phi_start = 0.0, phi_range = 1.0;
  double psi_start = 0.0, psi_range = 1.0;
};
[[nodiscard]] std::vector<AnglePair> map_to_angles(const std::function<double(double)>& f,
                                                   const std::vector<double>& x,
                                                   const AngleMap& map);

}  // namespace orthomech::synthesis
