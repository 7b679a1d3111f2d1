#pragma once
// The text of a bundled mechanism file (mechanisms/NAME.yaml of the source tree), read once: the
// mechanism the `--set` and study fuzz targets change.
#include <fstream>
#include <sstream>
#include <string>

namespace orthomech::fuzz {

inline const std::string& crank_rocker_text() {
  static const std::string text = [] {
    std::ifstream in(std::string(ORTHOMECH_SOURCE_DIR) + "/mechanisms/crank-rocker.yaml");
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
  }();
  return text;
}

}  // namespace orthomech::fuzz
