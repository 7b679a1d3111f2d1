#pragma once
// Private (src/): a RunMonitor over a run made of several loops (orthomech/run_control.hpp). It
// keeps the first bound met, so that every later tick says stop and each loop ends at its next
// unit of work, and the fraction of the run it was met at, for the stop message. Used by
// `assemble` (over Ipopt's iterations) and `validate` (over its multi-starts and traces).
#include <string>

#include "orthomech/run_control.hpp"

namespace orthomech {

class RunWatch {
 public:
  explicit RunWatch(const RunControl& control) : monitor_(control, 0) {}
  RunWatch(const RunWatch&) = delete;
  RunWatch& operator=(const RunWatch&) = delete;
  // The fraction of the run the next ticks are at (loops that do not know it themselves).
  void set_fraction(double fraction) { fraction_ = fraction; }
  // One unit of work done: false once a bound is met (then and at every later call).
  bool go_on() {
    if (stop_ == StopReason::none) stop_ = monitor_.tick(fraction_);
    return stop_ == StopReason::none;
  }
  bool go_on(double fraction) {
    set_fraction(fraction);
    return go_on();
  }
  [[nodiscard]] bool stopped() const { return stop_ != StopReason::none; }
  [[nodiscard]] StopReason stop() const { return stop_; }
  // "stopped at 37 % of the run after 1.2 s: the time limit of 1 s is reached (--time-limit)".
  [[nodiscard]] std::string message() const {
    return monitor_.stop_message(stop_, fraction_, "unit", "");
  }

 private:
  RunMonitor monitor_;
  double fraction_ = 0.0;
  StopReason stop_ = StopReason::none;
};

}  // namespace orthomech
