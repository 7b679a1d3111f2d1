#include "orthomech/analysis/balancing.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>
#include <variant>
#include <vector>

#include "../solvers/nlopt_minimize.hpp"
#include "orthomech/analysis/shaking.hpp"

namespace orthomech {

namespace {

constexpr double kRoundingOfMu = 1e-12;

// The motion of a site's body frame at one position: its origin's position, velocity and
// acceleration (world), its rotation R(φ), ω and α. A point p of the frame is at r_o + R p,
// moves with v_o + ω ẑ × R p and accelerates with a_o + α ẑ × R p − ω² R p.
struct FrameMotion {
  Vec2 r, v, a;
  double c = 1.0, s = 0.0, w = 0.0, alpha = 0.0;
  [[nodiscard]] Vec2 rotate(const Vec2& p) const {
    return {c * p.x() - s * p.y(), s * p.x() + c * p.y()};
  }
};

Vec2 perp(const Vec2& x) { return {-x.y(), x.x()}; }  // ẑ × x

FrameMotion frame_motion(const Body& b, const DrivenPointView& p) {
  FrameMotion f;
  const int o = b.q_offset, v = b.u_offset;
  const double phi = p.q(o + 2);
  f.c = std::cos(phi);
  f.s = std::sin(phi);
  f.w = p.u(v + 2);
  f.alpha = p.udot(v + 2);
  const Vec2 rc = f.rotate(b.com_local);  // origin → centre of mass, world
  f.r = Vec2(p.q(o), p.q(o + 1)) - rc;
  f.v = Vec2(p.u(v), p.u(v + 1)) - f.w * perp(rc);
  f.a = Vec2(p.udot(v), p.udot(v + 1)) - f.alpha * perp(rc) + f.w * f.w * rc;
  return f;
}

// The sweep as the objective sees it: per reported position its shaking force and moment, the
// drive and ṡ, and the motion of every site's body.
struct SweepData {
  std::vector<Vec2> force;
  std::vector<double> moment, drive, rate;
  std::vector<std::vector<FrameMotion>> frames;  // [position][site]
};

SweepData sweep_data(const Model& model, const CycleResult& sweep, const BalanceOptions& opt) {
  SweepData d;
  const ShakingSeries s = shaking_series(model, sweep, opt.about);
  for (std::size_t k = 0; k < sweep.points.size(); ++k) {
    const DrivenPointView p = sweep.points[k];
    if (!s.reported[k] || !drive_reported(p)) continue;
    d.force.emplace_back(s.force[k].x(), s.force[k].y());
    d.moment.push_back(s.moment[k].z());
    d.drive.push_back(p.drive);
    d.rate.push_back(p.input_rate);
    std::vector<FrameMotion> f;
    for (const CounterweightSite& site : opt.sites)
      f.push_back(frame_motion(model.bodies[static_cast<std::size_t>(site.body)], p));
    d.frames.push_back(std::move(f));
  }
  return d;
}

Vec2 gravity_of(const Model& model) {
  Vec2 g = Vec2::Zero();
  for (const Load& l : model.loads)
    if (const auto* gr = std::get_if<Gravity>(&l.kind)) g += gr->g;
  return g;
}

// A site's counterweight from its first moment μ = m_c p at |p| = r.
struct PointMass {
  double mass = 0.0;
  Vec2 p = Vec2::Zero();
};
PointMass point_mass(const Eigen::VectorXd& x, std::size_t site, double radius) {
  const Vec2 mu(x(static_cast<Eigen::Index>(2 * site)), x(static_cast<Eigen::Index>(2 * site + 1)));
  const double n = mu.norm();
  if (!(n > 0.0)) return {0.0, Vec2(radius, 0.0)};
  return {n / radius, mu * (radius / n)};
}

// The terms with the counterweights x (x = 0: the mechanism as it is).
BalanceTerms terms_with(const SweepData& d, const BalanceOptions& opt, const Vec2& g,
                        const Eigen::VectorXd& x) {
  BalanceTerms t;
  const std::size_t n = d.force.size();
  if (n == 0) return t;
  std::vector<PointMass> cw;
  for (std::size_t i = 0; i < opt.sites.size(); ++i)
    cw.push_back(point_mass(x, i, opt.sites[i].radius));
  const Vec2 about(opt.about.x(), opt.about.y());
  double f2 = 0.0, m2 = 0.0, tau2 = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    Vec2 force = d.force[k];
    double moment = d.moment[k], drive = d.drive[k];
    for (std::size_t i = 0; i < cw.size(); ++i) {
      if (cw[i].mass == 0.0) continue;
      const FrameMotion& f = d.frames[k][i];
      const Vec2 rho = f.rotate(cw[i].p);
      const Vec2 a = f.a + f.alpha * perp(rho) - f.w * f.w * rho;
      const Vec2 v = f.v + f.w * perp(rho);
      const Vec2 r = f.r + rho - about;
      const Vec2 ma = cw[i].mass * a;
      force -= ma;                                // ΔF_s = −m_c a_P
      moment -= r.x() * ma.y() - r.y() * ma.x();  // ΔM_s = −(r_P − O) × m_c a_P
      if (d.rate[k] != 0.0) drive += cw[i].mass * (a - g).dot(v) / d.rate[k];  // power balance
    }
    f2 += force.squaredNorm();
    m2 += moment * moment;
    tau2 += drive * drive;
    t.force_peak = std::max(t.force_peak, force.norm());
  }
  t.force_rms = std::sqrt(f2 / static_cast<double>(n));
  t.moment_rms = std::sqrt(m2 / static_cast<double>(n));
  t.drive_rms = std::sqrt(tau2 / static_cast<double>(n));
  return t;
}

double objective(const BalanceTerms& t, const BalanceTerms& t0, const BalanceWeights& w) {
  auto term = [](double weight, double value, double before) {
    return weight > 0.0 && before > 0.0 ? weight * (value / before) * (value / before) : 0.0;
  };
  return term(w.force, t.force_rms, t0.force_rms) + term(w.moment, t.moment_rms, t0.moment_rms) +
         term(w.drive, t.drive_rms, t0.drive_rms);
}

// Why the request cannot be balanced ("" when it can).
std::string invalid_request(const Model& model, const CycleResult& sweep,
                            const BalanceOptions& opt) {
  if (model.dimension != 2) return "balancing is for planar mechanisms (dimension 2)";
  if (opt.sites.empty()) return "no counterweight site";
  if (sweep.points.empty()) return "the sweep has no position";
  const BalanceWeights& w = opt.weights;
  for (const double x : {w.force, w.moment, w.drive})
    if (!(x >= 0.0) || !std::isfinite(x)) return "the weights must be finite and ≥ 0";
  if (!(w.force + w.moment + w.drive > 0.0)) return "every weight is 0: nothing to minimise";
  for (std::size_t i = 0; i < opt.sites.size(); ++i) {
    const CounterweightSite& s = opt.sites[i];
    if (s.body < 0 || static_cast<std::size_t>(s.body) >= model.bodies.size())
      return "a counterweight site is not on a moving body";
    for (std::size_t j = 0; j < i; ++j)
      if (opt.sites[j].body == s.body)
        return "body '" + model.bodies[static_cast<std::size_t>(s.body)].name +
               "' has two counterweight sites: one per body";
    const Body& b = model.bodies[static_cast<std::size_t>(s.body)];
    if (b.kind != BodyKind::rigid)
      return "body '" + b.name + "' is a particle: a counterweight goes on a rigid body";
    if (!(s.radius > 0.0) || !std::isfinite(s.radius))
      return "body '" + b.name + "': the counterweight's radius must be > 0";
  }
  return "";
}

}  // namespace

const char* to_string(BalanceStatus s) {
  switch (s) {
    case BalanceStatus::balanced:
      return "balanced";
    case BalanceStatus::evaluation_limit:
      return "evaluation_limit";
    case BalanceStatus::invalid_request:
      return "invalid_request";
    case BalanceStatus::failed:
      break;
  }
  return "failed";
}

BalanceTerms balance_terms(const Model& model, const CycleResult& sweep, const Vec3& about) {
  BalanceOptions opt;
  opt.about = about;
  const SweepData d = sweep_data(model, sweep, opt);
  return terms_with(d, opt, gravity_of(model), Eigen::VectorXd());
}

BalanceResult balance_counterweights(const Model& model, const CycleResult& sweep,
                                     const BalanceOptions& opt) {
  BalanceResult out;
  out.message = invalid_request(model, sweep, opt);
  if (!out.message.empty()) {
    out.status = BalanceStatus::invalid_request;
    return out;
  }
  // Step 1: the sweep's terms and the counterweights' motion.
  const SweepData d = sweep_data(model, sweep, opt);
  const Vec2 g = gravity_of(model);
  const auto n = static_cast<Eigen::Index>(2 * opt.sites.size());
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(n);
  out.before = terms_with(d, opt, g, zero);
  out.objective_before = objective(out.before, out.before, opt.weights);
  // Step 2: the box of the first moments.
  double total = 0.0;
  for (const Body& b : model.bodies) total += b.mass;
  const double mass_limit = opt.mass_limit > 0.0 ? opt.mass_limit : 10.0 * total;
  Eigen::VectorXd upper(n);
  for (std::size_t i = 0; i < opt.sites.size(); ++i)
    upper.segment<2>(static_cast<Eigen::Index>(2 * i))
        .setConstant(mass_limit * opt.sites[i].radius);
  // Step 3: BOBYQA from no counterweight.
  solvers::NloptSettings settings;
  settings.max_evaluations = opt.max_evaluations;
  settings.xtol_abs = 1e-14 * upper.maxCoeff();
  const solvers::NloptOutcome o = solvers::minimize_bounded(
      [&](const Eigen::VectorXd& x) {
        return objective(terms_with(d, opt, g, x), out.before, opt.weights);
      },
      zero, -upper, upper, settings);
  out.evaluations = o.evaluations;
  switch (o.kind) {
    case solvers::NloptOutcomeKind::converged:
    case solvers::NloptOutcomeKind::roundoff:
      out.status = BalanceStatus::balanced;
      break;
    case solvers::NloptOutcomeKind::max_evaluations:
      out.status = BalanceStatus::evaluation_limit;
      out.message = "the optimiser stopped after " + std::to_string(o.evaluations) +
                    " evaluations; the best counterweights found are reported";
      break;
    default:
      out.status = BalanceStatus::failed;
      out.message = "the optimiser failed: " + o.message;
      return out;
  }
  // Step 4: the counterweights and the bodies that carry them.
  // A component of μ at the optimiser's rounding (1e-12 of |μ|: a counterweight along a body's
  // axis, 1e-14 mm off it) is written as 0.
  Eigen::VectorXd x = o.x;
  for (Eigen::Index i = 0; i + 1 < x.size(); i += 2) {
    const double mu = std::hypot(x(i), x(i + 1));
    for (const Eigen::Index k : {i, i + 1})
      if (std::abs(x(k)) <= kRoundingOfMu * mu) x(k) = 0.0;
  }
  out.after = terms_with(d, opt, g, x);
  out.objective_after = objective(out.after, out.before, opt.weights);
  for (std::size_t i = 0; i < opt.sites.size(); ++i) {
    const PointMass pm = point_mass(x, i, opt.sites[i].radius);
    const Body& b = model.bodies[static_cast<std::size_t>(opt.sites[i].body)];
    Counterweight c;
    c.body = opt.sites[i].body;
    c.mass = pm.mass;
    c.position = pm.p;
    c.body_mass = b.mass + pm.mass;
    c.body_com = (b.mass * b.com_local + pm.mass * pm.p) / c.body_mass;
    c.body_inertia = b.inertia + b.mass * (b.com_local - c.body_com).squaredNorm() +
                     pm.mass * (pm.p - c.body_com).squaredNorm();
    out.counterweights.push_back(c);
  }
  return out;
}

}  // namespace orthomech
