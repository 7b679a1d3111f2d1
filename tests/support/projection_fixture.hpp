#pragma once
// The fixture of the paper's theorems as tests (dual_test.cpp, primal_test.cpp): every bundled
// mechanism assembled, with an admissible velocity and both projections evaluated; tolerances;
// motion along the constraint manifold for central differences.
#include <gtest/gtest.h>

#include <Eigen/SVD>
#include <memory>
#include <string>

#include "orthomech/analysis/mobility.hpp"
#include "orthomech/analysis/positions.hpp"
#include "orthomech/projection/dual.hpp"
#include "orthomech/projection/primal.hpp"
#include "support/fixtures.hpp"

namespace orthomech::test {

// Identities hold to rounding: entries of α, β are O(1)…O(100) (they mix m and rad), products
// of a few n × n matrices lose ~n·eps·‖·‖²; 1e-9 relative is far above that and far below any
// formula error.
inline constexpr double kIdentityTol = 1e-9;
// Central differences on the manifold: step 1e-6 s at |u| ~ 1; truncation ~1e-12, rounding of
// the re-projection (1e-14) / h ~ 1e-8 relative.
inline constexpr double kFdStep = 1e-6;
inline constexpr double kFdTol = 1e-6;

inline double rel(const MatX& a, const MatX& b) { return (a - b).norm() / (1.0 + b.norm()); }
inline int numeric_rank(const MatX& m) {
  Eigen::JacobiSVD<MatX> svd(m);
  svd.setThreshold(1e-9);
  return static_cast<int>(svd.rank());
}

struct Evaluated {
  Model model;
  VecX q;
  Mobility mob;
  State state;
  std::unique_ptr<Workspace> ws;
  bool primal_ok = false;
  explicit Evaluated(const std::string& name, unsigned seed = 1)
      : model(load_bundled(name)), q(assembled_q(model)), mob(compute_mobility(model, q)) {
    state = State(model);
    state.q = q;
    state.u = admissible_velocity(model, q, seed);
    ws = std::make_unique<Workspace>(model, mob.rank);
    EXPECT_EQ(evaluate_dual(model, state, *ws), ProjectionStatus::ok);
    primal_ok = evaluate_primal(model, state, *ws) == ProjectionStatus::ok;
  }
  const MatX& M() const { return ws->free.M; }
  const MatX& A() const { return ws->free.A; }
  const MatX& Et() const { return ws->constraints.Et; }
};

inline const char* const kAll[] = {
    "crank-rocker", "double-rocker", "slider-crank", "watt-six-bar",     "stephenson-six-bar",
    "quick-return", "n-four-bar-2",  "pendulum",     "andrews-squeezer", "triple-crank"};

// The suite of the theorems, instantiated on kAll in dual_test.cpp (TEST_Ps in both files).
class Projection : public ::testing::TestWithParam<const char*> {};

// ---- derivatives along admissible motion, by central differences on the manifold -------------
// q(t): step along u, then re-project with the chart corrector (independent coordinates held),
// so q(t) stays on f = 0 and q̇(0) = u.
inline VecX on_manifold(const Model& model, const VecX& q, const VecX& u, double t,
                        Workspace& chart_ws) {
  VecX qt = q + t * u;
  const SolveResult r =
      correct_positions_in_chart(model, qt, chart_ws, {.tolerance = 1e-15, .max_iterations = 50});
  EXPECT_NE(r.status, SolveStatus::singular);
  return qt;
}

}  // namespace orthomech::test
