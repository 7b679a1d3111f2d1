// `orthomech synthesize TASK [--out DIR] [--report FILE.html] [--json]`: planar four-bars (or
// slider-cranks, task key `linkage`) from the motion, path or input–output law a designer wants
// (issue 50; docs/cli.md "synthesize"). The library runs the task, validates every candidate
// (synthesis/synthesize.hpp) and renders the documents (io/synthesis_output.hpp); this file only
// prints and writes them. Under mpirun the ranks share the global search's starts (rank 0 writes).
// Exit 0 when a candidate is accepted, 1 when every one is rejected, 3 when the generator finds no
// linkage.
#include "orthomech/synthesis/synthesize.hpp"

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>

#include "commands.hpp"
#include "common.hpp"
#include "orthomech/io/file_writer.hpp"
#include "orthomech/io/synthesis_output.hpp"
#include "orthomech/study/distributed.hpp"

namespace orthomech::cli {

namespace {

using synthesis::SynthesisResult;
using synthesis::SynthesisTask;

struct SynthesizeCliOptions {
  std::string file;
  std::string out;
  std::string report;
  bool json = false;
  int jobs = 0;
};

// The exit status of a result (0 accepted, 1 every one rejected, 3 none found).
int status_of(const SynthesisTask& task, const SynthesisResult& r, bool say) {
  if (r.accepted.empty() && r.rejected.empty()) {
    if (say)
      spdlog::error("synthesize: {}: no {}: {}", task.file, to_string(task.linkage), r.message);
    return kNumerical;
  }
  if (r.accepted.empty()) {
    if (say)
      spdlog::error("synthesize: {}: every candidate is rejected (the reasons are listed)",
                    task.file);
    return kCheckFailed;
  }
  return kOk;
}

// The task run on this process, or under mpirun on every rank: the global searches' starts
// shared among the ranks (each rank holds every outcome, so every rank computes the same result;
// rank 0 alone writes and prints). The task is read before MPI starts: a mistake in it is
// exit 2 on every rank.
SynthesisResult run_task(const SynthesisTask& task, const SynthesizeCliOptions& opt,
                         std::optional<MpiSession>& mpi) {
  synthesis::SynthesisRunOptions run;
  run.threads = opt.jobs;
  if (mpi_launched()) {
    mpi.emplace();
    run.share = mpi_share(*mpi);
    if (mpi->rank() == 0)
      spdlog::info("{} MPI ranks share the global search's starts", mpi->size());
  }
  return synthesis::run_synthesis(task, run);
}

int run_synthesize(const SynthesizeCliOptions& opt) {
  const SynthesisTask task = synthesis::load_synthesis_task(opt.file);
  std::optional<MpiSession> mpi;
  const SynthesisResult r = run_task(task, opt, mpi);
  if (mpi) mpi->finish();  // every rank has the result; the collective calls are over
  if (mpi && mpi->rank() != 0) return status_of(task, r, false);
  if (!opt.out.empty()) {
    try {
      std::filesystem::create_directories(opt.out);
      for (const auto& c : r.accepted)
        write_file(std::filesystem::path(opt.out) / (c.name + ".yaml"), c.file_text);
      write_file(std::filesystem::path(opt.out) / "candidates.csv", synthesis_csv(task, r));
    } catch (const std::exception& e) {  // no such directory, no permission, a full disk
      spdlog::error("synthesize: --out {}: {}", opt.out, e.what());
      return kBadInput;
    }
  }
  if (!opt.report.empty()) {
    try {
      write_file(opt.report, synthesis_report_html(task, r));
    } catch (const std::exception& e) {
      spdlog::error("synthesize: --report {}: {}", opt.report, e.what());
      return kBadInput;
    }
  }
  if (opt.json)
    std::cout << synthesis_json(task, r) << '\n';
  else
    std::cout << synthesis_text(task, r, opt.out);
  std::cout.flush();
  return status_of(task, r, true);
}

}  // namespace

void register_synthesize(CLI::App& app, const GlobalOptions& globals, int& exit_code) {
  auto opt = std::make_shared<SynthesizeCliOptions>();
  CLI::App* cmd = app.add_subcommand(
      "synthesize",
      "planar four-bars from coupler poses, coupler points or an input-output law, each validated");
  cmd->add_option("task", opt->file, "synthesis task file (YAML, docs/file-format.md)")->required();
  cmd->add_option("--out", opt->out,
                  "directory for the accepted candidates' mechanism files and candidates.csv");
  cmd->add_option("--report", opt->report,
                  "an offline HTML page with every candidate drawn over the targets");
  cmd->add_flag("--json", opt->json, "one JSON document on stdout");
  cmd->add_option("--jobs,-j", opt->jobs,
                  "threads of the global search (default: every core; the result is the same)")
      ->check(CLI::Range(0, 4096));
  auto log = std::make_shared<LogFlags>();
  add_log_flags(cmd, *log);
  cmd->callback([opt, log, &globals, &exit_code] {
    setup_logging(globals, *log);
    exit_code = run_synthesize(*opt);
  });
}

}  // namespace orthomech::cli
