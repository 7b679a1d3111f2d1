#pragma once
// Motion generation (rigid-body guidance) of planar four-bars by Burmester theory (issue 50,
// item 3; docs/synthesis.md, "Motion generation", (L14)–(L21)); [Sandor & Erdman 1984, ch. 2],
// [McCarthy & Soh 2011, ch. 4–5].
//
// A pose is a frame of the guided body (the coupler) in the world: position P_j, angle θ_j. A
// dyad is a fixed pivot m (world) and a moving pivot z given in the body frame; its positions
// Z_j = P_j + R(θ_j) z must lie on one circle about m:
//   g_j(m, z) = |Z_j − m|² − |Z_1 − m|² = 0,   j = 2 … n.                                (L14)
// For fixed z the g_j are linear in m and for fixed m linear in z (L15): 3 poses fix one from
// the other (2 × 2 systems), 4 poses leave a curve of centre points (the centre-point cubic,
// det C(m) = 0, (L16)), 5 poses leave at most 4 Burmester points (L17); more poses are fitted by
// least squares (L18).
#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "orthomech/synthesis/four_bar.hpp"

namespace orthomech::synthesis {

struct Pose {
  Vec2 position = Vec2::Zero();
  double angle = 0.0;
};

// A dyad (one grounded crank or follower): fixed pivot m (world), moving pivot z (body frame),
// radius |Z_j − m| (the mean over the poses) and the largest deviation of |Z_j − m| from it.
struct Dyad {
  Vec2 fixed_pivot = Vec2::Zero();
  Vec2 moving_pivot = Vec2::Zero();
  double radius = 0.0;
  double residual = 0.0;
};

// ---- 2 and 3 poses ----------------------------------------------------------------------------
// The pivot conjugate to a given one. 3 poses: the unique point (`direction` zero); 2 poses: the
// line of solutions, `point` on it (the midpoint of the two positions) and its unit `direction`.
// status no_linkage when the positions are collinear (3 poses: the centre is at infinity) or
// coincide (the given point is a pole: every point is a solution).
struct ConjugatePivot {
  SynthesisStatus status = SynthesisStatus::no_linkage;
  std::string message;
  Vec2 point = Vec2::Zero();
  Vec2 direction = Vec2::Zero();
};
// Centre point (fixed pivot, world) of the moving pivot z (body frame): the centre of the circle
// through Z_1, Z_2 (, Z_3) (L15a). Throws std::invalid_argument unless 2 or 3 poses.
[[nodiscard]] ConjugatePivot calc_centre_point(const std::vector<Pose>& poses,
                                               const Vec2& circle_point);
// Circle point (moving pivot, body frame) of the fixed pivot m (world): the inverse (L15b), the
// centre of the circle through m seen from the body in each pose, R(θ_j)ᵀ(m − P_j).
[[nodiscard]] ConjugatePivot calc_circle_point(const std::vector<Pose>& poses,
                                               const Vec2& centre_point);

// ---- 4 poses: the centre-point curve ------------------------------------------------------
// Sampled on `rays` lines through the pole P_1k of the largest rotation (every centre-point
// curve passes through the six poles): on each line det C(m) is a cubic with the root at the
// pole, and the other two roots are curve points (L16). Each point with its circle point.
struct CentrePointCurve {
  SynthesisStatus status = SynthesisStatus::no_linkage;
  std::string message;
  Vec2 pole = Vec2::Zero();
  std::vector<Dyad> points;
};
// Throws std::invalid_argument unless exactly 4 poses or rays < 1.
[[nodiscard]] CentrePointCurve sample_centre_point_curve(const std::vector<Pose>& poses,
                                                         int rays = 360);

// ---- a four-bar from two dyads, and where it meets a pose --------------------------------------
// The four-bar with crank `crank` and follower `follower`, whose coupler frame at P is the body
// frame (coupler_point, coupler_frame_angle), on the branch it has in `reference`.
[[nodiscard]] FourBar four_bar_from_dyads(const Dyad& crank, const Dyad& follower,
                                          const Pose& reference);

// Where `linkage` carries its coupler frame into `pose` (L19): the crank angle that puts A at
// its place in the pose, and the branch whose closed-form position (calc_position) comes
// nearest; the residuals are those of that position (|P − P_pose| and the wrapped angle error).
struct PoseMatch {
  bool assembles = false;
  double crank_angle = 0.0;
  int branch = 1;
  double position_error = 0.0;
  double angle_error = 0.0;
};
[[nodiscard]] PoseMatch find_pose(const FourBar& linkage, const Pose& pose) noexcept;

// ---- 5 and more poses ---------------------------------------------------------------------------
struct MotionCandidate {
  FourBar linkage;
  int crank_dyad = 0;  // indices into MotionSynthesisResult::dyads
  int follower_dyad = 0;
  double max_position_error = 0.0;  // over the poses, by find_pose
  double max_angle_error = 0.0;
  bool branch_defect = false;        // the poses are reached on different branches
  std::vector<double> crank_angles;  // one per pose
};

struct MotionSynthesisResult {
  SynthesisStatus status = SynthesisStatus::no_linkage;
  std::string message;
  std::vector<Dyad> dyads;                  // the real Burmester (or fitted) dyads
  std::vector<MotionCandidate> candidates;  // every pair of distinct dyads, crank first
};

struct MotionSynthesisOptions {
  int rays = 720;          // 5 poses: resultant samples over the pencil of lines (L17)
  int starts = 96;         // > 5 poses: multistart size of the least-squares search (L18)
  unsigned long seed = 1;  // > 5 poses: the quasi-random design's shift
  double box = 4.0;        // > 5 poses: search box half-width, in units of the poses' spread
  int max_dyads = 4;       // > 5 poses: the best distinct local minima kept
};

// 5 poses: the Burmester points (L17), polished by Newton on (L14); > 5 poses: the dyads of the
// least-squares problem (L18) (multistart BOBYQA through NLopt). Each pair of distinct dyads gives
// a candidate, each with its residuals through find_pose. Throws std::invalid_argument for fewer
// than 5 poses (2–4: synthesize_motion_few_poses below).
[[nodiscard]] MotionSynthesisResult synthesize_motion_generator(
    const std::vector<Pose>& poses, const MotionSynthesisOptions& options = {});

// ---- 2, 3 and 4 poses with given pivots (docs/synthesis.md, "Motion generation for 2, 3 and 4
// poses", (L26)–(L32)) ---------------------------------------------------------------------------
// What a designer gives of one dyad: its fixed pivot (world) and/or its moving pivot, in WORLD
// coordinates where it is at the first pose (what is measured on a drawing); (L26) carries it
// into the body frame, z = R(θ_1)ᵀ(Z_1 − P_1).
//   2 poses: both; the moving pivot exact, the fixed pivot a guess moved onto the perpendicular
//            bisector of Z_1Z_2 (the nearest point, (L27)).
//   3 poses: exactly one; the other follows (L28) (calc_circle_point / calc_centre_point).
//   4 poses: at most one; a given one must lie on its curve (the centre-point curve for a fixed
//            pivot, the circle-point curve for a moving one) within `pivot_tolerance` (L29),
//            (L30); a free dyad is a point of the sampled centre-point curve.
struct GivenPivots {
  std::optional<Vec2> fixed_pivot;
  std::optional<Vec2> moving_pivot;
};

struct FewPoseOptions {
  int rays = 180;          // 4 poses: lines of the centre-point curve's pencil (L16)
  int max_candidates = 6;  // 4 poses: the best distinct four-bars kept (L31)
  double box = 4.0;  // 4 poses: curve points farther than box · spread from the poses' centroid
                     // are not used (near-slider dyads)
  double pivot_tolerance = 0.0;       // 4 poses: how far a given pivot may be from its curve (the
                                      // poses' length unit; 0: 1e-6 of the poses' spread)
  bool require_crank_rocker = false;  // 4 poses: only Grashof crank-rockers are kept
  double unit = 1.0;                  // messages: lengths divided by this, followed by unit_name
  std::string unit_name;
};

// dyads: the crank's and the follower's (2–3 poses: exactly these two; 4 poses: the dyads of the
// kept candidates, polished (L32)); candidates: 2–3 poses one four-bar (crank = the dyad called
// crank, not the shorter), 4 poses up to max_candidates, best worst transmission angle first
// (L31). status no_linkage with the reason (a degenerate pose set, a given pivot off its curve,
// no pair that meets the poses on one branch) — data, not an exception. Throws
// std::invalid_argument for a pose count outside 2–4 (5 poses give finitely many dyads:
// synthesize_motion_generator) or pivots the pose count does not admit (the message names the
// dyad).
[[nodiscard]] MotionSynthesisResult synthesize_motion_few_poses(const std::vector<Pose>& poses,
                                                                const GivenPivots& crank,
                                                                const GivenPivots& follower,
                                                                const FewPoseOptions& options = {});

}  // namespace orthomech::synthesis
