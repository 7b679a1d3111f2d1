// libFuzzer target (issue 17, "nothing lost"): arbitrary bytes as a mechanism file; when it
// reads, every design coordinate is moved (by amounts taken from the input's own bytes) and the
// poses are written back into the text as `assemble --write` does. The writer must either refuse
// with an InputError or return a text that the reader reads back with the moved coordinates
// (to 1e-9 relative: the file's units are converted once each way). A spatial body's moved
// quaternion is renormalised first (the writer writes a unit quaternion, the reader reads one),
// and poses are compared by their difference on the configuration space (difference_positions:
// e and −e are one orientation).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "orthomech/error.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/io/mechanism_writer.hpp"
#include "orthomech/model/free_system.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace orthomech;
  if (size > 100000) return 0;
  const std::string text(reinterpret_cast<const char*>(data), size);
  Model model;
  try {
    model = parse_mechanism(text, "fuzz.yaml");
  } catch (const InputError&) {
    return 0;
  }
  VecX q = model.design_q();
  for (Eigen::Index k = 0; k < q.size(); ++k)
    q(k) += 1e-3 * static_cast<double>(data[static_cast<size_t>(k) % size] % 17);
  normalize_coordinates(model, q);
  std::string written;
  try {
    written = replace_design_poses(text, "fuzz.yaml", model, q);
  } catch (const InputError&) {
    return 0;  // refused, with a reason: nothing would be written
  }
  const Model back = parse_mechanism(written, "fuzz.yaml");  // must read: else uncaught, a finding
  const VecX qb = back.design_q();
  if (qb.size() != q.size() || back.n != model.n) std::abort();
  VecX du(model.n);
  difference_positions(model, qb, q, du);
  const double scale = std::max(1.0, q.cwiseAbs().maxCoeff());
  for (Eigen::Index k = 0; k < du.size(); ++k)
    if (!(std::abs(du(k)) <= 1e-9 * scale)) std::abort();
  return 0;
}
