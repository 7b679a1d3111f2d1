// Errors (src/error.cpp): the "file:line:column: error: element: message" text of an InputError,
// with the parts that are unknown left out.
#include "orthomech/error.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

namespace orthomech {
namespace {

TEST(Error, SourceLocationWritesWhatIsKnown) {
  EXPECT_EQ((SourceLocation{"a.yaml", 3, 7}).str(), "a.yaml:3:7");
  EXPECT_EQ((SourceLocation{"a.yaml", 3, 0}).str(), "a.yaml:3");
  EXPECT_EQ((SourceLocation{"a.yaml", 0, 7}).str(), "a.yaml");  // a column without a line
  EXPECT_EQ((SourceLocation{"", 0, 0}).str(), "<input>");
}

TEST(Error, InputErrorComposesItsMessageAndKeepsItsParts) {
  const InputError e({"m.yaml", 12, 5}, "joints[2].length", "must be positive");
  EXPECT_STREQ(e.what(), "m.yaml:12:5: error: joints[2].length: must be positive");
  EXPECT_EQ(e.where().line, 12);
  EXPECT_EQ(e.where().column, 5);
  EXPECT_EQ(e.element(), "joints[2].length");
  EXPECT_EQ(e.message(), "must be positive");
  const InputError whole({"m.yaml", 1, 1}, "", "empty file");
  EXPECT_STREQ(whole.what(), "m.yaml:1:1: error: empty file");
  // One channel: caught as std::runtime_error too.
  try {
    throw InputError({}, "x", "y");
  } catch (const std::runtime_error& r) {
    EXPECT_EQ(std::string(r.what()), "<input>: error: x: y");
  }
}

}  // namespace
}  // namespace orthomech
