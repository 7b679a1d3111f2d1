// The limits of every number entering the tool (docs/file-format.md "Limits"; issue 17): the same
// check for a file and a command line, in SI, and whole-file problems placed at 1:1.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "orthomech/error.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/io/units.hpp"

namespace orthomech {
namespace {

TEST(Limits, RangeProblemAcceptsTheDocumentedRangeAndNothingBeyond) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  for (Quantity q :
       {Quantity::length, Quantity::angle, Quantity::mass, Quantity::inertia, Quantity::general}) {
    EXPECT_EQ(range_problem(nan, q), "must be finite");
    EXPECT_EQ(range_problem(inf, q), "must be finite");
    EXPECT_EQ(range_problem(-inf, q), "must be finite");
  }
  // The bounds themselves are inside; the next double outside is not.
  EXPECT_EQ(range_problem(kMaxLength, Quantity::length), "");
  EXPECT_EQ(range_problem(-kMaxLength, Quantity::length), "");
  EXPECT_NE(range_problem(std::nextafter(kMaxLength, inf), Quantity::length), "");
  EXPECT_EQ(range_problem(kMaxAngle, Quantity::angle), "");
  EXPECT_NE(range_problem(-std::nextafter(kMaxAngle, inf), Quantity::angle), "");
  EXPECT_EQ(range_problem(kMinMass, Quantity::mass), "");
  EXPECT_EQ(range_problem(1e-320, Quantity::mass), "must be at least 1e-09 kg");  // denormal
  EXPECT_EQ(range_problem(kMaxMass, Quantity::mass), "");
  EXPECT_NE(range_problem(std::nextafter(kMaxMass, inf), Quantity::mass), "");
  EXPECT_EQ(range_problem(kMinInertia, Quantity::inertia), "");
  EXPECT_NE(range_problem(std::nextafter(kMinInertia, 0.0), Quantity::inertia), "");
  EXPECT_EQ(range_problem(kMaxGeneral, Quantity::general), "");
  EXPECT_EQ(range_problem(0.0, Quantity::general), "");
  EXPECT_NE(range_problem(1e308, Quantity::general), "");
}

// The worst product of two in-range values stays finite (the reason for the limits): stiffness ×
// length, force × length, mass × speed², inertia × speed².
TEST(Limits, ProductsOfInRangeValuesAreFinite) {
  EXPECT_TRUE(std::isfinite(kMaxGeneral * kMaxLength * kMaxLength));
  EXPECT_TRUE(std::isfinite(kMaxMass * kMaxGeneral * kMaxGeneral));
  EXPECT_TRUE(std::isfinite(kMaxInertia * kMaxGeneral * kMaxGeneral));
  EXPECT_TRUE(std::isfinite(1.0 / kMinInertia * kMaxGeneral));
}

TEST(Limits, SpeedsAndPositionsWithUnitsAreCheckedInSI) {
  EXPECT_THROW((void)parse_speed("nan", true, 1.0), std::invalid_argument);
  EXPECT_THROW((void)parse_speed("1e300 rpm", true, 1.0), std::invalid_argument);
  EXPECT_THROW((void)parse_speed("0 rpm", true, 1.0), std::invalid_argument);
  EXPECT_THROW((void)parse_speed(std::string(200, '1'), true, 1.0), std::invalid_argument);
  EXPECT_DOUBLE_EQ(parse_speed("60 rpm", true, 1.0), 2.0 * M_PI);  // one turn per second
  // 1e6 rad is the angle limit: 57295779.5 deg is just inside, 57295780 deg just outside.
  EXPECT_NO_THROW((void)parse_position("57295779.5 deg", true, 1.0));
  EXPECT_THROW((void)parse_position("57295780 deg", true, 1.0), std::invalid_argument);
  EXPECT_THROW((void)parse_position("2000 km", false, 1.0), std::invalid_argument);  // no unit
  EXPECT_THROW((void)parse_position("1.000001e9 mm", false, 1.0),
               std::invalid_argument);  // 1e6 m + 1 mm
}

// Whole-file problems: an empty text, only whitespace, only comments: placed at 1:1.
TEST(Limits, AnEmptyFileIsAWholeFileErrorAtLineOneColumnOne) {
  for (const char* text : {"", "   \n\n", "# a comment\n# another\n", "\xEF\xBB\xBF"}) {
    try {
      (void)parse_mechanism(text, "empty.yaml");
      ADD_FAILURE() << "accepted '" << text << "'";
    } catch (const InputError& e) {
      EXPECT_EQ(e.where().line, 1);
      EXPECT_EQ(e.where().column, 1);
      EXPECT_EQ(e.element(), "file");
    }
  }
}

}  // namespace
}  // namespace orthomech
