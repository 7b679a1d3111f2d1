#include "nlopt_minimize.hpp"

#include <nlopt.h>
#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <exception>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace orthomech::solvers {

namespace {

struct Context {
  const std::function<double(const Eigen::VectorXd&)>* f;
  nlopt_opt opt;
  Eigen::VectorXd x;
  int evaluations = 0;
  std::exception_ptr error;
  bool nan = false;
};

// C trampoline: nothing may propagate into NLopt's C frames.
double trampoline(unsigned n, const double* x, double* grad, void* data) {
  auto* ctx = static_cast<Context*>(data);
  if (grad)
    for (unsigned i = 0; i < n; ++i) grad[i] = 0.0;  // derivative-free methods only
  try {
    for (unsigned i = 0; i < n; ++i) ctx->x(i) = x[i];
    ++ctx->evaluations;
    const double v = (*ctx->f)(ctx->x);
    if (std::isnan(v)) {
      ctx->nan = true;
      nlopt_force_stop(ctx->opt);
      return HUGE_VAL;
    }
    return v;
  } catch (...) {
    ctx->error = std::current_exception();
    nlopt_force_stop(ctx->opt);
    return HUGE_VAL;
  }
}

}  // namespace

const char* to_string(NloptOutcomeKind k) {
  switch (k) {
    case NloptOutcomeKind::converged:
      return "converged";
    case NloptOutcomeKind::max_evaluations:
      return "evaluation limit";
    case NloptOutcomeKind::roundoff:
      return "roundoff limited";
    case NloptOutcomeKind::invalid:
      return "invalid arguments";
    case NloptOutcomeKind::failed:
      return "failed";
    case NloptOutcomeKind::callback_error:
      return "callback error";
  }
  return "?";
}

void finish_outcome(int code, double value, const std::vector<double>& x, int evaluations,
                    const std::exception_ptr& error, bool nan, const char* what,
                    NloptOutcome& out) {
  out.code = code;
  out.evaluations = evaluations;
  out.error = error;
  if (std::isfinite(value)) {
    for (size_t i = 0; i < x.size(); ++i) out.x(static_cast<Eigen::Index>(i)) = x[i];
    out.value = value;
  }
  if (error) {
    out.kind = NloptOutcomeKind::callback_error;
    try {
      std::rethrow_exception(error);
    } catch (const std::exception& e) {
      out.message = std::string("the ") + what + " threw: " + e.what();
    } catch (...) {
      out.message = std::string("the ") + what + " threw a non-standard exception";
    }
    return;
  }
  if (nan) {
    out.kind = NloptOutcomeKind::callback_error;
    out.message = std::string("the ") + what + " returned NaN";
    return;
  }
  const auto r = static_cast<nlopt_result>(code);
  switch (r) {
    case NLOPT_SUCCESS:
    case NLOPT_STOPVAL_REACHED:
    case NLOPT_FTOL_REACHED:
    case NLOPT_XTOL_REACHED:
      out.kind = NloptOutcomeKind::converged;
      out.message = "converged";
      break;
    case NLOPT_MAXEVAL_REACHED:
    case NLOPT_MAXTIME_REACHED:
      out.kind = NloptOutcomeKind::max_evaluations;
      out.message = "evaluation limit reached";
      break;
    case NLOPT_ROUNDOFF_LIMITED:
      out.kind = NloptOutcomeKind::roundoff;
      out.message = "roundoff limited";
      break;
    case NLOPT_INVALID_ARGS:
      out.kind = NloptOutcomeKind::invalid;
      out.message = "invalid arguments (bounds or start)";
      break;
    default:
      out.kind = NloptOutcomeKind::failed;
      out.message = "NLopt failed (code " + std::to_string(static_cast<int>(r)) + ")";
      break;
  }
}

NloptOutcome minimize_bounded(const std::function<double(const Eigen::VectorXd&)>& f,
                              const Eigen::VectorXd& x0, const Eigen::VectorXd& lower,
                              const Eigen::VectorXd& upper, const NloptSettings& settings) {
  NloptOutcome out;
  const auto n = static_cast<unsigned>(x0.size());
  out.x = x0;
  out.value = HUGE_VAL;
  if (n == 0 || lower.size() != x0.size() || upper.size() != x0.size()) {
    out.kind = NloptOutcomeKind::invalid;
    out.message = "empty problem or bounds of the wrong size";
    return out;
  }
  nlopt_opt opt = nlopt_create(n >= 2 ? NLOPT_LN_BOBYQA : NLOPT_LN_COBYLA, n);
  if (!opt) {
    out.kind = NloptOutcomeKind::failed;
    out.message = "NLopt could not create the optimiser";
    return out;
  }
  Context ctx{&f, opt, x0, 0, nullptr, false};
  std::vector<double> x(x0.data(), x0.data() + n);
  std::vector<double> lo(lower.data(), lower.data() + n), hi(upper.data(), upper.data() + n);
  nlopt_result r = nlopt_set_lower_bounds(opt, lo.data());
  if (r > 0) r = nlopt_set_upper_bounds(opt, hi.data());
  if (r > 0) r = nlopt_set_min_objective(opt, trampoline, &ctx);
  if (r > 0) r = nlopt_set_xtol_abs1(opt, settings.xtol_abs);
  if (r > 0 && settings.ftol_abs > 0.0) r = nlopt_set_ftol_abs(opt, settings.ftol_abs);
  if (r > 0) r = nlopt_set_maxeval(opt, settings.max_evaluations);
  if (r > 0) {
    // Initial step: a quarter of the box (COBYLA/BOBYQA otherwise guess from x0).
    std::vector<double> dx(n);
    for (unsigned i = 0; i < n; ++i) dx[i] = std::max(0.25 * (hi[i] - lo[i]), 1e-12);
    r = nlopt_set_initial_step(opt, dx.data());
  }
  double value = HUGE_VAL;
  if (r > 0) r = nlopt_optimize(opt, x.data(), &value);
  nlopt_destroy(opt);
  finish_outcome(static_cast<int>(r), value, x, ctx.evaluations, ctx.error, ctx.nan, "objective",
                 out);
  return out;
}

namespace {

constexpr std::array<int, 40> kPrimes{
    2,  3,  5,  7,  11, 13,  17,  19,  23,  29,  31,  37,  41,  43,  47,  53,  59,  61,  67,  71,
    73, 79, 83, 89, 97, 101, 103, 107, 109, 113, 127, 131, 137, 139, 149, 151, 157, 163, 167, 173};

// The radical inverse of `index` in `base` (the Halton coordinate).
double radical_inverse(long long index, int base) {
  double inv = 1.0 / base, f = inv, r = 0.0;
  while (index > 0) {
    r += f * static_cast<double>(index % base);
    index /= base;
    f *= inv;
  }
  return r;
}

}  // namespace

Eigen::MatrixXd quasi_random_starts(const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                                    int count, unsigned long long seed) {
  const auto n = static_cast<int>(std::min<Eigen::Index>(lower.size(), kPrimes.size()));
  Eigen::MatrixXd X(lower.size(), std::max(count, 0));
  std::mt19937_64 rng(seed);
  Eigen::VectorXd shift(lower.size());
  // 53 random bits → [0, 1): the same numbers on every standard library.
  for (Eigen::Index i = 0; i < shift.size(); ++i)
    shift(i) = static_cast<double>(rng() >> 11) * 0x1.0p-53;
  for (int k = 0; k < count; ++k)
    for (Eigen::Index i = 0; i < lower.size(); ++i) {
      const int base = kPrimes[static_cast<std::size_t>(std::min<Eigen::Index>(i, n - 1))];
      double u = radical_inverse(k + 1, base) + shift(i);
      u -= std::floor(u);
      X(i, k) = lower(i) + u * (upper(i) - lower(i));
    }
  return X;
}

namespace {

// Every process's runs in every process (MultistartSettings::share): each run a record
// [kind, code, value, evaluations, x_1 … x_n], process r's runs k = r, r + size, … in order.
void gather_runs(const ProcessShare& share, int runs, Eigen::Index n,
                 std::vector<NloptOutcome>& locals) {
  const auto width = static_cast<std::size_t>(4 + n);
  const auto count = [&](int r) { return r < runs ? (runs - r + share.size - 1) / share.size : 0; };
  std::vector<double> mine;
  mine.reserve(static_cast<std::size_t>(count(share.rank)) * width);
  for (int k = share.rank; k < runs; k += share.size) {
    const NloptOutcome& o = locals[static_cast<std::size_t>(k)];
    mine.insert(mine.end(), {static_cast<double>(o.kind), static_cast<double>(o.code), o.value,
                             static_cast<double>(o.evaluations)});
    for (Eigen::Index i = 0; i < n; ++i) mine.push_back(i < o.x.size() ? o.x(i) : 0.0);
  }
  std::vector<int> counts(static_cast<std::size_t>(share.size));
  for (int r = 0; r < share.size; ++r)
    counts[static_cast<std::size_t>(r)] = count(r) * static_cast<int>(width);
  const std::vector<double> all = share.gather(mine, counts);
  std::size_t at = 0;
  for (int r = 0; r < share.size; ++r)
    for (int k = r; k < runs; k += share.size, at += width) {
      if (r == share.rank) continue;  // this process's own, with its message
      NloptOutcome& o = locals[static_cast<std::size_t>(k)];
      o.kind = static_cast<NloptOutcomeKind>(static_cast<int>(all[at]));
      o.code = static_cast<int>(all[at + 1]);
      o.value = all[at + 2];
      o.evaluations = static_cast<int>(all[at + 3]);
      o.x = Eigen::Map<const Eigen::VectorXd>(all.data() + at + 4, n);
      o.message = "run on process " + std::to_string(r);
      if (o.kind == NloptOutcomeKind::callback_error)
        o.error = std::make_exception_ptr(
            std::runtime_error("the objective failed on process " + std::to_string(r)));
    }
}

}  // namespace

MultistartOutcome minimize_multistart(const ObjectiveFactory& make, const Eigen::VectorXd& lower,
                                      const Eigen::VectorXd& upper,
                                      const MultistartSettings& settings) {
  // 1. The starts: extra ones first, then the quasi-random design.
  const Eigen::MatrixXd grid = quasi_random_starts(lower, upper, settings.starts, settings.seed);
  const auto extra = static_cast<int>(settings.extra_starts.size());
  const int runs = extra + static_cast<int>(grid.cols());
  // 2. This process's local runs (every run, unless processes share them), on as many threads
  //    as asked, each thread with its own objective.
  std::vector<NloptOutcome> locals(static_cast<std::size_t>(runs));
  const ProcessShare& share = settings.share;
  const int stride = share.shared() ? share.size : 1, first = share.shared() ? share.rank : 0;
  const int mine = first < runs ? (runs - first + stride - 1) / stride : 0;
  const int threads = settings.threads > 0 ? settings.threads : omp_get_max_threads();
#pragma omp parallel num_threads(threads) if (threads > 1 && mine > 1)
  {
    const Objective f = make();
#pragma omp for schedule(dynamic, 1)
    for (int j = 0; j < mine; ++j) {
      const int k = first + j * stride;
      const Eigen::VectorXd x0 =
          k < extra ? settings.extra_starts[static_cast<std::size_t>(k)] : grid.col(k - extra);
      locals[static_cast<std::size_t>(k)] = minimize_bounded(f, x0, lower, upper, settings.local);
    }
  }
  if (share.shared()) gather_runs(share, runs, lower.size(), locals);
  // 3. The outcome in start order, up to the first callback error.
  MultistartOutcome out;
  out.best.x = lower;
  out.best.value = HUGE_VAL;
  out.best.message = "no start";
  out.locals.reserve(locals.size());
  for (int k = 0; k < runs; ++k) {
    NloptOutcome& r = locals[static_cast<std::size_t>(k)];
    out.evaluations += r.evaluations;
    const bool stop = r.kind == NloptOutcomeKind::callback_error;
    if (stop || r.value < out.best.value || k == 0) out.best = r;
    out.locals.push_back(std::move(r));
    if (stop) break;
  }
  return out;
}

MultistartOutcome minimize_multistart(const Objective& f, const Eigen::VectorXd& lower,
                                      const Eigen::VectorXd& upper,
                                      const MultistartSettings& settings) {
  MultistartSettings one = settings;
  one.threads = 1;
  return minimize_multistart([&f] { return f; }, lower, upper, one);
}

}  // namespace orthomech::solvers
