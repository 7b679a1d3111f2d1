#pragma once
// The command line's side of a bounded run (orthomech/run_control.hpp): the progress line on a
// terminal's stderr, and SIGINT/SIGTERM turned into a clean stop (docs/cli.md "Limits and
// budgets").
#include <string>

#include "orthomech/run_control.hpp"

namespace orthomech::cli {

// While alive, SIGINT and SIGTERM set the interrupt flag of control() instead of killing the
// process: the run stops at its next unit of work and writes what it computed, marked
// incomplete. A second signal ends the process at once (the default action). The previous
// handlers are restored on destruction.
class InterruptScope {
 public:
  InterruptScope();
  ~InterruptScope();
  InterruptScope(const InterruptScope&) = delete;
  InterruptScope& operator=(const InterruptScope&) = delete;
  // Whether a signal arrived, and which (0: none).
  [[nodiscard]] static int signal_received();
};

// A RunControl for `command` with the interrupt flag, a wall-clock limit (0: none) and, when
// stderr is a terminal and the log level shows warnings (no -q), a progress line
// "simulate: 37 %" on stderr, rewritten in place (ORTHOMECH_PROGRESS=1 forces it, for tests
// and logs; it then ends each update with a newline). end_progress() clears it.
[[nodiscard]] RunControl run_control(const std::string& command, double time_limit);
void end_progress();

// run() (a library call whose RunControl came from run_control) with SIGINT/SIGTERM turned into a
// clean stop while it runs (InterruptScope) and the progress line cleared after it; its result.
template <class Run>
[[nodiscard]] auto run_bounded(Run&& run) {
  const InterruptScope interrupts;
  auto result = run();
  end_progress();
  return result;
}

}  // namespace orthomech::cli
