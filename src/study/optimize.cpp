#include "orthomech/study/optimize.hpp"

#include <omp.h>

#include <Eigen/Core>
#include <algorithm>
#include <boost/random/mersenne_twister.hpp>
#include <boost/random/uniform_real_distribution.hpp>
#include <cmath>
#include <cstdint>
#include <exception>
#include <limits>
#include <mutex>
#include <random>
#include <stdexcept>

#include "../solvers/nlopt_constrained.hpp"
#include "orthomech/analysis/cycle.hpp"
#include "orthomech/analysis/multi_drive.hpp"
#include "orthomech/error.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/io/mechanism_writer.hpp"

namespace orthomech {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A search stopped by the caller's `stop` (not an error: the best so far is kept).
struct Stopped : std::runtime_error {
  Stopped() : std::runtime_error("stopped") {}
};

double column(const VariantResult& r, const std::string& name) {
  for (const auto& [n, v] : r.metrics)
    if (n == name) return v;
  return kNaN;
}

double scale(const OptimizeConstraint& c) { return std::max(std::abs(c.bound), 1.0); }

// The scaled constraint values (≤ 0 where met) of a variant with every goal column.
std::vector<double> constraint_values(const OptimizeGoal& goal, const VariantResult& r) {
  std::vector<double> g;
  for (size_t k = 0; k < goal.constraints.size(); ++k) {
    const OptimizeConstraint& c = goal.constraints[k];
    const double v = column(r, "constraint." + std::to_string(k + 1)), s = scale(c);
    switch (c.kind) {
      case OptimizeConstraint::Kind::at_least:
        g.push_back((c.bound - v) / s);
        break;
      case OptimizeConstraint::Kind::at_most:
        g.push_back((v - c.bound) / s);
        break;
      case OptimizeConstraint::Kind::equal:
        g.push_back((v - c.bound - c.tolerance) / s);
        g.push_back((c.bound - c.tolerance - v) / s);
        break;
    }
  }
  return g;
}

int constraint_count(const OptimizeGoal& goal) {
  int m = 0;
  for (const OptimizeConstraint& c : goal.constraints)
    m += c.kind == OptimizeConstraint::Kind::equal ? 2 : 1;
  return m;
}

// Where a search starts in the unit box: the study's start, or (a multistart's search s ≥ 1) a
// point drawn from the search's own stream.
Eigen::VectorXd start_point(const Study& study, long search) {
  const size_t n = study.parameters.size();
  Eigen::VectorXd x0(n);
  if (search == 0) {
    for (size_t j = 0; j < n; ++j) {
      const StudyParameter& p = study.parameters[j];
      x0(j) = (p.mean - p.lower) / (p.upper - p.lower);
    }
    return x0;
  }
  std::seed_seq seq{static_cast<std::uint32_t>(study.seed),
                    static_cast<std::uint32_t>(study.seed >> 32),
                    static_cast<std::uint32_t>(search), static_cast<std::uint32_t>(search >> 32)};
  boost::random::mt19937_64 engine(seq);
  boost::random::uniform_real_distribution<double> unit(0.0, 1.0);
  for (size_t j = 0; j < n; ++j) x0(j) = unit(engine);
  return x0;
}

class Search {
 public:
  // Search number `search` of a multistart (0 otherwise): its evaluations numbered from `first`,
  // `stored` its stored ones in order.
  Search(const std::string& mechanism, const std::string& origin, const Study& study,
         const std::function<void(const VariantResult&, const OptimizeStep&)>& done,
         const std::function<bool()>& stop, const std::vector<VariantResult>& stored,
         long search = 0, long first = 0)
      : mechanism_(mechanism),
        origin_(origin),
        study_(study),
        done_(done),
        stop_(stop),
        stored_(stored),
        search_(search),
        first_(first) {}

  OptimizeResult run() {
    const size_t n = study_.parameters.size();
    const Eigen::VectorXd x0 = start_point(study_, search_);
    const Eigen::VectorXd lo = Eigen::VectorXd::Zero(n), hi = Eigen::VectorXd::Ones(n);
    solvers::ConstrainedSettings settings;
    settings.method = study_.goal.algorithm == OptimizeGoal::Algorithm::isres
                          ? solvers::ConstrainedMethod::isres
                          : solvers::ConstrainedMethod::cobyla;
    settings.xtol_abs = study_.goal.tolerance;
    settings.max_evaluations = static_cast<int>(study_.goal.evaluations);
    settings.seed = study_.seed;
    const solvers::NloptOutcome o =
        solvers::minimize_constrained([this](const Eigen::VectorXd& x) { return evaluate(x); },
                                      constraint_count(study_.goal), x0, lo, hi, settings);
    result_.evaluations = static_cast<long>(result_.steps.size());
    result_.outcome = solvers::to_string(o.kind);
    result_.message = o.message;
    if (o.kind == solvers::NloptOutcomeKind::callback_error && o.error) {
      try {
        std::rethrow_exception(o.error);
      } catch (const Stopped&) {
        result_.outcome = "stopped";
        result_.message = "stopped before the search ended";
      } catch (...) {
        throw;  // an internal error of the evaluation: not a variant's outcome
      }
    }
    return result_;
  }

 private:
  const std::string& mechanism_;
  const std::string& origin_;
  const Study& study_;
  const std::function<void(const VariantResult&, const OptimizeStep&)>& done_;
  const std::function<bool()>& stop_;
  const std::vector<VariantResult>& stored_;
  long search_ = 0, first_ = 0;
  OptimizeResult result_;
  double worst_ = kNaN;  // the worst objective (minimised sense) of the variants with numbers

  // Evaluation k: the stored one when there is one (at the same values), else computed.
  VariantResult variant(long k, const std::vector<double>& values, OptimizeStep& step) {
    if (k - first_ < static_cast<long>(stored_.size())) {
      const VariantResult& r = stored_[static_cast<size_t>(k - first_)];
      if (r.values != values) {
        std::string at;
        for (size_t j = 0; j < values.size(); ++j)
          at += (j ? ", " : "") + study_.parameters[j].name + " = " + value_text(values[j]) +
                " (stored " + (j < r.values.size() ? value_text(r.values[j]) : "none") + ")";
        throw std::invalid_argument("evaluation " + std::to_string(k) +
                                    " of the stored study was at other values (" + at +
                                    "): the stored evaluations are not this search's");
      }
      step.replayed = true;
      return r;
    }
    if (stop_ && stop_()) throw Stopped();
    return evaluate_variant(mechanism_, origin_, study_, k, values);
  }

  solvers::ConstrainedValue evaluate(const Eigen::VectorXd& x) {
    std::vector<double> values(x.size());
    for (Eigen::Index j = 0; j < x.size(); ++j) {
      const StudyParameter& p = study_.parameters[static_cast<size_t>(j)];
      values[static_cast<size_t>(j)] =
          std::clamp(p.lower + x(j) * (p.upper - p.lower), p.lower, p.upper);
    }
    OptimizeStep step;
    step.evaluation = first_ + static_cast<long>(result_.steps.size());
    const VariantResult r = variant(step.evaluation, values, step);
    const double sign = study_.goal.maximize ? -1.0 : 1.0;
    step.objective = column(r, "objective");
    std::vector<double> g = constraint_values(study_.goal, r);
    const bool numbers = r.status == "completed" && std::isfinite(step.objective) &&
                         std::all_of(g.begin(), g.end(), [](double v) { return std::isfinite(v); });
    solvers::ConstrainedValue out;
    if (numbers) {
      step.violation = 0.0;
      for (double v : g) step.violation = std::max(step.violation, v);
      step.feasible = step.violation <= kOptimizeFeasibility;
      out.objective = sign * step.objective;
      worst_ = std::isnan(worst_) ? out.objective : std::max(worst_, out.objective);
      out.constraints = std::move(g);
    } else {
      step.violation = 1.0;
      out.objective = std::isnan(worst_) ? 0.0 : worst_;
      out.constraints.assign(static_cast<size_t>(constraint_count(study_.goal)), 1.0);
    }
    const OptimizeStep* previous = result_.steps.empty() ? nullptr : &result_.steps.back();
    step.best = previous ? previous->best : -1;
    step.best_objective = previous ? previous->best_objective : kNaN;
    if (step.feasible && (step.best < 0 || sign * step.objective < sign * step.best_objective)) {
      step.best = step.evaluation;
      step.best_objective = step.objective;
      result_.found = true;
      result_.best = r;
    }
    result_.steps.push_back(step);
    if (done_) done_(r, step);
    return out;
  }
};

// The searches of a multistart merged: the steps in evaluation order with the best so far over
// them, the best feasible evaluation (the lowest on a tie), the outcome.
OptimizeResult merge_searches(const Study& study, std::vector<OptimizeResult>& searches) {
  OptimizeResult out;
  for (OptimizeResult& r : searches)
    out.steps.insert(out.steps.end(), r.steps.begin(), r.steps.end());
  std::sort(out.steps.begin(), out.steps.end(), [](const OptimizeStep& a, const OptimizeStep& b) {
    return a.evaluation < b.evaluation;
  });
  const double sign = study.goal.maximize ? -1.0 : 1.0;
  long best = -1;
  double best_objective = kNaN;
  for (OptimizeStep& s : out.steps) {
    if (s.feasible && (best < 0 || sign * s.objective < sign * best_objective)) {
      best = s.evaluation;
      best_objective = s.objective;
    }
    s.best = best;
    s.best_objective = best_objective;
  }
  long converged = 0, stopped = 0;
  for (const OptimizeResult& r : searches) {
    if (r.found && r.best.index == best) out.best = r.best;
    converged += r.outcome == "stopped" ? 0 : 1;
    stopped += r.outcome == "stopped" ? 1 : 0;
  }
  out.found = best >= 0;
  out.evaluations = static_cast<long>(out.steps.size());
  out.outcome = stopped > 0 ? "stopped" : "multistart completed";
  out.message = std::to_string(searches.size()) + " searches, " + std::to_string(converged) +
                " ended by themselves (converged or at their budget), " + std::to_string(stopped) +
                " stopped";
  return out;
}

OptimizeResult run_multistart(
    const std::string& mechanism, const std::string& origin, const Study& study,
    const std::function<void(const VariantResult&, const OptimizeStep&)>& done,
    const std::function<bool()>& stop, const std::vector<VariantResult>& stored, int jobs) {
  const long budget = study.goal.evaluations, count = study.goal.starts;
  // Each search's stored evaluations: those numbered s × budget, s × budget + 1, … in order.
  std::vector<std::vector<VariantResult>> slices(static_cast<size_t>(count));
  for (const VariantResult& r : stored) {
    const long s = r.index / budget;
    if (r.index < 0 || s >= count ||
        r.index != s * budget + static_cast<long>(slices[static_cast<size_t>(s)].size()))
      throw std::invalid_argument("stored evaluation " + std::to_string(r.index) +
                                  " is not the next of its search (search s numbers its "
                                  "evaluations from s × " +
                                  std::to_string(budget) + ")");
    slices[static_cast<size_t>(s)].push_back(r);
  }
  std::mutex lock;
  const std::function<void(const VariantResult&, const OptimizeStep&)> done_one =
      [&](const VariantResult& r, const OptimizeStep& step) {
        const std::lock_guard<std::mutex> hold(lock);
        if (done) done(r, step);
      };
  const std::function<bool()> stop_one = [&] {
    const std::lock_guard<std::mutex> hold(lock);
    return stop && stop();
  };
  std::vector<OptimizeResult> searches(static_cast<size_t>(count));
  std::exception_ptr failure;
  const int threads = jobs > 0 ? jobs : omp_get_max_threads();
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads) if (threads != 1)
  for (long s = 0; s < count; ++s) {
    try {
      searches[static_cast<size_t>(s)] = Search(mechanism, origin, study, done_one, stop_one,
                                                slices[static_cast<size_t>(s)], s, s * budget)
                                             .run();
    } catch (...) {
      const std::lock_guard<std::mutex> hold(lock);
      if (!failure) failure = std::current_exception();
    }
  }
  if (failure) std::rethrow_exception(failure);
  return merge_searches(study, searches);
}

}  // namespace

std::string variant_file(const std::string& mechanism, const std::string& origin,
                         const Study& study, const VariantResult& variant, std::string* note) {
  std::string text = with_file_values(mechanism, origin, variant_changes(study, variant.values));
  const Model model = parse_mechanism(text, origin, {});
  // The start: of the several drivers' sweep (the design position with each driven joint at its
  // law's value at t = 0), else of the one driver's cycle.
  VecX start;
  std::string why;
  if (!study.drivers.empty()) {
    MultiDriveOptions mo;
    for (const std::string& name : study.drivers)
      for (const Driver& d : model.drivers)
        if (d.name == name) mo.drivers.push_back(d);
    mo.steps = 2;  // the start is what is wanted
    const MultiDriveResult m = run_multi_drive(model, mo);
    if (!m.points.empty()) start = m.points[0].q;
    why = m.message;
  } else {
    const Driver* driver = study_driver(model);
    if (!driver) return text;
    CycleOptions co;
    co.driver = *driver;
    co.steps = 2;  // the start is what is wanted
    const CycleResult c = run_cycle(model, co);
    if (!c.points.empty()) start = c.points[0].q;
    why = c.message;
  }
  if (start.size() == 0) {
    if (note) *note = "the poses are as drawn: the cycle's start was not computed (" + why + ")";
    return text;
  }
  try {
    return edit_design_poses(text, origin, model, start).text;
  } catch (const InputError& e) {
    if (note) *note = std::string("the poses are as drawn: ") + e.what();
    return text;
  }
}

OptimizeResult run_optimize(
    const std::string& mechanism, const std::string& origin, const Study& study,
    const std::function<void(const VariantResult&, const OptimizeStep&)>& done,
    const std::function<bool()>& stop, const std::vector<VariantResult>& stored, int jobs) {
  if (study.kind != StudyKind::optimize)
    throw std::invalid_argument("run_optimize: the study is not an optimize study");
  if (study.goal.algorithm != OptimizeGoal::Algorithm::multistart) {
    for (size_t k = 0; k < stored.size(); ++k)
      if (stored[k].index != static_cast<long>(k))
        throw std::invalid_argument("the stored evaluations are not 0, 1, … in order (evaluation " +
                                    std::to_string(k) + " is missing)");
    return Search(mechanism, origin, study, done, stop, stored).run();
  }
  return run_multistart(mechanism, origin, study, done, stop, stored, jobs);
}

}  // namespace orthomech
