// Every file in tests/data/invalid/ is a small broken mechanism whose first line is
//   # expect: <file name>:<line>:<column>: error: <element>: <message>
// The reader must reject it with exactly that InputError (docs/file-format.md: errors name
// file:line:column and the element), and `orthomech info` must exit with status 2, print the
// message once on stderr and nothing on stdout.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <string>
#include <typeinfo>
#include <vector>

#include "orthomech/error.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "support/cli_runner.hpp"

namespace orthomech {
namespace {

namespace fs = std::filesystem;

fs::path invalid_dir() { return fs::path(ORTHOMECH_SOURCE_DIR) / "tests" / "data" / "invalid"; }

// File names (not paths) of every *.yaml in tests/data/invalid/, sorted; enumerated at run time.
std::vector<std::string> invalid_files() {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(invalid_dir(), ec))
    if (entry.is_regular_file() && entry.path().extension() == ".yaml")
      names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

size_t count_occurrences(const std::string& haystack, const std::string& needle) {
  if (needle.empty()) return 0;
  size_t count = 0;
  for (size_t pos = haystack.find(needle); pos != std::string::npos;
       pos = haystack.find(needle, pos + needle.size()))
    ++count;
  return count;
}

struct Expectation {
  std::string message;  // the full expected text, starting with the path passed to the reader
  int line = 0;
  int column = 0;
};

// Reads the `# expect:` line of `name` and turns "<name>:L:C: ..." into "<path>:L:C: ...".
::testing::AssertionResult expectation_of(const std::string& name, Expectation& out) {
  const fs::path path = invalid_dir() / name;
  std::ifstream in(path);
  std::string first;
  if (!in || !std::getline(in, first))
    return ::testing::AssertionFailure() << "cannot read " << path;
  const std::string tag = "# expect: ";
  if (first.rfind(tag, 0) != 0)
    return ::testing::AssertionFailure() << name << ": first line must start with '" << tag << "'";
  const std::string text = first.substr(tag.size());
  static const std::regex shape(R"(^([^:]+):([0-9]+):([0-9]+): error: .+$)");
  std::smatch m;
  if (!std::regex_match(text, m, shape))
    return ::testing::AssertionFailure()
           << name << ": expectation must look like '<file>:<line>:<column>: error: ...', got '"
           << text << "'";
  if (m[1].str() != name)
    return ::testing::AssertionFailure()
           << name << ": expectation names file '" << m[1].str() << "', not '" << name << "'";
  out.message = path.string() + text.substr(name.size());
  out.line = std::stoi(m[2].str());
  out.column = std::stoi(m[3].str());
  return ::testing::AssertionSuccess();
}

using test::CliResult;
using test::run_cli;

TEST(InvalidFiles, DirectoryHoldsAtLeastThirtyFiles) {
  const auto files = invalid_files();
  EXPECT_GE(files.size(), 30u) << "tests/data/invalid/ must not be (nearly) empty: "
                               << invalid_dir();
}

TEST(InvalidFiles, EveryFileHasAWellFormedExpectation) {
  for (const auto& name : invalid_files()) {
    Expectation e;
    EXPECT_TRUE(expectation_of(name, e));
  }
}

TEST(InvalidFiles, ExpectationsAreDistinct) {
  // One file per error: two files expecting the same message would test nothing new.
  std::vector<std::string> texts;
  for (const auto& name : invalid_files()) {
    Expectation e;
    if (!expectation_of(name, e)) continue;
    texts.push_back(e.message.substr(e.message.find(": error: ")));
  }
  std::sort(texts.begin(), texts.end());
  EXPECT_EQ(std::adjacent_find(texts.begin(), texts.end()), texts.end());
}

class InvalidFile : public ::testing::TestWithParam<std::string> {};

TEST_P(InvalidFile, LoadThrowsInputErrorWithTheExpectedMessage) {
  const std::string name = GetParam();
  Expectation expected;
  ASSERT_TRUE(expectation_of(name, expected));
  const std::string path = (invalid_dir() / name).string();
  try {
    (void)load_mechanism(path);
    FAIL() << path << ": loaded without an error; expected\n  " << expected.message;
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(expected.message), std::string::npos)
        << "expected: " << expected.message << "\n  actual: " << what;
    EXPECT_EQ(what.rfind(path, 0), 0u) << "the message must begin with the path: " << what;
    EXPECT_EQ(e.where().file, path);
    EXPECT_EQ(e.where().line, expected.line) << what;
    EXPECT_EQ(e.where().column, expected.column) << what;
  } catch (const std::exception& e) {
    FAIL() << path << ": threw a " << typeid(e).name() << " instead of an InputError: " << e.what();
  }
}

TEST_P(InvalidFile, CliInfoExitsWithBadInputAndPrintsTheMessageOnce) {
  const std::string name = GetParam();
  Expectation expected;
  ASSERT_TRUE(expectation_of(name, expected));
  const std::string path = (invalid_dir() / name).string();
  const CliResult r = run_cli({"info", path});
  EXPECT_EQ(r.status, 2) << "stderr: " << r.err;
  EXPECT_EQ(r.out, "") << "no partial output on stdout";
  EXPECT_EQ(count_occurrences(r.err, expected.message), 1u)
      << "expected once: " << expected.message << "\n  stderr: " << r.err;
  EXPECT_EQ(r.err.find("internal error"), std::string::npos) << r.err;
}

std::string test_name(const ::testing::TestParamInfo<std::string>& info) {
  std::string s = fs::path(info.param).stem().string();
  for (char& c : s)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return s;
}

INSTANTIATE_TEST_SUITE_P(Data, InvalidFile, ::testing::ValuesIn(invalid_files()), test_name);

// Formerly known bugs, fixed: the place of the error is checked.

// yaml-cpp reports an unclosed '[' at the end of the input (here 8:1, after the last line); the
// message should point at the bracket that is never closed (7:11).
TEST(InvalidFilesFixed, UnclosedBracketPointsAtTheBracket) {
  const std::string text =
      "# unclosed\northomech: 1\nbodies:\n  - name: crank\n    mass: 1\n    inertia: 0.1\n"
      "    pose: [0, 0, 0\n";
  try {
    (void)parse_mechanism(text, "unclosed.yaml");
    FAIL() << "loaded without an error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().line, 7) << e.what();
    EXPECT_EQ(e.where().column, 11) << e.what();
  }
}

// A point name given twice in `points:` is silently accepted (the first one wins).
TEST(InvalidFilesFixed, DuplicatePointNameIsAnError) {
  const std::string text =
      "orthomech: 1\nbodies:\n"
      "  - {name: crank, mass: 1, inertia: 0.1, pose: [0, 0, 0], points: {A: [0, 0], A: [1, 0]}}\n";
  try {
    (void)parse_mechanism(text, "dup-point.yaml");
    FAIL() << "loaded without an error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().line, 3) << e.what();
    EXPECT_EQ(e.where().column, 79) << e.what();
  }
}

}  // namespace
}  // namespace orthomech
