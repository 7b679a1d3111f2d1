// The one walk over YAML values (src/io/yaml_walk.hpp, issue 47): it visits every node once per
// use (aliases expanded), refuses a value that holds itself, an expansion beyond kMaxYamlNodes
// and nesting beyond kMaxYamlDepth, each at the node where it stopped.
#include "../../../src/io/yaml_walk.hpp"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <string>

namespace orthomech::detail {
namespace {

size_t visits(const std::string& text) {
  size_t n = 0;
  walk_yaml_value(YAML::Load(text), [&](const YAML::Node&) { ++n; });
  return n;
}

TEST(YamlWalk, VisitsEveryNodeOncePerUse) {
  // Counted by hand: the map, 2 keys, the list [1, 2, 3] (4 nodes), the scalar x.
  EXPECT_EQ(visits("{a: [1, 2, 3], b: x}"), 1u + 2u + 4u + 1u);
  // An alias is a use: {a: &l [1, 2], b: *l} visits the list twice (1 + 2 keys + 2 × 3).
  EXPECT_EQ(visits("{a: &l [1, 2], b: *l}"), 1u + 2u + 6u);
}

TEST(YamlWalk, RefusesAValueThatHoldsItself) {
  for (const char* text : {"&a [*a]", "{x: &a {y: [1, *a]}}", "&m {k: *m}"}) {
    SCOPED_TRACE(text);
    try {
      walk_yaml_value(YAML::Load(text));
      ADD_FAILURE() << "no refusal";
    } catch (const YamlWalkError& e) {
      EXPECT_NE(std::string(e.what()).find("holds itself"), std::string::npos) << e.what();
    }
  }
}

// Nine uses of nine uses of …: 9^k nodes from k short lines.
std::string alias_bomb(int levels) {
  std::string text = "a0: &a0 [x, x, x, x, x, x, x, x, x]\n";
  for (int k = 1; k <= levels; ++k) {
    const std::string p = "*a" + std::to_string(k - 1);
    text += "a" + std::to_string(k) + ": &a" + std::to_string(k) + " [" + p + ", " + p + ", " + p +
            ", " + p + ", " + p + ", " + p + ", " + p + ", " + p + ", " + p + "]\n";
  }
  return text;
}

TEST(YamlWalk, RefusesAnAliasBombBeyondTheLimit) {
  // Counted by the recursion c_0 = 10, c_k = 1 + 9 c_(k-1) over the document: 5 levels expand
  // to 672,610 nodes, within the limit; 7 levels to 54,481,013, beyond it.
  EXPECT_NO_THROW(walk_yaml_value(YAML::Load(alias_bomb(5))));
  try {
    walk_yaml_value(YAML::Load(alias_bomb(7)));
    ADD_FAILURE() << "no refusal";
  } catch (const YamlWalkError& e) {
    EXPECT_NE(std::string(e.what()).find("expands to more than 1000000 nodes"), std::string::npos)
        << e.what();
  }
}

TEST(YamlWalk, RefusesNestingBeyondTheLimit) {
  const std::string deep =
      std::string(kMaxYamlDepth + 5, '[') + std::string(kMaxYamlDepth + 5, ']');
  EXPECT_THROW(walk_yaml_value(YAML::Load(deep)), YamlWalkError);
  const std::string ok = std::string(kMaxYamlDepth - 1, '[') + std::string(kMaxYamlDepth - 1, ']');
  EXPECT_NO_THROW(walk_yaml_value(YAML::Load(ok)));
}

TEST(YamlWalk, DocumentRefusalIsAnInputErrorAtTheNodesPlace) {
  try {
    check_yaml_document(YAML::Load("name: x\ndescription: &a [*a]\n"), "f.yaml");
    ADD_FAILURE() << "no refusal";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().file, "f.yaml");
    EXPECT_EQ(e.where().line, 2) << e.what();
  }
}

}  // namespace
}  // namespace orthomech::detail
