#include "support/cli_runner.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <iterator>

namespace orthomech::test {

namespace fs = std::filesystem;

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

namespace {
std::string shell_quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}
}  // namespace

CliResult run_cli(const std::vector<std::string>& args) {
  static int counter = 0;
  const fs::path base = fs::temp_directory_path() / ("orthomech_cli_" + std::to_string(::getpid()) +
                                                     "_" + std::to_string(counter++));
  const fs::path out_file = base.string() + ".out", err_file = base.string() + ".err";
  std::string cmd = shell_quote(ORTHOMECH_CLI);
  for (const auto& a : args) cmd += ' ' + shell_quote(a);
  cmd += " >" + shell_quote(out_file.string()) + " 2>" + shell_quote(err_file.string()) +
         " </dev/null";
  const int raw = std::system(cmd.c_str());
  CliResult r;
  r.status = (raw != -1 && WIFEXITED(raw)) ? WEXITSTATUS(raw) : -1;
  r.out = read_text(out_file);
  r.err = read_text(err_file);
  std::error_code ec;
  fs::remove(out_file, ec);
  fs::remove(err_file, ec);
  return r;
}

std::string bundled_file(const std::string& name) {
  return std::string(ORTHOMECH_SOURCE_DIR) + "/mechanisms/" + name + ".yaml";
}

TempDir::TempDir(const std::string& prefix, bool create) {
  static int counter = 0;
  path = fs::temp_directory_path() /
         (prefix + std::to_string(::getpid()) + "_" + std::to_string(counter++));
  if (create) fs::create_directories(path);
}

TempDir::~TempDir() {
  std::error_code ec;
  fs::remove_all(path, ec);
}

}  // namespace orthomech::test
