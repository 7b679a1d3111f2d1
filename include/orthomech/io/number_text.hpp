#pragma once
// Numbers as the CSV files write them: the text of printf's "%.Pg" (P significant digits, the
// "C" locale), produced by std::to_chars, which the standard specifies to give that text and
// which does not go through printf's multi-precision arithmetic (`simulate --out` at 20 000
// samples of N = 40 spent over 40 % of its time in printf's floating-point formatting).
#include <string>

namespace orthomech {

// The significant digits of every number in the CSV files (`simulate --out`, `cycle --out`,
// `cycle --drivers --out`): 12, far above what a designer reads and above the rounding noise
// floor (io/noise.hpp).
inline constexpr int kCsvDigits = 12;

// The longest text of "%.Pg" for P ≤ 17: sign, 17 digits, point, exponent "e-308".
inline constexpr int kNumberTextMax = 32;

// Appends the text of printf("%.Pg", v) to `out` (precision P in 1 … 17).
void append_number(std::string& out, double v, int precision);
// The same as a string.
[[nodiscard]] std::string number_text(double v, int precision);

}  // namespace orthomech
