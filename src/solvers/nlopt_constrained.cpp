#include "nlopt_constrained.hpp"

#include <nlopt.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <string>

namespace orthomech::solvers {

namespace {

struct Context {
  const ConstrainedEvaluation* f = nullptr;
  nlopt_opt opt = nullptr;
  unsigned m = 0;
  Eigen::VectorXd x;
  ConstrainedValue last;
  bool cached = false;
  int evaluations = 0;
  std::exception_ptr error;
  bool nan = false;

  // The value at x, computed once per point.
  const ConstrainedValue* at(unsigned n, const double* xs) {
    if (cached && std::equal(xs, xs + n, x.data())) return &last;
    try {
      for (unsigned i = 0; i < n; ++i) x(i) = xs[i];
      ++evaluations;
      last = (*f)(x);
      cached = true;
      if (std::isnan(last.objective) || last.constraints.size() != m ||
          std::any_of(last.constraints.begin(), last.constraints.end(),
                      [](double c) { return std::isnan(c); })) {
        nan = true;
        nlopt_force_stop(opt);
        return nullptr;
      }
      return &last;
    } catch (...) {
      error = std::current_exception();
      cached = false;
      nlopt_force_stop(opt);
      return nullptr;
    }
  }
};

double objective(unsigned n, const double* x, double* grad, void* data) {
  if (grad) std::fill(grad, grad + n, 0.0);  // derivative-free methods only
  const ConstrainedValue* v = static_cast<Context*>(data)->at(n, x);
  return v ? v->objective : HUGE_VAL;
}

void constraints(unsigned m, double* result, unsigned n, const double* x, double* grad,
                 void* data) {
  if (grad) std::fill(grad, grad + static_cast<size_t>(m) * n, 0.0);
  const ConstrainedValue* v = static_cast<Context*>(data)->at(n, x);
  for (unsigned i = 0; i < m; ++i) result[i] = v ? v->constraints[i] : HUGE_VAL;
}

}  // namespace

NloptOutcome minimize_constrained(const ConstrainedEvaluation& f, int constraint_count,
                                  const Eigen::VectorXd& x0, const Eigen::VectorXd& lower,
                                  const Eigen::VectorXd& upper,
                                  const ConstrainedSettings& settings) {
  NloptOutcome out;
  const auto n = static_cast<unsigned>(x0.size());
  out.x = x0;
  out.value = HUGE_VAL;
  if (n == 0 || constraint_count < 0 || lower.size() != x0.size() || upper.size() != x0.size()) {
    out.kind = NloptOutcomeKind::invalid;
    out.message = "empty problem or bounds of the wrong size";
    return out;
  }
  const nlopt_algorithm a =
      settings.method == ConstrainedMethod::isres ? NLOPT_GN_ISRES : NLOPT_LN_COBYLA;
  nlopt_opt opt = nlopt_create(a, n);
  if (!opt) {
    out.kind = NloptOutcomeKind::failed;
    out.message = "NLopt could not create the optimiser";
    return out;
  }
  Context ctx;
  ctx.f = &f;
  ctx.opt = opt;
  ctx.m = static_cast<unsigned>(constraint_count);
  ctx.x = x0;
  std::vector<double> x(x0.data(), x0.data() + n);
  std::vector<double> lo(lower.data(), lower.data() + n), hi(upper.data(), upper.data() + n);
  std::vector<double> tol(ctx.m, 0.0);
  if (settings.method == ConstrainedMethod::isres) nlopt_srand(settings.seed);
  nlopt_result r = nlopt_set_lower_bounds(opt, lo.data());
  if (r > 0) r = nlopt_set_upper_bounds(opt, hi.data());
  if (r > 0) r = nlopt_set_min_objective(opt, objective, &ctx);
  if (r > 0 && ctx.m > 0)
    r = nlopt_add_inequality_mconstraint(opt, ctx.m, constraints, &ctx, tol.data());
  if (r > 0) r = nlopt_set_xtol_abs1(opt, settings.xtol_abs);
  if (r > 0) r = nlopt_set_maxeval(opt, settings.max_evaluations);
  if (r > 0 && settings.method == ConstrainedMethod::cobyla) {
    std::vector<double> dx(n);
    for (unsigned i = 0; i < n; ++i)
      dx[i] = settings.initial_step > 0.0 ? settings.initial_step
                                          : std::max(0.25 * (hi[i] - lo[i]), 1e-12);
    r = nlopt_set_initial_step(opt, dx.data());
  }
  double value = HUGE_VAL;
  if (r > 0) r = nlopt_optimize(opt, x.data(), &value);
  nlopt_destroy(opt);
  finish_outcome(static_cast<int>(r), value, x, ctx.evaluations, ctx.error, ctx.nan, "evaluation",
                 out);
  return out;
}

}  // namespace orthomech::solvers
