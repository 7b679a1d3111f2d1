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
// The path of a bundled mechanism file: mechanisms/<name>.yaml of the source tree.
[[nodiscard]] std::string bundled_file(const std::string& name);

// A fresh path in the temporary directory ("<prefix><pid>_<k>"), created when `create`, removed
// with everything in it when the object goes.
struct TempDir {
  explicit TempDir(const std::string& prefix, bool create = true);
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::filesystem::path path;
};

}  // namespace orthomech::test
