#pragma once
// One walk over a YAML value (internal to src/io and src/study): every node the value holds, its
// aliases followed, with two refusals that keep a walk bounded whatever the text is:
//  - a cycle: a node that holds itself through an alias (`&a [*a]`) — a recursive walk over it
//    would never end;
//  - an expansion beyond kMaxYamlNodes nodes, counted with every alias expanded (an "alias
//    bomb": nine aliases of nine aliases of ... expand to 9^k nodes from a few lines of text).
// The mechanism file, a `--set` value and a study file all go through it before any other walk,
// so that none of those walks can recurse without end or grow without bound
// (docs/file-format.md "Limits").
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstddef>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "orthomech/error.hpp"

namespace orthomech::detail {

// The most nodes a value may expand to (aliases expanded), and the deepest nesting. A bundled
// file of 1000 loops (n-four-bar-1000.yaml) has about 30,000 nodes.
inline constexpr std::size_t kMaxYamlNodes = 1'000'000;
inline constexpr std::size_t kMaxYamlDepth = 200;

// Why a walk stopped: the node at which it did (its Mark() is the place in the text) and a
// sentence for the message.
class YamlWalkError : public std::runtime_error {
 public:
  YamlWalkError(const YAML::Node& node, const std::string& message)
      : std::runtime_error(message), node_(node) {}
  [[nodiscard]] const YAML::Node& node() const { return node_; }

 private:
  YAML::Node node_;
};

// Calls `visit` on `value` and on every node it holds (map keys and values, sequence items), in
// document order, aliases expanded; throws YamlWalkError on a cycle, on more than kMaxYamlNodes
// nodes or on nesting deeper than kMaxYamlDepth. `visit` may be empty (a check only).
void walk_yaml_value(const YAML::Node& value,
                     const std::function<void(const YAML::Node&)>& visit = {});

// The same walk over a whole document read from `origin`: a refusal is an InputError at the
// node's line and column (element "YAML").
inline void check_yaml_document(const YAML::Node& root, const std::string& origin) {
  try {
    walk_yaml_value(root);
  } catch (const YamlWalkError& e) {
    const YAML::Mark m = e.node().Mark();
    throw InputError({origin, m.is_null() ? 1 : m.line + 1, m.is_null() ? 1 : m.column + 1}, "YAML",
                     e.what());
  }
}

// The readers of study and synthesis task files: a refusal at `node`'s place in `file` (line and
// column 1 when the node has none), and the check that a mapping holds only `allowed` keys.
[[noreturn]] inline void fail_at(const std::string& file, const YAML::Node& node,
                                 const std::string& element, const std::string& message) {
  const YAML::Mark m = node.Mark();
  throw InputError({file, m.is_null() ? 1 : m.line + 1, m.is_null() ? 1 : m.column + 1}, element,
                   message);
}
inline void expect_keys(const std::string& file, const YAML::Node& node, const std::string& element,
                        const std::vector<std::string>& allowed) {
  if (!node.IsMap()) fail_at(file, node, element, "expected a mapping");
  for (const auto& kv : node) {
    const std::string key = kv.first.Scalar();
    if (std::find(allowed.begin(), allowed.end(), key) != allowed.end()) continue;
    std::string list;
    for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
    fail_at(file, kv.first, element, "unknown key '" + key + "' (allowed: " + list + ")");
  }
}

}  // namespace orthomech::detail
