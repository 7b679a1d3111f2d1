// Motion generation for 2, 3 and 4 poses with given pivots (docs/synthesis.md, "Motion generation
// for 2, 3 and 4 poses", (L26)–(L32)); the 3-pose conjugates are (L15a/b), the 4-pose curve (L16)
// of motion_generation.cpp.
#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>

#include "burmester_rows.hpp"
#include "orthomech/synthesis/motion_generation.hpp"

namespace orthomech::synthesis {

namespace {

using detail::circle_point_of;
using detail::compatibility_row;
using detail::make_dyad;
using detail::normalise;
using detail::Normalised;
using detail::rotation;

constexpr double kPi = std::numbers::pi;
// Two fixed (or moving) pivots closer than this, relative to the poses' spread, are one point.
constexpr double kDegenerate = 1e-12;
// A curve pair's pose residual (relative to the spread; rad) below which it meets its poses before
// the polish: the curve points are exact to ~1e-13, so this only rejects the wrong branch.
constexpr double kPoseCheck = 1e-6;
// Two kept four-bars differ by more than this (relative to the spread) in some pivot.
constexpr double kSameFourBar = 0.2;
// Default pivot_tolerance, relative to the spread.
constexpr double kPivotTolerance = 1e-6;
// Newton (L29), (L32): iteration caps; (L32) stops below this |g_j| (normalised units).
constexpr int kNewtonIterations = 40;
constexpr double kPolished = 1e-15;

const char* role_name(int role) { return role == 0 ? "crank" : "follower"; }

std::string length_text(double v, const FewPoseOptions& o) {
  char b[64];
  std::snprintf(b, sizeof b, "%.6g%s%s", v / o.unit, o.unit_name.empty() ? "" : " ",
                o.unit_name.c_str());
  return b;
}

// ---- Step 0: which pivots each pose count admits -------------------------------------------
void check_given(std::size_t poses, const GivenPivots& g, int role) {
  const std::string who = std::string("the ") + role_name(role);
  const bool f = g.fixed_pivot.has_value(), m = g.moving_pivot.has_value();
  const auto refuse = [&](const std::string& why) {
    throw std::invalid_argument("synthesize_motion_few_poses: " + who + " " + why);
  };
  if (poses == 2 && !(f && m))
    refuse("needs its moving pivot and a guess of its fixed pivot for 2 poses");
  if (poses == 3 && f == m)
    refuse("needs exactly one pivot given (fixed or moving) for 3 poses; the other follows");
  if (poses == 4 && f && m)
    refuse("takes at most one pivot for 4 poses (the other follows from its curve)");
}

// (L26): the moving pivot given in the world at the first pose, in the body frame.
Vec2 body_point(const std::vector<Pose>& poses, const Vec2& world_at_first) {
  return rotation(poses[0].angle).transpose() * (world_at_first - poses[0].position);
}

// (L30): the inverse motion: the ground seen from the body, pose j at (−R_jᵀP_j, −θ_j). Its
// centre points are the body-frame circle points of the poses and its circle points (in the
// ground's frame, the world) the fixed pivots.
std::vector<Pose> inverted(const std::vector<Pose>& poses) {
  std::vector<Pose> inv;
  inv.reserve(poses.size());
  for (const Pose& p : poses)
    inv.push_back({-(rotation(p.angle).transpose() * p.position), -p.angle});
  return inv;
}

// ---- 2 and 3 poses -----------------------------------------------------------------------------
struct DyadOutcome {
  bool ok = false;
  std::string message;
  Dyad dyad;
};

// 3 poses (L28): the fixed pivot's circle point (L15b) or the moving pivot's centre point (L15a).
// 2 poses (L27): the centre points of z form the bisector M + s u of Z_1Z_2; the guess g moves to
// its nearest point m = M + ((g − M)·u) u.
DyadOutcome dyad_from_given(const std::vector<Pose>& poses, const GivenPivots& g, int role) {
  DyadOutcome out;
  const std::string who = std::string("the ") + role_name(role) + "'s ";
  if (poses.size() == 3 && g.fixed_pivot) {
    const ConjugatePivot z = calc_circle_point(poses, *g.fixed_pivot);
    if (z.status != SynthesisStatus::ok) return {false, who + "fixed pivot: " + z.message, {}};
    return {true, "", make_dyad(poses, *g.fixed_pivot, z.point)};
  }
  const Vec2 z = body_point(poses, *g.moving_pivot);
  const ConjugatePivot m = calc_centre_point(poses, z);
  if (m.status != SynthesisStatus::ok) return {false, who + "moving pivot: " + m.message, {}};
  if (poses.size() == 3) return {true, "", make_dyad(poses, m.point, z)};
  const Vec2 guess = *g.fixed_pivot;
  const Vec2 fixed = m.point + (guess - m.point).dot(m.direction) * m.direction;  // (L27)
  return {true, "", make_dyad(poses, fixed, z)};
}

// One four-bar from two dyads, each pose met through find_pose (L19), like the 5-pose candidates.
MotionCandidate candidate_of(const std::vector<Pose>& poses, const std::vector<Dyad>& dyads,
                             int crank, int follower) {
  MotionCandidate c;
  c.linkage = four_bar_from_dyads(dyads[static_cast<std::size_t>(crank)],
                                  dyads[static_cast<std::size_t>(follower)], poses.front());
  c.crank_dyad = crank;
  c.follower_dyad = follower;
  for (const Pose& p : poses) {
    const PoseMatch match = find_pose(c.linkage, p);
    c.crank_angles.push_back(match.crank_angle);
    c.max_position_error = std::max(c.max_position_error, match.position_error);
    c.max_angle_error = std::max(c.max_angle_error, match.angle_error);
    c.branch_defect = c.branch_defect || match.branch != c.linkage.branch;
  }
  return c;
}

MotionSynthesisResult two_or_three_poses(const std::vector<Pose>& poses, const GivenPivots& crank,
                                         const GivenPivots& follower) {
  MotionSynthesisResult r;
  const DyadOutcome dc = dyad_from_given(poses, crank, 0);
  const DyadOutcome df = dyad_from_given(poses, follower, 1);
  for (const DyadOutcome* d : {&dc, &df})
    if (!d->ok) {
      r.message = d->message;
      return r;
    }
  const double spread = normalise(poses).scale;
  if ((dc.dyad.fixed_pivot - df.dyad.fixed_pivot).norm() <= kDegenerate * spread ||
      (dc.dyad.moving_pivot - df.dyad.moving_pivot).norm() <= kDegenerate * spread) {
    r.message = "the crank and the follower share a pivot: no four-bar";
    return r;
  }
  r.dyads = {dc.dyad, df.dyad};
  r.candidates.push_back(candidate_of(poses, r.dyads, 0, 1));
  r.status = SynthesisStatus::ok;
  r.message = std::to_string(poses.size()) + " poses: one four-bar";
  return r;
}

// ---- 4 poses -----------------------------------------------------------------------------------

// f(m) = det C(m), C's rows (a_jᵀ, c_j), j = 2, 3, 4 (L16), in normalised units.
double curve_function(const Normalised& n, const Vec2& m) {
  Eigen::Matrix3d C;
  for (int i = 0; i < 3; ++i)
    C.row(i) = compatibility_row(n, static_cast<std::size_t>(i + 1), m).transpose();
  return C.determinant();
}

// (L29): Newton's projection onto f = 0, m ← m − f ∇f / |∇f|² (∇f by central differences; f is
// a cubic, so h² = 1e-12 of the curvature terms): the foot reached from m0.
Vec2 project_onto_curve(const Normalised& n, const Vec2& m0) {
  constexpr double h = 1e-6;
  Vec2 m = m0;
  for (int it = 0; it < kNewtonIterations; ++it) {
    const double f = curve_function(n, m);
    const Vec2 grad(
        (curve_function(n, m + Vec2(h, 0)) - curve_function(n, m - Vec2(h, 0))) / (2 * h),
        (curve_function(n, m + Vec2(0, h)) - curve_function(n, m - Vec2(0, h))) / (2 * h));
    const double g2 = grad.squaredNorm();
    if (!(g2 > 0.0) || !std::isfinite(f)) break;
    const Vec2 step = -f / g2 * grad;
    m += step;
    if (step.norm() < 1e-15 * (1.0 + m.norm())) break;
  }
  return m;
}

// (L32): Newton on the three equations (L14) g_2, g_3, g_4 in the four unknowns (m, z), the
// minimum-norm step Δ = −J⁺g (complete orthogonal decomposition): the nearest exact dyad.
Dyad polish(const std::vector<Pose>& poses, const Dyad& d) {
  const Normalised n = normalise(poses);
  Vec2 m = (d.fixed_pivot - n.centre) / n.scale, z = d.moving_pivot / n.scale;
  Eigen::Vector3d g;
  Eigen::Matrix<double, 3, 4> J;
  for (int it = 0; it < kNewtonIterations; ++it) {
    const Vec2 Z1 = n.P[0] + n.R[0] * z;
    for (int i = 0; i < 3; ++i) {
      const auto j = static_cast<std::size_t>(i + 1);
      const Vec2 Zj = n.P[j] + n.R[j] * z;
      g(i) = (Zj - m).squaredNorm() - (Z1 - m).squaredNorm();
      J.block<1, 2>(i, 0) = (-2.0 * (Zj - Z1)).transpose();
      J.block<1, 2>(i, 2) =
          (2.0 * (n.R[j].transpose() * (Zj - m) - n.R[0].transpose() * (Z1 - m))).transpose();
    }
    if (!g.allFinite() || g.lpNorm<Eigen::Infinity>() < kPolished) break;
    const Eigen::Vector4d step = J.completeOrthogonalDecomposition().solve(-g);
    m += step.head<2>();
    z += step.tail<2>();
    if (step.norm() < 1e-16 * (1.0 + m.norm() + z.norm())) break;
  }
  if (!g.allFinite()) return d;
  return make_dyad(poses, n.centre + n.scale * m, n.scale * z);
}

// A given pivot of a 4-pose dyad, on its curve (L29) (a moving pivot: on the centre-point curve of
// the inverse motion (L30)), with its conjugate; the reason when it is too far from the curve.
DyadOutcome dyad_on_curve(const std::vector<Pose>& poses, const GivenPivots& g, int role,
                          double tolerance, const FewPoseOptions& o) {
  const bool fixed = g.fixed_pivot.has_value();
  const std::vector<Pose> motion = fixed ? poses : inverted(poses);
  const Normalised n = normalise(motion);
  const Vec2 given = fixed ? *g.fixed_pivot : body_point(poses, *g.moving_pivot);
  const Vec2 on = project_onto_curve(n, (given - n.centre) / n.scale);
  const double distance = (n.centre + n.scale * on - given).norm();
  const std::string what =
      std::string("the ") + role_name(role) + "'s " + (fixed ? "fixed pivot" : "moving pivot") +
      " is " + length_text(distance, o) + " from the " + (fixed ? "centre-point" : "circle-point") +
      " curve of the 4 poses (tolerance " + length_text(tolerance, o) + ")";
  if (!std::isfinite(distance) || distance > tolerance)
    return {false, what + ": 4 poses admit only pivots on it", {}};
  const Vec2 conjugate = n.scale * circle_point_of(n, {1, 2, 3}, on);
  const Vec2 point = n.centre + n.scale * on;
  const Dyad d = fixed ? make_dyad(poses, point, conjugate) : make_dyad(poses, conjugate, point);
  return {true, what, polish(poses, d)};
}

// The crank's interval through the poses in their order, turning the way with the smaller total
// (as run_synthesis unwraps them); nullopt when no sense reaches them within a turn.
std::optional<std::array<double, 2>> crank_interval(const std::vector<double>& angles) {
  double ccw = 0.0, cw = 0.0;
  for (std::size_t j = 1; j < angles.size(); ++j) {
    const double step = std::fmod(std::fmod(angles[j] - angles[j - 1], 2 * kPi) + 2 * kPi, 2 * kPi);
    ccw += step;
    cw += step > 0.0 ? 2 * kPi - step : 0.0;
  }
  if (std::min(ccw, cw) >= 2 * kPi) return std::nullopt;
  if (ccw <= cw) return std::array<double, 2>{angles.front(), angles.front() + ccw};
  return std::array<double, 2>{angles.front() - cw, angles.front()};
}

// (L31): the worst transmission angle over θ ∈ [lo, hi] in closed form. |AB0|² = a² + d² −
// 2ad cos(θ − θ_g) and cos μ = (b² + c² − |AB0|²)/(2bc) are monotone between the endpoints and
// the interior extremes θ_g + kπ, so min(μ, π − μ) is least at one of those; nullopt when the loop
// cannot close at one (it does not assemble on the whole interval).
std::optional<double> worst_transmission(const FourBar& fb, double lo, double hi) {
  const double d = ground_length(fb), tg = ground_angle(fb);
  std::vector<double> at{lo, hi};
  for (double t = tg + kPi * std::ceil((lo - tg) / kPi); t < hi; t += kPi) at.push_back(t);
  double worst = kPi / 2;
  for (const double t : at) {
    const double e2 = fb.a * fb.a + d * d - 2 * fb.a * d * std::cos(t - tg);
    const double cos_mu = (fb.b * fb.b + fb.c * fb.c - e2) / (2 * fb.b * fb.c);
    if (!(std::abs(cos_mu) <= 1.0)) return std::nullopt;
    const double mu = std::acos(cos_mu);
    worst = std::min(worst, std::min(mu, kPi - mu));
  }
  return worst;
}

// A pair's cheap score (L31): all four poses met on the linkage's branch (find_pose), the task's
// Grashof requirement, the poses reached in order within a turn, assembled all the way; the worst
// transmission angle over that motion.
std::optional<double> pair_score(const std::vector<Pose>& poses, const Dyad& crank,
                                 const Dyad& follower, double spread, bool crank_rocker) {
  if ((crank.fixed_pivot - follower.fixed_pivot).norm() <= 1e-9 * spread ||
      (crank.moving_pivot - follower.moving_pivot).norm() <= 1e-9 * spread)
    return std::nullopt;
  const FourBar fb = four_bar_from_dyads(crank, follower, poses.front());
  if (crank_rocker && classify_grashof(fb) != GrashofType::crank_rocker) return std::nullopt;
  std::vector<double> angles;
  for (const Pose& p : poses) {
    const PoseMatch m = find_pose(fb, p);
    if (!m.assembles || m.branch != fb.branch || m.position_error > kPoseCheck * spread ||
        m.angle_error > kPoseCheck)
      return std::nullopt;
    angles.push_back(m.crank_angle);
  }
  const auto interval = crank_interval(angles);
  if (!interval) return std::nullopt;
  return worst_transmission(fb, (*interval)[0], (*interval)[1]);
}

struct ScoredPair {
  double score = 0.0;
  std::size_t crank = 0, follower = 0;  // into the crank's and the follower's choices
};

bool same_four_bar(const Dyad& c1, const Dyad& f1, const Dyad& c2, const Dyad& f2, double tol) {
  return (c1.fixed_pivot - c2.fixed_pivot).norm() < tol &&
         (f1.fixed_pivot - f2.fixed_pivot).norm() < tol &&
         (c1.moving_pivot - c2.moving_pivot).norm() < tol &&
         (f1.moving_pivot - f2.moving_pivot).norm() < tol;
}

MotionSynthesisResult four_poses(const std::vector<Pose>& poses, const GivenPivots& crank,
                                 const GivenPivots& follower, const FewPoseOptions& o) {
  MotionSynthesisResult r;
  const Normalised n = normalise(poses);
  const double spread = n.scale;
  const double tolerance = o.pivot_tolerance > 0.0 ? o.pivot_tolerance : kPivotTolerance * spread;
  // Step 1: each dyad's choices: its given pivot on its curve (L29, L30), or the sampled curve.
  std::vector<Dyad> curve;
  const bool any_free = !(crank.fixed_pivot || crank.moving_pivot) ||
                        !(follower.fixed_pivot || follower.moving_pivot);
  if (any_free) {
    const CentrePointCurve c = sample_centre_point_curve(poses, o.rays);
    if (c.status != SynthesisStatus::ok) {
      r.message = "4 poses: " + c.message;
      return r;
    }
    for (const Dyad& d : c.points)
      if ((d.fixed_pivot - n.centre).norm() <= o.box * spread &&
          d.moving_pivot.norm() <= o.box * spread && std::isfinite(d.radius))
        curve.push_back(d);
  }
  std::array<std::vector<Dyad>, 2> choices;
  std::string given_note;
  for (int role = 0; role < 2; ++role) {
    const GivenPivots& g = role == 0 ? crank : follower;
    if (!g.fixed_pivot && !g.moving_pivot) {
      choices[static_cast<std::size_t>(role)] = curve;
      continue;
    }
    const DyadOutcome d = dyad_on_curve(poses, g, role, tolerance, o);
    if (!d.ok) {
      r.message = d.message;
      return r;
    }
    given_note += "; " + d.message;
    choices[static_cast<std::size_t>(role)] = {d.dyad};
  }
  // Step 2: every pair scored by the closed form (L31). Both free: unordered pairs of distinct
  // curve points, the shorter radius the crank (as for 5 poses).
  const bool both_free = !(crank.fixed_pivot || crank.moving_pivot) &&
                         !(follower.fixed_pivot || follower.moving_pivot);
  std::vector<ScoredPair> scored;
  for (std::size_t i = 0; i < choices[0].size(); ++i)
    for (std::size_t j = both_free ? i + 1 : 0; j < choices[1].size(); ++j) {
      std::size_t ic = i, jf = j;
      if (both_free && choices[0][i].radius > choices[1][j].radius) std::swap(ic, jf);
      const auto s =
          pair_score(poses, choices[0][ic], choices[1][jf], spread, o.require_crank_rocker);
      if (s) scored.push_back({*s, ic, jf});
    }
  if (scored.empty()) {
    r.message = "4 poses: no pair of dyads" + given_note +
                " meets the poses on one branch in their order and assembles between them" +
                (o.require_crank_rocker ? " as a crank-rocker" : "");
    return r;
  }
  // Step 3: the best distinct pairs, each dyad polished (L32) and checked by find_pose (L19).
  std::stable_sort(scored.begin(), scored.end(),
                   [](const ScoredPair& x, const ScoredPair& y) { return x.score > y.score; });
  std::vector<ScoredPair> kept;
  for (const ScoredPair& s : scored) {
    if (static_cast<int>(kept.size()) >= o.max_candidates) break;
    bool same = false;
    for (const ScoredPair& k : kept)
      same = same || same_four_bar(choices[0][s.crank], choices[1][s.follower], choices[0][k.crank],
                                   choices[1][k.follower], kSameFourBar * spread);
    if (!same) kept.push_back(s);
  }
  double residual = 0.0;
  for (const ScoredPair& s : kept) {
    r.dyads.push_back(polish(poses, choices[0][s.crank]));
    r.dyads.push_back(polish(poses, choices[1][s.follower]));
    const int k = static_cast<int>(r.dyads.size());
    residual = std::max({residual, r.dyads[r.dyads.size() - 2].residual, r.dyads.back().residual});
    r.candidates.push_back(candidate_of(poses, r.dyads, k - 2, k - 1));
  }
  r.status = SynthesisStatus::ok;
  r.message = "4 poses: " + std::to_string(scored.size()) + " pairs meet the poses; the best " +
              std::to_string(kept.size()) +
              " distinct kept (largest radius deviation after the polish " +
              length_text(residual, o) + ")" + given_note;
  return r;
}

}  // namespace

MotionSynthesisResult synthesize_motion_few_poses(const std::vector<Pose>& poses,
                                                  const GivenPivots& crank,
                                                  const GivenPivots& follower,
                                                  const FewPoseOptions& options) {
  if (poses.size() < 2 || poses.size() > 4)
    throw std::invalid_argument(
        "synthesize_motion_few_poses: needs 2 to 4 poses, got " + std::to_string(poses.size()) +
        (poses.size() >= 5 ? " (5 poses give finitely many dyads, the Burmester points, so no "
                             "pivot can be given: synthesize_motion_generator)"
                           : ""));
  if (options.rays < 1 || options.max_candidates < 1 || !(options.box > 0.0) ||
      !(options.unit > 0.0) || !(options.pivot_tolerance >= 0.0))
    throw std::invalid_argument(
        "synthesize_motion_few_poses: options need rays ≥ 1, max_candidates ≥ 1, box > 0, unit > "
        "0, pivot_tolerance ≥ 0");
  check_given(poses.size(), crank, 0);
  check_given(poses.size(), follower, 1);
  if (poses.size() == 4) return four_poses(poses, crank, follower, options);
  return two_or_three_poses(poses, crank, follower);
}

}  // namespace orthomech::synthesis
