#pragma once
// Shared by the subcommands: exit codes, loading with error reporting, logging set-up.
// No math here (house style: cli/ holds no math).
#include <CLI/CLI.hpp>
#include <string>

#include "orthomech/model/model.hpp"

namespace orthomech::cli {

// Documented exit codes (docs/cli.md).
enum ExitCode : int {
  kOk = 0,
  kCheckFailed = 1,  // an analysis ran and a check failed
  kBadInput = 2,     // bad mechanism file or command line
  kNumerical = 3,    // numerical failure (cannot assemble, singular, no convergence)
  kInternal = 4,     // a bug: please report
};

struct GlobalOptions {
  bool quiet = false;
  bool verbose = false;
};

void setup_logging(const GlobalOptions& options);

// A number option that must be finite and lie in [lo, hi] (or (lo, hi] with `lo_open`): NaN and
// inf are refused (CLI::Range and CLI::PositiveNumber let them through). Exit 2 naming the option.
[[nodiscard]] CLI::Validator finite_range(double lo, double hi, bool lo_open = false);
// A command-line number with no unit (e.g. "--rate x=1.5", "--velocity b=0,1"): the whole text
// is a number, finite and within the limits of Quantity::general. Throws CLI::ValidationError
// naming `option` otherwise.
[[nodiscard]] double parse_number(const std::string& text, const std::string& option);
// Loads a mechanism; on failure throws InputError (main maps it to exit code 2).
[[nodiscard]] Model load(const std::string& path);

}  // namespace orthomech::cli
