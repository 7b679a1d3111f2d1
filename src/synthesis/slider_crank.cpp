#include "orthomech/synthesis/slider_crank.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <optional>

#include "../solvers/nlopt_minimize.hpp"
#include "levenberg_marquardt.hpp"
#include "orthomech/check.hpp"

namespace orthomech::synthesis {

namespace {

constexpr double kPi = std::numbers::pi;
// |K1| below this (relative to the pairs' largest |s|) means a crank of (near) zero length.
constexpr double kTinyCrank = 1e-14;
// A precision pair is "on the other branch" when the chosen branch misses it by more than this
// (relative to the pairs' largest |s|) and the other branch is at least twice as close.
constexpr double kBranchMiss = 1e-6;

// ---- function generation ---------------------------------------------------------------------

// Solves (L42) / (L43): the linear system [2 s_i cos φ_i, 2 sin φ_i, −1] K = s_i² (L41), exactly
// for 3 pairs, in the least-squares sense for more (column-pivoting QR, which minimises
// Σ (row_i·K − s_i²)², the normal equations' solution). False when the pairs do not determine K.
bool solve_slider_equation(const std::vector<SliderPair>& pairs, Eigen::Vector3d& K) {
  const auto n = static_cast<Eigen::Index>(pairs.size());
  Eigen::MatrixXd M(n, 3);
  Eigen::VectorXd rhs(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const SliderPair& pr = pairs[static_cast<std::size_t>(i)];
    M(i, 0) = 2.0 * pr.s * std::cos(pr.phi);  // (L41)
    M(i, 1) = 2.0 * std::sin(pr.phi);
    M(i, 2) = -1.0;
    rhs(i) = pr.s * pr.s;
  }
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(M);
  if (qr.rank() < 3) return false;
  K = qr.solve(rhs);
  return K.allFinite();
}

// Slider-position error of pair `pr` on branch `branch` (the oracle: the closed form (L8)).
double position_error(const SliderFunctionResult& r, const SliderPair& pr, int branch) {
  SliderCrank sc = r.linkage;
  sc.branch = branch;
  const SliderCrankPosition pos = calc_position(sc, pr.phi + r.input_offset);
  if (!pos.assembles) return HUGE_VAL;
  return std::abs(pos.s - pr.s);
}

// (L45) The branch that reproduces the pairs best (the sign of s − r cos θ); a defect when some
// pair is clearly on the other branch.
void choose_branch(const std::vector<SliderPair>& pairs, double size, SliderFunctionResult& r) {
  std::array<double, 2> worst{0.0, 0.0};
  for (const SliderPair& pr : pairs) {
    worst[0] = std::max(worst[0], position_error(r, pr, 1));
    worst[1] = std::max(worst[1], position_error(r, pr, -1));
  }
  r.linkage.branch = worst[0] <= worst[1] ? 1 : -1;
  r.max_position_error = std::min(worst[0], worst[1]);
  for (const SliderPair& pr : pairs) {
    const double on = position_error(r, pr, r.linkage.branch);
    const double off = position_error(r, pr, -r.linkage.branch);
    if (on > kBranchMiss * size && off < 0.5 * on) {
      r.status = SynthesisStatus::branch_defect;
      r.message =
          "the precision pairs lie on different assembly branches (the slider ahead of the crank "
          "pin at some, behind it at others; worst position error " +
          std::to_string(r.max_position_error) + " on the better branch)";
      return;
    }
  }
  r.status = SynthesisStatus::ok;
  r.message = "ok";
}

}  // namespace

bool crank_turns_fully(const SliderCrank& linkage) noexcept {
  return linkage.r + std::abs(linkage.offset) < linkage.l;
}

// Slider-crank function generation (docs/synthesis.md (L40)–(L45)):
//   1. K from (L41): exactly through 3 pairs (L42), by linear least squares through more (L43);
//   2. the lengths (L44): r = |K1| (input offset π when K1 < 0), e = K2 / K1,
//      l² = K1² + e² − K3, refused when l² ≤ 0;
//   3. the branch from the pairs and the position error, both by calc_position ((L8), (L45)).
SliderFunctionResult synthesize_slider_function_generator(const std::vector<SliderPair>& pairs) {
  check_argument(pairs.size() >= 3, "synthesize_slider_function_generator", "pairs",
                 "needs at least 3 precision pairs");
  double size = 0.0;
  for (const SliderPair& pr : pairs) {
    check_argument(std::isfinite(pr.phi) && std::isfinite(pr.s),
                   "synthesize_slider_function_generator", "pairs", "must be finite");
    size = std::max(size, std::abs(pr.s));
  }
  SliderFunctionResult r;
  // Step 1: K (L42)/(L43).
  if (!solve_slider_equation(pairs, r.K)) {
    r.message = "the precision pairs do not determine K1, K2, K3 (rank-deficient system)";
    return r;
  }
  // Step 2: the lengths (L44).
  const double K1 = r.K(0), K2 = r.K(1), K3 = r.K(2);
  if (std::abs(K1) <= kTinyCrank * std::max(size, 1e-300)) {
    r.message = "K1 = r vanishes: the crank would have no length";
    return r;
  }
  const double e = K2 / K1;
  const double l2 = K1 * K1 + e * e - K3;  // (L44)
  if (!(l2 > 0.0)) {
    r.message = "no real coupler: l² = r² + e² − K3 = " + std::to_string(l2) +
                " ≤ 0 (r = " + std::to_string(std::abs(K1)) + ", e = " + std::to_string(e) + ")";
    return r;
  }
  r.linkage.O = Vec2::Zero();
  r.linkage.line_angle = 0.0;
  r.linkage.r = std::abs(K1);
  r.linkage.l = std::sqrt(l2);
  r.linkage.offset = e;
  r.input_offset = K1 < 0.0 ? kPi : 0.0;
  // Step 3: the branch and the error by the closed form (L45).
  choose_branch(pairs, size, r);
  return r;
}

// ---- path generation -------------------------------------------------------------------------

namespace {

// The full-turn requirement holds with this margin (normalised units), as kGrashofMargin of
// path_generation.cpp; the loop closes with this slack at every target (kAssemblyMargin there).
constexpr double kFullTurnMargin = 1e-5;
constexpr double kAssemblyMargin = 1e-5;

// Where each variable sits in the decision vector x (−1: not a variable) (L47).
struct SliderLayout {
  int O = -1, line_angle = -1, r = -1, l = -1, e = -1, p = -1, q = -1;
  int start = -1, increments = -1;  // θ_0; δ_2 … δ_N
  int size = 0;
};

// The problem in normalised units (targets about their centroid, divided by their RMS spread).
struct SliderProblem {
  std::vector<Vec2> T;
  std::vector<double> phi;
  PathTiming timing = PathTiming::prescribed;
  std::optional<Vec2> O;
  std::optional<double> line_angle;
  bool full_turn = false;
  int branch = 1;
  double sense = 1.0;
  double sqrt_w = 1.0;
  SliderLayout L;
  Vec2 centre = Vec2::Zero();
  double scale = 1.0;
};

SliderLayout make_layout(const SliderProblem& pb) {
  SliderLayout L;
  int k = 0;
  if (!pb.O) L.O = k, k += 2;
  if (!pb.line_angle) L.line_angle = k++;
  L.r = k++, L.l = k++, L.e = k++, L.p = k++, L.q = k++;
  if (pb.timing != PathTiming::prescribed) L.start = k++;
  if (pb.timing == PathTiming::free) L.increments = k, k += static_cast<int>(pb.T.size()) - 1;
  L.size = k;
  return L;
}

// (L47) The linkage of x (normalised) and its crank angles θ_i: γ + φ_i (prescribed),
// γ + θ_0 + φ_i (free start), θ_0 + s Σ_{k≤i} δ_k (free).
SliderCrank decode(const SliderProblem& pb, const Eigen::VectorXd& x, std::vector<double>& theta) {
  const SliderLayout& L = pb.L;
  SliderCrank sc;
  sc.O = pb.O ? *pb.O : Vec2(x(L.O), x(L.O + 1));
  sc.line_angle = pb.line_angle ? *pb.line_angle : x(L.line_angle);
  sc.r = x(L.r), sc.l = x(L.l), sc.offset = x(L.e);
  sc.coupler_point = Vec2(x(L.p), x(L.q));
  sc.branch = pb.branch;
  const std::size_t n = pb.T.size();
  if (pb.timing == PathTiming::free) {
    double t = x(L.start);
    for (std::size_t i = 0; i < n; ++i) {
      if (i > 0) t += pb.sense * x(L.increments + static_cast<int>(i) - 1);
      theta[i] = t;
    }
  } else {
    const double t0 = pb.timing == PathTiming::prescribed_free_start ? x(L.start) : 0.0;
    for (std::size_t i = 0; i < n; ++i) theta[i] = sc.line_angle + t0 + pb.phi[i];
  }
  return sc;
}

// The residual vector of (L46): coupler-point misses (2N), √w · closure-slack deficits (N, (L48)),
// √w · the full-turn violation (1, (L49)), √w · the timing's excess over a turn (1).
int residual_count(const SliderProblem& pb) { return 3 * static_cast<int>(pb.T.size()) + 2; }

void residuals(const SliderProblem& pb, const Eigen::VectorXd& x, std::vector<double>& theta,
               Eigen::VectorXd& res) {
  const SliderCrank sc = decode(pb, x, theta);
  const auto n = static_cast<Eigen::Index>(pb.T.size());
  const Vec2 nrm(-std::sin(sc.line_angle), std::cos(sc.line_angle));
  for (Eigen::Index i = 0; i < n; ++i) {
    const SliderCrankPosition pos = calc_position(sc, theta[static_cast<std::size_t>(i)]);
    res.segment<2>(2 * i) = pos.P - pb.T[static_cast<std::size_t>(i)];
    // (L48) the slack of the loop closure: l − |e − v|, v the crank pin's distance from the
    // line through O (> 0 inside).
    const double slack = sc.l - std::abs(sc.offset - (pos.A - sc.O).dot(nrm));
    res(2 * n + i) = pb.sqrt_w * std::max(0.0, kAssemblyMargin - slack);
  }
  // (L49) the full turn: r + |e| − l < 0 with the margin.
  const double turn =
      pb.full_turn ? std::max(0.0, sc.r + std::abs(sc.offset) - sc.l + kFullTurnMargin) : 0.0;
  double excess = 0.0;
  if (pb.timing == PathTiming::free)
    excess = std::max(0.0, std::abs(theta.back() - theta.front()) - 2.0 * kPi);
  res(3 * n) = pb.sqrt_w * turn;
  res(3 * n + 1) = pb.sqrt_w * excess;
}

// The search box (normalised) and the narrower box the starts are drawn from (the increments
// start within an even share of one turn), as make_boxes of path_generation.cpp: the offset e in
// [−max_link, max_link].
void make_boxes(const SliderProblem& pb, const PathSynthesisOptions& o, Eigen::VectorXd& lo,
                Eigen::VectorXd& hi, Eigen::VectorXd& start_hi) {
  const SliderLayout& L = pb.L;
  lo.resize(L.size);
  hi.resize(L.size);
  if (L.O >= 0)
    lo.segment<2>(L.O).setConstant(-o.pivot_box), hi.segment<2>(L.O).setConstant(o.pivot_box);
  if (L.line_angle >= 0) lo(L.line_angle) = -kPi, hi(L.line_angle) = kPi;
  for (const int i : {L.r, L.l}) lo(i) = o.min_link, hi(i) = o.max_link;
  lo(L.e) = -o.max_link, hi(L.e) = o.max_link;
  for (const int i : {L.p, L.q}) lo(i) = -o.max_coupler, hi(i) = o.max_coupler;
  if (L.start >= 0) lo(L.start) = -kPi, hi(L.start) = kPi;
  start_hi = hi;
  const auto inc = static_cast<int>(pb.T.size()) - 1;
  for (int k = 0; L.increments >= 0 && k < inc; ++k) {
    lo(L.increments + k) = 0.0;
    hi(L.increments + k) = 2.0 * kPi;
    start_hi(L.increments + k) = 2.0 * kPi / inc;
  }
}

SliderProblem normalised_problem(const std::vector<Vec2>& targets, const PathSynthesisOptions& o) {
  SliderProblem pb;
  for (const Vec2& t : targets) pb.centre += t;
  pb.centre /= static_cast<double>(targets.size());
  double spread = 0.0;
  for (const Vec2& t : targets) spread += (t - pb.centre).squaredNorm();
  spread = std::sqrt(spread / static_cast<double>(targets.size()));
  pb.scale = spread > 0.0 ? spread : 1.0;
  for (const Vec2& t : targets) pb.T.emplace_back((t - pb.centre) / pb.scale);
  pb.phi = o.crank_angles;
  pb.timing = o.timing;
  if (o.fixed_A0) pb.O = Vec2((*o.fixed_A0 - pb.centre) / pb.scale);
  pb.line_angle = o.fixed_ground_angle;
  pb.full_turn = o.require_crank_rocker;
  pb.sqrt_w = std::sqrt(o.penalty_weight);
  pb.L = make_layout(pb);
  return pb;
}

struct SliderRun {
  Eigen::VectorXd x;
  double value = HUGE_VAL;
  int branch = 1;
  double sense = 1.0;
};

// One branch and turning sense: multistart BOBYQA over the quasi-random design, every local
// result kept (as `search` of path_generation.cpp).
void search(const SliderProblem& pb, const PathSynthesisOptions& o, std::vector<SliderRun>& runs,
            int& evaluations) {
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
  s.share = o.share;
  const Eigen::MatrixXd X = solvers::quasi_random_starts(lo, start_hi, o.starts, o.seed);
  for (Eigen::Index k = 0; k < X.cols(); ++k) s.extra_starts.emplace_back(X.col(k));
  const solvers::MultistartOutcome out = solvers::minimize_multistart(f, lo, hi, s);
  evaluations += out.evaluations;
  for (const auto& l : out.locals)
    if (std::isfinite(l.value)) runs.push_back({l.x, l.value, pb.branch, pb.sense});
}

// The best run in world units, checked by calc_position.
SliderPathResult finish(const SliderProblem& pb, const SliderRun& best,
                        const std::vector<Vec2>& targets) {
  SliderPathResult res;
  std::vector<double> theta(pb.T.size());
  SliderCrank sc = decode(pb, best.x, theta);
  sc.O = pb.centre + pb.scale * sc.O;
  sc.r *= pb.scale, sc.l *= pb.scale, sc.offset *= pb.scale;
  sc.coupler_point *= pb.scale;
  res.linkage = sc;
  res.crank_angles = theta;
  res.assembles = true;
  for (std::size_t i = 0; i < targets.size(); ++i) {
    const SliderCrankPosition pos = calc_position(sc, theta[i]);
    res.assembles = res.assembles && pos.assembles;
    res.error += (pos.P - targets[i]).squaredNorm();  // (L46)
    res.max_distance = std::max(res.max_distance, (pos.P - targets[i]).norm());
  }
  const bool turn_ok = !pb.full_turn || crank_turns_fully(sc);
  res.status = res.assembles && turn_ok ? SynthesisStatus::ok : SynthesisStatus::not_converged;
  res.message = res.status == SynthesisStatus::ok
                    ? "ok"
                    : (!res.assembles ? "the best slider-crank does not assemble at every target"
                                      : "the best slider-crank's crank does not turn fully");
  return res;
}

}  // namespace

// Slider-crank path synthesis (L46)–(L49): normalise, multistart BOBYQA on every branch and
// turning sense asked for, polish the best runs by Levenberg–Marquardt (L23), map back and check
// by calc_position.
SliderPathResult synthesize_slider_path_generator(const std::vector<Vec2>& targets,
                                                  const PathSynthesisOptions& options) {
  constexpr const char* fn = "synthesize_slider_path_generator";
  check_argument(targets.size() >= 2, fn, "targets", "needs at least 2 points");
  check_argument(
      options.timing == PathTiming::free || options.crank_angles.size() == targets.size(), fn,
      "options.crank_angles", "needs one angle per target for a timed problem");
  check_argument(options.pivot_box > 0.0 && options.max_coupler > 0.0 && options.min_link > 0.0 &&
                     options.max_link > options.min_link,
                 fn, "options", "needs a non-empty search box");
  check_argument(options.starts >= 1 && options.local_evaluations >= 1, fn, "options",
                 "needs starts ≥ 1 and local_evaluations ≥ 1");
  SliderProblem pb = normalised_problem(targets, options);
  // Step 1: the global search per branch and turning sense.
  std::vector<SliderRun> runs;
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
    SliderPathResult res;
    res.message = "no run returned a finite objective";
    return res;
  }
  // Step 2: polish the best runs (L23).
  std::sort(runs.begin(), runs.end(),
            [](const SliderRun& x, const SliderRun& y) { return x.value < y.value; });
  Eigen::VectorXd lo, hi, start_hi;
  make_boxes(pb, options, lo, hi, start_hi);
  std::vector<double> theta(pb.T.size());
  Eigen::VectorXd r(residual_count(pb));
  SliderRun best = runs.front();
  for (std::size_t k = 0; k < runs.size() && static_cast<int>(k) < options.polished; ++k) {
    pb.branch = runs[k].branch, pb.sense = runs[k].sense;
    const auto res = [&](const Eigen::VectorXd& y, Eigen::VectorXd& out) {
      residuals(pb, y, theta, out);
    };
    const Eigen::VectorXd x =
        detail::levenberg_marquardt(res, residual_count(pb), runs[k].x, lo, hi, 200, evaluations);
    residuals(pb, x, theta, r);
    if (r.squaredNorm() < best.value) best = {x, r.squaredNorm(), runs[k].branch, runs[k].sense};
  }
  // Step 3: world units, checked by the closed form.
  pb.branch = best.branch, pb.sense = best.sense;
  SliderPathResult res = finish(pb, best, targets);
  res.evaluations = evaluations;
  return res;
}

}  // namespace orthomech::synthesis
