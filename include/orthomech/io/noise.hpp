#pragma once
// Rounding noise in the files and documents the tool writes (issue 11). A quantity that is zero
// by construction comes out of the arithmetic as a few ulps of the quantities it is computed
// from: the y velocity of a slider on a horizontal guide is 1e-17 m/s next to crank-pin
// velocities of 2 m/s, the axial force of a frictionless slide 1e-13 N next to 1e3 N. Written
// as such it reads as a (tiny) value; it is written as exactly 0 instead.
//
// The rule: a value whose magnitude is at most kNoiseRelative times the largest magnitude of
// the same dimension in the same output (all lengths, all velocities, all forces, … of every
// row) is written as 0. 256 ε ≈ 5.7e-14: far below any digit a designer reads (the outputs
// carry 12 significant digits at most), far above the ulps of a sum of a few dozen terms.
#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <cstddef>

#include "orthomech/io/units.hpp"

namespace orthomech {

inline constexpr double kNoiseRelative = 256.0 * DBL_EPSILON;

class NoiseFloor {
 public:
  // Takes a value (SI) into its dimension's scale.
  void see(Dimension d, double v) {
    if (std::isfinite(v)) scale_[index(d)] = std::max(scale_[index(d)], std::abs(v));
  }
  // 0 when v is rounding noise for its dimension; v otherwise (NaN and inf unchanged). An
  // angle (SI, rad) is noise against at least half a turn: angles live on the circle, and a
  // mechanism whose bodies all lie at 0 has angles of 1e-17 rad that are noise all the same.
  [[nodiscard]] double clean(Dimension d, double v) const {
    return std::abs(v) <= kNoiseRelative * scale(d) ? 0.0 : v;
  }
  [[nodiscard]] double scale(Dimension d) const {
    return d == Dimension::angle ? std::max(scale_[index(d)], kHalfTurn) : scale_[index(d)];
  }

 private:
  static constexpr double kHalfTurn = 3.14159265358979323846;
  static std::size_t index(Dimension d) { return static_cast<std::size_t>(d); }
  std::array<double, static_cast<std::size_t>(Dimension::frequency) + 1> scale_{};
};

}  // namespace orthomech
