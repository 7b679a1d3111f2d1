#pragma once
// Design metrics of a driven sweep (issue 11 item 4), from the positions of a CycleResult:
//   - transmission angle μ of every planar four-bar loop (min of min(μ, π − μ), where) and
//     pressure angle α of every slider-crank loop (max, where) — analysis/validate.hpp finds the
//     loops;
//   - drive power P = τ ṡ: mean, signed max/min; the energy fluctuation of the drive
//     ΔE = max E − min E, E(t) = ∫₀ᵗ (P − P̄) dt (trapezoid rule over the positions), and the
//     flywheel inertia I = ΔE / (C_s ω̄²) for a coefficient of speed fluctuation C_s
//     [Shigley, Mechanical Engineering Design, §16-12]: a flywheel of that inertia on the input
//     keeps (ω_max − ω_min)/ω̄ ≤ C_s;
//   - every prismatic joint, every position measure and the x and y of every named point that no
//     joint uses and no measure reports (a tracer point: coupler point, foot): extreme values (with
//     where; refined by a parabola through the extreme sample and its neighbours), range (the
//     stroke) and, over a full cycle, the time ratio forward/return (time from min to max over time
//     from max to min).
// Positions flagged `singular` are left out (their drive is not meaningful).
#include <optional>
#include <string>
#include <vector>

#include "orthomech/analysis/cycle.hpp"
#include "orthomech/model/model.hpp"

namespace orthomech {

struct LoopAngleMetric {
  std::string loop;           // "A0-A-B-B0"
  bool slider_crank = false;  // pressure angle (slider-crank) or transmission angle (four-bar)
  // four-bar: μ ∈ [0, π] (min, max) and the worst deviation min(μ, π − μ) (its smallest);
  // slider-crank: α ∈ [0, π/2] (min, max) and the worst = its largest.
  SeriesExtreme min, max, worst;
};

struct PowerMetric {
  bool available = false;                  // at least two positions with a drive
  double mean = 0.0;                       // P̄ = ∫ P dt / T, W
  SeriesExtreme max, min;                  // signed P, W
  double peak = 0.0;                       // max |P|, W
  double energy_fluctuation = 0.0;         // ΔE = max E − min E, J
  SeriesExtreme energy_max, energy_min;    // E(t) extremes, J
  double mean_speed = 0.0;                 // ω̄ = |Δs| / T (rad/s or m/s)
  std::optional<double> flywheel_inertia;  // kg·m², for options' C_s (angular drivers)
};

struct StrokeMetric {
  std::string name;  // joint or measure name
  std::string unit;  // SI unit of the value ("m", "rad", …)
  SeriesExtreme min, max;
  double range = 0.0;  // max − min: the stroke
  // Full cycles: the turning maxima per cycle (0: not a full cycle). The time ratio forward
  // (min → max) / return (max → min) only where it is 1: with several maxima per cycle there is no
  // one forward stroke, and no ratio is given.
  int maxima = 0;
  std::optional<double> time_ratio;
  double forward_time = 0.0, return_time = 0.0;
};

// A joint outside its `limits` during the sweep: where it first leaves them and the furthest
// value it reaches beyond them.
struct LimitExcursion {
  int joint = -1;
  SeriesExtreme first;     // value, input and time of the first position outside
  SeriesExtreme furthest;  // the value furthest outside
  int positions = 0;       // positions outside
};

struct CycleMetrics {
  std::vector<LoopAngleMetric> loops;
  PowerMetric power;
  std::vector<StrokeMetric> strokes;
  std::vector<LimitExcursion> limits;
};

// The coordinate of a joint compared with its limits: a slide as it is; an angle (planar
// revolute φ_j − φ_i, or a spatial revolute, cylindrical or screw joint's (P5) angle) taken
// modulo 2π nearest the middle of the limits (or of [−π, π]).
[[nodiscard]] double limit_coordinate(const Model& model, int joint, const VecX& q);
// Whether the joint is outside its limits at q by more than kLimitSlack (none: false).
[[nodiscard]] bool outside_limits(const Model& model, int joint, const VecX& q);
inline constexpr double kLimitSlack = 1e-9;
// A turning point of a stroke counts once the series has come back from it by this share of its
// range (a wiggle below one part per million of the stroke is not a second maximum).
inline constexpr double kTurningHysteresis = 1e-6;  // rad or m: a joint at its limit is inside

struct CycleMetricsOptions {
  int driver_joint = -1;
  bool full_cycle = true;                   // the sweep is one period (time ratios, ΔE)
  std::optional<double> speed_fluctuation;  // C_s for the flywheel inertia
};

[[nodiscard]] CycleMetrics compute_cycle_metrics(const Model& model, const CycleResult& result,
                                                 const CycleMetricsOptions& options);

}  // namespace orthomech
