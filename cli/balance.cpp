// `orthomech balance FILE --counterweight BODY:RADIUS …`: counterweights that cancel (or, weighed
// against the shaking moment and the drive, reduce) the shaking force of a planar driven
// mechanism (issue 49 item 4; docs/cli.md). No math here: the balancing is
// balance_counterweights (analysis/balancing.hpp), the sweep run_cycle, the file edit
// edit_mass_properties (io/mechanism_writer.hpp). The balanced mechanism is always read back and
// swept again, and its own shaking force, moment and drive are what is reported as "after".
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "commands.hpp"
#include "common.hpp"
#include "orthomech/analysis/balancing.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/error.hpp"
#include "orthomech/io/file_writer.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/io/mechanism_writer.hpp"
#include "orthomech/io/units.hpp"
#include "run_bounds.hpp"

namespace orthomech::cli {

namespace {

struct BalanceCliOptions {
  std::string file;
  std::vector<std::string> sets;
  std::vector<std::string> counterweights;  // BODY:RADIUS
  double force_weight = 1.0, moment_weight = 0.0, drive_weight = 0.0;
  std::string about;  // --shaking-about
  int steps = 0;      // 0: the file's analysis.steps
  double max_mass = 0.0;
  double time_limit = 0.0;  // --time-limit (s of wall clock; 0: none), each sweep
  std::string write;
  bool json = false;
  std::string units = "file";
  LogFlags log;
};

// Agreement asked of the balanced file's own sweep with the prediction (relative to the
// mechanism's terms before): the two differ by the 15 digits written and the sweeps' tolerance.
constexpr double kAgreement = 1e-6;

std::string fmt(double v, int precision = 5) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.*g", precision, v);
  return buf;
}

// The sites of --counterweight BODY:RADIUS (radius in the file's length unit).
std::vector<CounterweightSite> parse_sites(const Model& model, const BalanceCliOptions& opt) {
  std::vector<CounterweightSite> sites;
  const double unit = unit_system(model.units).length_si;
  for (const std::string& c : opt.counterweights) {
    const auto colon = c.find(':');
    if (colon == std::string::npos)
      throw CLI::ValidationError("--counterweight",
                                 "'" + c + "': give BODY:RADIUS (e.g. crank:40)");
    const std::string body = c.substr(0, colon);
    const int b = model.find_body(body);
    if (b < 0)
      throw CLI::ValidationError("--counterweight", "'" + c + "': body '" + body +
                                                        "' is not a moving body of " + model.file);
    const double r = parse_number(c.substr(colon + 1), "--counterweight");
    if (!(r > 0.0))
      throw CLI::ValidationError("--counterweight", "'" + c + "': the radius must be > 0");
    sites.push_back({b, r * unit});
  }
  return sites;
}

// The file's driver (analysis.driver, else its first).
const Driver& driver_of(const Model& model) {
  const Driver* d = nullptr;
  for (const Driver& x : model.drivers)
    if (x.name == model.analysis.driver) d = &x;
  if (!d && !model.drivers.empty()) d = &model.drivers.front();
  if (!d)
    throw InputError({model.file, 0, 0}, "drivers",
                     "balance needs a driver (drivers:) to sweep the mechanism over its cycle");
  return *d;
}

// A full cycle of the file's driver, bounded (run_bounds.hpp: --time-limit, SIGINT/SIGTERM, a
// progress line on a terminal).
CycleResult sweep_of(const Model& model, int steps, double time_limit) {
  CycleOptions co;
  co.driver = driver_of(model);
  co.steps = steps > 0 ? steps : model.analysis.steps;
  co.control = run_control("balance", time_limit);
  return run_bounded([&] { return run_cycle(model, co); });
}

// Exit 5 for a sweep a bound stopped, 3 for one that failed; nullopt when it completed.
std::optional<int> sweep_problem(const Model& model, const CycleResult& sweep, const char* which) {
  if (sweep.status == CycleStatus::completed) return std::nullopt;
  if (sweep.status == CycleStatus::stopped) {
    spdlog::error("{}: balance stopped during the {} sweep: {}; nothing was written", model.file,
                  which, sweep.message);
    return kStopped;
  }
  spdlog::error("{}: the {} cycle cannot be swept ({}); balancing needs a full cycle", model.file,
                which, sweep.message);
  return kNumerical;
}

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

struct Report {
  const Model& model;
  const BalanceResult& r;
  const BalanceTerms& swept;
  const UnitSystem& U;
  const Vec3& about;
  Dimension drive;  // moment (revolute driver) or force
  std::string written;
  // The output units of the file's unit system, for both renderings.
  const OutputUnit mass_u = output_unit(Dimension::mass, U);
  const OutputUnit length_u = output_unit(Dimension::length, U);
  const OutputUnit inertia_u = output_unit(Dimension::inertia, U);
  const OutputUnit force_u = output_unit(Dimension::force, U);
  const OutputUnit moment_u = output_unit(Dimension::moment, U);

  [[nodiscard]] nlohmann::json json() const {
    nlohmann::json j;
    j["mechanism"] = model.name;
    j["file"] = model.file;
    j["units"] = units_json(U);
    j["status"] = to_string(r.status);
    j["message"] = r.message;
    j["objective"] = {{"before", r.objective_before}, {"after", r.objective_after}};
    j["evaluations"] = r.evaluations;
    nlohmann::json cws = nlohmann::json::array();
    for (const Counterweight& c : r.counterweights)
      cws.push_back(
          {{"body", model.bodies[static_cast<size_t>(c.body)].name},
           {"mass", mass_u.from_si(c.mass)},
           {"position", {length_u.from_si(c.position.x()), length_u.from_si(c.position.y())}},
           {"body_mass", mass_u.from_si(c.body_mass)},
           {"body_com", {length_u.from_si(c.body_com.x()), length_u.from_si(c.body_com.y())}},
           {"body_inertia", inertia_u.from_si(c.body_inertia)}});
    j["counterweights"] = cws;
    auto terms = [&](const BalanceTerms& t) {
      return nlohmann::json{{"shaking_force_rms", force_u.from_si(t.force_rms)},
                            {"shaking_force_peak", force_u.from_si(t.force_peak)},
                            {"shaking_moment_rms", moment_u.from_si(t.moment_rms)},
                            {"drive_rms", output_unit(drive, U).from_si(t.drive_rms)}};
    };
    j["before"] = terms(r.before);
    j["after"] = terms(swept);
    j["predicted"] = terms(r.after);
    j["about"] = {length_u.from_si(about.x()), length_u.from_si(about.y())};
    j["written"] = written;
    return j;
  }

  [[nodiscard]] std::string text() const {
    std::ostringstream out;
    out << "mechanism       " << model.name << "  (" << model.file << ")\n";
    out << "status          " << to_string(r.status) << ", objective " << fmt(r.objective_before)
        << " -> " << fmt(r.objective_after) << " (" << r.evaluations << " evaluations)\n";
    for (const Counterweight& c : r.counterweights)
      out << "counterweight   " << model.bodies[static_cast<size_t>(c.body)].name << ": "
          << fmt(mass_u.from_si(c.mass)) << " " << mass_u.name << " at ["
          << fmt(length_u.from_si(c.position.x())) << ", " << fmt(length_u.from_si(c.position.y()))
          << "] " << length_u.name << " (body frame); the body becomes mass "
          << fmt(mass_u.from_si(c.body_mass), 8) << " " << mass_u.name << ", com ["
          << fmt(length_u.from_si(c.body_com.x()), 8) << ", "
          << fmt(length_u.from_si(c.body_com.y()), 8) << "] " << length_u.name << ", inertia "
          << fmt(inertia_u.from_si(c.body_inertia), 8) << " " << inertia_u.name << "\n";
    char line[200];
    std::snprintf(line, sizeof line, "\n%-22s %-6s %12s %12s\n", "quantity", "unit", "before",
                  "after");
    out << line;
    auto row = [&](const char* name, const OutputUnit& u, double before, double after) {
      std::snprintf(line, sizeof line, "%-22s %-6s %12.5g %12.5g\n", name, u.name.c_str(),
                    u.from_si(before), u.from_si(after));
      out << line;
    };
    row("shaking force RMS", force_u, r.before.force_rms, swept.force_rms);
    row("shaking force peak", force_u, r.before.force_peak, swept.force_peak);
    row("shaking moment RMS", moment_u, r.before.moment_rms, swept.moment_rms);
    row("drive RMS", output_unit(drive, U), r.before.drive_rms, swept.drive_rms);
    out << "(shaking moment about (" << fmt(length_u.from_si(about.x())) << ", "
        << fmt(length_u.from_si(about.y())) << ") " << length_u.name
        << "; after: the balanced mechanism read back and swept again)\n";
    if (!written.empty()) out << "wrote           " << written << "\n";
    return out.str();
  }
};

int run_balance(const BalanceCliOptions& opt) {
  if (!opt.sets.empty() && !opt.write.empty())
    throw CLI::ValidationError("--write",
                               "--set cannot be combined with --write: it writes the "
                               "file as it is on disk; change the file itself");
  const Model model = load(opt.file, opt.sets);
  require_planar(model, "balance");
  const UnitSystem U = resolve_units(model, opt.units);
  BalanceOptions bo;
  bo.sites = parse_sites(model, opt);
  bo.weights = {opt.force_weight, opt.moment_weight, opt.drive_weight};
  bo.about = parse_point(model, opt.about, "--shaking-about");
  bo.mass_limit = opt.max_mass * unit_system(model.units).mass_si;
  // Step 1: the mechanism's own sweep.
  const CycleResult sweep = sweep_of(model, opt.steps, opt.time_limit);
  if (const std::optional<int> code = sweep_problem(model, sweep, "mechanism's")) return *code;
  // Step 2: the counterweights.
  const BalanceResult r = balance_counterweights(model, sweep, bo);
  if (r.status == BalanceStatus::invalid_request)
    throw InputError({model.file, 0, 0}, "balance", r.message);
  if (r.status == BalanceStatus::failed) {
    spdlog::error("{}: {}", model.file, r.message);
    return kNumerical;
  }
  // Step 3: the balanced file, read back and swept again (what is reported as "after").
  std::vector<MassEdit> edits;
  for (const Counterweight& c : r.counterweights)
    edits.push_back({c.body, c.body_mass, c.body_com, c.body_inertia});
  const std::string text = edit_mass_properties(read_text(opt.file), opt.file, model, edits);
  const Model balanced = parse_mechanism(text, opt.file);
  const CycleResult again = sweep_of(balanced, opt.steps, opt.time_limit);
  if (const std::optional<int> code = sweep_problem(model, again, "balanced mechanism's"))
    return *code;
  const BalanceTerms swept = balance_terms(balanced, again, bo.about);
  const bool agrees =
      std::abs(swept.force_rms - r.after.force_rms) <= kAgreement * r.before.force_rms &&
      std::abs(swept.moment_rms - r.after.moment_rms) <= kAgreement * r.before.moment_rms &&
      std::abs(swept.drive_rms - r.after.drive_rms) <= kAgreement * r.before.drive_rms;
  if (!agrees) {
    spdlog::error(
        "{}: the balanced mechanism swept again does not do what the balancing predicted (shaking "
        "force RMS {} N against {} N); nothing was written",
        model.file, swept.force_rms, r.after.force_rms);
    return kNumerical;
  }
  const bool angular =
      joint_coordinate_kind(model.joints[static_cast<size_t>(driver_of(model).joint)]) ==
      CoordinateKind::angle;
  Report report{model, r, swept, U, bo.about, angular ? Dimension::moment : Dimension::force, ""};
  if (!opt.write.empty()) {
    std::error_code ec;
    if (std::filesystem::exists(opt.write, ec) &&
        std::filesystem::equivalent(opt.write, opt.file, ec))
      throw CLI::ValidationError("--write", "would overwrite the input file '" + opt.file + "'");
    try {
      write_file(opt.write, text);
    } catch (const std::runtime_error& e) {
      spdlog::error("{}", e.what());
      return kBadInput;
    }
    report.written = opt.write;
    spdlog::info("wrote {}", opt.write);
  }
  if (!r.message.empty()) spdlog::warn("{}: {}", model.file, r.message);
  if (opt.json)
    std::cout << report.json().dump(2) << "\n";
  else
    std::cout << report.text();
  return r.status == BalanceStatus::balanced ? kOk : kStopped;
}

}  // namespace

void register_balance(CLI::App& app, const GlobalOptions& globals, int& exit_code) {
  auto opt = std::make_shared<BalanceCliOptions>();
  CLI::App* cmd = app.add_subcommand(
      "balance",
      "counterweights on chosen bodies that cancel or reduce the shaking force (weighed against "
      "the shaking moment and the drive) of a planar driven mechanism; writes the balanced file");
  cmd->add_option("file", opt->file, "mechanism file (YAML)")->required();
  add_set_option(cmd, opt->sets);
  cmd->add_option("--counterweight", opt->counterweights,
                  "BODY:RADIUS: a counterweight on this body at this distance from its frame's "
                  "origin (file's length unit), its mass and direction found; repeatable")
      ->required();
  cmd->add_option("--force-weight", opt->force_weight,
                  "weight of the shaking force RMS (default 1)")
      ->check(finite_range(0.0, 1e6));
  cmd->add_option("--moment-weight", opt->moment_weight,
                  "weight of the shaking moment RMS (default 0)")
      ->check(finite_range(0.0, 1e6));
  cmd->add_option("--drive-weight", opt->drive_weight, "weight of the drive RMS (default 0)")
      ->check(finite_range(0.0, 1e6));
  cmd->add_option("--shaking-about", opt->about,
                  "X,Y in the file's length unit: the point of the shaking moment (default the "
                  "origin)");
  cmd->add_option("--steps", opt->steps, "positions of the cycle (default: the file's)")
      ->check(CLI::Range(8, 100000));
  cmd->add_option("--max-mass", opt->max_mass,
                  "largest counterweight mass in the file's mass unit (default 10 x the moving "
                  "bodies' mass)")
      ->check(finite_range(0.0, 1e12, true));
  cmd->add_option("--time-limit", opt->time_limit,
                  "wall-clock limit in seconds of each of its two sweeps (default: none): exit 5, "
                  "nothing written")
      ->check(finite_range(0.0, 1e9, true));
  cmd->add_option("--write", opt->write,
                  "FILE.yaml: the balanced mechanism (mass, com, inertia "
                  "of the counterweighted bodies edited in place)");
  cmd->add_flag("--json", opt->json, "one JSON document on stdout");
  add_units_option(cmd, opt->units);
  add_log_flags(cmd, opt->log);
  cmd->callback([opt, &globals, &exit_code] {
    setup_logging(globals, opt->log);
    exit_code = run_balance(*opt);
  });
}

}  // namespace orthomech::cli
