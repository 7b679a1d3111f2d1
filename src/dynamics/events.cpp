#include "events.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>

#include "orthomech/analysis/cycle_metrics.hpp"
#include "orthomech/analysis/friction.hpp"
#include "orthomech/model/measures.hpp"

namespace orthomech::detail {

Events::Events(const Model& model, double span)
    : span_(std::max(span, 1.0)), tolerance_(kEventTimeTolerance * std::max(span, 1.0)) {
  for (size_t k = 0; k < model.loads.size(); ++k) {
    const ActiveWhile& aw = model.loads[k].active_while;
    if (aw.measure >= 0) values_.push_back({static_cast<int>(k), aw.measure, -1, aw.sign, 0.0});
  }
  loads_switched_ = !values_.empty();
  for (size_t j = 0; j < model.joints.size(); ++j) {
    const Joint& joint = model.joints[j];
    if (!joint.stop_restitution || !joint.limits) continue;
    values_.push_back({-1, -1, static_cast<int>(j), 1, joint.limits->x()});
    values_.push_back({-1, -1, static_cast<int>(j), -1, joint.limits->y()});
  }
  const std::vector<FrictionPin> pins = friction_pins(model);
  for (size_t k = 0; k < pins.size(); ++k) {
    Value w;
    w.pin = static_cast<int>(k);
    w.joint = pins[k].joint;
    w.u_first = pins[k].u_first;
    w.u_second = pins[k].u_second;
    values_.push_back(w);
  }
  pin_sign_.assign(pins.size(), 0.0);
  last_.assign(values_.size(), 0.0);
  end_ = lo_ = hi_ = contact_ = last_;
}

namespace {
double sign_of(double x) { return x > 0.0 ? 1.0 : x < 0.0 ? -1.0 : 0.0; }
}  // namespace

size_t Events::stop_index(const StopHit& stop) const {
  if (stop.pin >= 0) {
    for (size_t i = 0; i < values_.size(); ++i)
      if (values_[i].pin == stop.pin) return i;
    throw std::logic_error("Events: no friction pin " + std::to_string(stop.pin));
  }
  for (size_t i = 0; i < values_.size(); ++i)
    if (values_[i].joint == stop.joint && values_[i].sign == stop.side) return i;
  throw std::logic_error("Events: joint " + std::to_string(stop.joint) + " has no such end stop");
}

void Events::hold(const StopHit& stop, double contact) {
  const size_t i = stop_index(stop);
  values_[i].held = true;
  values_[i].shift = 0.0;
  contact_[i] = contact;
  last_[i] = contact;
  held_.push_back({stop.joint, stop.side, false, stop.pin});
  if (stop.pin >= 0) pin_sign_[static_cast<size_t>(stop.pin)] = 0.0;  // stuck: no kinetic friction
  in_a_row_ = 0;
  stop_in_run_ = false;
}

void Events::set_held(const std::vector<StopHit>& held) {
  for (Value& w : values_) w.held = false;
  held_.clear();
  for (const StopHit& h : held) {
    values_[stop_index(h)].held = true;
    held_.push_back({h.joint, h.side, false, h.pin});
  }
}

void Events::set_contact_forces(const std::vector<double>& contact) {
  for (size_t k = 0; k < held_.size() && k < contact.size(); ++k)
    contact_[stop_index(held_[k])] = contact[k];
}

void Events::modes_from_values(std::vector<std::uint8_t>& load_on) const {
  for (size_t i = 0; i < values_.size(); ++i)
    if (values_[i].load >= 0)
      load_on[static_cast<size_t>(values_[i].load)] = last_[i] > 0.0 ? 1 : 0;
}

void Events::evaluate(const Model& model, const VecX& q, const VecX& u,
                      std::vector<double>& s) const {
  for (size_t i = 0; i < values_.size(); ++i) {
    const Value& w = values_[i];
    if (w.load >= 0) {
      const Measure& m = model.measures[static_cast<size_t>(w.measure)];
      s[i] = w.sign * compute_scalar(model, m.kind, q, &u).rate;
    } else if (w.pin >= 0 && !w.held) {
      s[i] = (w.u_second < 0 ? 0.0 : u(w.u_second)) - (w.u_first < 0 ? 0.0 : u(w.u_first));
    } else if (w.held) {
      s[i] = contact_[i];
    } else {
      s[i] = w.sign * (limit_coordinate(model, w.joint, q) - w.limit) + w.shift;
    }
  }
}

bool Events::crosses(size_t i, double a, double b) const {
  if (values_[i].load >= 0) return (a > 0.0) != (b > 0.0);
  if (values_[i].pin >= 0 && !values_[i].held) return sign_of(a) != sign_of(b);
  return a > 0.0 && !(b > 0.0);
}

void Events::start(const Model& model, const VecX& q, const VecX& u,
                   std::vector<std::uint8_t>& load_on) {
  if (values_.empty()) return;
  evaluate(model, q, u, last_);
  for (size_t i = 0; i < values_.size(); ++i)
    if (values_[i].pin >= 0) pin_sign_[static_cast<size_t>(values_[i].pin)] = sign_of(last_[i]);
  if (!loads_switched_) return;
  load_on.assign(model.loads.size(), 1);
  for (size_t i = 0; i < values_.size(); ++i)
    if (values_[i].load >= 0)
      load_on[static_cast<size_t>(values_[i].load)] = last_[i] > 0.0 ? 1 : 0;
}

Events::StepEnd Events::step_end(const Model& model, double t0, double t1, const VecX& q,
                                 const VecX& u) {
  if (values_.empty()) return StepEnd::smooth;
  evaluate(model, q, u, end_);
  bool crossed = false;
  for (size_t i = 0; i < values_.size(); ++i) crossed = crossed || crosses(i, last_[i], end_[i]);
  if (!crossed) return StepEnd::smooth;
  return t1 - t0 <= tolerance_ ? StepEnd::switch_here : StepEnd::locate;
}

void Events::keep_step_end() {
  last_ = end_;
  for (size_t i = 0; i < values_.size(); ++i) {  // a released stop out of its margin: armed
    Value& w = values_[i];
    if (w.shift > 0.0 && last_[i] > 2.0 * w.shift) {
      last_[i] -= w.shift;
      w.shift = 0.0;
    }
  }
}

void Events::restored(const Model& model, const VecX& q, const VecX& u) {
  if (!values_.empty()) evaluate(model, q, u, last_);
}

Events::Chatter Events::switch_at(const Model& model, double t, std::vector<std::uint8_t>& load_on,
                                  std::vector<StopHit>& hits, std::string& message) {
  hits.clear();
  bool pin_switched = false;
  for (size_t i = 0; i < values_.size(); ++i) {
    if (!crosses(i, last_[i], end_[i])) continue;
    const Value& w = values_[i];
    if (w.load >= 0) {
      load_on[static_cast<size_t>(w.load)] = end_[i] > 0.0 ? 1 : 0;
    } else if (w.pin >= 0 && w.held) {
      // Its static friction no longer holds it: it slips (the Simulation sets its sign).
      hits.push_back({w.joint, 1, true, w.pin});
      values_[i].held = false;
      std::erase_if(held_, [&](const StopHit& h) { return h.pin == w.pin; });
      end_[i] = 0.0;
    } else if (w.pin >= 0) {
      pin_sign_[static_cast<size_t>(w.pin)] = sign_of(end_[i]);
      pin_switched = true;
      sticking_ = {w.joint, 1, false, w.pin};
    } else if (w.held) {
      // The contact force reached zero: the joint leaves the stop, just outside it.
      hits.push_back({w.joint, w.sign, true});
      values_[i].held = false;
      values_[i].shift = kReleaseMargin;
      std::erase_if(held_, [&](const StopHit& h) {
        return h.pin < 0 && h.joint == w.joint && h.side == w.sign;
      });
      end_[i] = kReleaseMargin;
    } else {
      hits.push_back({w.joint, w.sign, false});
      resting_ = {w.joint, w.sign, false};
      // At the stop (to the tolerance's penetration): counted as outside, so that a motion that
      // goes on into the stop after the impact (e = 0, pushed) meets it again.
      end_[i] = std::numeric_limits<double>::min();
    }
  }
  last_ = end_;
  const bool impact =
      std::any_of(hits.begin(), hits.end(), [](const StopHit& h) { return !h.release; });
  const bool in_run = t - t_last_event_ <= kChatterGap * span_;
  in_a_row_ = in_run ? in_a_row_ + 1 : 1;
  stop_in_run_ = (in_run && stop_in_run_) || impact;
  pin_in_run_ = (in_run && pin_in_run_) || pin_switched;
  t_last_event_ = t;
  kept_side_ = 0;
  iterations_ = 0;
  if (in_a_row_ < kMaxChatter) return Chatter::none;
  // (Loads switched by the rebounds of a joint coming to rest on its stop chatter with it: the
  // stop's.)
  const Chatter what = stop_in_run_  ? Chatter::stop
                       : pin_in_run_ ? Chatter::sticks
                                     : Chatter::loads;
  message = chatter_message(model, t, what);
  return what;
}

std::string Events::chatter_message(const Model& model, double t, Chatter what) const {
  char text[96];
  std::snprintf(text, sizeof text, "%d events within %.3g s up to t = %.9g s", kMaxChatter,
                kChatterGap * span_ * kMaxChatter, t);
  std::string names;
  for (const Value& w : values_) {
    const bool kind = what == Chatter::loads    ? w.load >= 0
                      : what == Chatter::sticks ? w.pin >= 0
                                                : (w.load < 0 && w.pin < 0);
    if (!kind) continue;
    const std::string name = "'" +
                             (w.load >= 0 ? model.loads[static_cast<size_t>(w.load)].name
                                          : model.joints[static_cast<size_t>(w.joint)].name) +
                             "'";
    if (names.find(name) == std::string::npos) names += (names.empty() ? "" : ", ") + name;
  }
  if (what == Chatter::sticks)
    return "the friction in joint " + names +
           " sticks: its relative rate comes back through zero at once after each change of "
           "sign (" +
           text +
           "), the joint held by its static friction; stick-slip is not modelled yet, so the "
           "motion from here is not determined";
  if (what == Chatter::stop)
    return "joint " + names + " comes to rest against its end stop (impacts at ever shorter " +
           "intervals, " + text +
           ") where no contact force can hold it (the stop would have to pull at once): the " +
           "motion from here is not determined";
  return "the loads switched by active_while (" + names +
         ") chatter: each switch turns their measure's rate back (" + text +
         "), which holds it at 0 (a sliding mode, as a Coulomb friction torque written with "
         "active_while that sticks); a load switched by the sign of a rate cannot hold a joint "
         "stuck, so the motion from here is not determined";
}

void Events::abandon() {
  kept_side_ = 0;
  iterations_ = 0;
}

void Events::open_bracket(double t_lo, double t_hi) {
  // A new upper end with the lower end kept (the crossing found before the last try): the
  // Illinois step halves the kept end's values when it is kept twice in a row.
  const bool low_kept = iterations_ > 0 && t_lo == t_lo_;
  if (low_kept && kept_side_ < 0)
    for (double& v : lo_) v *= 0.5;
  kept_side_ = low_kept ? -1 : 0;
  if (!low_kept) lo_ = last_;
  t_lo_ = t_lo;
  t_hi_ = t_hi;
  hi_ = end_;
  ++iterations_;
}

double Events::next_time() const {
  const double w = t_hi_ - t_lo_;
  if (w <= tolerance_) return t_hi_;
  // Bisection after kBisectAfter tries (bounded: w / 2^k reaches the tolerance), regula falsi
  // before.
  if (iterations_ > kBisectAfter) return t_lo_ + 0.5 * w;
  // The earliest regula falsi root among the values that cross, kept a hundredth of the
  // bracket from either end (so that the bracket shrinks by that much at least).
  double t = t_hi_;
  for (size_t i = 0; i < values_.size(); ++i) {
    if (!crosses(i, lo_[i], hi_[i])) continue;
    const double d = lo_[i] - hi_[i];
    const double f = d != 0.0 ? lo_[i] / d : 0.5;
    t = std::min(t, t_lo_ + w * std::clamp(f, 0.01, 0.99));
  }
  return t >= t_hi_ ? t_lo_ + 0.5 * w : t;
}

bool Events::reached(double t) {
  // The lower end moved up; the upper end kept: halved on its second time in a row.
  if (kept_side_ > 0)
    for (double& v : hi_) v *= 0.5;
  kept_side_ = 1;
  t_lo_ = t;
  lo_ = last_;
  return ++iterations_ <= kMaxEventIterations;
}

}  // namespace orthomech::detail
