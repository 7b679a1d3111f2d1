// `orthomech validate FILE`: the design positions report (analysis/validate.hpp): assembly,
// target, DOF, singularity measures and distance to the nearest dead/change point, four-bar
// Grashof type and transmission angle, assembly modes, circuit/branch/order defects. Planar and
// spatial files (on a spatial one the planar-only checks read "not applicable"). Exit status 0
// only when every position passes every check, 1 otherwise (docs/cli.md).
#include "orthomech/analysis/validate.hpp"

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>

#include "commands.hpp"
#include "common.hpp"
#include "run_bounds.hpp"

namespace orthomech::cli {

namespace {

struct ValidateCliOptions {
  std::string file;
  std::vector<std::string> sets;  // --set PATH=VALUE
  bool json = false;
  std::string min_transmission = "30deg";
  double min_transmission_index = -1.0;  // < 0: sin(min_transmission)
  int starts = 24;
  unsigned seed = 1;
  double time_limit = 0.0;  // --time-limit (s of wall clock; 0: none)
  std::string units = "file";
};

nlohmann::json opt_json(const std::optional<double>& v) {
  return v ? nlohmann::json(*v) : nlohmann::json(nullptr);
}

std::string cell(const std::optional<double>& v, double scale, const char* f = "%.4g") {
  if (!v) return "-";
  char buf[64];
  std::snprintf(buf, sizeof buf, f, *v * scale);
  return buf;
}

int run_validate(const ValidateCliOptions& opt) {
  const Model model = load(opt.file, opt.sets);
  const UnitSystem U = resolve_units(model, opt.units);
  ValidateOptions vo;
  try {  // a bare number is in the file's angle unit
    vo.min_transmission =
        parse_position(opt.min_transmission, true, unit_system(model.units).angle_si);
  } catch (const std::invalid_argument& e) {
    throw CLI::ValidationError("--min-transmission", e.what());
  }
  if (!(vo.min_transmission >= 0.0 && vo.min_transmission <= std::numbers::pi / 2))
    throw CLI::ValidationError("--min-transmission", "must lie in [0, 90] deg");
  if (opt.min_transmission_index >= 0.0) vo.min_transmission_index = opt.min_transmission_index;
  vo.starts = opt.starts;
  vo.seed = opt.seed;
  if (model.design_positions.empty())
    spdlog::warn("{}: no design positions: nothing to validate", model.file);
  // Bounded (run_bounds.hpp): --time-limit, SIGINT/SIGTERM, a progress line on a terminal.
  vo.control = run_control("validate", opt.time_limit);
  const ValidationReport rep = run_bounded([&] { return validate_design_positions(model, vo); });
  const bool input_angular = rep.input_angular;
  const bool applicable = rep.not_applicable.empty();  // the planar loop checks
  const OutputUnit length_u = output_unit(Dimension::length, U);
  const OutputUnit angle_u = output_unit(Dimension::angle, U);
  const OutputUnit in_u = input_angular ? angle_u : length_u;
  const double in_scale = 1.0 / in_u.si;
  const std::string in_unit = "[" + in_u.name + "]";
  auto conv = [](const std::optional<double>& v, const OutputUnit& u) {
    return v ? nlohmann::json(u.from_si(*v)) : nlohmann::json(nullptr);
  };

  std::ostringstream out;
  if (opt.json) {
    nlohmann::json j;
    j["mechanism"] = model.name;
    j["file"] = model.file;
    j["units"] = units_json(U);
    j["pass"] = rep.pass();
    j["complete"] = rep.stop == StopReason::none;
    if (rep.stop != StopReason::none) {
      j["stop"] = to_string(rep.stop);
      j["message"] = rep.stop_message;
    }
    j["input"] = rep.input;
    j["generic_rank"] = rep.generic_rank;
    j["loop_basis"] = loop_basis_size(model);
    j["circuits"] = rep.circuits;
    // positions[].modes counts the modes the multi-start found: a lower bound (issue 47).
    j["modes_search"] = {{"starts", opt.starts}, {"seed", opt.seed}, {"lower_bound", true}};
    j["circuit_defect"] = rep.circuit_defect;
    j["branch_defect"] = rep.branch_defect;
    j["order_defect"] = rep.order_defect;
    j["defects"] = rep.defects;
    j["singular_points"] = rep.singular_points;
    j["not_applicable"] = rep.not_applicable;
    j["transmission_index_bound"] = rep.transmission_index_bound;
    j["min_loop_transmission_index"] =
        rep.min_transmission_index ? nlohmann::json({{"index", *rep.min_transmission_index},
                                                     {"position", rep.min_transmission_index_at}})
                                   : nlohmann::json(nullptr);
    // An array whenever the mechanism has spatial transmission loops (empty where a position
    // does not assemble).
    const bool any_spatial_loop = !find_spatial_transmission_loops(model, -1).empty();
    nlohmann::json positions = nlohmann::json::array();
    for (const PositionReport& p : rep.positions) {
      nlohmann::json fb = nlohmann::json::array();
      for (const FourBarReport& f : p.four_bars)
        fb.push_back({{"joints", f.joints},
                      {"grashof", to_string(f.type)},
                      {"transmission_angle", angle_u.from_si(f.transmission)},
                      {"ok", f.ok}});
      nlohmann::json sc = nlohmann::json::array();
      for (const SliderCrankReport& c : p.slider_cranks)
        sc.push_back(
            {{"joints", c.joints}, {"pressure_angle", angle_u.from_si(c.pressure)}, {"ok", c.ok}});
      nlohmann::json tl = nlohmann::json::array();
      for (const SpatialLoopReport& l : p.spatial_loops)
        tl.push_back({{"joints", l.joints}, {"type", l.type}, {"index", l.index}, {"ok", l.ok}});
      nlohmann::json blocks = nlohmann::json::array();
      for (const LimitBlock& b : p.limit_blocks) {
        const Joint& jt = model.joints[static_cast<size_t>(b.joint)];
        const OutputUnit u = b.angular ? angle_u : length_u;
        blocks.push_back({{"joint", jt.name},
                          {"needed", u.from_si(b.needed)},
                          {"limits", {u.from_si(jt.limits->x()), u.from_si(jt.limits->y())}},
                          {"unit", u.name}});
      }
      nlohmann::json idle = nlohmann::json::array();
      for (const Mobility::Idle& i : p.idle) idle.push_back({{"body", i.body}, {"count", i.count}});
      const nlohmann::json na = "not applicable";
      positions.push_back({{"name", p.name},
                           {"pass", rep.stop == StopReason::none && p.pass()},
                           {"failures", p.failures},
                           {"assembles", p.assembles},
                           {"assembly_status", to_string(p.assembly)},
                           {"distance", mass_metric_unit(U).from_si(p.distance)},
                           {"distance_unit", mass_metric_unit(U).name},
                           {"max_translation", length_u.from_si(p.max_translation)},
                           {"target_error", conv(p.target_error, length_u)},
                           {"target_angle_error", conv(p.target_angle_error, angle_u)},
                           {"target_met", p.target_met},
                           {"dof", p.dof},
                           {"rank", p.rank},
                           {"redundant", p.redundant},
                           {"idle", idle},
                           {"sigma_min", p.singular.sigma_min},
                           {"transmission_index", opt_json(p.singular.eta)},
                           {"singular_distance", conv(p.singular_distance, in_u)},
                           {"singular_kind", p.singular_kind},
                           {"singular_input", conv(p.singular_input, in_u)},
                           {"four_bars", applicable ? fb : na},
                           {"slider_cranks", applicable ? sc : na},
                           {"transmission_loops", any_spatial_loop ? tl : na},
                           {"limit_blocks", blocks},
                           {"modes", p.modes},
                           {"mode", p.mode},
                           {"mode_signature", p.mode_signature},
                           {"circuit", p.circuit},
                           {"branch", p.branch}});
    }
    j["positions"] = positions;
    out << j.dump(2) << '\n';
  } else {
    out << "mechanism  " << model.name << "  (" << model.file << ")\n";
    out << "input      " << (rep.input.empty() ? "(none common)" : rep.input) << "   generic rank "
        << rep.generic_rank << ", circuits traced " << rep.circuits << "\n\n";
    char line[512];
    std::snprintf(line, sizeof line, "%-10s %-5s %9s %9s %3s %9s %9s %11s %8s %7s %5s %5s  %s\n",
                  "position", "asm", "moved", "target", "dof", "sigma_min", "eta", "to_singular",
                  "mu_min", "mode", "circ", "br", "result");
    out << line;
    std::snprintf(line, sizeof line, "%-10s %-5s %9s %9s %3s %9s %9s %11s %8s %7s %5s %5s\n", "",
                  "", ("[" + length_u.name + "]").c_str(), ("[" + length_u.name + "]").c_str(), "",
                  "", "", in_unit.c_str(), ("[" + angle_u.name + "]").c_str(), "", "", "");
    out << line;
    const bool stopped = rep.stop != StopReason::none;  // the checks did not all run
    for (const PositionReport& p : rep.positions) {
      std::optional<double> mu;
      for (const FourBarReport& f : p.four_bars) {
        const double m = std::min(f.transmission, std::numbers::pi - f.transmission);
        if (!mu || m < *mu) mu = m;
      }
      const std::string mode =
          p.mode > 0 ? std::to_string(p.mode) + "/" + std::to_string(p.modes) : "-";
      std::snprintf(line, sizeof line, "%-10s %-5s %9s %9s %3d %9s %9s %11s %8s %7s %5s %5s  %s\n",
                    p.name.c_str(), p.assembles ? "yes" : "NO",
                    cell(std::optional<double>(p.max_translation), 1.0 / length_u.si).c_str(),
                    cell(p.target_error, 1.0 / length_u.si).c_str(), p.dof,
                    cell(std::optional<double>(p.singular.sigma_min), 1.0, "%.3g").c_str(),
                    cell(p.singular.eta, 1.0, "%.3g").c_str(),
                    cell(p.singular_distance, in_scale).c_str(),
                    applicable ? cell(mu, 1.0 / angle_u.si, "%.2f").c_str() : "n/a", mode.c_str(),
                    p.circuit > 0 ? std::to_string(p.circuit).c_str() : "-",
                    p.branch > 0 ? std::to_string(p.branch).c_str() : "-",
                    stopped    ? "-"
                    : p.pass() ? "pass"
                               : "FAIL");
      out << line;
    }
    bool any_mode = false;
    for (const PositionReport& p : rep.positions) any_mode = any_mode || p.mode > 0;
    if (any_mode)
      out << "\nmode m/N: the position's assembly mode among the N found by " << opt.starts
          << " multi-start projections (seed " << opt.seed
          << "): at least N modes exist; more --starts may find more\n";
    bool any_loop = false;
    for (const PositionReport& p : rep.positions)
      if (!p.four_bars.empty() && !any_loop) {
        any_loop = true;
        out << "\nfour-bar loops (every 4-cycle of the pin graph; a loop basis of the joint "
               "graph has "
            << loop_basis_size(model) << " loops)\n";
        for (const FourBarReport& f : p.four_bars)
          out << "  " << f.joints << "  " << to_string(f.type) << "\n";
      }
    for (const PositionReport& p : rep.positions)
      for (const SliderCrankReport& c : p.slider_cranks)
        out << (&c == &p.slider_cranks.front() ? "\nslider-crank loops at " + p.name + "\n" : "")
            << "  " << c.joints << "  pressure angle " << format_input(c.pressure, true, U)
            << (c.ok ? "" : "  (too large)") << "\n";
    if (rep.min_transmission_index) {
      out << "\ntransmission index of the spatial loops (Sutherland & Roth 1973; needs at least "
          << rep.transmission_index_bound << ")\n";
      for (const PositionReport& p : rep.positions)
        for (const SpatialLoopReport& l : p.spatial_loops) {
          std::snprintf(line, sizeof line, "  %-10s %s (%s)  %.4f%s\n", p.name.c_str(),
                        l.joints.c_str(), l.type.c_str(), l.index, l.ok ? "" : "  (too small)");
          out << line;
        }
      std::snprintf(line, sizeof line, "  minimum %.4f at %s\n", *rep.min_transmission_index,
                    rep.min_transmission_index_at.c_str());
      out << line;
    }
    if (!applicable) {
      out << "\nnot applicable (spatial mechanism)\n";
      for (const std::string& s : rep.not_applicable) out << "  " << s << "\n";
    }
    bool header = false;
    for (const PositionReport& p : rep.positions)
      if (!p.idle.empty()) {
        if (!header) out << "\n";
        header = true;
        out << "idle degrees of freedom at " << p.name << " (held at zero rate):";
        for (size_t k = 0; k < p.idle.size(); ++k)
          out << (k ? ";" : "") << " body '" << p.idle[k].body << "' (" << p.idle[k].count
              << (p.idle[k].count == 1 ? " direction)" : " directions)");
        out << "\n";
      }
    header = false;
    for (const PositionReport& p : rep.positions)
      if (!p.redundant.empty()) {
        if (!header) out << "\n";
        header = true;
        out << "redundant equations at " << p.name << ":";
        for (size_t k = 0; k < p.redundant.size(); ++k) out << (k ? "; " : " ") << p.redundant[k];
        out << "\n";
      }
    if (!rep.singular_points.empty()) {
      out << "\nsingular positions on the traced circuits\n";
      for (const std::string& s : rep.singular_points) out << "  " << s << "\n";
    }
    out << "\n";
    for (const PositionReport& p : rep.positions)
      for (const std::string& f : p.failures) out << "FAIL " << p.name << ": " << f << "\n";
    if (rep.stop != StopReason::none)
      out << "stopped: " << rep.stop_message << "\n";
    else if (rep.pass())
      out << "every position passes every check\n";
  }
  std::cout << out.str();
  if (rep.stop != StopReason::none) {  // the checks after the stop did not run
    spdlog::error("validate: stopped: {}", rep.stop_message);
    return kStopped;
  }
  return rep.pass() ? kOk : kCheckFailed;
}

}  // namespace

void register_validate(CLI::App& app, const GlobalOptions& globals, int& exit_code) {
  auto opt = std::make_shared<ValidateCliOptions>();
  CLI::App* cmd = app.add_subcommand(
      "validate",
      "design positions report: assembly, target, DOF, singularity, transmission, Grashof, "
      "assembly modes, circuit/branch/order defects; exit 0 only when every position passes");
  cmd->add_option("file", opt->file, "mechanism file (YAML)")->required();
  add_set_option(cmd, opt->sets);
  cmd->add_flag("--json", opt->json, "one JSON document on stdout");
  cmd->add_option("--min-transmission", opt->min_transmission,
                  "smallest acceptable transmission angle deviation from a straight line, e.g. "
                  "30deg (default); a bare number is in the file's angle unit");
  cmd->add_option("--min-transmission-index", opt->min_transmission_index,
                  "smallest acceptable Sutherland-Roth transmission index of a spatial loop, in "
                  "[0, 1] (default: sin of --min-transmission, 0.5)")
      ->check(finite_range(0.0, 1.0));
  cmd->add_option("--starts", opt->starts, "multi-start projections per position (default 24)")
      ->check(CLI::Range(0, 100000));
  cmd->add_option("--seed", opt->seed, "seed of the multi-start (default 1)");
  cmd->add_option("--time-limit", opt->time_limit,
                  "wall-clock limit in seconds (default: none): the checks stop there, the report "
                  "does not pass, exit 5")
      ->check(finite_range(0.0, 1e9, true));
  add_units_option(cmd, opt->units);
  auto log = std::make_shared<LogFlags>();
  add_log_flags(cmd, *log);
  cmd->callback([opt, log, &globals, &exit_code] {
    setup_logging(globals, *log);
    exit_code = run_validate(*opt);
  });
}

}  // namespace orthomech::cli
