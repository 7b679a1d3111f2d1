// The study reader's refusals (issue 47): laws whose draws overflow, values outside the field's
// limits, a path given twice or naming a text field, parameter names that collide with a column
// of the study's table, an unknown `best` metric, and a study file that holds itself through an
// alias. Each is an InputError at the study file's line (docs/cli.md "sweep").
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "orthomech/error.hpp"
#include "orthomech/study/study.hpp"
#include "support/cli_runner.hpp"

namespace orthomech {
namespace {

const std::string& crank_rocker() {
  static const std::string text = test::read_text(test::bundled_file("crank-rocker"));
  return text;
}

// The InputError of parsing `study` (the test fails when there is none).
InputError refusal(const std::string& study) {
  try {
    (void)parse_study(study, "s.yaml", crank_rocker(), "crank-rocker.yaml");
  } catch (const InputError& e) {
    return e;
  }
  ADD_FAILURE() << "no InputError for:\n" << study;
  return InputError({"", 0, 0}, "", "");
}

void expect_refused(const std::string& study, int line, const std::string& part) {
  const InputError e = refusal(study);
  EXPECT_EQ(e.where().file, "s.yaml") << e.what();
  EXPECT_EQ(e.where().line, line) << e.what();
  EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
}

TEST(StudyLimits, LawWhoseDrawsOverflowIsRefused) {
  // uniform: mean ± tolerance overflows; normal: mean ± 10 σ does (both crashed or wrote inf).
  for (const char* law :
       {"uniform: {mean: 1e308, tolerance: 1e308}", "normal: {mean: 1e308, sigma: 1e307}"}) {
    SCOPED_TRACE(law);
    expect_refused(std::string("study: monte-carlo\nsamples: 10\nparameters:\n"
                               "  - path: bodies.crank.mass\n    ") +
                       law + "\n",
                   5, "must be finite numbers");
  }
}

TEST(StudyLimits, LawBeyondTheFieldsLimitsIsRefusedNamingTheEnd) {
  // A mass of 0.03 ± 0.05 kg reaches −0.02 kg: not a mass (the file's own limit).
  expect_refused(R"(study: monte-carlo
samples: 10
parameters:
  - path: bodies.crank.mass
    uniform: {tolerance: 0.05}
)",
                 5, "mean − tolerance");
  // The same law within the limits reads, and every draw is a valid mass (the oracle: the
  // limits of the file, 1e-9 kg to 1e9 kg, and the law's own range).
  const Study ok = parse_study(R"(study: monte-carlo
samples: 50
parameters:
  - path: bodies.crank.mass
    uniform: {tolerance: 0.01}
)",
                               "s.yaml", crank_rocker(), "crank-rocker.yaml");
  for (long k = 0; k < 50; ++k) {
    const double m = variant_values(ok, k)[0];
    EXPECT_GE(m, 0.02);
    EXPECT_LE(m, 0.04);
  }
}

TEST(StudyLimits, GridValueBeyondTheFieldsLimitsIsRefused) {
  expect_refused(R"(study: grid
parameters:
  - {path: bodies.crank.mass, values: [0.03, -1]}
)",
                 3, "the smallest value (-1)");
}

TEST(StudyLimits, PathGivenTwiceIsRefused) {
  expect_refused(R"(study: grid
parameters:
  - {path: bodies.crank.mass, values: [0.03]}
  - {path: bodies.crank.mass, name: m2, values: [0.04]}
)",
                 4, "listed twice");
}

TEST(StudyLimits, PathThatIsNotANumberIsRefused) {
  expect_refused(R"(study: grid
parameters:
  - {path: description, values: [1, 2]}
)",
                 3, "is not a number");
}

TEST(StudyLimits, NamesEqualUpToCaseOrAColumnAreRefused) {
  expect_refused(R"(study: grid
parameters:
  - {path: bodies.crank.mass, name: m, values: [0.03]}
  - {path: bodies.rocker.mass, name: M, values: [0.06]}
)",
                 4, "equal up to case");
  expect_refused(R"(study: grid
parameters:
  - {path: bodies.crank.mass, name: Status, values: [0.03]}
)",
                 3, "column of the study's table");
  expect_refused(R"(study: grid
parameters:
  - {path: bodies.crank.mass, name: drive.peak, values: [0.03]}
)",
                 3, "metric column");
}

TEST(StudyLimits, UnknownBestMetricIsRefusedListingTheMetrics) {
  const InputError e = refusal(R"(study: grid
parameters:
  - {path: bodies.crank.mass, values: [0.03, 0.04]}
best: {metric: drive.peek}
)");
  EXPECT_EQ(e.where().line, 4) << e.what();
  EXPECT_NE(std::string(e.what()).find("unknown metric 'drive.peek'"), std::string::npos);
  EXPECT_NE(std::string(e.what()).find("drive.peak"), std::string::npos) << e.what();
  // A known one reads.
  EXPECT_NO_THROW((void)parse_study(R"(study: grid
parameters:
  - {path: bodies.crank.mass, values: [0.03, 0.04]}
best: {metric: drive.rms}
)",
                                    "s.yaml", crank_rocker(), "crank-rocker.yaml"));
}

TEST(StudyLimits, CyclicAliasInTheStudyFileIsRefusedAtItsLine) {
  expect_refused(
      "study: grid\nparameters:\n  - {path: bodies.crank.mass, values: [0.03]}\n"
      "best: &b [*b]\n",
      4, "holds itself");
}

}  // namespace
}  // namespace orthomech
