#include "common.hpp"

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>

#include "orthomech/io/mechanism_file.hpp"

namespace orthomech::cli {

void setup_logging(const GlobalOptions& options) {
  auto logger = spdlog::stderr_color_mt("orthomech");  // logs to stderr, results to stdout
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

Model load(const std::string& path) {
  spdlog::debug("reading {}", path);
  Model model = load_mechanism(path);
  for (const std::string& w : model.warnings) spdlog::warn("{}", w);
  return model;
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

}  // namespace orthomech::cli
