// The assertion facility (orthomech/check.hpp): each kind of check fires through its channel —
// the always-on check aborts naming file:line and the condition, the debug check does so without
// NDEBUG and compiles out (condition not evaluated) with it, and the argument check throws
// std::invalid_argument naming the function and the argument; the public entry points that use
// it (assemble, compute_driven, build_scene, Model::constraint_row_name) do so.
#include "orthomech/check.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "orthomech/analysis/assembly.hpp"
#include "orthomech/analysis/cycle.hpp"
#include "orthomech/analysis/mobility.hpp"
#include "orthomech/io/render.hpp"
#include "orthomech/projection/workspace.hpp"
#include "support/fixtures.hpp"

namespace orthomech {
namespace {

// The message of the std::invalid_argument `f` throws ("" if none).
template <class F>
std::string invalid_argument_message(F f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(CheckDeathTest, AlwaysOnCheckAbortsWithFileLineAndCondition) {
  const int rows = 3;
  EXPECT_DEATH(ORTHOMECH_CHECK(rows == 4, "rows of a revolute"),
               "check_test\\.cpp:[0-9]+: check failed: rows == 4 \\(rows of a revolute\\)");
}

TEST(CheckDeathTest, AlwaysOnCheckPassesSilently) {
  int evaluated = 0;
  ORTHOMECH_CHECK(++evaluated == 1, "evaluated once");
  EXPECT_EQ(evaluated, 1);
}

TEST(CheckDeathTest, DebugCheckFiresOnlyWithoutNdebug) {
  int evaluated = 0;
#ifdef NDEBUG
  ORTHOMECH_DEBUG_CHECK(++evaluated == 0, "never evaluated under NDEBUG");
  EXPECT_EQ(evaluated, 0) << "a debug check compiles out under NDEBUG";
#else
  EXPECT_DEATH(ORTHOMECH_DEBUG_CHECK(++evaluated == 0, "debug"),
               "check_test\\.cpp:[0-9]+: check failed: \\+\\+evaluated == 0 \\(debug\\)");
#endif
}

TEST(CheckArgument, ThrowsInvalidArgumentNamingFunctionAndArgument) {
  EXPECT_NO_THROW(check_argument(true, "f", "x", "must be positive"));
  EXPECT_EQ(invalid_argument_message([] { check_argument(false, "f", "x", "must be positive"); }),
            "f: argument 'x' must be positive");
}

TEST(CheckArgument, AssembleNamesQ0) {
  const Model model = test::load_bundled("crank-rocker");
  const VecX q0 = VecX::Zero(model.nq + 1);
  EXPECT_EQ(invalid_argument_message([&] { (void)assemble(model, q0); }),
            "assemble: argument 'q0' must have model.nq coordinates");
}

TEST(CheckArgument, ComputeDrivenNamesDriverJointStateAndWorkspace) {
  const Model model = test::load_bundled("crank-rocker");
  const Model other = test::load_bundled("crank-rocker");
  State s(model);
  s.q = test::assembled_q(model);
  const int rank = compute_mobility(model, s.q).rank;
  Workspace ws(model, rank);
  Workspace ws_other(other, rank);
  DrivenWorkspace w(model, rank);
  DrivenPoint p;
  const int joint = model.drivers.at(0).joint;
  EXPECT_EQ(
      invalid_argument_message([&] { (void)compute_driven(model, -1, 1.0, 0.0, s, ws, w, p); }),
      "compute_driven: argument 'driver_joint' is not a joint of the model");
  EXPECT_EQ(invalid_argument_message(
                [&] { (void)compute_driven(model, joint, 1.0, 0.0, s, ws_other, w, p); }),
            "compute_driven: argument 'ws' was built for another Model");
  State wrong = s;
  wrong.q.resize(model.nq + 1);
  EXPECT_EQ(
      invalid_argument_message(
          [&] { (void)compute_driven(model, joint, 1.0, 0.0, wrong, ws, w, p); }),
      "compute_driven: argument 'state' must have model.nq coordinates and model.n velocities");
  EXPECT_TRUE(compute_driven(model, joint, 1.0, 0.0, s, ws, w, p)) << "the valid call succeeds";
}

TEST(CheckArgument, BuildSceneAndConstraintRowNameNameTheirArguments) {
  const Model model = test::load_bundled("crank-rocker");
  EXPECT_EQ(invalid_argument_message(
                [&] { (void)build_scene(model, VecX::Zero(model.nq + 2), RenderOptions{}); }),
            "build_scene: argument 'q' must have model.nq coordinates");
  EXPECT_EQ(invalid_argument_message([&] { (void)model.constraint_row_name(model.nc); }),
            "constraint_row_name: argument 'row' is out of range [0, nc)");
}

}  // namespace
}  // namespace orthomech
