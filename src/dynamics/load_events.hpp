#pragma once
// Private: the loads switched by `active_while` as events of simulate's motion (issue 49,
// item 3). Between two events each switched load is held on or off (State::load_on), so the
// right-hand side is smooth and the step-size control meets its tolerance; an event is a
// change of sign of a switching value
//   s_k = sign_k · ṁ_k(q, u)      (ṁ_k: the rate of load k's `active_while` measure),
// the load acting while s_k > 0 (load_active's rule). A step across which some s_k changes
// sign is undone and the crossing located by re-integration from the bracket's lower end
// (regula falsi, Illinois variant [Dowell & Jarratt 1971, BIT 11]) until the bracket is shorter
// than the time tolerance; the step that then crosses is kept, the loads switched at its end and
// the integrator restarted there (its first-same-as-last derivative recomputed). A run's cost
// grows with its number of events, each a few re-integrations of part of one step.
//
// A load that switches back at once, again and again (a Coulomb torque written with
// active_while where the friction exceeds the other loads: the rate is held at 0, a sliding
// mode in Filippov's sense), is a chatter: after kMaxChatter events within kChatterGap of each
// other the run stops (status `sliding`): active_while cannot hold a joint stuck.
//
// This class keeps the switching values, the bracket and the count of events; it integrates
// nothing (the Simulation does, dynamics/simulate.cpp).
#include <cstdint>
#include <string>
#include <vector>

#include "orthomech/dynamics/simulate.hpp"
#include "orthomech/model/model.hpp"

namespace orthomech::detail {

// The bracket's time tolerance, relative to the run's span max(t_end, 1 s): kEventTimeTolerance
// (orthomech/dynamics/simulate.hpp).
// Regula falsi for the first kBisectAfter tries, bisection after them; a location that takes
// more than kMaxEventIterations fails (the run stops).
inline constexpr int kBisectAfter = 8;
inline constexpr int kMaxEventIterations = 100;
// Events closer to the previous one than kChatterGap (relative to the span), kMaxChatter in a
// row: a chatter.
inline constexpr double kChatterGap = 1e-7;
inline constexpr int kMaxChatter = 12;

class LoadEvents {
 public:
  // What a step's end means for the switched loads.
  enum class StepEnd {
    smooth,       // no switching value changed sign
    switch_here,  // one did, within a step no longer than the tolerance: switch at its end
    locate        // one did within a longer step: undo it and locate the crossing
  };

  LoadEvents(const Model& model, double span);

  [[nodiscard]] bool empty() const { return loads_.empty(); }
  [[nodiscard]] double tolerance() const { return tolerance_; }
  [[nodiscard]] long events() const { return events_; }

  // The modes at the start (t0, q, u): each switched load on iff s_k > 0; the others' entries
  // are 1. Sets load_on (size Model::loads) and the values at the last step end.
  void start(const Model& model, const VecX& q, const VecX& u, std::vector<std::uint8_t>& load_on);
  // After a step [t0, t1] whose corrected end is (q, u): the switching values there (kept as
  // the candidate values at the end) and what they mean.
  StepEnd step_end(const Model& model, double t0, double t1, const VecX& q, const VecX& u);
  // The step's end is kept: its values become the last step end's.
  void keep_step_end();
  // switch_here: the loads whose value changed sign switched (load_on), the event counted.
  // Returns false when the events chatter (message set).
  bool switch_at(const Model& model, double t, std::vector<std::uint8_t>& load_on,
                 std::string& message);
  // The run went back to a saved step end at (q, u): its values become the last step end's.
  void restored(const Model& model, const VecX& q, const VecX& u);

  // ---- The crossing's location (after StepEnd::locate) ----
  // The bracket [t_lo, t_hi] from the last step end and the candidate end just rejected.
  void open_bracket(double t_lo, double t_hi);
  // The next time to integrate to from the bracket's lower end: the regula falsi point, or
  // t_hi once the bracket is within the tolerance (the step there then switches).
  [[nodiscard]] double next_time() const;
  // The integration reached t = next_time() without a change of sign (the last step end's
  // values are those there): the bracket's lower end moves up. False after
  // kMaxEventIterations.
  bool reached(double t);
  // The location is given up (a change point came first, or the crossing was not found again).
  void abandon();
  [[nodiscard]] double bracket_low() const { return t_lo_; }
  [[nodiscard]] double bracket_high() const { return t_hi_; }

 private:
  struct Switched {
    int load = -1;
    int measure = -1;
    int sign = 0;
  };
  void values(const Model& model, const VecX& q, const VecX& u, std::vector<double>& s) const;
  [[nodiscard]] static bool crosses(double before, double after) {
    return (before > 0.0) != (after > 0.0);
  }
  [[nodiscard]] std::string chatter_message(const Model& model, double t) const;

  std::vector<Switched> loads_;
  double span_ = 1.0, tolerance_ = 0.0;
  std::vector<double> last_, end_;  // values at the last kept step end, at the candidate end
  // The bracket: values at its ends (the Illinois scaling applied), the side kept last.
  double t_lo_ = 0.0, t_hi_ = 0.0;
  std::vector<double> lo_, hi_;
  int kept_side_ = 0, iterations_ = 0;
  // Events: how many, the last one's time, how many in a row within kChatterGap.
  long events_ = 0;
  double t_last_event_ = -1e300;
  int in_a_row_ = 0;
};

}  // namespace orthomech::detail
