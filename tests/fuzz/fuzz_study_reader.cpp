// libFuzzer target (issue 47): arbitrary bytes as a study file (`sweep --study`) of the bundled
// crank-rocker. The study reader must return a Study or throw InputError, nothing else (no
// crash on cyclic aliases or overflowing laws, no other exception); a Study it returns has a
// variant count within its limit and finite parameter values. Run with scripts/fuzz.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "bundled_text.hpp"
#include "orthomech/error.hpp"
#include "orthomech/study/study.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace orthomech;
  if (size > 20000) return 0;
  const std::string text(reinterpret_cast<const char*>(data), size);
  Study study;
  try {
    study =
        parse_study(text, "study.yaml", orthomech::fuzz::crank_rocker_text(), "crank-rocker.yaml");
  } catch (const InputError&) {
    return 0;
  }
  const long n = variant_count(study);
  if (n < 1 || n > 1'000'000'000) std::abort();
  for (long index : {0L, n - 1})
    for (double v : variant_values(study, index))
      if (!std::isfinite(v)) std::abort();
  return 0;
}
