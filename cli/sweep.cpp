// `orthomech sweep FILE --study STUDY --out DIR`: a design study (docs/cli.md "sweep"): every
// variant of the study swept through its cycle on every core (OpenMP), one SQLite row per variant
// committed as it finishes (`--resume` continues a killed study), the CSV in variant order, and a
// summary: the best variants of a grid, or the quantiles and sensitivities of a Monte Carlo study.
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "commands.hpp"
#include "common.hpp"
#include "orthomech/io/cycle_output.hpp"
#include "orthomech/io/file_writer.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/io/study_db.hpp"
#include "orthomech/io/study_report.hpp"
#include "orthomech/study/distributed.hpp"
#include "orthomech/study/study.hpp"
#include "run_bounds.hpp"

namespace orthomech::cli {

namespace {

namespace fs = std::filesystem;

struct SweepCliOptions {
  std::string file, study, out;
  StudyReportOptions report;
  std::vector<std::string> combine;  // --combine DIR,DIR: stored studies to join
  int jobs = 0;
  bool resume = false, json = false;
  double time_limit = 0.0;  // s of wall clock; 0: none
};

// Thrown by the store callback to end the variants' loop at a bound (run_variants and
// coordinate_variants stop handing out variants when `done` throws, and rethrow it).
struct StopSweep {
  StopReason reason;
};

// OpenMP takes the pending variants in blocks of this many indices, so that the memory does not
// grow with the study (a grid of 1e9 variants holds one block, not 8 GB of indices).
constexpr long kPendingBlock = 4096;

// The summary: counts by status; per metric the nominal value and, for Monte Carlo, the
// statistics and sensitivities; for a grid, the best variants.
nlohmann::json summarize(const Study& study, const StudyDatabase& db,
                         const VariantResult& nominal) {
  const std::vector<StudyDatabase::Row> rows = db.rows();
  nlohmann::json j;
  j["study"] = study.kind == StudyKind::grid ? "grid" : "monte-carlo";
  j["variants"] = rows.size();
  std::map<std::string, long> counts;
  for (const auto& r : rows) ++counts[r.status];
  j["status"] = counts;
  j["parameters"] = db.parameters();
  nlohmann::json nominal_j = nlohmann::json::object();
  for (const auto& [name, value] : nominal.metrics) nominal_j[name] = number_or_null(value);
  j["nominal"] = nominal_j;
  // Metrics of the cycle only of variants whose cycle completed (a stopped sweep's peaks are
  // partial); the checks of the design (validate.*, assemble.*) of every variant that has them
  // (a variant that does not assemble is part of the yield).
  std::vector<std::vector<double>> values;
  values.reserve(rows.size());
  for (const auto& r : rows) values.push_back(r.values);
  const auto metric_column = [&](size_t m) { return summarized_metric(rows, m, db.metrics()[m]); };
  if (study.kind == StudyKind::monte_carlo) {
    nlohmann::json metrics = nlohmann::json::array();
    for (size_t m = 0; m < db.metrics().size(); ++m) {
      const MetricStatistics s = metric_statistics(db.metrics()[m], values, metric_column(m));
      nlohmann::json e = {{"metric", s.metric}, {"n", s.n}};
      if (s.n > 0) {
        e["mean"] = s.mean;
        e["std"] = s.stddev;
        e["min"] = s.min;
        e["q05"] = s.q05;
        e["q50"] = s.q50;
        e["q95"] = s.q95;
        e["max"] = s.max;
      }
      nlohmann::json sens = nlohmann::json::object();
      for (size_t p = 0; p < s.sensitivity.size(); ++p)
        if (s.sensitivity[p])
          sens[db.parameters()[p]] = {{"coefficient", s.sensitivity[p]->coefficient},
                                      {"std_error", s.sensitivity[p]->std_error},
                                      {"ci95", {s.sensitivity[p]->low, s.sensitivity[p]->high}}};
      e["sensitivity"] = sens;
      metrics.push_back(e);
    }
    j["metrics"] = metrics;
  } else {
    const auto& names = db.metrics();
    const auto it = std::find(names.begin(), names.end(), study.best_metric);
    nlohmann::json best = nlohmann::json::array();
    if (it != names.end()) {
      const size_t m = static_cast<size_t>(it - names.begin());
      for (const StudyDatabase::Row* row :
           best_rows(rows, m, study.best_largest, study.best_count)) {
        nlohmann::json e = {{"variant", row->index}, {study.best_metric, row->metrics[m]}};
        for (size_t p = 0; p < db.parameters().size(); ++p) e[db.parameters()[p]] = row->values[p];
        best.push_back(e);
      }
    }
    j["best"] = {{"metric", study.best_metric},
                 {"order", study.best_largest ? "max" : "min"},
                 {"variants", best}};
  }
  return j;
}

std::string fixed(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.6g", v);
  return buffer;
}

std::string summary_text(const nlohmann::json& j, const fs::path& out) {
  std::ostringstream o;
  o << "study       " << j["study"].get<std::string>() << ", " << j["variants"].get<long>()
    << " variants:";
  for (const auto& [status, n] : j["status"].items()) o << " " << n.get<long>() << " " << status;
  o << "\noutput      " << (out / "study.sqlite").string() << ", "
    << (out / "variants.csv").string() << ", " << (out / "summary.json").string() << "\n";
  if (j.contains("metrics")) {
    o << "metrics in the file's units (of the completed variants; checks of every variant):\n";
    char line[256];
    int width = 16;  // the longest metric name (validate.p1.transmission, …)
    for (const auto& m : j["metrics"])
      width = std::max(width, static_cast<int>(m["metric"].get<std::string>().size()));
    std::snprintf(line, sizeof line, "  %-*s %12s %12s %12s %12s %12s %12s\n", width, "metric",
                  "nominal", "mean", "std", "q05", "q50", "q95");
    o << line;
    for (const auto& m : j["metrics"]) {
      const std::string name = m["metric"];
      const auto value = [&](const nlohmann::json& v) {
        return v.is_number() ? fixed(v.get<double>()) : std::string("-");
      };
      std::snprintf(line, sizeof line, "  %-*s %12s %12s %12s %12s %12s %12s\n", width,
                    name.c_str(), value(j["nominal"].value(name, nlohmann::json())).c_str(),
                    value(m.value("mean", nlohmann::json())).c_str(),
                    value(m.value("std", nlohmann::json())).c_str(),
                    value(m.value("q05", nlohmann::json())).c_str(),
                    value(m.value("q50", nlohmann::json())).c_str(),
                    value(m.value("q95", nlohmann::json())).c_str());
      o << line;
    }
    o << "sensitivities (metric change per unit of the parameter, least squares; 95 % interval):\n";
    for (const auto& m : j["metrics"])
      for (const auto& [parameter, s] : m["sensitivity"].items())
        o << "  " << m["metric"].get<std::string>() << " / " << parameter << "  "
          << fixed(s["coefficient"].get<double>()) << "  [" << fixed(s["ci95"][0].get<double>())
          << ", " << fixed(s["ci95"][1].get<double>()) << "]\n";
  } else {
    const auto& best = j["best"];
    o << "best by " << best["metric"].get<std::string>() << " (" << best["order"].get<std::string>()
      << "):\n";
    for (const auto& v : best["variants"]) {
      o << "  variant " << v["variant"].get<long>() << ":";
      for (const auto& [k, x] : v.items())
        if (k != "variant") o << "  " << k << " = " << fixed(x.get<double>());
      o << "\n";
    }
  }
  return o.str();
}

// --report and --figures: the page and the figures of the stored study (io/study_report.hpp).
void write_report(const SweepCliOptions& opt, const Study& study, const StudyDatabase& db,
                  const std::string& mechanism, const std::string& summary) {
  if (opt.report.html.empty() && opt.report.figures.empty()) return;
  StudyReportRequest request;
  request.title = opt.study + " on " + opt.file;
  request.summary = summary;
  request.metrics = opt.report.metrics;
  write_study_report(opt.report, study_report_of(study, db, mechanism, opt.file, request));
}

// The files of a stored study (`--out`): the CSV, the summary, the report; the summary printed.
int write_study_files(const SweepCliOptions& opt, const Study& study, const StudyDatabase& db,
                      const std::string& mechanism, nlohmann::json summary) {
  const fs::path out = opt.out;
  const std::string text = summary_text(summary, out);
  try {
    write_file(out / "variants.csv", study_csv(db));
    write_file(out / "summary.json", summary.dump(2) + "\n");
    write_report(opt, study, db, mechanism, text);
  } catch (const std::runtime_error& e) {
    spdlog::error("{}", e.what());
    return kBadInput;
  }
  if (opt.json)
    std::cout << summary.dump(2) << "\n";
  else
    std::cout << text;
  return kOk;
}

// --combine DIR1,DIR2,…: the stored studies of the same mechanism file, with the study's columns,
// joined into --out as one study: DIR1's variants first, renumbered 0, 1, … in that order; the
// summary (quantiles, sensitivities or the best variants) over all of them. Nothing is computed.
int combine_studies(const SweepCliOptions& opt, const Study& study, const std::string& study_text,
                    const std::string& mechanism, const VariantResult& nominal) {
  std::vector<std::string> parameters, metrics;
  for (const auto& p : study.parameters) parameters.push_back(p.name);
  for (const auto& [name, value] : nominal.metrics) metrics.push_back(name);
  std::vector<StoredStudy> parts;
  nlohmann::json sources = nlohmann::json::array();
  for (const std::string& dir : opt.combine) {
    try {
      parts.push_back(read_stored_study(fs::path(dir) / "study.sqlite"));
    } catch (const std::runtime_error& e) {
      spdlog::error("--combine: {}", e.what());
      return kBadInput;
    }
    const StoredStudy& s = parts.back();
    const auto mech = std::find_if(s.identity.begin(), s.identity.end(),
                                   [](const auto& kv) { return kv.first == "mechanism"; });
    if (mech == s.identity.end() || mech->second != mechanism) {
      spdlog::error(
          "--combine: {}: a study of another mechanism file (combined studies have the "
          "nominal file {})",
          dir, opt.file);
      return kBadInput;
    }
    if (s.parameters != parameters || s.metrics != metrics) {
      spdlog::error(
          "--combine: {}: other columns than {}'s ({} parameters, {} metrics there; {} "
          "and {} here)",
          dir, opt.study, s.parameters.size(), s.metrics.size(), parameters.size(), metrics.size());
      return kBadInput;
    }
    sources.push_back({{"study", dir}, {"variants", s.rows.size()}});
  }
  std::error_code ec;
  fs::create_directories(opt.out, ec);
  std::unique_ptr<StudyDatabase> db;
  try {  // a combined study is not a study to --resume: its identity says so
    db = std::make_unique<StudyDatabase>(fs::path(opt.out) / "study.sqlite", false,
                                         std::vector<std::pair<std::string, std::string>>{
                                             {"mechanism", mechanism},
                                             {"study", study_identity(study_text, "study")},
                                             {"combined", sources.dump()}},
                                         parameters, metrics);
    long index = 0;
    for (const StoredStudy& s : parts)
      for (const StudyDatabase::Row& row : s.rows) {
        VariantResult r;
        r.index = index++;
        r.values = row.values;
        r.status = row.status;
        r.message = row.message;
        for (size_t m = 0; m < metrics.size(); ++m)
          r.metrics.emplace_back(metrics[m], row.metrics[m]);
        db->insert(r);
      }
  } catch (const std::runtime_error& e) {
    spdlog::error("{}", e.what());
    return kBadInput;
  }
  nlohmann::json summary = summarize(study, *db, nominal);
  summary["complete"] = true;
  summary["combined"] = sources;
  return write_study_files(opt, study, *db, mechanism, summary);
}

// Under mpirun: rank 0 releases the other ranks with "stop" when it returns before the study
// starts (it alone reports why), then finalises MPI.
struct MpiStartGuard {
  MpiSession* mpi = nullptr;
  bool started = false;
  ~MpiStartGuard() {
    if (mpi && !started) {
      (void)broadcast_start(false);
      mpi->finish();
    }
  }
};

// Ranks other than 0: wait for rank 0's go, then evaluate the variants it hands out; no output.
int serve_sweep(const SweepCliOptions& opt, MpiSession& mpi) {
  if (!broadcast_start(false)) {
    mpi.finish();
    return kOk;
  }
  const std::string mechanism = read_input_file(opt.file, "file");
  Study study = parse_study(read_input_file(opt.study, "study"), opt.study, mechanism, opt.file);
  attach_nominal_paths(study, mechanism, opt.file);
  serve_variants(mechanism, opt.file, study);
  mpi.finish();
  return kOk;
}

int run_sweep_command(const SweepCliOptions& opt) {
  std::optional<MpiSession> mpi;
  if (mpi_launched()) mpi.emplace();
  if (mpi && mpi->rank() != 0) return serve_sweep(opt, *mpi);
  MpiStartGuard guard{mpi ? &*mpi : nullptr};

  const std::string mechanism = read_input_file(opt.file, "file");
  {  // the nominal file must be valid: its errors are the file's, with their line
    const Model model = load(opt.file);
    (void)model;
  }
  const std::string study_text = read_input_file(opt.study, "study");
  Study study = parse_study(study_text, opt.study, mechanism, opt.file);
  if (study.kind == StudyKind::optimize) {
    spdlog::error("{}: an optimize study: run it with `orthomech optimize`", opt.study);
    return kBadInput;
  }
  attach_nominal_paths(study, mechanism, opt.file);  // the deviations' reference, computed once

  // The nominal design fixes the metric columns.
  Study nominal_study = study;
  nominal_study.parameters.clear();
  const VariantResult nominal = evaluate_variant(mechanism, opt.file, nominal_study, -1, {});
  const bool needs_cycle = study.metrics.cycle || !study.metrics.deviation.empty();
  if (!unknown_report_metrics(opt.report, nominal).empty()) return kBadInput;  // before any variant
  if (nominal.metrics.empty() || (needs_cycle && nominal.positions == 0)) {
    spdlog::error("{}: the nominal design cannot be swept ({}): {}", opt.file, nominal.status,
                  nominal.message);
    return kNumerical;
  }
  // (A parameter named as a column, up to case, was refused by the study's reader at its line.)
  if (!opt.combine.empty()) return combine_studies(opt, study, study_text, mechanism, nominal);
  const fs::path out = opt.out;
  const std::unique_ptr<StudyDatabase> db =
      open_study_database(opt.out, opt.resume, mechanism, study_text, study, nominal);
  if (!db) return kBadInput;
  const long total = variant_count(study);
  const std::vector<long> stored = db->stored();
  spdlog::info("{}: {} variants, {} stored, {} to compute", opt.study, total, stored.size(),
               total - static_cast<long>(stored.size()));
  // The run's bounds: the time limit, SIGINT/SIGTERM, the progress line (run_bounds.hpp).
  const InterruptScope interrupts;
  const RunControl control = run_control("sweep", opt.time_limit);
  RunMonitor monitor(control, 0);
  const double to_compute = std::max(1.0, double(total) - double(stored.size()));
  long finished = 0;
  const auto store = [&](const VariantResult& r) {
    try {
      db->insert(r);
    } catch (const std::runtime_error& e) {  // a full disk: the rows stored before are kept
      throw std::runtime_error(std::string(e.what()) + "; the " +
                               std::to_string(static_cast<long>(stored.size()) + finished) +
                               " variants stored before are kept: free space and run again "
                               "with --resume");
    }
    ++finished;
    if (r.status != "completed") spdlog::debug("variant {}: {}: {}", r.index, r.status, r.message);
    if (const StopReason why = monitor.tick(double(finished) / to_compute); why != StopReason::none)
      throw StopSweep{why};
  };
  // The pending variants in index order, the stored ones skipped: drawn one at a time (MPI) or
  // a block at a time (OpenMP), never all at once.
  StopReason stop = StopReason::none;
  long i = 0;
  size_t s = 0;
  const auto next_pending = [&]() -> long {
    for (; i < total; ++i) {
      while (s < stored.size() && stored[s] < i) ++s;
      if (s < stored.size() && stored[s] == i) continue;
      return i++;
    }
    return -1;
  };
  if (mpi) {
    spdlog::info("{} MPI ranks: rank 0 stores, {} evaluate", mpi->size(), mpi->size() - 1);
    guard.started = broadcast_start(true);
  }
  try {
    try {
      if (mpi) {
        coordinate_variants(next_pending, store);
      } else {
        std::vector<long> pending;
        pending.reserve(kPendingBlock);
        do {
          pending.clear();
          for (long k;
               static_cast<long>(pending.size()) < kPendingBlock && (k = next_pending()) >= 0;)
            pending.push_back(k);
          if (!pending.empty()) run_variants(mechanism, opt.file, study, pending, opt.jobs, store);
        } while (!pending.empty());
      }
    } catch (const StopSweep& e) {
      stop = e.reason;
    }
  } catch (const std::runtime_error& e) {
    if (mpi) mpi->finish();
    end_progress();
    spdlog::error("{}", e.what());
    return kBadInput;
  } catch (...) {
    if (mpi) mpi->finish();  // every rank was released
    throw;
  }
  if (mpi) mpi->finish();
  end_progress();
  if (stop != StopReason::none)
    spdlog::error("sweep: {}; {} of {} variants are stored: run again with --resume",
                  monitor.stop_message(stop, double(finished) / to_compute, "variant", ""),
                  stored.size() + static_cast<size_t>(finished), total);
  spdlog::info("computed {} variants", finished);

  nlohmann::json summary = summarize(study, *db, nominal);
  summary["complete"] = stop == StopReason::none;  // a stopped sweep: the stored variants only
  if (stop != StopReason::none) summary["stop"] = to_string(stop);
  const int written = write_study_files(opt, study, *db, mechanism, summary);
  if (written != kOk) return written;
  return stop == StopReason::none ? kOk : kStopped;
}

}  // namespace

void register_sweep(CLI::App& app, const GlobalOptions& globals, int& exit_code) {
  auto opt = std::make_shared<SweepCliOptions>();
  CLI::App* cmd = app.add_subcommand(
      "sweep", "a design study: many variants of the file (grid or Monte Carlo), every core");
  cmd->add_option("file", opt->file, "mechanism file (YAML)")->required();
  cmd->add_option("--study", opt->study, "study file (YAML, docs/cli.md \"sweep\")")->required();
  cmd->add_option("--out,-o", opt->out, "directory of study.sqlite, variants.csv and summary.json")
      ->required();
  cmd->add_option("--jobs,-j", opt->jobs, "threads (default: every core)")
      ->check(CLI::Range(0, 4096));
  cmd->add_flag("--resume", opt->resume,
                "continue the study stored in --out (computes only the variants not stored)");
  cmd->add_flag("--json", opt->json, "the summary as one JSON document on stdout");
  add_study_report_options(cmd, opt->report);
  cmd->add_option("--combine", opt->combine,
                  "DIR,DIR,…: join these stored studies of the same mechanism file and columns "
                  "into --out as one study (nothing computed): its summary over all variants")
      ->delimiter(',');
  cmd->add_option("--time-limit", opt->time_limit,
                  "wall-clock limit in seconds (default: none): the sweep stops there, keeps the "
                  "variants stored and exits 5 (continue with --resume)")
      ->check(finite_range(0.0, 1e9, true));
  auto log = std::make_shared<LogFlags>();
  add_log_flags(cmd, *log);
  cmd->callback([opt, log, &globals, &exit_code] {
    setup_logging(globals, *log);
    exit_code = run_sweep_command(*opt);
  });
}

}  // namespace orthomech::cli
