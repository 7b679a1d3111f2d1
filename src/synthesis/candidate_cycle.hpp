#pragma once
// Step 5 of run_synthesis (synthesize.hpp): an accepted candidate's mechanism file through
// `cycle` (analysis/cycle.hpp), the one kinetostatic analysis of the tool: the drive torque and
// every joint's reaction over the motion the candidate is built for, at the task's speed with
// links of the task's mass per length. A run that does not complete is a rejection.
#include "orthomech/synthesis/synthesize.hpp"

namespace orthomech::synthesis::detail {

// The motion: a full turn of the crank from the first target when `full_turn`, else the crank
// from the first target's angle to the last's (c.crank_angles, unwrapped in order).
void check_by_cycle(SynthesisCandidate& c, bool full_turn);

}  // namespace orthomech::synthesis::detail
