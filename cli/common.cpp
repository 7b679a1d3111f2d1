#include "common.hpp"

#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "orthomech/io/file_writer.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/io/noise.hpp"
#include "orthomech/io/study_db.hpp"
#include "orthomech/io/study_report.hpp"
#include "orthomech/io/units.hpp"
#include "orthomech/study/study.hpp"

namespace orthomech::cli {

namespace {
std::ostream* log_stream = nullptr;
}  // namespace

void set_log_stream(std::ostream* stream) { log_stream = stream; }

void setup_logging(const GlobalOptions& options) {
  spdlog::drop("orthomech");  // a second command line in the same process (the Python module)
  auto logger = log_stream
                    ? spdlog::synchronous_factory::create<spdlog::sinks::ostream_sink_mt>(
                          "orthomech", *log_stream)
                    : spdlog::stderr_color_mt("orthomech");  // logs to stderr, results to stdout
  logger->set_pattern("%^%l%$: %v");
  logger->set_level(options.quiet     ? spdlog::level::err
                    : options.verbose ? spdlog::level::debug
                                      : spdlog::level::warn);
  spdlog::set_default_logger(logger);
}

void add_log_flags(CLI::App* cmd, LogFlags& flags) {
  cmd->add_flag("-q,--quiet", flags.quiet, "only errors on stderr (also before the command)");
  cmd->add_flag("-v,--verbose", flags.verbose,
                "debug messages on stderr (also before the command)");
}

void setup_logging(const GlobalOptions& options, const LogFlags& flags) {
  GlobalOptions merged = options;
  merged.quiet = merged.quiet || flags.quiet;
  merged.verbose = merged.verbose || flags.verbose;
  setup_logging(merged);
}

CLI::Validator finite_range(double lo, double hi, bool lo_open) {
  char description[80];
  std::snprintf(description, sizeof description, "NUMBER in %s%g, %g]", lo_open ? "(" : "[", lo,
                hi);
  return CLI::Validator(
      [lo, hi, lo_open](std::string& text) -> std::string {
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        if (text.empty() || end != text.c_str() + text.size())
          return "'" + text + "' is not a number";
        if (!std::isfinite(v)) return "'" + text + "' is not finite";
        if (v > hi || v < lo || (lo_open && v == lo)) {
          char buf[120];
          std::snprintf(buf, sizeof buf, "%s must be in %s%g, %g]", text.c_str(),
                        lo_open ? "(" : "[", lo, hi);
          return buf;
        }
        return "";
      },
      description);
}

double parse_number(const std::string& text, const std::string& option) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || text.size() > kMaxNumberLength || end != text.c_str() + text.size())
    throw CLI::ValidationError(option, "'" + text + "' is not a number");
  const std::string problem = range_problem(v, Quantity::general);
  if (!problem.empty()) throw CLI::ValidationError(option, "'" + text + "': the value " + problem);
  return v;
}

void add_set_option(CLI::App* cmd, std::vector<std::string>& sets) {
  cmd->add_option("--set", sets,
                  "change a value of the file before reading it: PATH=VALUE in the file's units, "
                  "e.g. loads.spring.stiffness=4000 or a parameter L=120 (repeatable)")
      ->allow_extra_args(false)
      ->type_name("PATH=VALUE");
}

namespace {
struct MechanismText {
  std::string origin, text;
};
MechanismText& mechanism_text() {
  static MechanismText given;
  return given;
}
}  // namespace

void set_mechanism_text(const std::string& origin, const std::string& text) {
  mechanism_text() = {origin, origin.empty() ? std::string() : text};
}

Model load(const std::string& path, const std::vector<std::string>& sets) {
  spdlog::debug("reading {}", path);
  std::vector<FileChange> changes;
  for (const std::string& set : sets) {
    try {
      changes.push_back(parse_file_change(set));
    } catch (const std::invalid_argument& e) {
      throw CLI::ValidationError("--set", e.what());
    }
  }
  const MechanismText& given = mechanism_text();
  Model model = !given.origin.empty() && given.origin == path
                    ? parse_mechanism(given.text, path, changes)
                    : load_mechanism(path, changes);
  for (const std::string& w : model.warnings) spdlog::warn("{}", w);
  return model;
}

void require_planar(const Model& model, const std::string& command) {
  if (model.dimension == 2) return;
  throw InputError({model.file, 0, 0}, "dimension: 3",
                   "'" + command +
                       "' is not available for spatial mechanisms yet (info, assemble, simulate, "
                       "crosscheck, cycle, validate, render, sweep and optimize are)");
}

void add_units_option(CLI::App* cmd, std::string& choice) {
  cmd->add_option("--units", choice,
                  "units of every output: 'file' (the file's declared units, default) or 'si'")
      ->check(CLI::IsMember({"file", "si"}));
}

UnitSystem resolve_units(const Model& model, const std::string& choice) {
  try {
    return output_units(model, choice);
  } catch (const std::invalid_argument& e) {
    throw CLI::ValidationError("--units", e.what());
  }
}

std::vector<double> coordinates_out(const Model& model, const VecX& v, const UnitSystem& units,
                                    bool rates) {
  const OutputUnit length = output_unit(rates ? Dimension::velocity : Dimension::length, units);
  const OutputUnit angle =
      output_unit(rates ? Dimension::angular_velocity : Dimension::angle, units);
  const Dimension dims[] = {rates ? Dimension::velocity : Dimension::length,
                            rates ? Dimension::angular_velocity : Dimension::angle};
  // Which of them coordinate k of a body is: 0 length, 1 angle, 2 neither (a spatial body's
  // q = (x, y, z, e0..e3): the quaternion is unit-free; its u = (vx, vy, vz, ωx, ωy, ωz)).
  auto kind = [&](const Body& b, int k) {
    const int lengths = b.kind == BodyKind::spatial ? 3 : 2;
    if (k < lengths) return 0;
    return b.kind == BodyKind::spatial && !rates ? 2 : 1;
  };
  // Rounding noise (a slider's y on a horizontal guide) as 0: io/noise.hpp.
  NoiseFloor noise;
  for (const Body& b : model.bodies) {
    const int offset = rates ? b.u_offset : b.q_offset;
    for (int k = 0; k < (rates ? b.nu() : b.nq()); ++k)
      if (kind(b, k) < 2) noise.see(dims[kind(b, k)], v(offset + k));
  }
  std::vector<double> out(v.data(), v.data() + v.size());
  for (const Body& b : model.bodies) {
    const int offset = rates ? b.u_offset : b.q_offset;
    for (int k = 0; k < (rates ? b.nu() : b.nq()); ++k) {
      double& x = out[static_cast<size_t>(offset + k)];
      const int c = kind(b, k);
      if (c < 2) x = (c == 0 ? length : angle).from_si(noise.clean(dims[c], x));
    }
  }
  return out;
}

OutputUnit mass_metric_unit(const UnitSystem& units) {
  return {"sqrt(" + units.mass + ")*" + units.length, std::sqrt(units.mass_si) * units.length_si};
}

nlohmann::json number_or_null(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json();
}

std::unique_ptr<StudyDatabase> open_study_database(const std::string& out, bool resume,
                                                   const std::string& mechanism,
                                                   const std::string& study_text,
                                                   const Study& study,
                                                   const VariantResult& columns) {
  std::vector<std::string> parameters, metrics;
  for (const auto& p : study.parameters) parameters.push_back(p.name);
  for (const auto& [name, value] : columns.metrics) metrics.push_back(name);
  std::error_code ec;
  std::filesystem::create_directories(out, ec);
  if (ec) {
    spdlog::error("{}: cannot create the directory: {}", out, ec.message());
    return nullptr;
  }
  // The same study: the same mechanism and study file, a Monte Carlo study's samples aside.
  std::vector<std::pair<std::string, std::string>> identity{
      {"mechanism", mechanism}, {"study", study_identity(study_text, "study")}};
  if (study.kind == StudyKind::monte_carlo)
    identity.emplace_back("samples", std::to_string(study.samples));
  if (study.kind == StudyKind::optimize)  // the budget of evaluations, which may grow as well
    identity.emplace_back("samples", std::to_string(study.goal.evaluations));
  try {
    return std::make_unique<StudyDatabase>(std::filesystem::path(out) / "study.sqlite", resume,
                                           identity, parameters, metrics);
  } catch (const std::runtime_error& e) {
    spdlog::error("{}", e.what());
    return nullptr;
  }
}

void add_study_report_options(CLI::App* cmd, StudyReportOptions& options) {
  cmd->add_option("--report", options.html,
                  "write the study report, one offline HTML page: scatter plots of parameters "
                  "against metrics, histograms, sensitivities, the best variants' cycles");
  cmd->add_option("--figures", options.figures,
                  "write the report's figures as SVG files into this directory (for papers)");
  cmd->add_option("--report-metrics", options.metrics,
                  "the metrics the report shows (default: the best metric, the expressions, then "
                  "the metrics that vary, 8 in all)")
      ->delimiter(',');
}

std::vector<std::string> unknown_report_metrics(const StudyReportOptions& options,
                                                const VariantResult& columns) {
  std::vector<std::string> unknown;
  for (const std::string& m : options.metrics)
    if (std::none_of(columns.metrics.begin(), columns.metrics.end(),
                     [&](const auto& c) { return c.first == m; })) {
      std::string list;
      for (const auto& [name, value] : columns.metrics) list += (list.empty() ? "" : ", ") + name;
      spdlog::error("--report-metrics: unknown metric '{}' (the study's metrics: {})", m, list);
      unknown.push_back(m);
    }
  return unknown;
}

void write_study_report(const StudyReportOptions& options, const StudyReport& report) {
  if (!options.html.empty()) write_file(options.html, study_report_html(report));
  if (options.figures.empty()) return;
  std::filesystem::create_directories(options.figures);
  for (const StudyFigure& f : study_report_figures(report))
    write_file(std::filesystem::path(options.figures) / f.file, f.svg);
}

std::string read_input_file(const std::string& path, const std::string& what) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw InputError({path, 0, 0}, what, "cannot open the file: no such file");
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

nlohmann::json units_json(const UnitSystem& u) {
  nlohmann::json j;
  const std::pair<const char*, Dimension> kinds[] = {
      {"length", Dimension::length},
      {"angle", Dimension::angle},
      {"mass", Dimension::mass},
      {"time", Dimension::time},
      {"force", Dimension::force},
      {"moment", Dimension::moment},
      {"energy", Dimension::moment},
      {"power", Dimension::power},
      {"velocity", Dimension::velocity},
      {"angular_velocity", Dimension::angular_velocity},
      {"acceleration", Dimension::acceleration},
      {"angular_acceleration", Dimension::angular_acceleration},
      {"inertia", Dimension::inertia}};
  for (const auto& [name, q] : kinds) j[name] = output_unit(q, u).name;
  return j;
}

Vec3 parse_point(const Model& model, const std::string& text, const std::string& option) {
  Vec3 o = Vec3::Zero();
  if (text.empty()) return o;
  const double unit = unit_system(model.units).length_si;
  std::vector<double> v;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');)
    v.push_back(parse_number(item, option) * unit);
  const auto dim = static_cast<size_t>(model.dimension);
  if (v.size() != dim || text.back() == ',')
    throw CLI::ValidationError(option, "'" + text + "' is not a point of a " +
                                           (dim == 2 ? "planar" : "spatial") + " mechanism: give " +
                                           (dim == 2 ? "X,Y" : "X,Y,Z") +
                                           " in the file's length unit");
  for (size_t i = 0; i < dim; ++i) o(static_cast<Eigen::Index>(i)) = v[i];
  return o;
}

void warn_friction_not_applied(const Model& model, const std::string& command) {
  for (const Joint& j : model.joints)
    if (j.friction)
      spdlog::warn(
          "{}: joint '{}': {} does not apply joint friction yet (cycle and simulate do): its "
          "results "
          "are frictionless",
          j.where.str(), j.name, command);
}

}  // namespace orthomech::cli
