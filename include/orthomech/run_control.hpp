#pragma once
// What bounds a long run, and what it reports while it goes (docs/cli.md "Limits and budgets"):
// a budget of work units (steps of a motion, positions of a cycle, variants of a study), a
// wall-clock limit, an interrupt flag that a signal handler may set, and a progress callback.
// A run that meets a bound stops at a consistent point with what it computed so far and says
// which bound (StopReason): a result, not an exception (house style, "Errors").
#include <atomic>
#include <chrono>
#include <functional>
#include <string>

namespace orthomech {

struct RunControl {
  double time_limit = 0.0;                       // s of wall clock; 0: none
  const std::atomic<bool>* interrupt = nullptr;  // when set: stop at the next unit of work
  // Called with the done fraction in [0, 1] once the run has taken progress_after seconds, then
  // at most every progress_every seconds (the CLI prints it on a terminal's stderr).
  std::function<void(double fraction)> progress;
  double progress_after = 2.0;  // s before the first progress call
  double progress_every = 0.5;  // s between progress calls
};

enum class StopReason { none, work_budget, time_limit, interrupted };
// "", "step budget", … : the reason in words ("the step budget of 10000000 steps is spent").
[[nodiscard]] const char* to_string(StopReason r);

// Watches one run against its RunControl and its budget of `max_units` work units. tick() is
// cheap (a counter, one clock read, no allocation): it may be called once per step.
class RunMonitor {
 public:
  RunMonitor(const RunControl& control, long max_units);
  // One unit of work done, at `fraction` of the run. Returns the bound met (none: go on).
  [[nodiscard]] StopReason tick(double fraction);
  [[nodiscard]] long units() const { return units_; }
  [[nodiscard]] long max_units() const { return max_units_; }
  [[nodiscard]] double elapsed() const;  // s since construction
  // A sentence for the run's message: "stopped at 37 % of the run: the step budget of 10000000
  // steps is spent (--max-steps)". `unit` names one unit ("step"), `option` the budget's option.
  [[nodiscard]] std::string stop_message(StopReason r, double fraction, const char* unit,
                                         const char* budget_option) const;

 private:
  const RunControl& control_;
  long max_units_;
  long units_ = 0;
  std::chrono::steady_clock::time_point start_;
  double next_progress_;
};

}  // namespace orthomech
