#include "common.hpp"

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

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

Model load(const std::string& path) {
  spdlog::debug("reading {}", path);
  return load_mechanism(path);
}

}  // namespace orthomech::cli
