// libFuzzer target (issue 17): arbitrary bytes as a mechanism file. The reader must either build
// a Model or throw InputError, nothing else (no crash, no other exception, no sanitizer report);
// a model it builds is then taken through what `info` does (the design position projected onto
// the constraints, the mobility analysis) and one velocity projection (the dual form's α, β),
// whose results must be finite when the projection succeeds.
// Build and run: scripts/fuzz (docs/architecture.md, "Reliability").
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "orthomech/analysis/mobility.hpp"
#include "orthomech/analysis/positions.hpp"
#include "orthomech/error.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/projection/dual.hpp"
#include "orthomech/projection/workspace.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace orthomech;
  if (size > 100000) return 0;  // a mechanism file is small; the limit keeps each run fast
  const std::string text(reinterpret_cast<const char*>(data), size);
  Model model;
  try {
    model = parse_mechanism(text, "fuzz.yaml");
  } catch (const InputError&) {
    return 0;  // the documented outcome for a bad file
  }
  // Anything else escaping the reader is a finding: libFuzzer reports the uncaught exception.
  if (model.n > 300) return 0;  // big models are valid but slow; the fuzzer wants speed
  VecX q = model.design_q();
  const SolveResult assembly = project_positions(model, q);
  if (assembly.status != SolveStatus::converged) q = model.design_q();
  const Mobility mob = compute_mobility(model, q);
  if (mob.rank < 0 || mob.rank > model.nc || mob.dof < 0) std::abort();
  State state(model);
  state.q = q;
  state.u = VecX::Ones(model.n);
  Workspace ws(model, mob.rank);
  if (compute_dual(model, state, ws) == ProjectionStatus::ok) {
    if (!ws.dual.alpha.allFinite() || !ws.dual.beta.allFinite()) std::abort();
  }
  return 0;
}
