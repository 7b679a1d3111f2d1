#include "load_events.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "orthomech/model/measures.hpp"

namespace orthomech::detail {

LoadEvents::LoadEvents(const Model& model, double span)
    : span_(std::max(span, 1.0)), tolerance_(kEventTimeTolerance * std::max(span, 1.0)) {
  for (size_t k = 0; k < model.loads.size(); ++k) {
    const ActiveWhile& aw = model.loads[k].active_while;
    if (aw.measure >= 0) loads_.push_back({static_cast<int>(k), aw.measure, aw.sign});
  }
  last_.assign(loads_.size(), 0.0);
  end_ = lo_ = hi_ = last_;
}

void LoadEvents::values(const Model& model, const VecX& q, const VecX& u,
                        std::vector<double>& s) const {
  for (size_t i = 0; i < loads_.size(); ++i) {
    const Switched& w = loads_[i];
    const Measure& m = model.measures[static_cast<size_t>(w.measure)];
    s[i] = w.sign * compute_scalar(model, m.kind, q, &u).rate;
  }
}

void LoadEvents::start(const Model& model, const VecX& q, const VecX& u,
                       std::vector<std::uint8_t>& load_on) {
  if (loads_.empty()) return;
  load_on.assign(model.loads.size(), 1);
  values(model, q, u, last_);
  for (size_t i = 0; i < loads_.size(); ++i)
    load_on[static_cast<size_t>(loads_[i].load)] = last_[i] > 0.0 ? 1 : 0;
}

LoadEvents::StepEnd LoadEvents::step_end(const Model& model, double t0, double t1, const VecX& q,
                                         const VecX& u) {
  if (loads_.empty()) return StepEnd::smooth;
  values(model, q, u, end_);
  bool crossed = false;
  for (size_t i = 0; i < loads_.size(); ++i) crossed = crossed || crosses(last_[i], end_[i]);
  if (!crossed) return StepEnd::smooth;
  return t1 - t0 <= tolerance_ ? StepEnd::switch_here : StepEnd::locate;
}

void LoadEvents::keep_step_end() { last_ = end_; }

void LoadEvents::restored(const Model& model, const VecX& q, const VecX& u) {
  if (!loads_.empty()) values(model, q, u, last_);
}

bool LoadEvents::switch_at(const Model& model, double t, std::vector<std::uint8_t>& load_on,
                           std::string& message) {
  for (size_t i = 0; i < loads_.size(); ++i)
    if (crosses(last_[i], end_[i]))
      load_on[static_cast<size_t>(loads_[i].load)] = end_[i] > 0.0 ? 1 : 0;
  last_ = end_;
  ++events_;
  in_a_row_ = t - t_last_event_ <= kChatterGap * span_ ? in_a_row_ + 1 : 1;
  t_last_event_ = t;
  kept_side_ = 0;
  iterations_ = 0;
  if (in_a_row_ < kMaxChatter) return true;
  message = chatter_message(model, t);
  return false;
}

std::string LoadEvents::chatter_message(const Model& model, double t) const {
  std::string names;
  for (const Switched& w : loads_) {
    if (!names.empty()) names += ", ";
    names += "'" + model.loads[static_cast<size_t>(w.load)].name + "'";
  }
  char text[96];
  std::snprintf(text, sizeof text, "%d switches within %.3g s up to t = %.9g s", kMaxChatter,
                kChatterGap * span_ * kMaxChatter, t);
  return "the loads switched by active_while (" + names +
         ") chatter: each switch turns their measure's rate back (" + text +
         "), which holds it at 0 (a sliding mode, as a Coulomb friction torque written with "
         "active_while that sticks); a load switched by the sign of a rate cannot hold a joint "
         "stuck, so the motion from here is not determined";
}

void LoadEvents::abandon() {
  kept_side_ = 0;
  iterations_ = 0;
}

void LoadEvents::open_bracket(double t_lo, double t_hi) {
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

double LoadEvents::next_time() const {
  const double w = t_hi_ - t_lo_;
  if (w <= tolerance_) return t_hi_;
  // Bisection after kBisectAfter tries (bounded: w / 2^k reaches the tolerance), regula falsi
  // before.
  if (iterations_ > kBisectAfter) return t_lo_ + 0.5 * w;
  // The earliest regula falsi root among the values that change sign, kept a hundredth of the
  // bracket from either end (so that the bracket shrinks by that much at least).
  double t = t_hi_;
  for (size_t i = 0; i < loads_.size(); ++i) {
    if (!crosses(lo_[i], hi_[i])) continue;
    const double d = lo_[i] - hi_[i];
    const double f = d != 0.0 ? lo_[i] / d : 0.5;
    t = std::min(t, t_lo_ + w * std::clamp(f, 0.01, 0.99));
  }
  return t >= t_hi_ ? t_lo_ + 0.5 * w : t;
}

bool LoadEvents::reached(double t) {
  // The lower end moved up; the upper end kept: halved on its second time in a row.
  if (kept_side_ > 0)
    for (double& v : hi_) v *= 0.5;
  kept_side_ = 1;
  t_lo_ = t;
  lo_ = last_;
  return ++iterations_ <= kMaxEventIterations;
}

}  // namespace orthomech::detail
