#pragma once
// Private: the events of simulate's motion (issue 49, item 3): loads switched by
// `active_while` and joints meeting their end stops. Each has a switching value
//   load k:  s_k = sign_k · ṁ_k(q, u)   (ṁ_k: the rate of its `active_while` measure); the load
//            acts while s_k > 0 (load_active's rule);
//   stop:    g = x − x_min (lower) or x_max − x (upper), x the joint's coordinate at its limits;
//            the motion is inside while g > 0.
// Between two events each switched load is held on or off (State::load_on), so the right-hand
// side is smooth and the step-size control meets its tolerance. An event is a change of sign of
// a load's value, or a stop's value reaching 0 from above. A step across which one happens is
// undone and the crossing located by re-integration from the bracket's lower end (regula falsi,
// Illinois variant [Dowell & Jarratt 1971, BIT 11], bisection after kBisectAfter tries) until the
// bracket is shorter than the time tolerance; the step that then crosses is kept, the event
// applied at its end (the loads switched; at a stop, the impact: the Simulation's velocity jump)
// and the integrator restarted there (its first-same-as-last derivative recomputed). A run's cost
// grows with its number of events, each a few re-integrations of part of one step.
//
// Events that come back at once, again and again, are a chatter: a load that switches back (a
// Coulomb torque written with active_while where the friction exceeds the other loads: the rate
// is held at 0, a sliding mode in Filippov's sense), or impacts at ever shorter intervals (a
// joint coming to rest against its stop). After kMaxChatter events within kChatterGap of each
// other the run stops (status `sliding` or `resting`): neither is a motion these events can
// continue.
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
// How far past a stop just released the joint may go back before it meets the stop again
// (m or rad): far below any tolerance of the positions, far above the distance's rounding.
inline constexpr double kReleaseMargin = 1e-9;

// An end stop met at an event: the joint, and +1 at its lower limit (the coordinate must grow
// away from it) or −1 at its upper one; `release`: a stop held as a resting contact whose
// contact force reached zero (the joint leaves it) rather than an impact.
struct StopHit {
  int joint = -1;
  int side = 0;
  bool release = false;
  // A friction pin held stuck (its index among the model's friction pins; side +1): its joint's
  // relative angle held like a stop's coordinate, while the moment that takes stays inside the
  // static bound μ r |F|.
  int pin = -1;
};

class Events {
 public:
  // What a step's end means for the events.
  enum class StepEnd {
    smooth,       // nothing crossed
    switch_here,  // something did, within a step no longer than the tolerance: apply it at its end
    locate        // something did within a longer step: undo it and locate the crossing
  };
  // How a chatter ended the run (Events::switch_at).
  enum class Chatter { none, loads, stop, sticks };

  Events(const Model& model, double span);

  [[nodiscard]] bool empty() const { return values_.empty(); }
  [[nodiscard]] double tolerance() const { return tolerance_; }

  // The modes at the start (t0, q, u): each switched load on iff s_k > 0; the others' entries
  // are 1 (load_on is left empty when no load is switched). The values there become the last
  // step end's.
  void start(const Model& model, const VecX& q, const VecX& u, std::vector<std::uint8_t>& load_on);
  // After a step [t0, t1] whose corrected end is (q, u): the switching values there (kept as
  // the candidate values at the end) and what they mean.
  StepEnd step_end(const Model& model, double t0, double t1, const VecX& q, const VecX& u);
  // The step's end is kept without an event: its values become the last step end's.
  void keep_step_end();
  // switch_here: the loads whose value changed sign switched (load_on), the stops met listed in
  // hits (the Simulation applies their impacts), the event counted. Returns Chatter::none, or
  // what chattered (message set): the run stops.
  Chatter switch_at(const Model& model, double t, std::vector<std::uint8_t>& load_on,
                    std::vector<StopHit>& hits, std::string& message);
  // The run went back to a saved step end at (q, u): its values become the last step end's.
  void restored(const Model& model, const VecX& q, const VecX& u);

  // ---- Resting contacts (a stop held as a constraint) ----
  // While a stop is held its switching value is its contact force (the Simulation computes it,
  // set_contact_forces), not its distance: the stop is released when the force reaches zero
  // from above (switch_at lists it with `release`).
  // The stop that chattered (the last one hit in the run of events that ended in Chatter::stop).
  [[nodiscard]] StopHit resting_stop() const { return resting_; }
  // The pin that chattered (the last one reversed in the run of events that ended in
  // Chatter::sticks), as a hold: {joint, +1, false, pin}. A held pin's switching value is the
  // margin of its static friction, μ r |F| − |μ| (the Simulation computes it), and it is
  // released (switch_at lists it with `release`) when that reaches zero.
  [[nodiscard]] StopHit sticking_pin() const { return sticking_; }
  // Holds `stop` from here, its contact force `contact` (> 0); the chatter count starts again.
  void hold(const StopHit& stop, double contact);
  [[nodiscard]] bool holding() const { return !held_.empty(); }
  [[nodiscard]] const std::vector<StopHit>& held() const { return held_; }
  // The held stops as they were at a saved step end (restore).
  void set_held(const std::vector<StopHit>& held);
  // The held stops' contact forces (in held() order) at the state about to be evaluated.
  void set_contact_forces(const std::vector<double>& contact);
  // The friction pins' signs (analysis/friction.hpp's pins, in order): the sign of each one's
  // relative rate, held between the events where it changes (the friction moment opposes it).
  [[nodiscard]] const std::vector<double>& pin_signs() const { return pin_sign_; }
  void set_pin_signs(const std::vector<double>& signs) { pin_sign_ = signs; }
  // Each switched load on iff its last value is > 0 (the loads' modes after a resting contact
  // begins: a rate held at exactly 0 switches its load off, load_active's rule).
  void modes_from_values(std::vector<std::uint8_t>& load_on) const;

  // ---- The crossing's location (after StepEnd::locate) ----
  // The bracket [t_lo, t_hi] from the last step end and the candidate end just rejected.
  void open_bracket(double t_lo, double t_hi);
  // The next time to integrate to from the bracket's lower end: the regula falsi point, or
  // t_hi once the bracket is within the tolerance (the step there then switches).
  [[nodiscard]] double next_time() const;
  // The integration reached t = next_time() without a crossing (the last step end's values are
  // those there): the bracket's lower end moves up. False after kMaxEventIterations.
  bool reached(double t);
  // The location is given up (a change point came first, or the crossing was not found again).
  void abandon();
  [[nodiscard]] double bracket_low() const { return t_lo_; }
  [[nodiscard]] double bracket_high() const { return t_hi_; }

 private:
  // One switching value: a switched load (load ≥ 0) or an end stop (joint ≥ 0).
  struct Value {
    int load = -1, measure = -1;  // load: its index and its active_while measure
    int joint = -1;               // stop: the joint
    int sign = 0;                 // load: active_while's sign; stop: +1 lower, −1 upper
    double limit = 0.0;           // stop: the limit
    bool held = false;            // stop: held as a resting contact (value: its contact force)
    // stop: after a release, the value is the distance plus kReleaseMargin until the distance
    // exceeds twice it (the joint leaves the stop with zero speed and acceleration: within the
    // margin the distance's rounding would meet the stop again and again).
    double shift = 0.0;
    int pin = -1;  // friction pin: its index; the value is its relative rate
    int u_first = -1, u_second = -1;
  };
  [[nodiscard]] size_t stop_index(const StopHit& stop) const;
  void evaluate(const Model& model, const VecX& q, const VecX& u, std::vector<double>& s) const;
  // Whether value i crosses between a and b: a load's changes sign, a stop's reaches 0 from
  // above (leaving a stop is no event).
  [[nodiscard]] bool crosses(size_t i, double a, double b) const;
  [[nodiscard]] std::string chatter_message(const Model& model, double t, Chatter what) const;

  std::vector<Value> values_;
  bool loads_switched_ = false;  // some value is a load's
  double span_ = 1.0, tolerance_ = 0.0;
  std::vector<double> last_, end_;  // values at the last kept step end, at the candidate end
  // The bracket: values at its ends (the Illinois scaling applied), the side kept last.
  double t_lo_ = 0.0, t_hi_ = 0.0;
  std::vector<double> lo_, hi_;
  int kept_side_ = 0, iterations_ = 0;
  // Events: the last one's time, how many in a row within kChatterGap, whether a stop was hit
  // in that run (then a chatter is the stop's: resting_).
  double t_last_event_ = -1e300;
  int in_a_row_ = 0;
  bool stop_in_run_ = false, pin_in_run_ = false;
  std::vector<double> pin_sign_;
  StopHit resting_, sticking_;
  std::vector<StopHit> held_;
  std::vector<double> contact_;  // per value: a held stop's contact force
};

}  // namespace orthomech::detail
