// `orthomech crosscheck FILE [--samples N]`: dual versus primal form at states along a motion,
// and the paper's identities (issue 5; docs/design.md §8). Exit 1 when a difference exceeds the
// tolerance.
#include "orthomech/dynamics/crosscheck.hpp"

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "commands.hpp"
#include "common.hpp"
#include "run_bounds.hpp"

namespace orthomech::cli {

namespace {

struct CrosscheckCliOptions {
  std::string file;
  std::vector<std::string> sets;  // --set PATH=VALUE
  int samples = 10;
  double t_end = 0.2;
  double tolerance = 1e-8;
  unsigned seed = 1;
  std::string method = "auto";
  long max_steps = kDefaultMaxSteps;
  double time_limit = 0.0;  // s of wall clock; 0: none
  bool json = false;
  std::string units = "file";
};

int run_crosscheck_cmd(const CrosscheckCliOptions& opt) {
  const Model model = load(opt.file, opt.sets);
  warn_friction_not_applied(model, "crosscheck");
  const UnitSystem U = resolve_units(model, opt.units);
  const OutputUnit time_u = output_unit(Dimension::time, U);
  CrosscheckOptions co;
  co.samples = opt.samples;
  co.t_end = opt.t_end * unit_system(model.units).time_si;  // bare: the file's time unit
  co.tolerance = opt.tolerance;
  co.seed = opt.seed;
  (void)parse_crosscheck_method(opt.method, co.method);  // checked by CLI11 (IsMember)
  co.max_steps = opt.max_steps;
  co.control = run_control("crosscheck", opt.time_limit);
  // SIGINT/SIGTERM: stop, print what was compared.
  const CrosscheckResult res = run_bounded([&] { return run_crosscheck(model, co); });
  std::ostringstream out;
  if (opt.json) {
    nlohmann::json j;
    j["mechanism"] = model.name;
    j["units"] = units_json(U);
    j["pass"] = res.pass;
    j["complete"] = res.stop == StopReason::none;
    if (res.stop != StopReason::none) j["stop"] = to_string(res.stop);
    j["message"] = res.message;
    j["samples"] = res.samples;
    j["tolerance"] = res.tolerance;
    j["method"] = to_string(res.method);
    j["rank"] = res.rank;
    j["constraints"] = res.nc;
    j["primal_checked"] = res.primal_checked;
    j["primal_skipped_reason"] = res.primal_skipped_reason;
    nlohmann::json items = nlohmann::json::array();
    for (const auto& it : res.items)
      items.push_back({{"name", it.name},
                       {"kind", it.kind},
                       {"max_relative", it.max_relative},
                       {"at_t", time_u.from_si(it.at_t)},
                       {"pass", it.pass}});
    j["checks"] = items;
    out << j.dump(2) << '\n';
  } else {
    out << "mechanism   " << model.name << "  (" << model.file << ")\n";
    out << "states      " << res.samples << " along a " << time_u.from_si(co.t_end) << " "
        << time_u.name << " motion; tolerance " << res.tolerance << " (relative)\n";
    out << "method      " << to_string(res.method)
        << (res.method == CrosscheckMethod::probes
                ? " (the projections applied to seeded vectors, no n × n matrix)\n"
                : " (the projections formed as n × n matrices)\n");
    if (!res.primal_skipped_reason.empty())
      out << "primal      skipped: " << res.primal_skipped_reason << "\n";
    out << "\n";
    for (const auto& it : res.items) {
      std::ostringstream v;
      v.precision(3);
      v << it.max_relative;
      out << (it.pass ? "  ok    " : "  FAIL  ") << v.str() << "\t" << it.name << "\n";
    }
    out << "\n"
        << (res.pass ? "PASS" : "FAIL") << (res.message.empty() ? "" : ": ") << res.message << "\n";
  }
  std::cout << out.str();
  if (res.stop != StopReason::none) {
    spdlog::error("crosscheck: {}: {}", model.file, res.message);
    return kStopped;
  }
  if (res.samples == 0) {
    spdlog::error("{}: {}", model.file, res.message);
    return kNumerical;
  }
  return res.pass ? kOk : kCheckFailed;
}

}  // namespace

void register_crosscheck(CLI::App& app, const GlobalOptions& globals, int& exit_code) {
  auto opt = std::make_shared<CrosscheckCliOptions>();
  CLI::App* cmd = app.add_subcommand(
      "crosscheck", "dual versus primal form at states along a motion, and the paper's identities");
  cmd->add_option("file", opt->file, "mechanism file (YAML)")->required();
  add_set_option(cmd, opt->sets);
  cmd->add_option("--samples", opt->samples, "number of states (default 10)")
      ->check(CLI::Range(1, 100000));
  cmd->add_option("--t-end", opt->t_end,
                  "length of the motion, in the file's time unit (default 0.2)")
      ->check(finite_range(0.0, 1e6, true));
  cmd->add_option("--tolerance", opt->tolerance, "largest relative difference (default 1e-8)")
      ->check(finite_range(0.0, 1.0, true));
  cmd->add_option("--seed", opt->seed, "seed of the initial velocity guess (default 1)");
  cmd->add_option("--method", opt->method,
                  "dense: the projections as n × n matrices; probes: applied to seeded vectors "
                  "on the sparse stages (default auto: probes from 300 velocities)")
      ->check(CLI::IsMember({"auto", "dense", "probes"}));
  cmd->add_option("--max-steps", opt->max_steps,
                  "step budget of the motion (default 1e7): the run stops there, exit 5")
      ->check(CLI::Range(1L, kMaxMaxSteps));
  cmd->add_option("--time-limit", opt->time_limit,
                  "wall-clock limit in seconds (default: none): the run stops there, exit 5")
      ->check(finite_range(0.0, 1e9, true));
  cmd->add_flag("--json", opt->json, "one JSON document on stdout");
  add_units_option(cmd, opt->units);
  auto log = std::make_shared<LogFlags>();
  add_log_flags(cmd, *log);
  cmd->callback([opt, log, &globals, &exit_code] {
    setup_logging(globals, *log);
    exit_code = run_crosscheck_cmd(*opt);
  });
}

}  // namespace orthomech::cli
