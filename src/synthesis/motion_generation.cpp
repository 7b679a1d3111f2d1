#include "orthomech/synthesis/motion_generation.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <optional>

#include "../solvers/nlopt_minimize.hpp"
#include "burmester_rows.hpp"
#include "orthomech/check.hpp"

namespace orthomech::synthesis {

namespace {

using detail::circle_point_of;
using detail::compatibility_row;
using detail::cross;
using detail::Mat2;
using detail::normalise;
using detail::Normalised;
using detail::perp;
using detail::rotation;
using detail::to_world;
constexpr double kPi = std::numbers::pi;
// Relative size (to the poses' spread) below which two positions coincide or three are collinear.
constexpr double kDegenerate = 1e-12;
// Newton on (L14) in normalised units (spread 1): converged below this residual of g_j.
constexpr double kNewtonTolerance = 1e-10;
// Two dyads are the same when their pivots differ by less than this (relative, normalised units).
constexpr double kSameDyad = 1e-7;
// Rotation |sin(Δθ/2)| below which a displacement is a translation (its pole at infinity).
constexpr double kTranslation = 1e-9;

// The centre of the circle through 2 or 3 points (the shared step of (L15a) and (L15b)).
ConjugatePivot circumcentre(const std::vector<Vec2>& pts, double scale) {
  ConjugatePivot out;
  const Vec2 d2 = pts[1] - pts[0];
  if (d2.norm() <= kDegenerate * scale) {
    out.message = "the pivot's positions coincide: it is the pole of the displacement";
    return out;
  }
  if (pts.size() == 2) {  // the perpendicular bisector
    out.status = SynthesisStatus::ok;
    out.message = "ok";
    out.point = 0.5 * (pts[0] + pts[1]);
    out.direction = perp(d2).normalized();
    return out;
  }
  const Vec2 d3 = pts[2] - pts[0];
  const double det = cross(d2, d3);
  if (std::abs(det) <= kDegenerate * d2.norm() * d3.norm() || d3.norm() <= kDegenerate * scale) {
    out.message = "the pivot's three positions are collinear: the conjugate pivot is at infinity";
    return out;
  }
  // (Z_j − Z_1)·y = ½|Z_j − Z_1|², m = Z_1 + y (Cramer).
  const double r2 = 0.5 * d2.squaredNorm(), r3 = 0.5 * d3.squaredNorm();
  const Vec2 y((r2 * d3.y() - r3 * d2.y()) / det, (d2.x() * r3 - d3.x() * r2) / det);
  out.status = SynthesisStatus::ok;
  out.message = "ok";
  out.point = pts[0] + y;
  return out;
}

double pose_spread(const std::vector<Pose>& poses) { return normalise(poses).scale; }

// The pole of the displacement from pose 0 to pose k (normalised): P_0 + R_0 x = P_k + R_k x.
Vec2 pole_of(const Normalised& n, std::size_t k) {
  const Vec2 x = (n.R[0] - n.R[k]).colPivHouseholderQr().solve(n.P[k] - n.P[0]);
  return n.P[0] + n.R[0] * x;
}

// The pose k ∈ candidates whose displacement from pose 0 rotates most (its pole is finite).
std::optional<std::size_t> largest_rotation(const std::vector<Pose>& poses,
                                            const std::vector<std::size_t>& candidates) {
  std::size_t best = candidates.front();
  double best_s = -1.0;
  for (const std::size_t k : candidates) {
    const double s = std::abs(std::sin(0.5 * (poses[k].angle - poses[0].angle)));
    if (s > best_s) best_s = s, best = k;
  }
  if (best_s < kTranslation) return std::nullopt;
  return best;
}

// det(C0 + t C1) = c0 + c1 t + c2 t² + c3 t³ for 3 × 3 matrices (columns mixed by subsets).
Eigen::Vector4d det_cubic(const Eigen::Matrix3d& C0, const Eigen::Matrix3d& C1) {
  Eigen::Vector4d c = Eigen::Vector4d::Zero();
  for (int mask = 0; mask < 8; ++mask) {  // column i from C1 when bit i is set
    Eigen::Matrix3d M;
    int ones = 0;
    for (int i = 0; i < 3; ++i) {
      const bool from1 = ((mask >> i) & 1) != 0;
      M.col(i) = from1 ? C1.col(i) : C0.col(i);
      ones += from1 ? 1 : 0;
    }
    c(ones) += M.determinant();
  }
  return c;
}

// The quadratic left on the line m = pole + t u by rows `rows` after dividing out the pole's root
// t = 0 (L16): (c1, c2, c3) of the cubic, scaled to unit norm (a positive factor).
Eigen::Vector3d pencil_quadratic(const Normalised& n, const std::array<std::size_t, 3>& rows,
                                 const Vec2& pole, const Vec2& u) {
  Eigen::Matrix3d C0, Cu;
  for (int i = 0; i < 3; ++i) {
    C0.row(i) = compatibility_row(n, rows[static_cast<std::size_t>(i)], pole).transpose();
    Cu.row(i) = compatibility_row(n, rows[static_cast<std::size_t>(i)], pole + u).transpose();
  }
  const Eigen::Vector4d c = det_cubic(C0, Cu - C0);
  Eigen::Vector3d q(c(1), c(2), c(3));
  const double norm = q.norm();
  return norm > 0.0 ? Eigen::Vector3d(q / norm) : q;
}

// Real roots of q0 + q1 t + q2 t² (the stable formula; a linear equation when q2 ≈ 0).
std::vector<double> real_roots(const Eigen::Vector3d& q) {
  const double c = q(0), b = q(1), a = q(2);
  if (std::abs(a) <= 1e-14 * q.norm()) {
    if (std::abs(b) > 0.0) return {-c / b};
    return {};
  }
  const double disc = b * b - 4.0 * a * c;
  if (disc < 0.0) return {};
  const double s = -0.5 * (b + std::copysign(std::sqrt(disc), b));
  std::vector<double> t{s / a};
  if (s != 0.0) t.push_back(c / s);
  return t;
}

// Newton on g_2 … g_n of (L14) in (m, z) (square for 5 poses; Gauss–Newton otherwise).
bool polish_dyad(const Normalised& n, Vec2& m, Vec2& z) {
  const auto rows = static_cast<Eigen::Index>(n.P.size() - 1);
  Eigen::VectorXd g(rows);
  Eigen::MatrixXd J(rows, 4);
  for (int iter = 0; iter < 40; ++iter) {
    const Vec2 Z1 = n.P[0] + n.R[0] * z;
    for (Eigen::Index i = 0; i < rows; ++i) {
      const auto j = static_cast<std::size_t>(i + 1);
      const Vec2 Zj = n.P[j] + n.R[j] * z;
      g(i) = (Zj - m).squaredNorm() - (Z1 - m).squaredNorm();
      J.block<1, 2>(i, 0) = (-2.0 * (Zj - Z1)).transpose();
      J.block<1, 2>(i, 2) =
          (2.0 * (n.R[j].transpose() * (Zj - m) - n.R[0].transpose() * (Z1 - m))).transpose();
    }
    if (!g.allFinite()) return false;
    if (g.lpNorm<Eigen::Infinity>() < 1e-15) return true;
    const Eigen::Vector4d step = J.colPivHouseholderQr().solve(-g);
    m += step.head<2>();
    z += step.tail<2>();
    if (step.norm() < 1e-16 * (1.0 + m.norm() + z.norm())) break;
  }
  return g.lpNorm<Eigen::Infinity>() < kNewtonTolerance;
}

void add_unique(std::vector<std::array<Vec2, 2>>& found, const Vec2& m, const Vec2& z) {
  for (const auto& f : found)
    if ((f[0] - m).norm() + (f[1] - z).norm() < kSameDyad * (1.0 + m.norm() + z.norm())) return;
  found.push_back({m, z});
}

// The resultant of two quadratics (q0 + q1 t + q2 t²): zero iff they share a root.
double resultant(const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
  const double a = p(2) * q(0) - p(0) * q(2);
  return a * a - (p(2) * q(1) - p(1) * q(2)) * (p(1) * q(0) - p(0) * q(1));
}

// The Burmester points of 5 poses (L17): along the pencil of lines through the pole P_1k common
// to the centre-point curves of poses {1,2,3,4} and {1,2,3,5}, a Burmester point is a common
// root of the two curves' pencil quadratics: a zero of their resultant ρ(α), α the line's
// angle. Zeros (sign changes, bisected) and local minima of |ρ| seed Newton on (L14).
std::vector<std::array<Vec2, 2>> burmester_points(const Normalised& n, std::size_t k, int rays) {
  const Vec2 pole = pole_of(n, k);
  const std::array<std::size_t, 3> rows_a{1, 2, 3}, rows_b{1, 2, 4};
  const auto rho = [&](double alpha) {
    const Vec2 u(std::cos(alpha), std::sin(alpha));
    return resultant(pencil_quadratic(n, rows_a, pole, u), pencil_quadratic(n, rows_b, pole, u));
  };
  // Step 1: ρ on the pencil; the seeds are sign changes (bisected) and minima of |ρ|.
  std::vector<double> values(static_cast<std::size_t>(rays) + 1), seeds;
  for (int i = 0; i <= rays; ++i) values[static_cast<std::size_t>(i)] = rho(kPi * i / rays);
  for (int i = 0; i < rays; ++i) {
    double lo = kPi * i / rays, hi = kPi * (i + 1) / rays;
    const double vlo = values[static_cast<std::size_t>(i)];
    const double vhi = values[static_cast<std::size_t>(i) + 1];
    const double vprev = values[static_cast<std::size_t>(i == 0 ? rays - 1 : i - 1)];
    if (std::abs(vlo) <= std::abs(vprev) && std::abs(vlo) <= std::abs(vhi)) seeds.push_back(lo);
    if ((vlo < 0.0) == (vhi < 0.0)) continue;
    for (int it = 0; it < 60; ++it) {
      const double mid = 0.5 * (lo + hi);
      ((rho(mid) < 0.0) == (vlo < 0.0) ? lo : hi) = mid;
    }
    seeds.push_back(0.5 * (lo + hi));
  }
  // Step 2: every real root of either quadratic on a seed line starts Newton on (L14).
  std::vector<std::array<Vec2, 2>> found;
  const std::vector<std::size_t> all{1, 2, 3, 4};
  for (const double alpha : seeds) {
    const Vec2 u(std::cos(alpha), std::sin(alpha));
    for (const auto& rows : {rows_a, rows_b})
      for (const double t : real_roots(pencil_quadratic(n, rows, pole, u))) {
        Vec2 m = pole + t * u;
        Vec2 z = circle_point_of(n, all, m);
        if (polish_dyad(n, m, z)) add_unique(found, m, z);
      }
  }
  return found;
}

// (L18): E(m, z) = (1/n) Σ_j (|Z_j − m|² − ρ²)², ρ² the mean of |Z_j − m|² (its minimiser).
double least_squares_objective(const Normalised& n, const Eigen::VectorXd& x) {
  const Vec2 m = x.head<2>(), z = x.tail<2>();
  const auto r2 = [&](std::size_t j) { return (n.P[j] + n.R[j] * z - m).squaredNorm(); };
  const auto count = static_cast<double>(n.P.size());
  double mean = 0.0;  // two passes: no cancellation near E = 0
  for (std::size_t j = 0; j < n.P.size(); ++j) mean += r2(j) / count;
  double E = 0.0;
  for (std::size_t j = 0; j < n.P.size(); ++j) E += (r2(j) - mean) * (r2(j) - mean) / count;
  return E;
}

// The dyads of (L18): the distinct local minima of a multistart search, best first.
std::vector<std::array<Vec2, 2>> least_squares_dyads(const Normalised& n,
                                                     const MotionSynthesisOptions& options) {
  const auto f = [&n](const Eigen::VectorXd& x) { return least_squares_objective(n, x); };
  solvers::MultistartSettings settings;
  settings.starts = options.starts;
  settings.seed = options.seed;
  settings.local.max_evaluations = 4000;
  settings.local.xtol_abs = 1e-13;
  const Eigen::VectorXd hi = Eigen::VectorXd::Constant(4, options.box);
  const solvers::MultistartOutcome out = minimize_multistart(f, -hi, hi, settings);
  std::vector<const solvers::NloptOutcome*> runs;
  for (const auto& r : out.locals)
    if (r.kind == solvers::NloptOutcomeKind::converged ||
        r.kind == solvers::NloptOutcomeKind::max_evaluations ||
        r.kind == solvers::NloptOutcomeKind::roundoff)
      runs.push_back(&r);
  std::sort(runs.begin(), runs.end(), [](auto* x, auto* y) { return x->value < y->value; });
  std::vector<std::array<Vec2, 2>> found;
  for (const auto* r : runs) {
    if (static_cast<int>(found.size()) >= options.max_dyads) break;
    Vec2 m = r->x.head<2>(), z = r->x.tail<2>();
    // A Gauss–Newton polish on (L14), kept only when it lowers E (exact data: E → 0).
    Vec2 pm = m, pz = z;
    polish_dyad(n, pm, pz);
    Eigen::Vector4d xp;
    xp << pm, pz;
    if (xp.allFinite() && least_squares_objective(n, xp) <= r->value) m = pm, z = pz;
    bool same = false;
    for (const auto& d : found) same = same || (d[0] - m).norm() + (d[1] - z).norm() < 1e-4;
    if (!same) found.push_back({m, z});
  }
  return found;
}

// Every pair of distinct dyads, the shorter radius as the crank, checked pose by pose (L19).
void build_candidates(const std::vector<Pose>& poses, MotionSynthesisResult& r) {
  const double spread = pose_spread(poses);
  for (std::size_t k = 0; k < r.dyads.size(); ++k)
    for (std::size_t l = k + 1; l < r.dyads.size(); ++l) {
      const bool k_crank = r.dyads[k].radius <= r.dyads[l].radius;
      const std::size_t ic = k_crank ? k : l, jf = k_crank ? l : k;
      const Dyad &crank = r.dyads[ic], &follower = r.dyads[jf];
      if ((crank.fixed_pivot - follower.fixed_pivot).norm() <= kDegenerate * spread ||
          (crank.moving_pivot - follower.moving_pivot).norm() <= kDegenerate * spread)
        continue;
      MotionCandidate cand;
      cand.linkage = four_bar_from_dyads(crank, follower, poses.front());
      cand.crank_dyad = static_cast<int>(ic);
      cand.follower_dyad = static_cast<int>(jf);
      for (const Pose& p : poses) {
        const PoseMatch match = find_pose(cand.linkage, p);
        cand.crank_angles.push_back(match.crank_angle);
        cand.max_position_error = std::max(cand.max_position_error, match.position_error);
        cand.max_angle_error = std::max(cand.max_angle_error, match.angle_error);
        cand.branch_defect = cand.branch_defect || match.branch != cand.linkage.branch;
      }
      r.candidates.push_back(std::move(cand));
    }
}

}  // namespace

ConjugatePivot calc_centre_point(const std::vector<Pose>& poses, const Vec2& circle_point) {
  check_argument(poses.size() == 2 || poses.size() == 3, "calc_centre_point", "poses",
                 "needs 2 or 3 poses");
  std::vector<Vec2> Z;  // (L15a): the moving pivot's world positions Z_j = P_j + R(θ_j) z
  Z.reserve(poses.size());
  for (const Pose& p : poses) Z.emplace_back(p.position + rotation(p.angle) * circle_point);
  return circumcentre(Z, pose_spread(poses) + circle_point.norm());
}

ConjugatePivot calc_circle_point(const std::vector<Pose>& poses, const Vec2& centre_point) {
  check_argument(poses.size() == 2 || poses.size() == 3, "calc_circle_point", "poses",
                 "needs 2 or 3 poses");
  std::vector<Vec2> w;  // (L15b): the fixed pivot seen from the body, R(θ_j)ᵀ(m − P_j)
  w.reserve(poses.size());
  for (const Pose& p : poses)
    w.emplace_back(rotation(p.angle).transpose() * (centre_point - p.position));
  return circumcentre(w, pose_spread(poses) + centre_point.norm());
}

// The centre-point curve of 4 poses (L16) [Sandor & Erdman 1984, ch. 2; McCarthy & Soh
// 2011, ch. 4]: det C(m) = 0 with C's rows (a_j(m)ᵀ, c_j(m)), j = 2, 3, 4. On the line m = P_1k + t
// u the entries are affine in t, det C is a cubic with the root t = 0 (the pole is on the curve);
// the other two roots are curve points, each with its circle point from the (compatible) rows.
CentrePointCurve sample_centre_point_curve(const std::vector<Pose>& poses, int rays) {
  check_argument(poses.size() == 4, "sample_centre_point_curve", "poses", "needs exactly 4 poses");
  check_argument(rays >= 1, "sample_centre_point_curve", "rays", "must be at least 1");
  CentrePointCurve out;
  const Normalised n = normalise(poses);
  const auto k = largest_rotation(poses, {1, 2, 3});
  if (!k) {
    out.message = "the poses differ by translations only: the poles are at infinity";
    return out;
  }
  const Vec2 pole = pole_of(n, *k);
  out.pole = n.centre + n.scale * pole;
  const std::array<std::size_t, 3> rows{1, 2, 3};
  const std::vector<std::size_t> row_list{1, 2, 3};
  for (int i = 0; i < rays; ++i) {
    const double alpha = kPi * i / rays;
    const Vec2 u(std::cos(alpha), std::sin(alpha));
    for (const double t : real_roots(pencil_quadratic(n, rows, pole, u))) {
      const Vec2 m = pole + t * u;
      out.points.push_back(to_world(poses, n, m, circle_point_of(n, row_list, m)));
    }
  }
  out.status = out.points.empty() ? SynthesisStatus::no_linkage : SynthesisStatus::ok;
  out.message = out.points.empty() ? "no real point on the sampled lines" : "ok";
  return out;
}

// (L20): the crank A0 → A = crank.moving_pivot, the follower B0 → B = follower.moving_pivot; the
// coupler frame's x axis is z_B − z_A at the angle β_b in the body frame, so the body's origin is
// at R(−β_b)(−z_A) in the coupler frame and its angle relative to A→B is −β_b.
FourBar four_bar_from_dyads(const Dyad& crank, const Dyad& follower, const Pose& reference) {
  FourBar fb;
  fb.A0 = crank.fixed_pivot;
  fb.B0 = follower.fixed_pivot;
  fb.a = crank.radius;
  fb.c = follower.radius;
  const Vec2 ab = follower.moving_pivot - crank.moving_pivot;
  fb.b = ab.norm();
  const double beta_b = std::atan2(ab.y(), ab.x());
  fb.coupler_point = rotation(-beta_b) * (-crank.moving_pivot);
  fb.coupler_frame_angle = -beta_b;
  const Mat2 R = rotation(reference.angle);
  const Vec2 A = reference.position + R * crank.moving_pivot;
  const Vec2 B = reference.position + R * follower.moving_pivot;
  fb.branch = cross(fb.B0 - A, B - A) >= 0.0 ? 1 : -1;
  return fb;
}

// (L19): the coupler angle in the pose is β = θ_pose − coupler_frame_angle, so A = P_pose −
// R(β)(p, q) and the crank angle is arg(A − A0); the branch whose calc_position is nearer wins.
PoseMatch find_pose(const FourBar& linkage, const Pose& pose) noexcept {
  PoseMatch best;
  const double beta = pose.angle - linkage.coupler_frame_angle;
  const Vec2 A = pose.position - rotation(beta) * linkage.coupler_point;
  const Vec2 r = A - linkage.A0;
  const double theta = std::atan2(r.y(), r.x());
  const double length = std::max({linkage.b, linkage.a, 1e-300});
  double best_score = HUGE_VAL;
  for (const int branch : {linkage.branch, -linkage.branch}) {
    const FourBarPosition pos = calc_position(linkage, theta, branch);
    const double dp = (pos.P - pose.position).norm();
    const double da = std::abs(std::remainder(pos.frame_angle - pose.angle, 2.0 * kPi));
    const double score = dp + length * da;
    if (score < best_score) {
      best_score = score;
      best = {pos.assembles, theta, branch, dp, da};
    }
  }
  return best;
}

MotionSynthesisResult synthesize_motion_generator(const std::vector<Pose>& poses,
                                                  const MotionSynthesisOptions& options) {
  check_argument(poses.size() >= 5, "synthesize_motion_generator", "poses",
                 "needs at least 5 poses (2–4: synthesize_motion_few_poses)");
  check_argument(options.rays >= 8 && options.starts >= 1 && options.box > 0.0,
                 "synthesize_motion_generator", "options", "needs rays ≥ 8, starts ≥ 1, box > 0");
  MotionSynthesisResult r;
  const Normalised n = normalise(poses);
  // Step 1: the dyads, exact (5 poses, L17) or fitted (more, L18).
  std::vector<std::array<Vec2, 2>> found;
  if (poses.size() == 5) {
    const auto k = largest_rotation(poses, {1, 2});
    if (!k) {
      r.message = "poses 1–3 differ by translations only: the pencil's pole is at infinity";
      return r;
    }
    found = burmester_points(n, *k, options.rays);
  } else {
    found = least_squares_dyads(n, options);
  }
  for (const auto& f : found) r.dyads.push_back(to_world(poses, n, f[0], f[1]));
  // Step 2: the four-bars, each checked by the closed form (L19).
  build_candidates(poses, r);
  if (r.candidates.empty()) {
    r.message = std::to_string(r.dyads.size()) + " real dyad(s): no pair forms a four-bar";
    return r;
  }
  r.status = SynthesisStatus::ok;
  r.message = std::to_string(r.dyads.size()) + " dyads, " + std::to_string(r.candidates.size()) +
              " four-bars";
  return r;
}

}  // namespace orthomech::synthesis
