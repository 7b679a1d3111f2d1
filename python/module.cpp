// orthomech._orthomech: the compiled part of the Python module (orthomech/__init__.py is the
// rest). It runs the command line of the CLI in this process (cli/run.cpp, the same code as the
// executable), with std::cout and std::cerr captured, so every result is the CLI's JSON
// document, byte for byte; and it checks mechanism text with the library's reader.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "common.hpp"
#include "orthomech/error.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/version.hpp"
#include "orthomech_git_revision.hpp"
#include "run.hpp"

namespace py = pybind11;

namespace {

// std::cout / std::cerr redirected into a string for the lifetime of the object.
class Capture {
 public:
  explicit Capture(std::ostream& stream) : stream_(stream), old_(stream.rdbuf(text_.rdbuf())) {}
  ~Capture() { stream_.rdbuf(old_); }
  Capture(const Capture&) = delete;
  Capture& operator=(const Capture&) = delete;
  [[nodiscard]] std::string str() const { return text_.str(); }

 private:
  std::ostream& stream_;
  std::ostringstream text_;
  std::streambuf* old_;
};

// Clears the mechanism text on every way out.
struct TextSource {
  TextSource(const std::string& origin, const std::string& text) {
    orthomech::cli::set_mechanism_text(origin, text);
  }
  ~TextSource() { orthomech::cli::set_mechanism_text("", ""); }
  TextSource(const TextSource&) = delete;
  TextSource& operator=(const TextSource&) = delete;
};

// `orthomech ARGS...` in this process: (exit code, stdout, stderr). A FILE argument equal to
// `origin` (when not empty) is read from `text`.
std::tuple<int, std::string, std::string> run(const std::vector<std::string>& args,
                                              const std::string& origin, const std::string& text) {
  std::vector<const char*> argv{"orthomech"};
  for (const std::string& a : args) argv.push_back(a.c_str());
  std::fflush(stdout);
  const TextSource source(origin, text);
  std::string out, err;
  int code = 0;
  {
    const Capture capture_out(std::cout), capture_err(std::cerr);
    code = orthomech::cli::run(static_cast<int>(argv.size()), argv.data());
    out = capture_out.str();
    err = capture_err.str();
  }
  std::fflush(stderr);
  return {code, out, err};
}

// Reads mechanism text as the CLI reads a file: None when it is a valid mechanism, else
// (message, file, line, column) of the first problem.
std::optional<std::tuple<std::string, std::string, int, int>> check(const std::string& text,
                                                                    const std::string& origin) {
  try {
    (void)orthomech::parse_mechanism(text, origin);
  } catch (const orthomech::InputError& e) {
    return std::make_tuple(std::string(e.what()), e.where().file, e.where().line, e.where().column);
  }
  return std::nullopt;
}

}  // namespace

PYBIND11_MODULE(_orthomech, m) {
  m.doc() = "compiled part of orthomech (use the package orthomech)";
  // The CLI's logs (warnings, errors) into the captured stderr: the package shows them.
  orthomech::cli::set_log_stream(&std::cerr);
  m.attr("version") = orthomech::kVersion;
  m.attr("git_revision") = ORTHOMECH_GIT_REVISION;
  m.attr("version_line") = ORTHOMECH_VERSION_LINE;
  m.def("run", &run, py::arg("args"), py::arg("origin") = "", py::arg("text") = "",
        "run `orthomech ARGS...` in this process: (exit code, stdout, stderr)");
  m.def("check", &check, py::arg("text"), py::arg("origin"),
        "None for a valid mechanism text, else (message, file, line, column)");
}
