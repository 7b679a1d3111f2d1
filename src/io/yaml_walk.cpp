#include "yaml_walk.hpp"

#include <vector>

namespace orthomech::detail {

namespace {

class Walk {
 public:
  explicit Walk(const std::function<void(const YAML::Node&)>& visit) : visit_(visit) {}

  void node(const YAML::Node& n) {
    // 1. Bounded expansion: every node counts, an alias's target as often as it is used.
    if (++count_ > kMaxYamlNodes)
      throw YamlWalkError(n, "the value expands to more than " + std::to_string(kMaxYamlNodes) +
                                 " nodes through its aliases");
    if (visit_) visit_(n);
    if (!n.IsMap() && !n.IsSequence()) return;
    // 2. A cycle: the node is one of the nodes that hold it (the path from the root).
    for (const YAML::Node& above : path_)
      if (above.is(n)) throw YamlWalkError(n, "the value holds itself through an alias (a cycle)");
    if (path_.size() >= kMaxYamlDepth)
      throw YamlWalkError(
          n, "the value is nested deeper than " + std::to_string(kMaxYamlDepth) + " levels");
    // 3. The nodes it holds, one level down.
    path_.push_back(n);
    if (n.IsSequence()) {
      for (const auto& item : n) node(item);
    } else {
      for (const auto& kv : n) {
        node(kv.first);
        node(kv.second);
      }
    }
    path_.pop_back();
  }

 private:
  const std::function<void(const YAML::Node&)>& visit_;
  std::vector<YAML::Node> path_;
  std::size_t count_ = 0;
};

}  // namespace

void walk_yaml_value(const YAML::Node& value, const std::function<void(const YAML::Node&)>& visit) {
  Walk(visit).node(value);
}

}  // namespace orthomech::detail
