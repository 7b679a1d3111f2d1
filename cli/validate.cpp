// `orthomech validate FILE`: the design positions report (analysis/validate.hpp): assembly,
// target, DOF, singularity measures and distance to the nearest dead/change point, four-bar
// Grashof type and transmission angle, assembly modes, circuit/branch/order defects. Exit status
// 0 only when every position passes every check, 1 otherwise (docs/cli.md).
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

namespace orthomech::cli {

namespace {

struct ValidateCliOptions {
  std::string file;
  bool json = false;
  double min_transmission_deg = 30.0;
  int starts = 24;
  unsigned seed = 1;
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
  const Model model = load(opt.file);
  ValidateOptions vo;
  vo.min_transmission = opt.min_transmission_deg * std::numbers::pi / 180.0;
  vo.starts = opt.starts;
  vo.seed = opt.seed;
  if (model.design_positions.empty())
    spdlog::warn("{}: no design positions: nothing to validate", model.file);
  const ValidationReport rep = validate_design_positions(model, vo);
  const bool input_angular =
      !rep.input.empty() &&
      std::holds_alternative<Revolute>(
          model.joints[static_cast<size_t>(model.find_joint(rep.input))].kind);
  const double in_scale = input_angular ? 180.0 / std::numbers::pi : 1e3;
  const char* in_unit = input_angular ? "deg" : "mm";

  std::ostringstream out;
  if (opt.json) {
    nlohmann::json j;
    j["mechanism"] = model.name;
    j["file"] = model.file;
    j["pass"] = rep.pass();
    j["input"] = rep.input;
    j["generic_rank"] = rep.generic_rank;
    j["circuits"] = rep.circuits;
    j["circuit_defect"] = rep.circuit_defect;
    j["branch_defect"] = rep.branch_defect;
    j["order_defect"] = rep.order_defect;
    j["defects"] = rep.defects;
    j["singular_points"] = rep.singular_points;
    nlohmann::json positions = nlohmann::json::array();
    for (const PositionReport& p : rep.positions) {
      nlohmann::json fb = nlohmann::json::array();
      for (const FourBarReport& f : p.four_bars)
        fb.push_back({{"joints", f.joints},
                      {"grashof", to_string(f.type)},
                      {"transmission_angle", f.transmission},
                      {"ok", f.ok}});
      positions.push_back({{"name", p.name},
                           {"pass", p.pass()},
                           {"failures", p.failures},
                           {"assembles", p.assembles},
                           {"assembly_status", to_string(p.assembly)},
                           {"distance", p.distance},
                           {"max_translation", p.max_translation},
                           {"target_error", opt_json(p.target_error)},
                           {"target_angle_error", opt_json(p.target_angle_error)},
                           {"target_met", p.target_met},
                           {"dof", p.dof},
                           {"rank", p.rank},
                           {"redundant", p.redundant},
                           {"sigma_min", p.singular.sigma_min},
                           {"transmission_index", opt_json(p.singular.eta)},
                           {"singular_distance", opt_json(p.singular_distance)},
                           {"singular_kind", p.singular_kind},
                           {"singular_input", opt_json(p.singular_input)},
                           {"four_bars", fb},
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
                  "", "[mm]", "[mm]", "", "", "", in_unit, "[deg]", "", "", "");
    out << line;
    for (const PositionReport& p : rep.positions) {
      std::optional<double> mu;
      for (const FourBarReport& f : p.four_bars) {
        const double m = std::min(f.transmission, std::numbers::pi - f.transmission);
        if (!mu || m < *mu) mu = m;
      }
      const std::string mode =
          p.mode > 0 ? std::to_string(p.mode) + "/" + std::to_string(p.modes) : "-";
      std::snprintf(
          line, sizeof line, "%-10s %-5s %9s %9s %3d %9s %9s %11s %8s %7s %5s %5s  %s\n",
          p.name.c_str(), p.assembles ? "yes" : "NO",
          cell(std::optional<double>(p.max_translation), 1e3).c_str(),
          cell(p.target_error, 1e3).c_str(), p.dof,
          cell(std::optional<double>(p.singular.sigma_min), 1.0, "%.3g").c_str(),
          cell(p.singular.eta, 1.0, "%.3g").c_str(), cell(p.singular_distance, in_scale).c_str(),
          cell(mu, 180.0 / std::numbers::pi, "%.2f").c_str(), mode.c_str(),
          p.circuit > 0 ? std::to_string(p.circuit).c_str() : "-",
          p.branch > 0 ? std::to_string(p.branch).c_str() : "-", p.pass() ? "pass" : "FAIL");
      out << line;
    }
    bool any_loop = false;
    for (const PositionReport& p : rep.positions)
      if (!p.four_bars.empty() && !any_loop) {
        any_loop = true;
        out << "\nfour-bar loops\n";
        for (const FourBarReport& f : p.four_bars)
          out << "  " << f.joints << "  " << to_string(f.type) << "\n";
      }
    bool header = false;
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
    if (rep.pass()) out << "every position passes every check\n";
  }
  std::cout << out.str();
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
  cmd->add_flag("--json", opt->json, "one JSON document on stdout");
  cmd->add_option("--min-transmission", opt->min_transmission_deg,
                  "smallest acceptable transmission angle deviation from a straight line, deg "
                  "(default 30)")
      ->check(finite_range(0.0, 90.0));
  cmd->add_option("--starts", opt->starts, "multi-start projections per position (default 24)")
      ->check(CLI::Range(0, 100000));
  cmd->add_option("--seed", opt->seed, "seed of the multi-start (default 1)");
  cmd->callback([opt, &globals, &exit_code] {
    setup_logging(globals);
    exit_code = run_validate(*opt);
  });
}

}  // namespace orthomech::cli
