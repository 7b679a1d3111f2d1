// Expressions of the named design variables (src/io/expressions.cpp, private): values against the
// same arithmetic done here in C++, and every rejection as std::invalid_argument.
#include "../../../src/io/expressions.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace orthomech::detail {
namespace {

TEST(Expressions, ValuesEqualTheSameArithmeticInCpp) {
  Expressions e;
  e.define("L", 80.0);
  e.define("r", 12.5);
  e.define("a_2", 3.0);
  e.define("b", 4.0);
  EXPECT_DOUBLE_EQ(e.evaluate("L/2"), 40.0);
  EXPECT_DOUBLE_EQ(e.evaluate("2*r + 5"), 30.0);
  EXPECT_DOUBLE_EQ(e.evaluate("sqrt(a_2^2 + b^2)"), 5.0);
  EXPECT_DOUBLE_EQ(e.evaluate("atan2(b, a_2) * 180 / pi"),
                   std::atan2(4.0, 3.0) * 180.0 / std::numbers::pi);
  EXPECT_DOUBLE_EQ(e.evaluate("-L + r*(b - a_2)"), -80.0 + 12.5);
  EXPECT_DOUBLE_EQ(e.evaluate("7"), 7.0);
  ASSERT_EQ(e.parameters().size(), 4u);
  EXPECT_EQ(e.parameters()[0].first, "L");
  EXPECT_EQ(e.parameters()[3].second, 4.0);
}

TEST(Expressions, BadDefinitionsAreRefused) {
  Expressions e;
  e.define("x", 1.0);
  EXPECT_THROW(e.define("x", 2.0), std::invalid_argument);     // twice
  EXPECT_THROW(e.define("2x", 1.0), std::invalid_argument);    // not an identifier
  EXPECT_THROW(e.define("a-b", 1.0), std::invalid_argument);   // not an identifier
  EXPECT_THROW(e.define("pi", 3.0), std::invalid_argument);    // the constant
  EXPECT_THROW(e.define("sqrt", 1.0), std::invalid_argument);  // a built-in function
  EXPECT_DOUBLE_EQ(e.evaluate("x"), 1.0);                      // unchanged
}

TEST(Expressions, BadExpressionsAreRefused) {
  Expressions e;
  e.define("x", 1.0);
  try {
    (void)e.evaluate("x + y");
    FAIL() << "an unknown name must throw";
  } catch (const UnknownName& u) {
    EXPECT_EQ(u.name, "y");
  }
  EXPECT_THROW((void)e.evaluate("x +"), std::invalid_argument);
  EXPECT_THROW((void)e.evaluate("(x"), std::invalid_argument);
  EXPECT_THROW((void)e.evaluate(""), std::invalid_argument);
  EXPECT_THROW((void)e.evaluate("x, x"), std::invalid_argument);  // one value only
}

}  // namespace
}  // namespace orthomech::detail
