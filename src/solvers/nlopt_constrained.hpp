#pragma once
// Private adapter (house style: no NLopt type in a public header): minimisation under
// inequality constraints c(x) ≤ 0 on a box, derivative-free, with NLopt's C interface — COBYLA
// (local: linear models of the objective and every constraint on a simplex, Powell 1994) or ISRES
// (global: an evolution strategy with stochastic ranking of the constraints, Runarsson and Yao
// 2005, seeded). One call of the evaluation gives the objective and every constraint at x (NLopt
// asks for them separately at the same x: the last point is cached). As nlopt_minimize.hpp, every
// outcome is data and an exception of the evaluation never crosses NLopt.
#include <Eigen/Core>
#include <functional>
#include <vector>

#include "nlopt_minimize.hpp"

namespace orthomech::solvers {

struct ConstrainedValue {
  double objective = 0.0;
  std::vector<double> constraints;  // each ≤ 0 where x is feasible
};
using ConstrainedEvaluation = std::function<ConstrainedValue(const Eigen::VectorXd&)>;

enum class ConstrainedMethod { cobyla, isres };

struct ConstrainedSettings {
  ConstrainedMethod method = ConstrainedMethod::cobyla;
  double xtol_abs = 1e-6;     // the search ends when a step changes every x_i by less
  double initial_step = 0.0;  // COBYLA's first simplex (0: a quarter of each bound's span)
  int max_evaluations = 200;
  unsigned long long seed = 1;  // ISRES (nlopt_srand)
};

// Minimises the objective over [lower, upper] subject to the `constraints` values ≤ 0, from x0
// (ISRES: the first member of its population). Never throws (std::bad_alloc aside); `x` and
// `value` are NLopt's final point (the caller keeps its own record of the best feasible one).
[[nodiscard]] NloptOutcome minimize_constrained(const ConstrainedEvaluation& f, int constraints,
                                                const Eigen::VectorXd& x0,
                                                const Eigen::VectorXd& lower,
                                                const Eigen::VectorXd& upper,
                                                const ConstrainedSettings& settings = {});

}  // namespace orthomech::solvers
