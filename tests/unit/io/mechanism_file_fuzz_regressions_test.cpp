// Every reproducer the fuzz target found (tests/fuzz/regressions/, issue 17) stays fixed: read
// as a mechanism file it gives a Model or an InputError and nothing else, and a Model it gives
// goes through what the fuzz target does (the design position projected, the mobility, one dual
// projection) with finite results. The same body as tests/fuzz/fuzz_mechanism_reader.cpp, run
// in the ordinary suite (and under the sanitizers in CI's build-asan).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "orthomech/analysis/mobility.hpp"
#include "orthomech/analysis/positions.hpp"
#include "orthomech/error.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/projection/dual.hpp"
#include "orthomech/projection/workspace.hpp"
#include "support/cli_runner.hpp"

namespace orthomech {
namespace {

namespace fs = std::filesystem;

std::vector<std::string> reproducers() {
  std::vector<std::string> out;
  const fs::path dir = fs::path(ORTHOMECH_SOURCE_DIR) / "tests" / "fuzz" / "regressions";
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (e.is_regular_file() && e.path().extension() != ".md") out.push_back(e.path().string());
  std::sort(out.begin(), out.end());
  return out;
}

TEST(FuzzRegressions, EveryReproducerReadsOrFailsWithAnInputError) {
  for (const std::string& path : reproducers()) {
    SCOPED_TRACE(path);
    Model model;
    try {
      model = parse_mechanism(test::read_text(path), "reproducer.yaml");
    } catch (const InputError& e) {
      EXPECT_GT(e.where().line, 0) << e.what();  // placed
      continue;
    }
    VecX q = model.design_q();
    if (project_positions(model, q).status != SolveStatus::converged) q = model.design_q();
    const Mobility mob = compute_mobility(model, q);
    EXPECT_GE(mob.dof, 0);
    State state(model);
    state.q = q;
    state.u = VecX::Ones(model.n);
    Workspace ws(model, mob.rank);
    if (compute_dual(model, state, ws) == ProjectionStatus::ok) {
      EXPECT_TRUE(ws.dual.alpha.allFinite());
      EXPECT_TRUE(ws.dual.beta.allFinite());
    }
  }
}

}  // namespace
}  // namespace orthomech
