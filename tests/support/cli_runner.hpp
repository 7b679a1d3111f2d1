#pragma once
// Runs the built orthomech executable (ORTHOMECH_CLI) with stdout and stderr captured.
#include <filesystem>
#include <string>
#include <vector>

namespace orthomech::test {

struct CliResult {
  int status = -1;  // exit status, or -1 if the process did not exit normally (e.g. a crash)
  std::string out, err;
};

// Whole file as text ("" if it cannot be read).
[[nodiscard]] std::string read_text(const std::filesystem::path& path);
// Runs `orthomech args...` with stdin from /dev/null; output captured in temporary files.
[[nodiscard]] CliResult run_cli(const std::vector<std::string>& args);

}  // namespace orthomech::test
