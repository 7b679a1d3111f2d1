// `orthomech optimize FILE --study OPT.yaml --out DIR`: design optimisation (docs/cli.md
// "optimize"): the study's design variables searched by NLopt for the best objective under the
// constraints (study/optimize.hpp), every evaluation one SQLite row committed as it finishes, the
// CSV of the evaluations, the optimal mechanism file and a summary with the convergence.
#include "orthomech/study/optimize.hpp"

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>

#include "commands.hpp"
#include "common.hpp"
#include "orthomech/io/file_writer.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/io/study_db.hpp"
#include "orthomech/io/study_report.hpp"
#include "run_bounds.hpp"

namespace orthomech::cli {

namespace {

namespace fs = std::filesystem;

struct OptimizeCliOptions {
  std::string file, study, out;
  bool json = false, resume = false;
  int jobs = 0;  // multistart: threads
  StudyReportOptions report;
  double time_limit = 0.0;  // s of wall clock; 0: none
};

// The summary document: the outcome, the optimum (variables, objective, constraints, every
// metric) and the convergence (each evaluation that improved the best feasible objective).
nlohmann::json summarize(const Study& study, const OptimizeResult& r, const std::string& optimum) {
  nlohmann::json j;
  j["study"] = "optimize";
  j["algorithm"] = study.goal.algorithm == OptimizeGoal::Algorithm::isres        ? "isres"
                   : study.goal.algorithm == OptimizeGoal::Algorithm::multistart ? "multistart"
                                                                                 : "cobyla";
  j["outcome"] = r.outcome;
  j["message"] = r.message;
  j["evaluations"] = r.evaluations;
  j["found"] = r.found;
  long feasible = 0;
  for (const OptimizeStep& s : r.steps) feasible += s.feasible ? 1 : 0;
  j["feasible_evaluations"] = feasible;
  j["objective"] = {{study.goal.maximize ? "maximize" : "minimize", study.goal.objective}};
  nlohmann::json convergence = nlohmann::json::array();
  for (const OptimizeStep& s : r.steps)
    if (s.best == s.evaluation)
      convergence.push_back({{"evaluation", s.evaluation}, {"objective", s.objective}});
  j["convergence"] = convergence;
  if (r.found) {
    nlohmann::json variables = nlohmann::json::object(), metrics = nlohmann::json::object();
    for (size_t k = 0; k < study.parameters.size(); ++k)
      variables[study.parameters[k].name] = r.best.values[k];
    for (const auto& [name, value] : r.best.metrics) metrics[name] = number_or_null(value);
    nlohmann::json constraints = nlohmann::json::array();
    for (size_t k = 0; k < study.goal.constraints.size(); ++k) {
      const OptimizeConstraint& c = study.goal.constraints[k];
      nlohmann::json e = {{"metric", c.text}};
      e[c.kind == OptimizeConstraint::Kind::at_least  ? "min"
        : c.kind == OptimizeConstraint::Kind::at_most ? "max"
                                                      : "equal"] = c.bound;
      if (c.kind == OptimizeConstraint::Kind::equal) e["tolerance"] = c.tolerance;
      const auto v = metrics.find("constraint." + std::to_string(k + 1));
      e["value"] = v == metrics.end() ? nlohmann::json() : *v;
      constraints.push_back(e);
    }
    j["optimum"] = {
        {"evaluation", r.best.index}, {"variables", variables}, {"objective", metrics["objective"]},
        {"constraints", constraints}, {"metrics", metrics},     {"file", optimum}};
  }
  return j;
}

std::string summary_text(const nlohmann::json& j, const fs::path& out) {
  std::ostringstream o;
  o << "optimize (" << j["algorithm"].get<std::string>() << "): " << j["outcome"].get<std::string>()
    << " after " << j["evaluations"].get<long>() << " evaluations ("
    << j["feasible_evaluations"].get<long>() << " feasible)\n";
  o << "objective: " << j["objective"].begin().key() << " "
    << j["objective"].begin()->get<std::string>() << "\n";
  o << "convergence (evaluation: best feasible objective):\n";
  for (const auto& c : j["convergence"])
    o << "  " << c["evaluation"].get<long>() << ": " << c["objective"].get<double>() << "\n";
  if (j.contains("optimum")) {
    const auto& opt = j["optimum"];
    o << "optimum (evaluation " << opt["evaluation"].get<long>() << "):\n";
    for (const auto& [name, v] : opt["variables"].items())
      o << "  " << name << " = " << v.get<double>() << "\n";
    o << "  objective = " << opt["objective"] << "\n";
    for (const auto& c : opt["constraints"]) o << "  constraint " << c.dump() << "\n";
    o << "optimal file: " << opt["file"].get<std::string>() << "\n";
  } else {
    o << "no feasible design was found\n";
  }
  o << "evaluations: " << (out / "evaluations.csv").string() << ", "
    << (out / "study.sqlite").string()
    << "; convergence plot: " << (out / "convergence.svg").string() << "\n";
  return o.str();
}

// The search's evaluations for the convergence plot, and its best feasible ones (the optimum
// first, at most `count`) for the report.
std::vector<ConvergencePoint> convergence_of(const OptimizeResult& r) {
  std::vector<ConvergencePoint> points;
  for (const OptimizeStep& s : r.steps)
    points.push_back({s.evaluation, s.objective, s.feasible,
                      s.best >= 0 ? s.best_objective : std::numeric_limits<double>::quiet_NaN()});
  return points;
}
std::vector<long> best_feasible(const OptimizeResult& r, bool maximize, size_t count) {
  std::vector<const OptimizeStep*> feasible;
  for (const OptimizeStep& s : r.steps)
    if (s.feasible) feasible.push_back(&s);
  std::stable_sort(feasible.begin(), feasible.end(), [&](const auto* a, const auto* b) {
    return maximize ? a->objective > b->objective : a->objective < b->objective;
  });
  std::vector<long> best;
  for (size_t k = 0; k < feasible.size() && k < count; ++k) best.push_back(feasible[k]->evaluation);
  return best;
}

int run_optimize_command(const OptimizeCliOptions& opt) {
  const std::string mechanism = read_input_file(opt.file, "file");
  {  // the nominal file must be valid: its errors are the file's, with their line
    const Model model = load(opt.file);
  }
  const std::string study_text = read_input_file(opt.study, "study");
  const Study study = parse_study(study_text, opt.study, mechanism, opt.file);
  if (study.kind != StudyKind::optimize) {
    spdlog::error("{}: the study is a {} study: run it with `orthomech sweep`", opt.study,
                  study.kind == StudyKind::grid ? "grid" : "monte-carlo");
    return kBadInput;
  }
  // The columns: those of the start design (the file with the starts of the variables).
  const VariantResult start =
      evaluate_variant(mechanism, opt.file, study, -1, variant_values(study, 0));
  if (start.metrics.empty()) {
    spdlog::error("{}: the start design cannot be evaluated ({}): {}", opt.file, start.status,
                  start.message);
    return kNumerical;
  }
  if (!unknown_report_metrics(opt.report, start).empty()) return kBadInput;
  const fs::path out = opt.out;
  const std::unique_ptr<StudyDatabase> db =
      open_study_database(opt.out, opt.resume, mechanism, study_text, study, start);
  if (!db) return kBadInput;
  // --resume: the stored evaluations, replayed by the search (run_optimize).
  std::vector<VariantResult> stored;
  for (const StudyDatabase::Row& row : db->rows()) {
    VariantResult r;
    r.index = row.index;
    r.values = row.values;
    r.status = row.status;
    r.message = row.message;
    for (size_t m = 0; m < db->metrics().size(); ++m)
      r.metrics.emplace_back(db->metrics()[m], row.metrics[m]);
    stored.push_back(std::move(r));
  }
  if (!stored.empty())
    spdlog::info("{}: {} evaluations stored, replayed before the search goes on", opt.study,
                 stored.size());
  const InterruptScope interrupts;
  const RunControl control = run_control("optimize", opt.time_limit);
  RunMonitor monitor(control, 0);
  StopReason stop = StopReason::none;
  // Progress: the evaluations computed over the budget (a multistart's: of every search).
  const double budget =
      double(study.goal.evaluations) *
      double(study.goal.algorithm == OptimizeGoal::Algorithm::multistart ? study.goal.starts : 1);
  long computed = 0;
  const auto store = [&](const VariantResult& r, const OptimizeStep& step) {
    if (step.replayed) return;
    db->insert(r);
    spdlog::debug("evaluation {}: {} objective {} violation {}", step.evaluation, r.status,
                  step.objective, step.violation);
    ++computed;
    stop = monitor.tick(double(computed) / budget);
  };
  OptimizeResult result;
  try {
    result = run_optimize(
        mechanism, opt.file, study, store, [&] { return stop != StopReason::none; }, stored,
        opt.jobs);
  } catch (const std::runtime_error& e) {  // the database (a full disk): the rows stored are kept
    end_progress();
    spdlog::error("{}", e.what());
    return kBadInput;
  } catch (const std::invalid_argument& e) {  // --resume of evaluations not this search's
    end_progress();
    spdlog::error("{}: {}", (out / "study.sqlite").string(), e.what());
    return kBadInput;
  }
  end_progress();
  if (stop != StopReason::none)
    spdlog::error("optimize: {}; the best design so far is kept",
                  monitor.stop_message(stop, double(computed) / budget, "evaluation", ""));
  std::string optimum;
  try {
    if (result.found) {
      std::string note;
      const std::string text = variant_file(mechanism, opt.file, study, result.best, &note);
      if (!note.empty()) spdlog::warn("{}: {}", (out / "optimum.yaml").string(), note);
      optimum = (out / "optimum.yaml").string();
      write_file(optimum, text);
    }
    nlohmann::json summary = summarize(study, result, optimum);
    summary["complete"] = stop == StopReason::none;  // stopped: the best of the evaluations so far
    if (stop != StopReason::none) summary["stop"] = to_string(stop);
    write_file(out / "evaluations.csv", study_csv(*db));
    write_file(out / "summary.json", summary.dump(2) + "\n");
    const std::string text = summary_text(summary, out);
    StudyReportRequest request;
    request.title = opt.study + " on " + opt.file;
    request.summary = text;
    request.metrics = opt.report.metrics;
    request.best = best_feasible(result, study.goal.maximize, 5);
    request.convergence = convergence_of(result);
    request.objective = study.goal.objective;
    const StudyReport report = study_report_of(study, *db, mechanism, opt.file, request);
    write_file(out / "convergence.svg", convergence_svg(report));
    write_study_report(opt.report, report);
    if (opt.json)
      std::cout << summary.dump(2) << "\n";
    else
      std::cout << text;
  } catch (const std::runtime_error& e) {
    spdlog::error("{}", e.what());
    return kBadInput;
  }
  if (stop != StopReason::none) return kStopped;
  if (!result.found) {
    spdlog::error("optimize: no evaluation met the constraints ({} evaluations)",
                  result.evaluations);
    return kNumerical;
  }
  return kOk;
}

}  // namespace

void register_optimize(CLI::App& app, const GlobalOptions& globals, int& exit_code) {
  auto opt = std::make_shared<OptimizeCliOptions>();
  CLI::App* cmd = app.add_subcommand(
      "optimize", "design optimisation: the best variables under constraints on any metric");
  cmd->add_option("file", opt->file, "mechanism file (YAML)")->required();
  cmd->add_option("--study", opt->study, "optimize study file (YAML, docs/cli.md \"optimize\")")
      ->required();
  cmd->add_option("--out,-o", opt->out,
                  "directory of study.sqlite, evaluations.csv, summary.json and optimum.yaml")
      ->required();
  cmd->add_flag("--json", opt->json, "the summary as one JSON document on stdout");
  cmd->add_flag("--resume", opt->resume,
                "continue the search stored in --out (its evaluations replayed, not computed "
                "again): the result of one uninterrupted run");
  cmd->add_option("--jobs,-j", opt->jobs,
                  "threads of a multistart's searches (default: every core); the results do not "
                  "depend on it")
      ->check(CLI::Range(0, 4096));
  add_study_report_options(cmd, opt->report);
  cmd->add_option("--time-limit", opt->time_limit,
                  "wall-clock limit in seconds (default: none): the search stops there, keeps the "
                  "best design so far and exits 5")
      ->check(finite_range(0.0, 1e9, true));
  auto log = std::make_shared<LogFlags>();
  add_log_flags(cmd, *log);
  cmd->callback([opt, log, &globals, &exit_code] {
    setup_logging(globals, *log);
    exit_code = run_optimize_command(*opt);
  });
}

}  // namespace orthomech::cli
