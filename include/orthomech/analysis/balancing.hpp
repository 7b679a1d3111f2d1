#pragma once
/// @file
/// Counterweights that balance a planar driven mechanism (issue 49 item 4).
///
/// A counterweight is a point mass m_c at a point p of a body's frame, |p| = r given by the
/// designer (where it can go), its mass and direction found here. The motion of a driven
/// mechanism does not depend on its masses, so a counterweight adds to the shaking force, the
/// shaking moment about O and the drive its own terms, evaluated on the motion of the sweep
/// already computed (no new sweep per trial):
///
///     ΔF_s = −m_c a_P,   ΔM_s = −(r_P − O) × m_c a_P,   Δτ ṡ = m_c (a_P − g) · v_P
///
/// (a_P, v_P: acceleration and velocity of the body point P; g: the file's gravity; the last by
/// the power balance of a one-input mechanism). The counterweights minimise
///
///     J = w_F (F_rms / F_rms,0)² + w_M (M_rms / M_rms,0)² + w_τ (τ_rms / τ_rms,0)²
///
/// (RMS over the sweep's reported positions, 0 the mechanism as it is; a term whose value before
/// is 0 is left out) by NLopt's BOBYQA over the counterweights' first moments μ = m_c p, each in
/// the box |μ_x|, |μ_y| ≤ mass_limit·r. With w_M = w_τ = 0, J is quadratic in μ for bodies
/// pivoted on the ground, and where the classical conditions allow a full force balance (a
/// four-bar with counterweights on crank and rocker: Berkof and Lowen's linearly independent
/// vectors) its minimum is F_s ≡ 0. docs/theory.md "Balancing".
#include <string>
#include <vector>

#include "orthomech/analysis/cycle.hpp"
#include "orthomech/model/model.hpp"

namespace orthomech {

/// Where a counterweight may go: on `body`, at distance `radius` (m) from the body frame's
/// origin, in the direction the balancing finds.
struct CounterweightSite {
  int body = -1;
  double radius = 0.0;
};

struct BalanceWeights {
  double force = 1.0, moment = 0.0, drive = 0.0;
};

struct BalanceOptions {
  std::vector<CounterweightSite> sites;
  BalanceWeights weights;
  Vec3 about = Vec3::Zero();  // O of the shaking moment (m)
  // The largest counterweight mass (kg): the box of μ is ±mass_limit·r; 0: 10 × the moving
  // bodies' total mass.
  double mass_limit = 0.0;
  int max_evaluations = 4000;
};

/// A counterweight found: its mass (kg) and point p in the body frame (m), and the body with it
/// (what the balanced file says): mass m + m_c, centre of mass (m c₀ + m_c p)/(m + m_c) in the
/// body frame, inertia about it J + m |c₀ − c|² + m_c |p − c|².
struct Counterweight {
  int body = -1;
  double mass = 0.0;
  Vec2 position = Vec2::Zero();
  double body_mass = 0.0;
  Vec2 body_com = Vec2::Zero();
  double body_inertia = 0.0;
};

/// RMS over the sweep's reported positions.
struct BalanceTerms {
  double force_rms = 0.0, force_peak = 0.0, moment_rms = 0.0, drive_rms = 0.0;
};

enum class BalanceStatus {
  balanced,          // the optimiser converged
  evaluation_limit,  // it stopped at max_evaluations: the best point found is reported
  invalid_request,   // a spatial mechanism, a site on the ground, a radius ≤ 0, no sweep, …
  failed,            // NLopt failed
};

struct BalanceResult {
  BalanceStatus status = BalanceStatus::failed;
  std::string message;
  std::vector<Counterweight> counterweights;  // one per site, in order
  BalanceTerms before, after;                 // after: predicted on the sweep's motion
  double objective_before = 0.0, objective_after = 0.0;
  int evaluations = 0;
};

/// Balances the mechanism whose sweep is `sweep` (run_cycle of `model`, one input).
[[nodiscard]] BalanceResult balance_counterweights(const Model& model, const CycleResult& sweep,
                                                   const BalanceOptions& options);

/// The terms of `sweep` as it is (its shaking force, moment about `about`, drive).
[[nodiscard]] BalanceTerms balance_terms(const Model& model, const CycleResult& sweep,
                                         const Vec3& about);

[[nodiscard]] const char* to_string(BalanceStatus s);

}  // namespace orthomech
