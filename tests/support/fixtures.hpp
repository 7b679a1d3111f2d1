#pragma once
// Test fixtures: mechanisms loaded from mechanisms/, assembled, with a workspace.
#include <string>

#include "orthomech/analysis/cycle.hpp"
#include "orthomech/model/model.hpp"
#include "orthomech/model/state.hpp"

namespace orthomech::test {

// Absolute path of a file in the source tree.
[[nodiscard]] std::string source_path(const std::string& relative);
// Loads mechanisms/<name>.yaml.
[[nodiscard]] Model load_bundled(const std::string& name);
// The design position projected onto f(q) = 0 (asserts convergence).
[[nodiscard]] VecX assembled_q(const Model& model);
// An admissible velocity at q: a seeded random combination of a basis of null(Eᵀ) computed by
// SVD (independent of the chart machinery).
[[nodiscard]] VecX admissible_velocity(const Model& model, const VecX& q, unsigned seed);
// Rank of Eᵀ at q by SVD (independent oracle for the QR-based rank).
[[nodiscard]] int svd_rank(const Model& model, const VecX& q, double rel_tol = 1e-8);
// The full turn of the file's first driver in `steps` steps (run_cycle).
[[nodiscard]] CycleResult full_cycle(const Model& model, int steps);
// Index of the measure `name` in model.measures (throws std::invalid_argument if there is none).
[[nodiscard]] size_t measure_index(const Model& model, const std::string& name);

}  // namespace orthomech::test
