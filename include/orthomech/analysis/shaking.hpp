#pragma once
/// @file
/// Shaking force and shaking moment of a mechanism on its frame (issue 49 item 4).
///
/// The shaking force is the resultant of the inertia forces of the moving bodies, and the shaking
/// moment their moment about a chosen point O of the frame:
///
///     F_s = −Σ m_i a_Gi = −Ṗ,     M_s = −Σ [(r_Gi − O) × m_i a_Gi + d/dt(J_i ω_i)] = −Ḣ_O,
///
/// P the linear momentum of the moving bodies and H_O their angular momentum about O (for a
/// spatial body d/dt(R J ω) = R (J ω̇ + ω × J ω), ω in the body frame). They are what the frame
/// has to carry beyond the static loads: by the momentum balance of the moving bodies, the force
/// that they exert on the frame through every joint and driver to the ground is F_s plus the
/// applied loads (the weights and every load of the file), whatever the split of the reactions
/// between the joints, so F_s and M_s are determined even where the reactions are not. They
/// depend only on q, u and u̇ of a position (docs/theory.md, "Shaking force and moment").
/// Each body kind's share is its `add_momentum_rate` (model/body_kinds.hpp).
#include <vector>

#include "orthomech/analysis/cycle.hpp"
#include "orthomech/model/model.hpp"

namespace orthomech {

/// The rates Ṗ and Ḣ_O of a state's linear momentum and angular momentum about `about` (world
/// frame, SI). Planar mechanisms: z of Ṗ is 0 and x, y of Ḣ_O are 0.
struct MomentumRate {
  Vec3 linear = Vec3::Zero();
  Vec3 angular = Vec3::Zero();
};
[[nodiscard]] MomentumRate momentum_rate(const Model& model, const VecX& q, const VecX& u,
                                         const VecX& udot, const Vec3& about);

/// The shaking force F_s = −Ṗ and moment M_s = −Ḣ_O at every position of a sweep (world frame,
/// SI; about `about`); `reported[k]` is false where the position's rates are not reported
/// (rates_reported: an unbridged change point), and its force and moment are then 0.
struct ShakingSeries {
  Vec3 about = Vec3::Zero();
  std::vector<Vec3> force, moment;
  std::vector<bool> reported;
};
[[nodiscard]] ShakingSeries shaking_series(const Model& model, const CycleResult& result,
                                           const Vec3& about);

/// Their summaries (summarize_values): "shaking force" |F_s| and "shaking moment" (planar: the
/// signed M_s,z; spatial: |M_s|), then their world components ("shaking force x", …; planar: x
/// and y of the force).
struct ShakingSummaries {
  std::vector<SeriesSummary> magnitudes, components;
};
[[nodiscard]] ShakingSummaries summarize_shaking(const Model& model, const CycleResult& result,
                                                 const ShakingSeries& series);

}  // namespace orthomech
