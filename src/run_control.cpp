#include "orthomech/run_control.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

namespace orthomech {

const char* to_string(StopReason r) {
  switch (r) {
    case StopReason::none:
      return "none";
    case StopReason::work_budget:
      return "budget";
    case StopReason::time_limit:
      return "time_limit";
    case StopReason::interrupted:
      return "interrupted";
  }
  return "?";
}

RunMonitor::RunMonitor(const RunControl& control, long max_units)
    : control_(control),
      max_units_(max_units),
      start_(std::chrono::steady_clock::now()),
      next_progress_(control.progress_after) {}

double RunMonitor::elapsed() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

StopReason RunMonitor::tick(double fraction) {
  ++units_;
  if (control_.interrupt && control_.interrupt->load(std::memory_order_relaxed))
    return StopReason::interrupted;
  if (max_units_ > 0 && units_ >= max_units_) return StopReason::work_budget;
  if (!control_.progress && !(control_.time_limit > 0.0)) return StopReason::none;
  const double t = elapsed();
  if (control_.time_limit > 0.0 && t >= control_.time_limit) return StopReason::time_limit;
  if (control_.progress && t >= next_progress_) {
    next_progress_ = t + control_.progress_every;
    control_.progress(std::isfinite(fraction) ? std::min(1.0, std::max(0.0, fraction)) : 0.0);
  }
  return StopReason::none;
}

std::string RunMonitor::stop_message(StopReason r, double fraction, const char* unit,
                                     const char* budget_option) const {
  char where[64];
  std::snprintf(where, sizeof where, "stopped at %.0f %% of the run after %.3g s: ",
                100.0 * std::min(1.0, std::max(0.0, fraction)), elapsed());
  std::string m(where);
  switch (r) {
    case StopReason::none:
      return "";
    case StopReason::work_budget:
      return m + "the budget of " + std::to_string(max_units_) + " " + unit + "s is spent (" +
             budget_option + ")";
    case StopReason::time_limit: {
      char limit[48];
      std::snprintf(limit, sizeof limit, "%g", control_.time_limit);
      return m + "the time limit of " + limit + " s is reached (--time-limit)";
    }
    case StopReason::interrupted:
      return m + "interrupted (SIGINT or SIGTERM)";
  }
  return m;
}

}  // namespace orthomech
