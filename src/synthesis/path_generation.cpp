#include "orthomech/synthesis/path_generation.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "../solvers/nlopt_minimize.hpp"
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

// The linkage of x (normalised) and its crank angles θ_i (L24).
FourBar decode(const Problem& pb, const Eigen::VectorXd& x, std::vector<double>& theta) {
  const Layout& L = pb.L;
  FourBar fb;
  fb.A0 = pb.A0 ? *pb.A0 : Vec2(x(L.A0), x(L.A0 + 1));
  const double tg = pb.ground_angle ? *pb.ground_angle : x(L.ground_angle);
  fb.B0 = fb.A0 + x(L.d) * Vec2(std::cos(tg), std::sin(tg));
  fb.a = x(L.a), fb.b = x(L.b), fb.c = x(L.c);
  fb.coupler_point = Vec2(x(L.p), x(L.q));
  fb.branch = pb.branch;
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
  double v1 = 0.0, v2 = 0.0;
  if (pb.crank_rocker) {  // (L22): a shortest and s + l ≤ p + q, i.e. a + 2l − (b + c + d) ≤ 0
    const double d = x(pb.L.d);
    const double l = std::max({fb.b, fb.c, d});
    v1 = std::max(0.0, fb.a + 2.0 * l - (fb.b + fb.c + d) + kGrashofMargin);
    v2 = std::max(0.0, fb.a - std::min({fb.b, fb.c, d}) + kGrashofMargin);
  }
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

// (L23) Levenberg–Marquardt on the residual vector, central-difference Jacobian, steps clamped
// to the box; a step is kept only when it lowers F.
Eigen::VectorXd polish(const Problem& pb, Eigen::VectorXd x, const Eigen::VectorXd& lo,
                       const Eigen::VectorXd& hi) {
  std::vector<double> theta(pb.T.size());
  const int m = residual_count(pb);
  Eigen::VectorXd r(m), rp(m), rm(m), r_try(m);
  Eigen::MatrixXd J(m, x.size());
  residuals(pb, x, theta, r);
  double F = r.squaredNorm(), lambda = 1e-3;
  for (int iter = 0; iter < 200 && F > 1e-30; ++iter) {
    for (Eigen::Index j = 0; j < x.size(); ++j) {  // central differences
      const double h = 1e-7 * (1.0 + std::abs(x(j)));
      Eigen::VectorXd xp = x, xm = x;
      xp(j) += h;
      xm(j) -= h;
      residuals(pb, xp, theta, rp);
      residuals(pb, xm, theta, rm);
      J.col(j) = (rp - rm) / (2.0 * h);
    }
    const Eigen::MatrixXd JtJ = J.transpose() * J;
    const Eigen::VectorXd g = J.transpose() * r;
    bool improved = false;
    for (int tries = 0; tries < 12 && !improved; ++tries) {
      Eigen::MatrixXd A = JtJ;
      A.diagonal() += lambda * (JtJ.diagonal().array() + 1e-12).matrix();
      const Eigen::VectorXd x_try = (x - A.ldlt().solve(g)).cwiseMax(lo).cwiseMin(hi);
      residuals(pb, x_try, theta, r_try);
      const double F_try = r_try.squaredNorm();
      if (F_try < F) {
        improved = F - F_try > 1e-15 * F;
        x = x_try, r = r_try, F = F_try;
        lambda = std::max(lambda / 3.0, 1e-12);
        if (!improved) return x;  // stalled
      } else {
        lambda *= 4.0;
      }
    }
    if (!improved) break;
  }
  return x;
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
  std::vector<double> theta(pb.T.size());
  Eigen::VectorXd r(residual_count(pb));
  const auto f = [&](const Eigen::VectorXd& x) {
    residuals(pb, x, theta, r);
    return r.squaredNorm();
  };
  solvers::MultistartSettings s;
  s.starts = 0;
  s.seed = o.seed;
  s.local.max_evaluations = o.local_evaluations;
  s.local.xtol_abs = 1e-12;
  const Eigen::MatrixXd X = solvers::quasi_random_starts(lo, start_hi, o.starts, o.seed);
  for (Eigen::Index k = 0; k < X.cols(); ++k) s.extra_starts.emplace_back(X.col(k));
  const solvers::MultistartOutcome out = solvers::minimize_multistart(f, lo, hi, s);
  evaluations += out.evaluations;
  for (const auto& l : out.locals)
    if (std::isfinite(l.value)) runs.push_back({l.x, l.value, pb.branch, pb.sense});
}

// (L23) The restart policy: `restarts` rounds of basin hopping from the best point. Each round
// moves every variable by a uniform step in ±restart_step·(hi − lo) (std::mt19937_64 seeded from
// options.seed, its bits mapped to [−1, 1) by hand so that the sequence is portable), runs BOBYQA
// and the polish from there and keeps the result when it lowers F.
void hop(Problem& pb, const PathSynthesisOptions& o, const Eigen::VectorXd& lo,
         const Eigen::VectorXd& hi, Run& best, int& evaluations) {
  std::mt19937_64 rng(o.seed + 0x9e3779b97f4a7c15ULL);
  const auto uniform = [&rng] {  // [−1, 1)
    return 2.0 * static_cast<double>(rng() >> 11) * 0x1.0p-53 - 1.0;
  };
  std::vector<double> theta(pb.T.size());
  Eigen::VectorXd r(residual_count(pb));
  solvers::NloptSettings local;
  local.max_evaluations = o.local_evaluations;
  local.xtol_abs = 1e-12;
  for (int k = 0; k < o.restarts; ++k) {
    pb.branch = best.branch, pb.sense = best.sense;
    Eigen::VectorXd x0 = best.x;
    for (Eigen::Index j = 0; j < x0.size(); ++j)
      x0(j) = std::clamp(x0(j) + o.restart_step * (hi(j) - lo(j)) * uniform(), lo(j), hi(j));
    const auto f = [&](const Eigen::VectorXd& x) {
      residuals(pb, x, theta, r);
      return r.squaredNorm();
    };
    const solvers::NloptOutcome out = solvers::minimize_bounded(f, x0, lo, hi, local);
    evaluations += out.evaluations;
    if (!std::isfinite(out.value)) continue;
    const Eigen::VectorXd x = polish(pb, out.x, lo, hi);
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
  check_argument(o.restarts >= 0 && o.restart_step > 0.0 && o.restart_step <= 1.0, fn, "options",
                 "needs restarts ≥ 0 and restart_step in (0, 1]");
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
  for (const int br : branches)
    for (const double s : senses) {
      pb.branch = br, pb.sense = s;
      search(pb, options, runs, evaluations);
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
  Run best = runs.front();
  std::vector<double> theta(pb.T.size());
  Eigen::VectorXd r(residual_count(pb));
  for (std::size_t k = 0; k < runs.size() && static_cast<int>(k) < options.polished; ++k) {
    pb.branch = runs[k].branch, pb.sense = runs[k].sense;
    const Eigen::VectorXd x = polish(pb, runs[k].x, lo, hi);
    residuals(pb, x, theta, r);
    if (r.squaredNorm() < best.value) best = {x, r.squaredNorm(), runs[k].branch, runs[k].sense};
  }
  // Step 3: the restart policy about the best point (L23).
  hop(pb, options, lo, hi, best, evaluations);
  // Step 4: world units, checked by the closed form.
  pb.branch = best.branch, pb.sense = best.sense;
  PathSynthesisResult res = finish(pb, best, targets, options);
  res.evaluations = evaluations;
  return res;
}

}  // namespace orthomech::synthesis
