#include "orthomech/analysis/cycle_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "orthomech/analysis/validate.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/io/noise.hpp"
#include "orthomech/model/measures.hpp"

namespace orthomech {

namespace {

// The positions that carry a drive (drive_reported: bridged values next to a change point
// count), in sweep order.
std::vector<size_t> regular_positions(const CycleResult& r) {
  std::vector<size_t> k;
  for (size_t i = 0; i < r.points.size(); ++i)
    if (drive_reported(r.points[i])) k.push_back(i);
  return k;
}

// The extreme of samples y at index k refined by the parabola through k − 1, k, k + 1 (M1):
// vertex offset δ = (y₋ − y₊) / (2 (y₋ − 2y + y₊)) in steps, value y − (y₋ − y₊) δ / 4. Times and
// inputs are interpolated linearly in δ. Neighbours wrap round on a full cycle; at the ends of a
// range (or where the parabola is flat) the sample itself is kept.
SeriesExtreme refined_extreme(const CycleResult& r, const std::vector<double>& y, size_t k,
                              bool cyclic, double period) {
  const size_t n = y.size();
  const DrivenPointView p = r.points[k];
  SeriesExtreme e{y[k], p.input, p.time};
  if (n < 3 || (!cyclic && (k == 0 || k + 1 == n))) return e;
  const size_t km = k == 0 ? n - 1 : k - 1, kp = k + 1 == n ? 0 : k + 1;
  const double ym = y[km], yp = y[kp];
  const double curvature = ym - 2.0 * y[k] + yp;
  if (curvature == 0.0) return e;
  const double delta = 0.5 * (ym - yp) / curvature;  // (M1)
  if (!(std::abs(delta) <= 1.0)) return e;
  e.value = y[k] - 0.25 * (ym - yp) * delta;
  // Step in time and input towards the neighbour on δ's side (a wrap adds one period).
  const size_t kn = delta > 0.0 ? kp : km;
  const DrivenPointView q = r.points[kn];
  double dt = q.time - p.time, ds = q.input - p.input;
  if (delta > 0.0 && kn == 0) dt += period, ds = r.points[1].input - r.points[0].input;
  if (delta < 0.0 && kn == n - 1) dt -= period, ds = r.points[0].input - r.points[1].input;
  e.time = p.time + std::abs(delta) * dt;
  e.input = p.input + std::abs(delta) * ds;
  return e;
}

// The turning maxima of the periodic samples y over one cycle, walked from its smallest sample
// kmin round to it again: a maximum counts once y has fallen from it by more than the hysteresis
// kTurningHysteresis × range (and a minimum once y has risen by as much), so that rounding noise
// on a flat stretch is not a turning point.
int maxima_per_cycle(const std::vector<double>& y, size_t kmin, double range) {
  const double h = kTurningHysteresis * range;
  const size_t n = y.size();
  int maxima = 0;
  bool rising = true;
  double extreme = y[kmin];
  for (size_t i = 1; i <= n; ++i) {
    const double v = y[(kmin + i) % n];
    if (rising) {
      if (v > extreme)
        extreme = v;
      else if (v < extreme - h)
        ++maxima, rising = false, extreme = v;
    } else {
      if (v < extreme)
        extreme = v;
      else if (v > extreme + h)
        rising = true, extreme = v;
    }
  }
  return std::max(maxima, 1);
}

// Extremes, range and time ratio of the series y over the positions (all of them). The time ratio
// only of a series with one maximum (and so one minimum) per cycle: with more, "from the minimum
// to the maximum" is not one stroke.
StrokeMetric stroke(const CycleResult& r, std::string name, std::string unit,
                    const std::vector<double>& y, bool cyclic, double period) {
  StrokeMetric s;
  s.name = std::move(name);
  s.unit = std::move(unit);
  const size_t kmin = static_cast<size_t>(std::min_element(y.begin(), y.end()) - y.begin());
  const size_t kmax = static_cast<size_t>(std::max_element(y.begin(), y.end()) - y.begin());
  s.min = refined_extreme(r, y, kmin, cyclic, period);
  s.max = refined_extreme(r, y, kmax, cyclic, period);
  s.range = s.max.value - s.min.value;
  if (cyclic && s.range > 0.0) s.maxima = maxima_per_cycle(y, kmin, s.range);
  if (cyclic && s.range > 0.0 && s.maxima == 1) {
    // Forward: from the minimum to the maximum, in time, round the period.
    double forward = std::fmod(s.max.time - s.min.time, period);
    if (forward < 0.0) forward += period;
    s.forward_time = forward;
    s.return_time = period - forward;
    if (s.return_time > 0.0) s.time_ratio = s.forward_time / s.return_time;
  }
  return s;
}

}  // namespace

double limit_coordinate(const Model& model, int joint, const VecX& q) {
  const Joint& j = model.joints[static_cast<size_t>(joint)];
  const double x = compute_scalar(model, JointCoordinate{joint}, q, nullptr).value;
  if (joint_coordinate_kind(j) != CoordinateKind::angle) return x;  // planar or spatial angle
  const double mid = j.limits ? 0.5 * (j.limits->x() + j.limits->y()) : 0.0;
  constexpr double kTurn = 2.0 * std::numbers::pi;
  return x - kTurn * std::round((x - mid) / kTurn);
}

bool outside_limits(const Model& model, int joint, const VecX& q) {
  const Joint& j = model.joints[static_cast<size_t>(joint)];
  if (!j.limits) return false;
  const double x = limit_coordinate(model, joint, q);
  return x < j.limits->x() - kLimitSlack || x > j.limits->y() + kLimitSlack;
}

CycleMetrics compute_cycle_metrics(const Model& model, const CycleResult& r,
                                   const CycleMetricsOptions& opt) {
  CycleMetrics out;
  const size_t n = r.points.size();
  if (n == 0) return out;
  // A full cycle: positions at t_k = k T / N, k = 0 … N − 1 (no repeated end), so T = N Δt.
  // (Not when the sweep stopped early, at a dead point or a failure, or reversed.)
  const bool cyclic =
      opt.full_cycle && n >= 3 && r.reversals == 0 && r.status == CycleStatus::completed;
  const double dt = n >= 2 ? r.points[1].time - r.points[0].time : 0.0;
  const double period = cyclic ? static_cast<double>(n) * dt : r.points.back().time;

  // ---- loop angles over the cycle ----------------------------------------------------------
  auto joint_names = [&](const int* joints) {
    std::string s;
    for (int k = 0; k < 4; ++k)
      s += (k ? "-" : "") + model.joints[static_cast<size_t>(joints[k])].name;
    return s;
  };
  // The loops' functions take the coordinates as a VecX: each position's q is copied once, the
  // loops inside (with the loops outside, one copy of q per loop and position: O(N²) on the
  // N-four-bar, 26 % of N = 1000's cycle).
  const std::vector<FourBarLoop> four_bars = find_four_bar_loops(model, opt.driver_joint);
  const std::vector<SliderCrankLoop> slider_cranks = find_slider_crank_loops(model);
  out.loops.resize(four_bars.size() + slider_cranks.size());
  for (size_t i = 0; i < four_bars.size(); ++i)
    out.loops[i].loop = joint_names(four_bars[i].joints);
  for (size_t i = 0; i < slider_cranks.size(); ++i) {
    LoopAngleMetric& m = out.loops[four_bars.size() + i];
    m.loop = joint_names(slider_cranks[i].joints);
    m.slider_crank = true;
  }
  VecX q(model.nq);
  for (size_t k = 0; k < n; ++k) {
    const DrivenPointView& p = r.points[k];
    const bool first = k == 0;
    q = p.q;
    for (size_t i = 0; i < four_bars.size(); ++i) {
      LoopAngleMetric& m = out.loops[i];
      const double mu = transmission_angle(model, four_bars[i], q);
      const double dev = std::min(mu, std::numbers::pi - mu);
      if (first || mu < m.min.value) m.min = {mu, p.input, p.time};
      if (first || mu > m.max.value) m.max = {mu, p.input, p.time};
      if (first || dev < m.worst.value) m.worst = {dev, p.input, p.time};
    }
    for (size_t i = 0; i < slider_cranks.size(); ++i) {
      LoopAngleMetric& m = out.loops[four_bars.size() + i];
      const double alpha = pressure_angle(model, slider_cranks[i], q);
      if (first || alpha < m.min.value) m.min = {alpha, p.input, p.time};
      if (first || alpha > m.max.value) m.max = {alpha, p.input, p.time};
    }
  }
  for (size_t i = 0; i < slider_cranks.size(); ++i) {
    LoopAngleMetric& m = out.loops[four_bars.size() + i];
    m.worst = m.max;
  }

  // ---- drive power and energy fluctuation --------------------------------------------------
  const std::vector<size_t> reg = regular_positions(r);
  PowerMetric& pw = out.power;
  if (reg.size() >= 2) {
    pw.available = true;
    std::vector<double> P(reg.size());
    for (size_t i = 0; i < reg.size(); ++i) {
      const DrivenPointView p = r.points[reg[i]];
      P[i] = p.drive * p.input_rate;  // power of the drive into the joint
      if (i == 0 || P[i] > pw.max.value) pw.max = {P[i], p.input, p.time};
      if (i == 0 || P[i] < pw.min.value) pw.min = {P[i], p.input, p.time};
      pw.peak = std::max(pw.peak, std::abs(P[i]));
    }
    // Trapezoid rule over the positions, closed round the period on a full cycle.
    const size_t segments = cyclic && reg.size() == n ? reg.size() : reg.size() - 1;
    auto t_of = [&](size_t i) {
      return i < reg.size() ? r.points[reg[i]].time : r.points[reg[0]].time + period;
    };
    auto P_of = [&](size_t i) { return P[i % reg.size()]; };
    double work = 0.0, span = 0.0;
    for (size_t i = 0; i < segments; ++i) {
      const double h = t_of(i + 1) - t_of(i);
      work += 0.5 * h * (P_of(i) + P_of(i + 1));
      span += h;
    }
    pw.mean = span > 0.0 ? work / span : 0.0;
    // A sum of N terms carries up to N times the rounding noise of one: a mean within N·256 ε of
    // the peak is 0 (the mean power of a conservative mechanism over a full cycle, ∮ P dt = ΔV =
    // 0, comes out as 1e-13 of the peak otherwise; io/noise.hpp).
    if (std::abs(pw.mean) <= kNoiseRelative * static_cast<double>(segments) * pw.peak)
      pw.mean = 0.0;
    // E(t) = ∫ (P − P̄) dt at every position; ΔE = max − min.
    double E = 0.0;
    pw.energy_max = pw.energy_min = {0.0, r.points[reg[0]].input, r.points[reg[0]].time};
    for (size_t i = 0; i < segments; ++i) {
      const double h = t_of(i + 1) - t_of(i);
      E += 0.5 * h * (P_of(i) + P_of(i + 1)) - pw.mean * h;
      if (i + 1 >= reg.size()) break;  // back at the start
      const DrivenPointView p = r.points[reg[i + 1]];
      if (E > pw.energy_max.value) pw.energy_max = {E, p.input, p.time};
      if (E < pw.energy_min.value) pw.energy_min = {E, p.input, p.time};
    }
    pw.energy_fluctuation = pw.energy_max.value - pw.energy_min.value;
    for (const size_t k : reg) pw.mean_speed += std::abs(r.points[k].input_rate);
    pw.mean_speed /= static_cast<double>(reg.size());  // ω̄: mean |ṡ| over the positions
    const bool angular =
        opt.driver_joint >= 0 &&
        joint_coordinate_kind(model.joints[static_cast<size_t>(opt.driver_joint)]) ==
            CoordinateKind::angle;
    if (opt.speed_fluctuation && *opt.speed_fluctuation > 0.0 && angular && pw.mean_speed > 0.0)
      pw.flywheel_inertia =
          pw.energy_fluctuation / (*opt.speed_fluctuation * pw.mean_speed * pw.mean_speed);
  }

  // ---- strokes: prismatic joints and position measures --------------------------------------
  // A series constant up to rounding noise (a translating coupler's angle, 1e-13 deg) has no
  // stroke and no time ratio: its range is at most kNoiseRelative of the largest value of its
  // dimension over the positions (every length or angle coordinate, every measure).
  NoiseFloor noise;
  for (const DrivenPointView& p : r.points) {
    for (const Body& b : model.bodies)
      for (int k = 0; k < b.nq(); ++k)
        noise.see(k < 2 ? Dimension::length : Dimension::angle, p.q(b.q_offset + k));
    for (size_t i = 0; i < p.measures.size(); ++i)
      if (measure_reported(model, p, i))
        noise.see(dimension_of(model.measures[i].unit), p.measures[i]);
  }
  // An angle that turns fully over the sweep (a crank's, sampled over 359° of 360°) has no
  // stroke either: its extremes are the ends of the sweep, not turning points.
  auto turns_fully = [&](const std::string& unit, const std::vector<double>& v) {
    if (dimension_of(unit) != Dimension::angle || v.size() < 3) return false;
    const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
    return *hi - *lo >= 2.0 * std::numbers::pi * (1.0 - 1.5 / static_cast<double>(v.size()));
  };
  auto add_stroke = [&](StrokeMetric s) {
    const Dimension d = dimension_of(s.unit);
    noise.see(d, s.min.value);
    noise.see(d, s.max.value);
    if (noise.clean(d, s.range) != 0.0) out.strokes.push_back(std::move(s));
  };
  // The series the positions do not carry (a prismatic joint's coordinate, a tracer point's x
  // and y) are listed first and evaluated together, each position's q copied once.
  struct Series {
    std::string name;
    MeasureKind kind;
    std::vector<double> y;
  };
  std::vector<Series> joint_series, point_series;
  for (size_t j = 0; j < model.joints.size(); ++j) {
    if (!std::holds_alternative<Prismatic>(model.joints[j].kind)) continue;
    if (static_cast<int>(j) == opt.driver_joint) continue;
    bool measured = false;  // a measure of this joint's coordinate reports it already
    for (const Measure& m : model.measures)
      if (const auto* jc = std::get_if<JointCoordinate>(&m.kind))
        measured = measured || (jc->joint == static_cast<int>(j) && m.derivative == 0);
    if (!measured)
      joint_series.push_back({model.joints[j].name, JointCoordinate{static_cast<int>(j)}, {}});
  }
  // Named points that no joint uses (tracer points: a coupler point, a foot) and no measure
  // reports: the range of their x and y. The joints' points are listed per body once (a look-up
  // over every joint for every named point was O(N²) on the N-four-bar: 8 % of N = 1000's cycle).
  std::vector<std::vector<const PointRef*>> joint_points(model.bodies.size());
  for (const Joint& j : model.joints)
    std::visit(
        [&](const auto& k) {
          using T = std::decay_t<decltype(k)>;
          if constexpr (requires { k.pi; } && !std::is_same_v<T, SpatialJoint>)
            for (const PointRef* ref : {&k.pi, &k.pj})
              if (ref->body >= 0) joint_points[static_cast<size_t>(ref->body)].push_back(ref);
        },
        j.kind);
  auto used_by_joint = [&](int body, const Vec2& local) {
    const Body& b = model.bodies[static_cast<size_t>(body)];
    for (const PointRef* ref : joint_points[static_cast<size_t>(body)])
      if ((ref->s + b.com_local - local).norm() < 1e-12) return true;
    return false;
  };
  for (size_t b = 0; b < model.bodies.size(); ++b) {
    const Body& body = model.bodies[b];
    for (const auto& [name, local] : body.points) {
      if (used_by_joint(static_cast<int>(b), local)) continue;
      for (int axis = 0; axis < 2; ++axis) {
        bool measured = false;
        for (const Measure& m : model.measures)
          if (const auto* pc = std::get_if<PointCoordinate>(&m.kind))
            measured = measured || (m.derivative == 0 && pc->axis == axis &&
                                    pc->point.body == static_cast<int>(b) &&
                                    (pc->point.s + body.com_local - local).norm() < 1e-12);
        if (measured) continue;
        const PointRef ref{static_cast<int>(b), local - body.com_local, ""};
        point_series.push_back(
            {body.name + "." + name + (axis == 0 ? ".x" : ".y"), PointCoordinate{ref, axis}, {}});
      }
    }
  }
  for (std::vector<Series>* list : {&joint_series, &point_series})
    for (Series& series : *list) series.y.resize(n);
  if (!joint_series.empty() || !point_series.empty())
    for (size_t k = 0; k < n; ++k) {
      q = r.points[k].q;
      for (std::vector<Series>* list : {&joint_series, &point_series})
        for (Series& series : *list)
          series.y[k] = compute_scalar(model, series.kind, q, nullptr).value;
    }
  for (Series& series : joint_series)
    add_stroke(stroke(r, std::move(series.name), "m", series.y, cyclic, period));
  std::vector<double> y(n);
  for (size_t i = 0; i < model.measures.size(); ++i) {
    const Measure& m = model.measures[i];
    if (m.derivative != 0) continue;
    if (const auto* jc = std::get_if<JointCoordinate>(&m.kind))
      if (jc->joint == opt.driver_joint) continue;  // the input itself
    for (size_t k = 0; k < n; ++k) y[k] = r.points[k].measures[i];
    if (turns_fully(m.unit, y)) continue;
    add_stroke(stroke(r, m.name, m.unit, y, cyclic, period));
  }
  for (Series& series : point_series)
    add_stroke(stroke(r, std::move(series.name), "m", series.y, cyclic, period));

  // ---- joints outside their limits ---------------------------------------------------------
  for (size_t j = 0; j < model.joints.size(); ++j) {
    const Joint& joint = model.joints[j];
    if (!joint.limits) continue;
    LimitExcursion ex;
    ex.joint = static_cast<int>(j);
    double worst = 0.0;
    for (const DrivenPointView& p : r.points) {
      q = p.q;
      if (!outside_limits(model, ex.joint, q)) continue;
      const double x = limit_coordinate(model, ex.joint, q);
      const double beyond = std::max(joint.limits->x() - x, x - joint.limits->y());
      if (ex.positions++ == 0) ex.first = {x, p.input, p.time};
      if (beyond > worst) worst = beyond, ex.furthest = {x, p.input, p.time};
    }
    if (ex.positions > 0) out.limits.push_back(ex);
  }
  return out;
}

}  // namespace orthomech
