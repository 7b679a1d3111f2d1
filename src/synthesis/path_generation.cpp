#include "orthomech/synthesis/path_generation.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "../solvers/nlopt_minimize.hpp"
#include "levenberg_marquardt.hpp"
#include "orthomech/check.hpp"

namespace orthomech::synthesis {

namespace {

constexpr double kPi = std::numbers::pi;
// The crank-rocker requirement holds with this margin (normalised units) so that the result
// classifies as a crank-rocker, not a change point.
constexpr double kGrashofMargin = 1e-5;
// The loop must close with this slack (normalised units) at every target: a quadratic penalty
// lets a constraint be violated by about |∇F| / w, so the margin keeps the optimum assembled.
constexpr double kAssemblyMargin = 1e-5;
// The shortest link a world box allows (normalised units), so that a box from 0 keeps links
// positive.
constexpr double kMinWorldLink = 1e-6;

// Where each variable sits in the decision vector x (−1: not a variable).
struct Layout {
  int A0 = -1, ground_angle = -1, d = -1, a = -1, b = -1, c = -1, p = -1, q = -1;
  int start = -1, increments = -1;  // θ_0; δ_2 … δ_N
  int size = 0;
};

// The problem in normalised units (targets about their centroid, divided by their RMS spread).
struct Problem {
  std::vector<Vec2> T;
  std::vector<double> phi;
  PathTiming timing = PathTiming::prescribed;
  std::optional<Vec2> A0;
  std::optional<double> ground_angle;
  bool crank_rocker = false;
  int branch = 1;
  double sense = 1.0;
  double sqrt_w = 1.0;
  Layout L;
  Vec2 centre = Vec2::Zero();
  double scale = 1.0;
};

Layout make_layout(const Problem& pb) {
  Layout L;
  int k = 0;
  if (!pb.A0) L.A0 = k, k += 2;
  if (!pb.ground_angle) L.ground_angle = k++;
  L.d = k++, L.a = k++, L.b = k++, L.c = k++, L.p = k++, L.q = k++;
  if (pb.timing != PathTiming::prescribed) L.start = k++;
  if (pb.timing == PathTiming::free) L.increments = k, k += static_cast<int>(pb.T.size()) - 1;
  L.size = k;
  return L;
}

// The linkage of x (normalised): the variables before the timing's.
FourBar decode_linkage(const Problem& pb, const Eigen::VectorXd& x) {
  const Layout& L = pb.L;
  FourBar fb;
  fb.A0 = pb.A0 ? *pb.A0 : Vec2(x(L.A0), x(L.A0 + 1));
  const double tg = pb.ground_angle ? *pb.ground_angle : x(L.ground_angle);
  fb.B0 = fb.A0 + x(L.d) * Vec2(std::cos(tg), std::sin(tg));
  fb.a = x(L.a), fb.b = x(L.b), fb.c = x(L.c);
  fb.coupler_point = Vec2(x(L.p), x(L.q));
  fb.branch = pb.branch;
  return fb;
}

// The linkage of x (normalised) and its crank angles θ_i (L24).
FourBar decode(const Problem& pb, const Eigen::VectorXd& x, std::vector<double>& theta) {
  const Layout& L = pb.L;
  FourBar fb = decode_linkage(pb, x);
  const double tg = pb.ground_angle ? *pb.ground_angle : x(L.ground_angle);
  const std::size_t n = pb.T.size();
  if (pb.timing == PathTiming::free) {
    double t = x(L.start);
    for (std::size_t i = 0; i < n; ++i) {
      if (i > 0) t += pb.sense * x(L.increments + static_cast<int>(i) - 1);
      theta[i] = t;
    }
  } else {
    const double t0 = pb.timing == PathTiming::prescribed_free_start ? x(L.start) : 0.0;
    for (std::size_t i = 0; i < n; ++i) theta[i] = tg + t0 + pb.phi[i];
  }
  return fb;
}

// The residual vector of (L21): coupler-point misses (2N), √w · closure-slack deficits (N), √w ·
// the crank-rocker violations (2, (L22)), √w · the timing's excess over a turn (1).
int residual_count(const Problem& pb) { return 3 * static_cast<int>(pb.T.size()) + 3; }

// The crank-rocker violations of (L22) (zero when not required): a shortest and s + l ≤ p + q,
// i.e. a + 2l − (b + c + d) ≤ 0, each with the margin.
Vec2 crank_rocker_violations(const Problem& pb, const Eigen::VectorXd& x, const FourBar& fb) {
  if (!pb.crank_rocker) return Vec2::Zero();
  const double d = x(pb.L.d);
  const double l = std::max({fb.b, fb.c, d});
  return {std::max(0.0, fb.a + 2.0 * l - (fb.b + fb.c + d) + kGrashofMargin),
          std::max(0.0, fb.a - std::min({fb.b, fb.c, d}) + kGrashofMargin)};
}

void residuals(const Problem& pb, const Eigen::VectorXd& x, std::vector<double>& theta,
               Eigen::VectorXd& r) {
  const FourBar fb = decode(pb, x, theta);
  const auto n = static_cast<Eigen::Index>(pb.T.size());
  for (Eigen::Index i = 0; i < n; ++i) {
    const FourBarPosition pos = calc_position(fb, theta[static_cast<std::size_t>(i)]);
    r.segment<2>(2 * i) = pos.P - pb.T[static_cast<std::size_t>(i)];
    // Slack of the loop closure: min(b + c − e, e − |b − c|) with e = |A B0| (> 0 inside).
    const double e = (fb.B0 - pos.A).norm();
    const double slack = std::min(fb.b + fb.c - e, e - std::abs(fb.b - fb.c));
    r(2 * n + i) = pb.sqrt_w * std::max(0.0, kAssemblyMargin - slack);
  }
  const Vec2 v = crank_rocker_violations(pb, x, fb);
  const double v1 = v(0), v2 = v(1);
  double excess = 0.0;
  if (pb.timing == PathTiming::free)
    excess = std::max(0.0, std::abs(theta.back() - theta.front()) - 2.0 * kPi);
  r(3 * n) = pb.sqrt_w * v1;
  r(3 * n + 1) = pb.sqrt_w * v2;
  r(3 * n + 2) = pb.sqrt_w * excess;
}

// The search box (normalised) and the narrower box the starts are drawn from (the increments
// start within an even share of one turn).
void make_boxes(const Problem& pb, const PathSynthesisOptions& o, Eigen::VectorXd& lo,
                Eigen::VectorXd& hi, Eigen::VectorXd& start_hi) {
  const Layout& L = pb.L;
  lo.resize(L.size);
  hi.resize(L.size);
  if (o.world_box) {  // the box in world units, normalised like the targets
    const PathSynthesisOptions::WorldBox& w = *o.world_box;
    for (int k = 0; L.A0 >= 0 && k < 2; ++k) {
      lo(L.A0 + k) = (w.pivot_lo - pb.centre(k)) / pb.scale;
      hi(L.A0 + k) = (w.pivot_hi - pb.centre(k)) / pb.scale;
    }
    for (const int i : {L.d, L.a, L.b, L.c})
      lo(i) = std::max(w.link_lo / pb.scale, kMinWorldLink), hi(i) = w.link_hi / pb.scale;
    for (const int i : {L.p, L.q}) lo(i) = w.coupler_lo / pb.scale, hi(i) = w.coupler_hi / pb.scale;
  } else {
    if (L.A0 >= 0)
      lo.segment<2>(L.A0).setConstant(-o.pivot_box), hi.segment<2>(L.A0).setConstant(o.pivot_box);
    for (const int i : {L.d, L.a, L.b, L.c}) lo(i) = o.min_link, hi(i) = o.max_link;
    for (const int i : {L.p, L.q}) lo(i) = -o.max_coupler, hi(i) = o.max_coupler;
  }
  if (L.ground_angle >= 0) lo(L.ground_angle) = -kPi, hi(L.ground_angle) = kPi;
  if (L.start >= 0) lo(L.start) = -kPi, hi(L.start) = kPi;
  start_hi = hi;
  const auto inc = static_cast<int>(pb.T.size()) - 1;
  for (int k = 0; L.increments >= 0 && k < inc; ++k) {
    lo(L.increments + k) = 0.0;
    hi(L.increments + k) = 2.0 * kPi;
    start_hi(L.increments + k) = 2.0 * kPi / inc;
  }
}

using detail::levenberg_marquardt;  // (L23), levenberg_marquardt.hpp

// The polish of (L23): Levenberg–Marquardt on the residual vector of (L21).
Eigen::VectorXd polish(const Problem& pb, const Eigen::VectorXd& x, const Eigen::VectorXd& lo,
                       const Eigen::VectorXd& hi, int& evaluations) {
  std::vector<double> theta(pb.T.size());
  const auto res = [&](const Eigen::VectorXd& y, Eigen::VectorXd& r) {
    residuals(pb, y, theta, r);
  };
  return levenberg_marquardt(res, residual_count(pb), x, lo, hi, 200, evaluations);
}

// ---- the nearest-point start of free timing (L25) ----------------------------------------------
// The samples of the coupler curve per turn, and the golden-section steps refining each target's
// nearest point between the neighbours of its nearest sample.
constexpr int kCurveSamples = 48;
constexpr int kRefineSteps = 6;
// The Levenberg–Marquardt iterations on the curve distance of a fit and of a restart round.
constexpr int kCurveFitIterations = 100;
constexpr int kCurveHopIterations = 30;
// The curve distance of a linkage none of whose samples assembles (normalised units): far above
// any assembled fit, finite for BOBYQA.
constexpr double kNoCurve = 1e3;

bool nearest_start(const PathSynthesisOptions& o) {
  return o.timing == PathTiming::free && o.start == PathStart::nearest_point;
}

// The coupler curve of fb sampled at kCurveSamples crank angles over one turn.
struct CurveSamples {
  std::vector<Vec2> P;
  std::vector<char> assembles;
};

void sample_curve(const FourBar& fb, CurveSamples& cs) {
  cs.P.resize(kCurveSamples);
  cs.assembles.resize(kCurveSamples);
  for (int j = 0; j < kCurveSamples; ++j) {
    const FourBarPosition pos = calc_position(fb, 2.0 * kPi * j / kCurveSamples);
    cs.P[static_cast<std::size_t>(j)] = pos.P;
    cs.assembles[static_cast<std::size_t>(j)] = pos.assembles ? 1 : 0;
  }
}

// The crank angle of the point of fb's coupler curve nearest to T (its nearest sample refined by
// golden section within the neighbouring samples) and the squared distance; false when no sample
// assembles.
bool nearest_point(const FourBar& fb, const CurveSamples& cs, const Vec2& T, double& theta,
                   double& dist2) {
  int best = -1;
  dist2 = HUGE_VAL;
  for (int j = 0; j < kCurveSamples; ++j) {
    const auto u = static_cast<std::size_t>(j);
    if (cs.assembles[u] == 0) continue;
    const double e = (cs.P[u] - T).squaredNorm();
    if (e < dist2) dist2 = e, best = j;
  }
  if (best < 0) return false;
  const double h = 2.0 * kPi / kCurveSamples;
  theta = h * best;
  const auto g = [&](double t) {
    const FourBarPosition pos = calc_position(fb, t);
    return pos.assembles ? (pos.P - T).squaredNorm() : HUGE_VAL;
  };
  // Safeguarded Newton steps on g'(t) = 0 with central differences, kept within the bracket
  // [θ_j − h, θ_j + h] and only when g drops.
  double t = theta, gt = dist2;
  constexpr double kStep = 1e-4;
  for (int k = 0; k < kRefineSteps; ++k) {
    const double gp = g(t + kStep), gm = g(t - kStep);
    if (!std::isfinite(gp) || !std::isfinite(gm)) break;
    const double d1 = (gp - gm) / (2.0 * kStep), d2 = (gp - 2.0 * gt + gm) / (kStep * kStep);
    double dt = d2 > 0.0 ? -d1 / d2 : (d1 > 0.0 ? -h : h) / 4.0;
    const double t_new = std::clamp(t + dt, theta - h, theta + h);
    const double g_new = g(t_new);
    if (!(g_new < gt)) break;
    dt = t_new - t;
    t = t_new, gt = g_new;
    if (std::abs(dt) < 1e-10) break;
  }
  theta = t, dist2 = gt;
  return true;
}

// (L25) The curve-distance residuals over the linkage variables alone (the crank angles
// eliminated): each target's miss P(θ*_i) − T_i from its nearest point θ*_i of the coupler curve
// (2N), then √w · the crank-rocker violations (2); the nearest-point crank angles in theta.
int curve_residual_count(const Problem& pb) { return 2 * static_cast<int>(pb.T.size()) + 2; }

void curve_residuals(const Problem& pb, const Eigen::VectorXd& x, CurveSamples& cs,
                     std::vector<double>& theta, Eigen::VectorXd& r) {
  const FourBar fb = decode_linkage(pb, x);
  sample_curve(fb, cs);
  const auto n = static_cast<Eigen::Index>(pb.T.size());
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto u = static_cast<std::size_t>(i);
    double e = 0.0;
    if (!nearest_point(fb, cs, pb.T[u], theta[u], e)) {
      r.head(2 * n).setConstant(std::sqrt(kNoCurve));
      break;
    }
    r.segment<2>(2 * i) = calc_position(fb, theta[u]).P - pb.T[u];
  }
  r.tail<2>() = pb.sqrt_w * crank_rocker_violations(pb, x, fb);
}

// The full variable vector of a free timing from linkage variables and nearest-point crank
// angles, turning in pb.sense: θ_0 = θ*_1 wrapped to [−π, π), δ_k = s(θ*_k − θ*_(k−1)) mod 2π.
// False when the increments add up to more than one turn (the targets are not met in this
// order and sense within a turn).
bool timed_from_nearest(const Problem& pb, const Eigen::VectorXd& linkage,
                        const std::vector<double>& theta, Eigen::VectorXd& x) {
  const Layout& L = pb.L;
  x.resize(L.size);
  x.head(L.start) = linkage.head(L.start);
  x(L.start) = std::remainder(theta.front(), 2.0 * kPi);
  if (x(L.start) >= kPi) x(L.start) -= 2.0 * kPi;
  double total = 0.0;
  for (std::size_t i = 1; i < theta.size(); ++i) {
    double dk = std::fmod(pb.sense * (theta[i] - theta[i - 1]), 2.0 * kPi);
    if (dk < 0.0) dk += 2.0 * kPi;
    x(L.increments + static_cast<int>(i) - 1) = dk;
    total += dk;
  }
  return total <= 2.0 * kPi * (1.0 + 1e-9);
}

struct Run {
  Eigen::VectorXd x;
  double value = HUGE_VAL;
  int branch = 1;
  double sense = 1.0;
};

// One branch and turning sense: multistart BOBYQA (L23), every local result kept.
void search(Problem& pb, const PathSynthesisOptions& o, std::vector<Run>& runs, int& evaluations) {
  Eigen::VectorXd lo, hi, start_hi;
  make_boxes(pb, o, lo, hi, start_hi);
  // The objective with its own scratch, one per thread of the multistart.
  const auto f = [&pb] {
    return [&pb, theta = std::vector<double>(pb.T.size()),
            r = Eigen::VectorXd(residual_count(pb))](const Eigen::VectorXd& x) mutable {
      residuals(pb, x, theta, r);
      return r.squaredNorm();
    };
  };
  solvers::MultistartSettings s;
  s.starts = 0;
  s.seed = o.seed;
  s.threads = o.threads;
  s.share = o.share;
  s.local.max_evaluations = o.local_evaluations;
  s.local.xtol_abs = 1e-12;
  const Eigen::MatrixXd X = solvers::quasi_random_starts(lo, start_hi, o.starts, o.seed);
  for (Eigen::Index k = 0; k < X.cols(); ++k) s.extra_starts.emplace_back(X.col(k));
  const solvers::MultistartOutcome out = solvers::minimize_multistart(f, lo, hi, s);
  evaluations += out.evaluations;
  for (const auto& l : out.locals)
    if (std::isfinite(l.value)) runs.push_back({l.x, l.value, pb.branch, pb.sense});
}

// (L25) The nearest-point start of free timing, on one branch: multistart BOBYQA on the curve
// distance over the linkage variables (the crank angles eliminated), each local result refined
// by Levenberg–Marquardt on the curve-distance residuals; then, from each fit and in every
// turning sense asked for whose nearest-point timing stays within one turn, the polish of the
// full problem (L21) with the timing started at the nearest-point crank angles. A branch none of
// whose fits gives such a timing falls back to the quasi-random design.
void search_nearest(Problem& pb, const PathSynthesisOptions& o, const std::vector<double>& senses,
                    std::vector<Run>& runs, int& evaluations) {
  Eigen::VectorXd lo, hi, start_hi;
  make_boxes(pb, o, lo, hi, start_hi);
  const int nl = pb.L.start;  // the linkage variables
  const Eigen::VectorXd lo1 = lo.head(nl), hi1 = hi.head(nl);
  std::vector<double> theta(pb.T.size());
  CurveSamples cs;
  Eigen::VectorXd rc(curve_residual_count(pb));
  const auto res1 = [&](const Eigen::VectorXd& x, Eigen::VectorXd& r1) {
    curve_residuals(pb, x, cs, theta, r1);
  };
  const auto f1 = [&pb] {  // one per thread of the multistart, with its own scratch
    return [&pb, cs1 = CurveSamples(), theta1 = std::vector<double>(pb.T.size()),
            r1 = Eigen::VectorXd(curve_residual_count(pb))](const Eigen::VectorXd& x) mutable {
      curve_residuals(pb, x, cs1, theta1, r1);
      return r1.squaredNorm();
    };
  };
  solvers::MultistartSettings s1;
  s1.starts = 0;
  s1.seed = o.seed;
  s1.threads = o.threads;
  s1.share = o.share;
  s1.local.max_evaluations = o.local_evaluations;
  s1.local.xtol_abs = 1e-10;
  const Eigen::MatrixXd X = solvers::quasi_random_starts(lo1, hi1, o.starts, o.seed);
  for (Eigen::Index k = 0; k < X.cols(); ++k) s1.extra_starts.emplace_back(X.col(k));
  const solvers::MultistartOutcome fits = solvers::minimize_multistart(f1, lo1, hi1, s1);
  evaluations += fits.evaluations;
  // Each fit polished on the curve distance, its nearest-point timing computed once.
  std::vector<Eigen::VectorXd> linkages;
  std::vector<std::vector<double>> timings;
  for (const auto& fit : fits.locals) {
    if (!std::isfinite(fit.value)) continue;
    linkages.push_back(levenberg_marquardt(res1, curve_residual_count(pb), fit.x, lo1, hi1,
                                           kCurveFitIterations, evaluations));
    res1(linkages.back(), rc);  // its nearest-point crank angles
    timings.push_back(theta);
  }
  std::vector<double> th(pb.T.size());
  Eigen::VectorXd r(residual_count(pb));
  const std::size_t before = runs.size();
  for (const double sense : senses) {
    pb.sense = sense;
    for (std::size_t k = 0; k < linkages.size(); ++k) {
      Eigen::VectorXd x;
      if (!timed_from_nearest(pb, linkages[k], timings[k], x)) continue;
      x = polish(pb, x, lo, hi, evaluations);
      residuals(pb, x, th, r);
      if (std::isfinite(r.squaredNorm())) runs.push_back({x, r.squaredNorm(), pb.branch, pb.sense});
    }
  }
  if (runs.size() > before) return;
  for (const double sense : senses) {
    pb.sense = sense;
    search(pb, o, runs, evaluations);
  }
}

// (L23) The restart policy: `rounds` rounds of basin hopping from best. Each round moves every
// variable by a uniform step in ±restart_step·(hi − lo) (std::mt19937_64 seeded from options.seed
// and the stream, its bits mapped to [−1, 1) by hand so that the sequence is portable), runs
// BOBYQA and the polish from there and keeps the result when it lowers F. With the nearest-point
// start (L25) a round re-fits the moved linkage variables on the curve distance instead
// (Levenberg–Marquardt, kCurveHopIterations), re-times from the nearest points in best's sense
// and polishes the full problem.
void hop(Problem& pb, const PathSynthesisOptions& o, const Eigen::VectorXd& lo,
         const Eigen::VectorXd& hi, int rounds, unsigned long long stream, Run& best,
         int& evaluations) {
  std::mt19937_64 rng(o.seed + 0x9e3779b97f4a7c15ULL * (stream + 1));  // stream 0: as before
  const auto uniform = [&rng] {                                        // [−1, 1)
    return 2.0 * static_cast<double>(rng() >> 11) * 0x1.0p-53 - 1.0;
  };
  std::vector<double> theta(pb.T.size());
  Eigen::VectorXd r(residual_count(pb));
  solvers::NloptSettings local;
  local.max_evaluations = o.local_evaluations;
  local.xtol_abs = 1e-12;
  const bool curve_hop = nearest_start(o);
  CurveSamples cs;
  Eigen::VectorXd rc(curve_residual_count(pb));
  for (int k = 0; k < rounds; ++k) {
    pb.branch = best.branch, pb.sense = best.sense;
    Eigen::VectorXd x0 = best.x;
    for (Eigen::Index j = 0; j < x0.size(); ++j)
      x0(j) = std::clamp(x0(j) + o.restart_step * (hi(j) - lo(j)) * uniform(), lo(j), hi(j));
    if (curve_hop) {
      const int nl = pb.L.start;
      const Eigen::VectorXd lo1 = lo.head(nl), hi1 = hi.head(nl);
      const auto res1 = [&](const Eigen::VectorXd& y, Eigen::VectorXd& r1) {
        curve_residuals(pb, y, cs, theta, r1);
      };
      const Eigen::VectorXd y =
          levenberg_marquardt(res1, curve_residual_count(pb), Eigen::VectorXd(x0.head(nl)), lo1,
                              hi1, kCurveHopIterations, evaluations);
      res1(y, rc);
      Eigen::VectorXd x;
      if (!timed_from_nearest(pb, y, theta, x)) continue;
      x = polish(pb, x, lo, hi, evaluations);
      residuals(pb, x, theta, r);
      if (r.squaredNorm() < best.value) best.x = x, best.value = r.squaredNorm();
      continue;
    }
    const auto f = [&](const Eigen::VectorXd& x) {
      residuals(pb, x, theta, r);
      return r.squaredNorm();
    };
    const solvers::NloptOutcome out = solvers::minimize_bounded(f, x0, lo, hi, local);
    evaluations += out.evaluations;
    if (!std::isfinite(out.value)) continue;
    const Eigen::VectorXd x = polish(pb, out.x, lo, hi, evaluations);
    residuals(pb, x, theta, r);
    if (r.squaredNorm() < best.value) best.x = x, best.value = r.squaredNorm();
  }
}

Problem normalised_problem(const std::vector<Vec2>& targets, const PathSynthesisOptions& o) {
  Problem pb;
  for (const Vec2& t : targets) pb.centre += t;
  pb.centre /= static_cast<double>(targets.size());
  double spread = 0.0;
  for (const Vec2& t : targets) spread += (t - pb.centre).squaredNorm();
  spread = std::sqrt(spread / static_cast<double>(targets.size()));
  pb.scale = spread > 0.0 ? spread : 1.0;
  for (const Vec2& t : targets) pb.T.emplace_back((t - pb.centre) / pb.scale);
  pb.phi = o.crank_angles;
  pb.timing = o.timing;
  if (o.fixed_A0) pb.A0 = Vec2((*o.fixed_A0 - pb.centre) / pb.scale);
  pb.ground_angle = o.fixed_ground_angle;
  pb.crank_rocker = o.require_crank_rocker;
  pb.sqrt_w = std::sqrt(o.penalty_weight);
  pb.L = make_layout(pb);
  return pb;
}

void check_options(const std::vector<Vec2>& targets, const PathSynthesisOptions& o) {
  constexpr const char* fn = "synthesize_path_generator";
  check_argument(targets.size() >= 2, fn, "targets", "needs at least 2 points");
  check_argument(o.timing == PathTiming::free || o.crank_angles.size() == targets.size(), fn,
                 "options.crank_angles", "needs one angle per target for a timed problem");
  check_argument(
      o.pivot_box > 0.0 && o.max_coupler > 0.0 && o.min_link > 0.0 && o.max_link > o.min_link, fn,
      "options", "needs a non-empty search box");
  if (o.world_box) {
    const PathSynthesisOptions::WorldBox& w = *o.world_box;
    check_argument(w.pivot_lo < w.pivot_hi && w.link_lo >= 0.0 && w.link_lo < w.link_hi &&
                       w.coupler_lo < w.coupler_hi,
                   fn, "options.world_box", "needs a non-empty box with link_lo ≥ 0");
  }
  check_argument(o.starts >= 1 && o.local_evaluations >= 1, fn, "options",
                 "needs starts ≥ 1 and local_evaluations ≥ 1");
  check_argument(
      o.restarts >= 0 && o.restart_step > 0.0 && o.restart_step <= 1.0 && o.restart_candidates >= 1,
      fn, "options", "needs restarts ≥ 0, restart_step in (0, 1] and restart_candidates ≥ 1");
}

// The best run in world units, checked by calc_position.
PathSynthesisResult finish(const Problem& pb, const Run& best, const std::vector<Vec2>& targets,
                           const PathSynthesisOptions& o) {
  PathSynthesisResult res;
  std::vector<double> theta(pb.T.size());
  FourBar fb = decode(pb, best.x, theta);
  fb.A0 = pb.centre + pb.scale * fb.A0;
  fb.B0 = pb.centre + pb.scale * fb.B0;
  fb.a *= pb.scale, fb.b *= pb.scale, fb.c *= pb.scale;
  fb.coupler_point *= pb.scale;
  res.linkage = fb;
  res.crank_angles = theta;
  res.error = path_error(fb, targets, theta);
  res.assembles = true;
  for (std::size_t i = 0; i < targets.size(); ++i) {
    const FourBarPosition pos = calc_position(fb, theta[i]);
    res.assembles = res.assembles && pos.assembles;
    res.max_distance = std::max(res.max_distance, (pos.P - targets[i]).norm());
  }
  res.grashof = classify_grashof(fb);
  const bool type_ok = !o.require_crank_rocker || res.grashof == GrashofType::crank_rocker;
  res.status = res.assembles && type_ok ? SynthesisStatus::ok : SynthesisStatus::not_converged;
  res.message = res.status == SynthesisStatus::ok
                    ? "ok"
                    : (!res.assembles ? "the best linkage does not assemble at every target"
                                      : "the best linkage is not a crank-rocker");
  return res;
}

}  // namespace

double path_error(const FourBar& linkage, const std::vector<Vec2>& targets,
                  const std::vector<double>& crank_angles) {
  check_argument(targets.size() == crank_angles.size(), "path_error", "crank_angles",
                 "needs one angle per target");
  double e = 0.0;
  for (std::size_t i = 0; i < targets.size(); ++i)
    e += (calc_position(linkage, crank_angles[i]).P - targets[i]).squaredNorm();  // (L21)
  return e;
}

// Path synthesis (L21)–(L24): normalise, multistart BOBYQA on every branch and turning sense
// asked for, polish the best runs by Levenberg–Marquardt, map back and check by calc_position.
PathSynthesisResult synthesize_path_generator(const std::vector<Vec2>& targets,
                                              const PathSynthesisOptions& options) {
  check_options(targets, options);
  Problem pb = normalised_problem(targets, options);
  // Step 1: the global search per branch and turning sense.
  std::vector<Run> runs;
  int evaluations = 0;
  const std::vector<int> branches =
      options.branch == 0 ? std::vector<int>{1, -1} : std::vector<int>{options.branch};
  const bool untimed = options.timing == PathTiming::free;
  const std::vector<double> senses = !untimed || options.turning > 0 ? std::vector<double>{1.0}
                                     : options.turning < 0           ? std::vector<double>{-1.0}
                                                           : std::vector<double>{1.0, -1.0};
  const bool nearest = nearest_start(options);
  for (const int br : branches) {
    pb.branch = br;
    if (nearest) {
      search_nearest(pb, options, senses, runs, evaluations);
      continue;
    }
    for (const double s : senses) {
      pb.sense = s;
      search(pb, options, runs, evaluations);
    }
  }
  if (runs.empty()) {
    PathSynthesisResult res;
    res.message = "no run returned a finite objective";
    return res;
  }
  // Step 2: polish the best runs (L23).
  std::sort(runs.begin(), runs.end(), [](const Run& x, const Run& y) { return x.value < y.value; });
  Eigen::VectorXd lo, hi, start_hi;
  make_boxes(pb, options, lo, hi, start_hi);
  std::vector<double> theta(pb.T.size());
  Eigen::VectorXd r(residual_count(pb));
  std::vector<Run> polished;  // each run kept as it was when its polish does not lower F
  for (std::size_t k = 0; k < runs.size() && static_cast<int>(k) < options.polished; ++k) {
    pb.branch = runs[k].branch, pb.sense = runs[k].sense;
    const Eigen::VectorXd x = polish(pb, runs[k].x, lo, hi, evaluations);
    residuals(pb, x, theta, r);
    polished.push_back(r.squaredNorm() < runs[k].value
                           ? Run{x, r.squaredNorm(), runs[k].branch, runs[k].sense}
                           : runs[k]);
  }
  if (polished.empty()) polished.push_back(runs.front());
  std::stable_sort(polished.begin(), polished.end(),
                   [](const Run& x, const Run& y) { return x.value < y.value; });
  // Step 3: the restart policy (L23) about each of the best `restart_candidates` distinct
  // points (values apart by more than 1e-9 relative), the rounds shared out evenly.
  std::vector<Run> candidates;
  for (const Run& run : polished)
    if (static_cast<int>(candidates.size()) < options.restart_candidates &&
        (candidates.empty() || run.value > candidates.back().value * (1.0 + 1e-9)))
      candidates.push_back(run);
  const auto nc = static_cast<int>(candidates.size());
  Run best = candidates.front();
  for (int k = 0; k < nc; ++k) {
    const int rounds = options.restarts / nc + (k < options.restarts % nc ? 1 : 0);
    hop(pb, options, lo, hi, rounds, static_cast<unsigned long long>(k), candidates[k],
        evaluations);
    if (candidates[k].value < best.value) best = candidates[k];
  }
  // Step 4: world units, checked by the closed form.
  pb.branch = best.branch, pb.sense = best.sense;
  PathSynthesisResult res = finish(pb, best, targets, options);
  res.evaluations = evaluations;
  return res;
}

}  // namespace orthomech::synthesis
