// RunMonitor (orthomech/run_control.hpp): the bounds of a run, each met exactly where it should
// be — the work budget at its last unit, the interrupt flag at the next tick, the time limit once
// the wall clock passes it — and the progress callback's schedule.
#include "orthomech/run_control.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <string>
#include <thread>
#include <vector>

namespace orthomech {
namespace {

TEST(RunMonitor, WorkBudgetIsMetAtItsLastUnit) {
  const RunControl control;
  RunMonitor m(control, 5);
  for (int k = 1; k < 5; ++k) EXPECT_EQ(m.tick(0.1 * k), StopReason::none) << k;
  EXPECT_EQ(m.tick(0.5), StopReason::work_budget);
  EXPECT_EQ(m.units(), 5);
  const std::string why = m.stop_message(StopReason::work_budget, 0.5, "step", "--max-steps");
  EXPECT_NE(why.find("stopped at 50 % of the run"), std::string::npos) << why;
  EXPECT_NE(why.find("the budget of 5 steps is spent (--max-steps)"), std::string::npos) << why;
  // No budget (0): never met.
  RunMonitor unbounded(control, 0);
  for (int k = 0; k < 1000; ++k) ASSERT_EQ(unbounded.tick(0.0), StopReason::none);
}

TEST(RunMonitor, InterruptIsSeenAtTheNextTick) {
  std::atomic<bool> flag{false};
  RunControl control;
  control.interrupt = &flag;
  RunMonitor m(control, 100);
  EXPECT_EQ(m.tick(0.0), StopReason::none);
  flag.store(true);
  EXPECT_EQ(m.tick(0.0), StopReason::interrupted);
  EXPECT_NE(m.stop_message(StopReason::interrupted, 0.0, "step", "").find("interrupted"),
            std::string::npos);
}

TEST(RunMonitor, TimeLimitIsMetOnceTheClockPassesIt) {
  RunControl control;
  control.time_limit = 0.05;
  RunMonitor m(control, 0);
  EXPECT_EQ(m.tick(0.0), StopReason::none);  // at once: within the limit
  std::this_thread::sleep_for(std::chrono::milliseconds(80));
  EXPECT_GE(m.elapsed(), 0.05);
  EXPECT_EQ(m.tick(0.0), StopReason::time_limit);
}

TEST(RunMonitor, ProgressStartsAfterItsDelayAndRepeatsAtItsInterval) {
  std::vector<double> calls;
  RunControl control;
  control.progress = [&](double f) { calls.push_back(f); };
  control.progress_after = 0.03;
  control.progress_every = 0.03;
  RunMonitor m(control, 0);
  (void)m.tick(0.1);
  EXPECT_TRUE(calls.empty());  // before progress_after
  std::this_thread::sleep_for(std::chrono::milliseconds(40));
  (void)m.tick(0.2);
  ASSERT_EQ(calls.size(), 1u);
  EXPECT_DOUBLE_EQ(calls[0], 0.2);
  (void)m.tick(0.3);  // within progress_every of the last call: none
  EXPECT_EQ(calls.size(), 1u);
  std::this_thread::sleep_for(std::chrono::milliseconds(40));
  (void)m.tick(1.7);  // clamped to [0, 1]
  ASSERT_EQ(calls.size(), 2u);
  EXPECT_DOUBLE_EQ(calls[1], 1.0);
}

}  // namespace
}  // namespace orthomech
