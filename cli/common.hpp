#pragma once
// Shared by the subcommands: exit codes, loading with error reporting, logging set-up.
// No math here (house style: cli/ holds no math).
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
// Loads a mechanism; on failure throws InputError (main maps it to exit code 2).
[[nodiscard]] Model load(const std::string& path);

}  // namespace orthomech::cli
