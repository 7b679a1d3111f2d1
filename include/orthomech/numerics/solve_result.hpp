#pragma once
// The outcome of a position solve (analysis/positions.hpp, the chart engine's corrector): data,
// not exceptions.
#include <string>

namespace orthomech {

enum class SolveStatus { converged, not_converged, singular };
[[nodiscard]] const char* to_string(SolveStatus s);

struct SolveResult {
  SolveStatus status = SolveStatus::not_converged;
  std::string message;
  int iterations = 0;
  double residual = 0.0;  // max |f_k| at the end (SI: m or rad)
};

}  // namespace orthomech
