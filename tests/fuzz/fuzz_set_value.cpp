// libFuzzer target (issue 47): arbitrary bytes as one `--set PATH=VALUE` (the text up to the
// first '=' is the path, the rest the value) applied to the bundled crank-rocker, and as a whole
// `--set` value of its description and of a body's mass. The reader must build a Model or throw
// InputError, nothing else: no crash on a cyclic alias (`&a [*a]`), no unbounded growth on an
// alias bomb (yaml_walk.hpp), no other exception. Run with scripts/fuzz.
#include <cstddef>
#include <cstdint>
#include <string>

#include "bundled_text.hpp"
#include "orthomech/error.hpp"
#include "orthomech/io/mechanism_file.hpp"

namespace {

void read_with(const std::string& path, const std::string& value) {
  try {
    (void)orthomech::parse_mechanism(orthomech::fuzz::crank_rocker_text(), "crank-rocker.yaml",
                                     {{path, value}});
  } catch (const orthomech::InputError&) {
    // the documented outcome of a bad change
  }
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size > 20000) return 0;
  const std::string text(reinterpret_cast<const char*>(data), size);
  const auto eq = text.find('=');
  if (eq != std::string::npos && eq > 0) read_with(text.substr(0, eq), text.substr(eq + 1));
  read_with("description", text);
  read_with("bodies.crank.mass", text);
  return 0;
}
