#include "orthomech/analysis/validate.hpp"

#include <Eigen/LU>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <random>
#include <set>
#include <sstream>

#include "../run_watch.hpp"
#include "../solvers/nlopt_minimize.hpp"
#include "orthomech/analysis/cycle_metrics.hpp"
#include "orthomech/analysis/mobility.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/constraints/spatial_joints.hpp"
#include "orthomech/io/units.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/model/measures.hpp"
#include "orthomech/model/spatial.hpp"
#include "orthomech/projection/gauss_newton.hpp"

namespace orthomech {

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kTwoPi = 2.0 * kPi;
// Two positions are the same when every coordinate agrees to this (angles in rad, lengths
// divided by the mechanism's length scale L): far above the 1e-12 projection tolerance, far
// below any distinct assembly mode.
constexpr double kSamePosition = 1e-6;

double wrap(double a) { return a - kTwoPi * std::round(a / kTwoPi); }

std::string fmt(double v, int precision = 4) {
  std::ostringstream s;
  s.precision(precision);
  s << v;
  return s.str();
}

// Whether a joint's coordinate is an angle (rad, compared modulo 2π): a planar revolute, or a
// spatial revolute, cylindrical or screw joint (docs/spatial.md §2.4: the (P5) twist angle).
bool is_revolute(const Model& model, int joint) {
  const JointKind& k = model.joints[static_cast<size_t>(joint)].kind;
  if (const auto* s = std::get_if<SpatialJoint>(&k))
    return spatial_joint_spec(s->type).coordinate == SpatialCoordinate::angle;
  return std::holds_alternative<Revolute>(k);
}

// The mechanism's length scale: the largest joint-point offset on a body or distance between
// ground points (m).
double length_scale(const Model& model) {
  double L = 0.0;
  std::vector<Vec3> ground;
  auto visit = [&](int body, const Vec3& s) {
    if (body == kGround)
      ground.push_back(s);
    else
      L = std::max(L, s.norm());
  };
  for (const Joint& j : model.joints)
    std::visit(
        [&](const auto& k) {
          using K = std::decay_t<decltype(k)>;
          if constexpr (std::is_same_v<K, SpatialJoint>) {
            visit(k.pi.body, k.pi.s);
            visit(k.pj.body, k.pj.s);
          } else if constexpr (!std::is_same_v<K, GearPair>) {
            visit(k.pi.body, Vec3(k.pi.s.x(), k.pi.s.y(), 0.0));
            visit(k.pj.body, Vec3(k.pj.s.x(), k.pj.s.y(), 0.0));
          }
        },
        j.kind);
  for (size_t a = 0; a < ground.size(); ++a)
    for (size_t b = 0; b < a; ++b) L = std::max(L, (ground[a] - ground[b]).norm());
  return std::max(L, 1e-6);
}

// The joint points of spatial body b (body frame): an idle body's own motion (docs/spatial.md §4.1)
// leaves them in place, so positions are compared by them.
std::vector<Vec3> joint_points_on(const Model& model, int b) {
  std::vector<Vec3> out;
  for (const Joint& j : model.joints)
    if (const auto* s = std::get_if<SpatialJoint>(&j.kind)) {
      if (s->pi.body == b) out.push_back(s->pi.s);
      if (s->pj.body == b) out.push_back(s->pj.s);
    }
  return out;
}

// Max over coordinates of |Δ| (angles wrapped, lengths / L). Spatial bodies: |Δr| / L of the
// centre of mass and the angle of the rotation between the two orientations; a body in
// `idle` (an idle degree of freedom) by the largest move of its joint points / L instead.
double scaled_distance(const Model& model, const VecX& a, const VecX& b, double L,
                       const std::vector<int>& idle = {}) {
  double d = 0.0;
  for (size_t k = 0; k < model.bodies.size(); ++k) {
    const Body& body = model.bodies[k];
    if (body.kind == BodyKind::spatial) {
      const int bi = static_cast<int>(k);
      if (std::find(idle.begin(), idle.end(), bi) != idle.end()) {
        const SpatialFrame fa = spatial_frame(model, bi, a, nullptr);
        const SpatialFrame fb = spatial_frame(model, bi, b, nullptr);
        for (const Vec3& s : joint_points_on(model, bi))
          d = std::max(d, (spatial_point(fa, s).r - spatial_point(fb, s).r).norm() / L);
        continue;
      }
      d = std::max(d, (a.segment<3>(body.q_offset) - b.segment<3>(body.q_offset)).norm() / L);
      // The relative rotation δ = e_a* ⊗ e_b: angle 2·atan2(|vec δ|, |δ₀|) (= 2·acos|e_a·e_b|,
      // accurate near 0).
      Quat ea = a.segment<4>(body.q_offset + 3).normalized();
      ea.tail<3>() = -ea.tail<3>();
      const Quat delta = quaternion_multiply(ea, b.segment<4>(body.q_offset + 3).normalized());
      d = std::max(d, 2.0 * std::atan2(delta.tail<3>().norm(), std::abs(delta(0))));
      continue;
    }
    d = std::max(d, std::abs(a(body.q_offset) - b(body.q_offset)) / L);
    d = std::max(d, std::abs(a(body.q_offset + 1) - b(body.q_offset + 1)) / L);
    if (body.kind == BodyKind::rigid)
      d = std::max(d, std::abs(wrap(a(body.q_offset + 2) - b(body.q_offset + 2))));
  }
  return d;
}

// A velocity-space vector (size n) scaled to be comparable: lengths / L, angles as they are
// (spatial bodies: v / L, ω as it is).
VecX scale_vector(const Model& model, const VecX& v, double L) {
  VecX s = v;
  for (const Body& body : model.bodies) {
    for (int c = 0; c < body.translations(); ++c) s(body.u_offset + c) /= L;
  }
  return s;
}

// δu with a ⊕ δu = b (size n; planar: b − a).
VecX difference(const Model& model, const VecX& b, const VecX& a) {
  VecX du(model.n);
  difference_positions(model, b, a, du);
  return du;
}

// a ⊕ h·du (size nq).
VecX moved(const Model& model, const VecX& a, const VecX& du, double h) {
  VecX q = a;
  integrate_positions(model, q, du, h);
  return q;
}

// Whether every spatial joint is on its drawn branch (docs/spatial.md §2.4): the rows f_i·h_j,
// g_i·h_j also vanish with the axis flipped (h_j = −h_i) and the twist row g_i·f_j at a half-turn,
// with Eᵀ of full rank there, so a projection from a random start may land on them. They are not
// assemblies of the joint as built: h_i·h_j > 0 and f_i·f_j > 0 (joints with a twist row).
bool on_drawn_branch(const Model& model, const VecX& q) {
  for (const Joint& j : model.joints) {
    const auto* s = std::get_if<SpatialJoint>(&j.kind);
    if (!s) continue;
    const SpatialJointSpec& spec = spatial_joint_spec(s->type);
    const Mat3 Ai = spatial_frame(model, s->pi.body, q, nullptr).R * s->frame_i;
    const Mat3 Aj = spatial_frame(model, s->pj.body, q, nullptr).R * s->frame_j;
    for (int r = 0; r < spec.rows; ++r) {
      const std::string name = spec.row[static_cast<size_t>(r)].name;
      if ((name == "f" || name == "g") && Ai.col(2).dot(Aj.col(2)) <= 0.0) return false;
      if (name == "twist" && Ai.col(0).dot(Aj.col(0)) <= 0.0) return false;
    }
  }
  return true;
}

// A spatial target's errors at q: |P − at| (m) and, with an orientation target, the angle of the
// rotation from the target frame to the body's, 2·atan2(|vec δ|, |δ₀|) with δ = e_t* ⊗ e (accurate
// near 0); with a direction target, the angle between R·b and the world direction w,
// atan2(|Rb × w|, Rb·w).
struct SpatialTargetErrors {
  double distance = 0.0;
  std::optional<double> angle;
};
SpatialTargetErrors spatial_target_errors(const Model& model, const DesignTarget& t,
                                          const VecX& q) {
  const int body = t.spatial_point.body;
  const SpatialFrame k = spatial_frame(model, body, q, nullptr);
  SpatialTargetErrors e;
  e.distance = (spatial_point(k, t.spatial_point.s).r - t.spatial_position).norm();
  if (t.orientation) {
    const Quat eb =
        body == kGround
            ? Quat(1.0, 0.0, 0.0, 0.0)
            : Quat(q.segment<4>(model.bodies[static_cast<size_t>(body)].q_offset + 3).normalized());
    Quat et = t.orientation->normalized();
    et.tail<3>() = -et.tail<3>();
    const Quat delta = quaternion_multiply(et, eb);
    e.angle = 2.0 * std::atan2(delta.tail<3>().norm(), std::abs(delta(0)));
  }
  if (t.direction) {
    const Vec3 a = k.R * t.direction->first;
    e.angle = std::atan2(a.cross(t.direction->second).norm(), a.dot(t.direction->second));
  }
  return e;
}

Vec2 world(const Model& model, const PointRef& p, const VecX& q) {
  return point_kinematics(model, p, q, nullptr).r;
}

const PointRef& side_on(const Revolute& r, int body) { return r.pi.body == body ? r.pi : r.pj; }

// ---- circuits: arclength continuation of the 1-DOF configuration curve ----------------------

struct Sample {
  VecX q, t;       // position and unit tangent (scaled ∞-norm 1)
  double s = 0.0;  // input value (unwrapped along the trace)
  double l = 0.0;  // arclength parameter (scaled)
  double dsdl = 0.0;
  double sigma = 1.0;  // σ_min of Eᵀ (relative)
};

struct SingularPoint {
  double l = 0.0, s = 0.0;
  std::string kind;
};

struct Circuit {
  std::vector<Sample> samples;
  bool closed = false;
  std::vector<SingularPoint> singular;
  [[nodiscard]] int branch_at(double l) const {
    const int n = static_cast<int>(singular.size());
    if (n == 0) return 1;
    int passed = 0;
    for (const SingularPoint& p : singular)
      if (p.l < l) ++passed;
    return (closed ? passed % n : passed) + 1;
  }
};

// The run's bounds over the checks (ValidateOptions::control, run_watch.hpp) are ticked at every
// multi-start projection and trace step: the first bound met ends each loop at its next step and
// the checks after it do not run.
class Tracer {
 public:
  Tracer(const Model& model, int input, int generic_rank, const ValidateOptions& o,
         std::vector<int> idle, RunWatch& bounds)
      : bounds_(bounds),
        m_(model),
        input_(input),
        rank_(generic_rank),
        idle_(std::move(idle)),
        opt_(o),
        L_(length_scale(model)),
        Et_(model.nc, model.n),
        d_(model.n) {}

  double L() const { return L_; }

  double input_value(const VecX& q) const { return joint_coordinate(m_, input_, q); }

  // Unit tangent of the curve f(q) = 0 at q (last right singular vector of Eᵀ), oriented along
  // `prev` (or so that the input increases).
  // Velocity space (size n): with idle bodies, their own motions held at zero rate.
  VecX tangent(const VecX& q, const VecX* prev) {
    compute_constraint_jacobian(m_, q, Et_);
    const MatX I = idle_rows(m_, q, idle_);
    MatX J(m_.nc + I.rows(), m_.n);
    J.topRows(m_.nc) = Et_;
    J.bottomRows(I.rows()) = I;
    Eigen::JacobiSVD<MatX> svd(J, Eigen::ComputeFullV);
    VecX t = svd.matrixV().col(m_.n - 1);
    const VecX ts = scale_vector(m_, t, L_);
    t /= ts.cwiseAbs().maxCoeff();
    if (prev) {
      if (scale_vector(m_, t, L_).dot(scale_vector(m_, *prev, L_)) < 0.0) t = -t;
    } else {
      compute_scalar(m_, JointCoordinate{input_}, q, nullptr, d_);
      if (d_.dot(t) < 0.0) t = -t;
    }
    return t;
  }

  double dsdl(const VecX& q, const VecX& t) {
    compute_scalar(m_, JointCoordinate{input_}, q, nullptr, d_);
    return d_.dot(t);
  }

  // σ_r / σ_1 of the scaled Eᵀ.
  double sigma(const VecX& q) { return singularity_measures(m_, q, {}, rank_).sigma_min; }

  // Newton on [f(q) = 0; tᵀ(q ⊖ q_pred) = 0] (the one Gauss–Newton corrector,
  // projection/gauss_newton.hpp: minimum-norm steps in velocity space, q ← q ⊕ −δu; idle bodies'
  // own motions held by rows with zero residual).
  bool correct(VecX& q, const VecX& q_pred, const VecX& t) {
    const MatX I = idle_rows(m_, q_pred, idle_);
    const auto ni = static_cast<int>(I.rows());
    const ExtraRows rows{ni + 1, [&](const VecX& x, Eigen::Ref<VecX> g, Eigen::Ref<MatX> G) {
                           g.head(ni).setZero();
                           G.topRows(ni) = I;
                           g(ni) = t.dot(difference(m_, x, q_pred));
                           G.row(ni) = t.transpose();
                         }};
    GaussNewtonOptions gn;
    gn.tolerance = 1e-12 * std::max(1.0, L_);
    gn.extra_tolerance = 1e-10;
    gn.max_iterations = 12;
    gn.accept = 1e-10 * std::max(1.0, L_);
    gn.metric = GaussNewtonOptions::Metric::euclidean;
    gn.descent = GaussNewtonOptions::Descent::free;
    return gauss_newton_positions(m_, q, rows, gn).converged;
  }

  // Point on the curve at parameter τ from sample `a` along its tangent.
  bool at(const Sample& a, double tau, VecX& q) {
    const VecX pred = moved(m_, a.q, a.t, tau);
    q = pred;
    return correct(q, pred, a.t);
  }

  Circuit trace(const VecX& q_start) {
    Circuit c;
    Sample s0;
    s0.q = q_start;
    s0.t = tangent(q_start, nullptr);
    s0.s = input_value(q_start);
    s0.dsdl = dsdl(q_start, s0.t);
    s0.sigma = sigma(q_start);
    c.samples.push_back(s0);
    double h = opt_.step;
    for (int step = 0; step < opt_.max_trace_steps; ++step) {
      if (!bounds_.go_on()) break;
      const Sample& a = c.samples.back();
      VecX q;
      if (!at(a, h, q)) {
        h *= 0.5;
        if (h < 1e-9) break;
        continue;
      }
      const VecX t = tangent(q, &a.t);
      const VecX ts = scale_vector(m_, t, L_), as = scale_vector(m_, a.t, L_);
      if (ts.dot(as) < 0.95 * ts.norm() * as.norm() && h > 1e-6) {  // turned too much: smaller
        h *= 0.5;
        continue;
      }
      Sample b;
      b.q = q;
      b.t = t;
      double ds = input_value(q) - input_value(a.q);
      if (is_revolute(m_, input_)) ds = wrap(ds);
      b.s = a.s + ds;
      b.l = a.l + h;
      b.dsdl = dsdl(q, t);
      b.sigma = sigma(q);
      c.samples.push_back(b);
      // A step moves every scaled component by at most h; the spatial distance takes norms of
      // 3-vectors (a translation, a rotation angle): up to √3 h.
      const double reach = (m_.dimension == 3 ? std::sqrt(3.0) : 1.0) * 1.01 * h;
      if (c.samples.size() > 8 && scaled_distance(m_, q, q_start, L_, idle_) < reach) {
        // Back at the start: close the loop with the start itself.
        Sample e = c.samples.front();
        double dse = input_value(q_start) - input_value(q);
        if (is_revolute(m_, input_)) dse = wrap(dse);
        e.s = b.s + dse;
        e.l = b.l + scaled_distance(m_, q, q_start, L_, idle_);
        c.samples.push_back(e);
        c.closed = true;
        break;
      }
      h = std::min(opt_.step, 1.5 * h);
    }
    locate_singular_points(c);
    return c;
  }

  // Dead points of the input: ds/dl changes sign; refined with NLopt as the extreme of s along
  // the curve. Change points: σ_min of Eᵀ has a local minimum below 0.05; refined with NLopt as
  // the minimum of σ_min.
  void locate_singular_points(Circuit& c) {
    const auto& S = c.samples;
    for (size_t i = 0; i + 1 < S.size(); ++i) {
      if (S[i].dsdl * S[i + 1].dsdl < 0.0) {
        const double sign = S[i].dsdl > 0.0 ? 1.0 : -1.0;  // s increasing: find its maximum
        const double h = S[i + 1].l - S[i].l;
        auto f = [&](const VecX& x) {
          VecX q;
          if (!at(S[i], x(0), q)) return 1e3;
          double ds = input_value(q) - input_value(S[i].q);
          if (is_revolute(m_, input_)) ds = wrap(ds);
          return -sign * ds;
        };
        solvers::NloptSettings ns;
        ns.xtol_abs = 1e-12 * std::max(h, 1e-12);
        const solvers::NloptOutcome out = solvers::minimize_bounded(
            f, VecX::Constant(1, 0.5 * h), VecX::Constant(1, 0.0), VecX::Constant(1, h), ns);
        if (out.error) std::rethrow_exception(out.error);
        const double tau = out.x(0);
        c.singular.push_back({S[i].l + tau, S[i].s - sign * out.value, "dead point"});
      }
    }
    for (size_t i = 1; i + 1 < S.size(); ++i) {
      if (!(S[i].sigma <= S[i - 1].sigma && S[i].sigma <= S[i + 1].sigma && S[i].sigma < 0.05))
        continue;
      const double lo = S[i - 1].l - S[i].l, hi = S[i + 1].l - S[i].l;
      auto f = [&](const VecX& x) {
        VecX q;
        if (!at(S[i], x(0), q)) return 1e3;
        return sigma(q);
      };
      solvers::NloptSettings ns;
      ns.xtol_abs = 1e-13;
      const solvers::NloptOutcome out = solvers::minimize_bounded(
          f, VecX::Constant(1, 0.0), VecX::Constant(1, lo), VecX::Constant(1, hi), ns);
      if (out.error) std::rethrow_exception(out.error);
      if (out.value < opt_.min_sigma) {
        VecX q;
        if (at(S[i], out.x(0), q)) {
          double ds = input_value(q) - input_value(S[i].q);
          if (is_revolute(m_, input_)) ds = wrap(ds);
          c.singular.push_back({S[i].l + out.x(0), S[i].s + ds, "change point"});
        }
      }
    }
    std::sort(c.singular.begin(), c.singular.end(),
              [](const SingularPoint& a, const SingularPoint& b) { return a.l < b.l; });
  }

  // Arclength of q on the circuit, if it lies on it: at every crossing of the input value of q,
  // project with the input locked from the neighbouring sample and compare.
  std::optional<double> locate(const Circuit& c, const VecX& q) {
    const double sq = input_value(q);
    const bool rev = is_revolute(m_, input_);
    const auto& S = c.samples;
    for (size_t i = 0; i + 1 < S.size(); ++i) {
      const double lo = std::min(S[i].s, S[i + 1].s), hi = std::max(S[i].s, S[i + 1].s);
      double target = sq;
      if (rev) target = sq + kTwoPi * std::ceil((lo - sq) / kTwoPi - 1e-12);
      if (target < lo - 1e-12 || target > hi + 1e-12) continue;
      const double frac = hi > lo ? (target - S[i].s) / (S[i + 1].s - S[i].s) : 0.0;
      VecX x = moved(m_, S[i].q, difference(m_, S[i + 1].q, S[i].q), frac);
      if (!project_with_locks(m_, x, {{input_, target}}, 1e-12, 30)) continue;
      if (scaled_distance(m_, x, q, L_, idle_) < kSamePosition)
        return S[i].l + frac * (S[i + 1].l - S[i].l);
    }
    return std::nullopt;
  }

 private:
  RunWatch& bounds_;
  const Model& m_;
  int input_;
  int rank_;
  std::vector<int> idle_;
  ValidateOptions opt_;
  double L_;
  MatX Et_;
  VecX d_;
};

// Distinct solutions of f = 0 with the inputs locked: the given one plus multi-start
// projections from random poses (body positions within ±L of the design, angles uniform; spatial
// bodies: half the starts uniformly random orientations, normalised Gaussian quaternions
// [Shoemake 1992], half the design orientation turned about one of the body's joint axes; only
// solutions on the drawn branch of every joint axis are kept). Idle bodies are compared by their
// joint points.
std::vector<VecX> assembly_modes(const Model& model, const std::vector<JointLock>& locks,
                                 const VecX& q_ref, const VecX& q_design, double L,
                                 const ValidateOptions& opt, std::mt19937& gen,
                                 const std::vector<int>& idle, RunWatch& bounds) {
  std::vector<VecX> modes = {q_ref};
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> gauss(0.0, 1.0);
  // The world axes (h) of every spatial body's joints at the design pose: turning a body about
  // them keeps its joints near their drawn branch, where uniformly random orientations mostly
  // land on flipped axes (rejected below); half the starts use each.
  std::vector<std::vector<Vec3>> axes_of(model.bodies.size());
  for (const Joint& j : model.joints)
    if (const auto* s = std::get_if<SpatialJoint>(&j.kind)) {
      if (s->type == SpatialJointType::spherical || s->type == SpatialJointType::distance) continue;
      for (const int body : {s->pi.body, s->pj.body}) {
        if (body == kGround) continue;
        const Mat3 R = spatial_frame(model, body, q_design, nullptr).R;
        const Mat3& F = body == s->pi.body ? s->frame_i : s->frame_j;
        axes_of[static_cast<size_t>(body)].push_back((R * F.col(2)).normalized());
      }
    }
  for (int k = 0; k < opt.starts; ++k) {
    if (!bounds.go_on()) break;  // the modes found so far (a lower bound in any case)
    VecX q = q_design;
    for (const Body& b : model.bodies) {
      if (b.kind == BodyKind::spatial) {
        for (int c = 0; c < 3; ++c) q(b.q_offset + c) += L * u(gen);
        const std::vector<Vec3>& axes = axes_of[static_cast<size_t>(&b - model.bodies.data())];
        if (axes.empty() || k % 2 == 0) {  // a uniformly random orientation
          Quat e;
          for (int c = 0; c < 4; ++c) e(c) = gauss(gen);
          q.segment<4>(b.q_offset + 3) = e.normalized();
        } else {  // the design orientation turned about one of its joint axes (world)
          const size_t pick = std::min(
              axes.size() - 1,
              static_cast<size_t>(0.5 * (u(gen) + 1.0) * static_cast<double>(axes.size())));
          q.segment<4>(b.q_offset + 3) =
              quaternion_multiply(quaternion_exp(kPi * u(gen) * axes[pick]),
                                  q_design.segment<4>(b.q_offset + 3).normalized());
        }
        continue;
      }
      q(b.q_offset) += L * u(gen);
      q(b.q_offset + 1) += L * u(gen);
      if (b.kind == BodyKind::rigid) q(b.q_offset + 2) = kPi * u(gen);
    }
    if (!project_with_locks(model, q, locks, 1e-12, 60)) continue;
    if (model.dimension == 3 && !on_drawn_branch(model, q)) continue;
    bool known = false;
    for (const VecX& m : modes)
      known = known || scaled_distance(model, m, q, L, idle) < kSamePosition;
    if (!known) modes.push_back(q);
  }
  return modes;
}

// "+"/"−" per four-bar loop (the coupler–follower turn), then "/±": the sign of det [Eᵀ_R; d]
// (R = `rows`, every row when empty) when it is square and `with_det`.
std::string mode_signature(const Model& model, const VecX& q, const std::vector<FourBarLoop>& loops,
                           const std::vector<int>& inputs, const std::vector<int>& rows,
                           bool with_det) {
  std::string sig;
  for (const FourBarLoop& l : loops) {
    const Vec2 A = world(model, l.at[0], q);
    const Vec2 B = world(model, l.at[1], q);
    const Vec2 B0 = world(model, l.at[2], q);
    const Vec2 u = A - B, v = B0 - B;
    sig += (u.x() * v.y() - u.y() * v.x()) >= 0.0 ? '+' : '-';
  }
  MatX Et(model.nc, model.n);
  compute_constraint_jacobian(model, q, Et);
  const int nr = rows.empty() ? model.nc : static_cast<int>(rows.size());
  if (with_det && nr + static_cast<int>(inputs.size()) == model.n) {
    MatX J(model.n, model.n);
    for (int r = 0; r < nr; ++r) J.row(r) = Et.row(rows.empty() ? r : rows[static_cast<size_t>(r)]);
    VecX d(model.n);
    for (size_t k = 0; k < inputs.size(); ++k) {
      compute_scalar(model, JointCoordinate{inputs[k]}, q, nullptr, d);
      J.row(nr + static_cast<int>(k)) = d.transpose();
    }
    const double det = J.partialPivLu().determinant();
    sig += det >= 0.0 ? "/+" : "/-";
  }
  return sig;
}

}  // namespace

// ---- four-bar loops ------------------------------------------------------------------------

const char* to_string(GrashofType t) {
  switch (t) {
    case GrashofType::crank_rocker:
      return "crank-rocker";
    case GrashofType::rocker_crank:
      return "rocker-crank";
    case GrashofType::double_crank:
      return "double-crank";
    case GrashofType::grashof_double_rocker:
      return "Grashof double-rocker";
    case GrashofType::triple_rocker:
      return "triple-rocker (non-Grashof)";
    case GrashofType::change_point:
      return "change point (s + l = p + q)";
  }
  return "?";
}

GrashofType classify_grashof(double ground, double crank, double coupler, double follower,
                             double tol) {
  const double len[4] = {ground, crank, coupler, follower};
  int shortest = 0;
  double s = len[0], l = len[0], sum = 0.0;
  for (int k = 0; k < 4; ++k) {
    sum += len[k];
    if (len[k] < s) {
      s = len[k];
      shortest = k;
    }
    l = std::max(l, len[k]);
  }
  const double pq = sum - s - l;
  const double diff = (s + l) - pq;  // Grashof: s + l ≤ p + q [Grashof 1883]
  if (std::abs(diff) <= tol * sum) return GrashofType::change_point;
  if (diff > 0.0) return GrashofType::triple_rocker;
  switch (shortest) {
    case 0:
      return GrashofType::double_crank;
    case 1:
      return GrashofType::crank_rocker;
    case 2:
      return GrashofType::grashof_double_rocker;
    default:
      return GrashofType::rocker_crank;
  }
}

std::vector<FourBarLoop> find_four_bar_loops(const Model& model, int input_joint) {
  // 1. Pin ends: the two ends (body, point) of every revolute, merged into pins (union-find):
  //    the two ends of a joint, and ends at the same point of one body.
  struct End {
    int joint, body;
    PointRef ref;
  };
  std::vector<End> ends;
  for (size_t j = 0; j < model.joints.size(); ++j)
    if (const auto* r = std::get_if<Revolute>(&model.joints[j].kind)) {
      ends.push_back({static_cast<int>(j), r->pi.body, r->pi});
      ends.push_back({static_cast<int>(j), r->pj.body, r->pj});
    }
  // Union–find (path halving); a pin is named by its root's index among the ends. The unions
  // come in a fixed order (joints, then same-point pairs by ascending end index), so the names,
  // and with them the order in which loops are found, depend only on the model.
  const size_t n_ends = ends.size();
  std::vector<int> parent(n_ends);
  for (size_t k = 0; k < n_ends; ++k) parent[k] = static_cast<int>(k);
  auto root = [&](int k) {
    while (parent[static_cast<size_t>(k)] != k) {
      auto& p = parent[static_cast<size_t>(k)];
      p = parent[static_cast<size_t>(p)];
      k = p;
    }
    return k;
  };
  auto unite = [&](int a, int b) { parent[static_cast<size_t>(root(a))] = root(b); };
  constexpr double kSamePoint = 1e-12;  // m: one pin
  for (size_t k = 0; k + 1 < n_ends; k += 2) unite(static_cast<int>(k), static_cast<int>(k + 1));
  std::map<int, std::vector<int>> ends_of_body;  // ascending end indices of each body
  for (size_t k = 0; k < n_ends; ++k) ends_of_body[ends[k].body].push_back(static_cast<int>(k));
  for (size_t a = 0; a < n_ends; ++a)
    for (const int b : ends_of_body[ends[a].body])
      if (b > static_cast<int>(a) &&
          (ends[a].ref.s - ends[static_cast<size_t>(b)].ref.s).norm() < kSamePoint)
        unite(static_cast<int>(a), b);
  // 2. The links: for each pin its ends (ascending) and bodies (ascending, the ground first); for
  //    each body its pins (ascending) and the point of each on it.
  std::vector<int> pin_of(n_ends);
  std::vector<std::vector<int>> ends_at(n_ends), bodies_at(n_ends);  // indexed by pin
  for (size_t k = 0; k < n_ends; ++k) {
    pin_of[k] = root(static_cast<int>(k));
    ends_at[static_cast<size_t>(pin_of[k])].push_back(static_cast<int>(k));
  }
  std::vector<int> pin_set;  // ascending
  for (size_t p = 0; p < n_ends; ++p)
    if (!ends_at[p].empty()) {
      pin_set.push_back(static_cast<int>(p));
      for (const int k : ends_at[p]) bodies_at[p].push_back(ends[static_cast<size_t>(k)].body);
      std::sort(bodies_at[p].begin(), bodies_at[p].end());
      bodies_at[p].erase(std::unique(bodies_at[p].begin(), bodies_at[p].end()), bodies_at[p].end());
    }
  // The first end of `pin` on `body` (nullptr: none).
  auto on = [&](int pin, int body) -> const End* {
    for (const int k : ends_at[static_cast<size_t>(pin)])
      if (ends[static_cast<size_t>(k)].body == body) return &ends[static_cast<size_t>(k)];
    return nullptr;
  };
  // A joint at a pin for its name: one that connects the two links meeting there if any.
  auto joint_at = [&](int pin, int b1, int b2) {
    int any = -1;
    for (const int k : ends_at[static_cast<size_t>(pin)]) {
      const End& e = ends[static_cast<size_t>(k)];
      const End& other = ends[static_cast<size_t>(k) ^ 1U];
      if ((e.body == b1 && other.body == b2) || (e.body == b2 && other.body == b1)) return e.joint;
      if (any < 0 || ((e.body == b1 || e.body == b2) && any > e.joint)) any = e.joint;
    }
    return any;
  };
  std::vector<int> bodies_all = {kGround};
  for (size_t b = 0; b < model.bodies.size(); ++b) bodies_all.push_back(static_cast<int>(b));
  std::vector<std::vector<int>> pins_of(bodies_all.size());  // index b + 1
  for (const int p : pin_set)
    for (const int b : bodies_at[static_cast<size_t>(p)])
      pins_of[static_cast<size_t>(b + 1)].push_back(p);
  auto has = [&](int body, int pin) {
    const auto& v = pins_of[static_cast<size_t>(body + 1)];
    return std::find(v.begin(), v.end(), pin) != v.end();
  };
  // 3. Distance of every body from the ground in the joint graph (for a floating loop's frame):
  //    breadth first, two bodies adjacent when they share a pin.
  std::vector<int> dist(bodies_all.size(), 1 << 20);
  dist[0] = 0;
  std::vector<int> queue = {kGround};
  for (size_t head = 0; head < queue.size(); ++head) {
    const int a = queue[head];
    for (const int p : pins_of[static_cast<size_t>(a + 1)])
      for (const int b : bodies_at[static_cast<size_t>(p)])
        if (dist[static_cast<size_t>(b + 1)] > dist[static_cast<size_t>(a + 1)] + 1) {
          dist[static_cast<size_t>(b + 1)] = dist[static_cast<size_t>(a + 1)] + 1;
          queue.push_back(b);
        }
  }
  // 4. Every cycle of four pins through four distinct links.
  std::vector<FourBarLoop> loops;
  std::set<std::vector<int>> seen;
  const double L_tol = 1e-12;
  for (const int b0 : bodies_all)
    for (const int p0 : pins_of[static_cast<size_t>(b0 + 1)])
      for (const int p1 : pins_of[static_cast<size_t>(b0 + 1)]) {
        if (p1 == p0) continue;
        for (const int b1 : bodies_at[static_cast<size_t>(p1)]) {
          if (b1 == b0) continue;
          for (const int p2 : pins_of[static_cast<size_t>(b1 + 1)]) {
            if (p2 == p1 || p2 == p0) continue;
            for (const int b2 : bodies_at[static_cast<size_t>(p2)]) {
              if (b2 == b0 || b2 == b1) continue;
              for (const int p3 : pins_of[static_cast<size_t>(b2 + 1)]) {
                if (p3 == p2 || p3 == p1 || p3 == p0) continue;
                for (const int b3 : bodies_at[static_cast<size_t>(p3)]) {
                  if (b3 == b0 || b3 == b1 || b3 == b2 || !has(b3, p0)) continue;
                  std::vector<int> key = {p0, p1, p2, p3};
                  std::sort(key.begin(), key.end());
                  std::vector<int> kb = {b0, b1, b2, b3};
                  std::sort(kb.begin(), kb.end());
                  key.insert(key.end(), kb.begin(), kb.end());
                  if (!seen.insert(key).second) continue;
                  // Ring of links b0 (p0–p1), b1 (p1–p2), b2 (p2–p3), b3 (p3–p0); rotate it
                  // so that the frame comes first.
                  int ring_b[4] = {b0, b1, b2, b3}, ring_p[4] = {p0, p1, p2, p3};
                  int f = 0;
                  for (int k = 1; k < 4; ++k) {
                    const auto dk = dist[static_cast<size_t>(ring_b[k] + 1)];
                    const auto df = dist[static_cast<size_t>(ring_b[f] + 1)];
                    if (dk < df || (dk == df && ring_b[k] < ring_b[f])) f = k;
                  }
                  // Frame F = ring_b[f] between pins ring_p[f] and ring_p[f+1]: the loop
                  // F —P0— X —P1— Y —P2— Z —P3— F with P0 = ring_p[f+1], going forward.
                  int B[4], P[4];
                  for (int k = 0; k < 4; ++k) {
                    B[k] = ring_b[(f + k) % 4];
                    P[k] = ring_p[(f + k + 1) % 4];
                  }
                  // B = {F, X, Y, Z}; pins: P[0] = F∩X, P[1] = X∩Y, P[2] = Y∩Z, P[3] = Z∩F.
                  int J[4] = {joint_at(P[0], B[0], B[1]), joint_at(P[1], B[1], B[2]),
                              joint_at(P[2], B[2], B[3]), joint_at(P[3], B[3], B[0])};
                  auto input_at = [&](int pin) {
                    for (const int k : ends_at[static_cast<size_t>(pin)])
                      if (ends[static_cast<size_t>(k)].joint == input_joint) return true;
                    return false;
                  };
                  const bool input_at_3 = input_joint >= 0 && input_at(P[3]);
                  const bool input_at_0 = input_joint >= 0 && input_at(P[0]);
                  const bool flip = input_at_3 || (!input_at_0 && J[3] < J[0]);
                  if (flip) {  // F —P3— Z —P2— Y —P1— X —P0— F
                    std::swap(B[1], B[3]);
                    std::swap(P[0], P[3]);
                    std::swap(P[1], P[2]);
                    std::swap(J[0], J[3]);
                    std::swap(J[1], J[2]);
                  }
                  FourBarLoop l;
                  std::copy(J, J + 4, l.joints);
                  l.bodies[0] = B[1], l.bodies[1] = B[2], l.bodies[2] = B[3];
                  l.frame = B[0];
                  l.at[0] = on(P[1], B[2])->ref;
                  l.at[1] = on(P[2], B[2])->ref;
                  l.at[2] = on(P[3], B[3])->ref;
                  auto length = [&](int body, int pa, int pb) {
                    return (on(pa, body)->ref.s - on(pb, body)->ref.s).norm();
                  };
                  l.ground = length(B[0], P[0], P[3]);
                  l.crank = length(B[1], P[0], P[1]);
                  l.coupler = length(B[2], P[1], P[2]);
                  l.follower = length(B[3], P[2], P[3]);
                  if (std::min({l.ground, l.crank, l.coupler, l.follower}) < L_tol) continue;
                  l.type = classify_grashof(l.ground, l.crank, l.coupler, l.follower);
                  loops.push_back(l);
                }
              }
            }
          }
        }
      }
  return loops;
}

int loop_basis_size(const Model& model) {
  int edges = 0;
  for (const Joint& j : model.joints)
    if (std::holds_alternative<Revolute>(j.kind) || std::holds_alternative<Prismatic>(j.kind) ||
        std::holds_alternative<SpatialJoint>(j.kind))  // every spatial joint joins two links
      ++edges;
  return edges - static_cast<int>(model.bodies.size() + 1) + 1;  // j − b + 1, b with the ground
}

double transmission_angle(const Model& model, const FourBarLoop& l, const VecX& q) {
  const Vec2 A = world(model, l.at[0], q);   // crank–coupler pin
  const Vec2 B = world(model, l.at[1], q);   // coupler–follower pin
  const Vec2 B0 = world(model, l.at[2], q);  // follower's frame pivot
  const Vec2 u = A - B, v = B0 - B;
  return std::atan2(std::abs(u.x() * v.y() - u.y() * v.x()), u.dot(v));
}

std::vector<SliderCrankLoop> find_slider_crank_loops(const Model& model) {
  // The joint graph with bodies as nodes: revolutes and prismatics as edges.
  struct Edge {
    int joint, a, b;
    bool prismatic;
  };
  std::vector<Edge> edges;
  for (size_t j = 0; j < model.joints.size(); ++j) {
    if (const auto* r = std::get_if<Revolute>(&model.joints[j].kind))
      edges.push_back({static_cast<int>(j), r->pi.body, r->pj.body, false});
    else if (const auto* p = std::get_if<Prismatic>(&model.joints[j].kind))
      edges.push_back({static_cast<int>(j), p->pi.body, p->pj.body, true});
  }
  auto other = [](const Edge& e, int body) { return e.a == body ? e.b : e.a; };
  auto touches = [](const Edge& e, int body) { return e.a == body || e.b == body; };
  auto pin = [&](int joint) -> const Revolute& {
    return std::get<Revolute>(model.joints[static_cast<size_t>(joint)].kind);
  };
  std::vector<SliderCrankLoop> loops;
  for (const Edge& g1 : edges) {  // ground —rev— crank
    if (g1.prismatic || !touches(g1, kGround)) continue;
    const int X = other(g1, kGround);
    for (const Edge& e2 : edges) {  // crank —rev— rod
      if (e2.prismatic || e2.joint == g1.joint || !touches(e2, X)) continue;
      const int Y = other(e2, X);
      if (Y == kGround || Y == X) continue;
      for (const Edge& e3 : edges) {  // rod —rev— slider
        if (e3.prismatic || e3.joint == e2.joint || e3.joint == g1.joint || !touches(e3, Y))
          continue;
        const int Z = other(e3, Y);
        if (Z == kGround || Z == X || Z == Y) continue;
        for (const Edge& g4 : edges) {  // slider —prismatic— ground
          if (!g4.prismatic || !touches(g4, Z) || other(g4, Z) != kGround) continue;
          SliderCrankLoop l;
          const int J[4] = {g1.joint, e2.joint, e3.joint, g4.joint};
          const int Bd[3] = {X, Y, Z};
          std::copy(J, J + 4, l.joints);
          std::copy(Bd, Bd + 3, l.bodies);
          l.crank = (side_on(pin(J[0]), X).s - side_on(pin(J[1]), X).s).norm();
          l.rod = (side_on(pin(J[1]), Y).s - side_on(pin(J[2]), Y).s).norm();
          loops.push_back(l);
        }
      }
    }
  }
  return loops;
}

double pressure_angle(const Model& model, const SliderCrankLoop& l, const VecX& q) {
  const auto& j1 = std::get<Revolute>(model.joints[static_cast<size_t>(l.joints[1])].kind);
  const auto& j2 = std::get<Revolute>(model.joints[static_cast<size_t>(l.joints[2])].kind);
  const auto& slide = std::get<Prismatic>(model.joints[static_cast<size_t>(l.joints[3])].kind);
  const Vec2 A = world(model, side_on(j1, l.bodies[1]), q);  // crank pin
  const Vec2 B = world(model, side_on(j2, l.bodies[1]), q);  // wrist pin
  // The slide axis in the world: axis_local turns with body i of the prismatic joint.
  const Vec2 axis = slide.pi.body == kGround
                        ? slide.axis_local
                        : Vec2(rotation(body_angle(model, slide.pi.body, q)) * slide.axis_local);
  const Vec2 u = B - A;
  return std::atan2(std::abs(u.x() * axis.y() - u.y() * axis.x()), std::abs(u.dot(axis)));
}

// ---- spatial transmission loops [Sutherland & Roth 1973] ---------------------------------------

namespace {

const SpatialJoint* spatial_joint(const Model& model, int joint) {
  return std::get_if<SpatialJoint>(&model.joints[static_cast<size_t>(joint)].kind);
}
const SpatialPointRef& spatial_side_on(const SpatialJoint& s, int body) {
  return s.pi.body == body ? s.pi : s.pj;
}
Vec3 spatial_world(const Model& model, const SpatialPointRef& p, const VecX& q) {
  return spatial_point(spatial_frame(model, p.body, q, nullptr), p.s).r;
}
// The joint axis h in world (body i's side; the same line for both sides when assembled).
Vec3 spatial_axis(const Model& model, const SpatialJoint& s, const VecX& q) {
  return (spatial_frame(model, s.pi.body, q, nullptr).R * s.frame_i.col(2)).normalized();
}
char joint_letter(SpatialJointType t) {
  switch (t) {
    case SpatialJointType::revolute:
      return 'R';
    case SpatialJointType::prismatic:
      return 'P';
    case SpatialJointType::spherical:
      return 'S';
    case SpatialJointType::universal:
      return 'U';
    case SpatialJointType::distance:
      return 'D';
    default:
      return '?';
  }
}

}  // namespace

std::vector<SpatialTransmissionLoop> find_spatial_transmission_loops(const Model& model,
                                                                     int input_joint) {
  std::vector<SpatialTransmissionLoop> loops;
  if (model.dimension != 3) return loops;
  using T = SpatialJointType;
  const int nj = static_cast<int>(model.joints.size());
  auto type_of = [&](int j) { return spatial_joint(model, j)->type; };
  auto other = [&](int j, int body) {
    const SpatialJoint& s = *spatial_joint(model, j);
    return s.pi.body == body ? s.pj.body : s.pi.body;
  };
  auto touches = [&](int j, int body) {
    const SpatialJoint& s = *spatial_joint(model, j);
    return s.pi.body == body || s.pj.body == body;
  };
  // Joints per body (every spatial joint; a binary coupler has exactly two).
  std::vector<std::vector<int>> joints_of(model.bodies.size());
  std::vector<int> grounded;  // revolute or prismatic joints to the ground
  for (int j = 0; j < nj; ++j) {
    const SpatialJoint* s = spatial_joint(model, j);
    if (!s) return loops;  // not a spatial model
    for (const int b : {s->pi.body, s->pj.body})
      if (b != kGround) joints_of[static_cast<size_t>(b)].push_back(j);
    if ((s->pi.body == kGround || s->pj.body == kGround) &&
        (s->type == T::revolute || s->type == T::prismatic))
      grounded.push_back(j);
  }
  const VecX q0 = model.design_q();
  constexpr double kParallel = 1e-9;  // |h_a × h_b|: parallel axes (the file's axes are exact)
  // Every revolute axis among `js` parallel, every prismatic axis perpendicular to them.
  auto planar_loop = [&](const std::vector<int>& js) {
    std::optional<Vec3> n;
    for (const int j : js)
      if (type_of(j) == T::revolute) {
        const Vec3 h = spatial_axis(model, *spatial_joint(model, j), q0);
        if (n && n->cross(h).norm() > kParallel) return false;
        if (!n) n = h;
      }
    if (!n) return false;
    for (const int j : js)
      if (type_of(j) == T::prismatic &&
          std::abs(n->dot(spatial_axis(model, *spatial_joint(model, j), q0))) > kParallel)
        return false;
    return true;
  };
  for (size_t a = 0; a < grounded.size(); ++a)
    for (size_t b = a + 1; b < grounded.size(); ++b) {
      int g_in = grounded[a], g_out = grounded[b];
      if (input_joint == g_out) std::swap(g_in, g_out);
      const int X = other(g_in, kGround), Y = other(g_out, kGround);
      if (X == Y || X == kGround || Y == kGround) continue;
      auto add = [&](int c_in, int c_out, int C, bool planar) {
        SpatialTransmissionLoop l;
        const int J[4] = {g_in, c_in, c_out, g_out};
        std::copy(J, J + 4, l.joints);
        l.bodies[0] = X, l.bodies[1] = C, l.bodies[2] = Y;
        l.planar = planar;
        l.prismatic_output = type_of(g_out) == T::prismatic;
        l.type += joint_letter(type_of(g_in));
        l.type += joint_letter(type_of(c_in));
        if (c_out != c_in) l.type += joint_letter(type_of(c_out));
        l.type += joint_letter(type_of(g_out));
        loops.push_back(l);
      };
      // A distance row between the two links.
      for (int d = 0; d < nj; ++d)
        if (type_of(d) == T::distance && touches(d, X) && touches(d, Y)) add(d, d, -1, false);
      // A binary coupler C between them.
      for (size_t c = 0; c < model.bodies.size(); ++c) {
        const int C = static_cast<int>(c);
        const std::vector<int>& cj = joints_of[c];
        if (C == X || C == Y || cj.size() != 2) continue;
        int c_in = cj[0], c_out = cj[1];
        if (touches(c_in, Y) && touches(c_out, X)) std::swap(c_in, c_out);
        if (!(touches(c_in, X) && other(c_in, C) == X && touches(c_out, Y) && other(c_out, C) == Y))
          continue;
        const T ti = type_of(c_in), to = type_of(c_out);
        const bool ends_su = (ti == T::spherical || ti == T::universal) &&
                             (to == T::spherical || to == T::universal) &&
                             (ti == T::spherical || to == T::spherical);
        if (ends_su)
          add(c_in, c_out, C, false);
        else if (ti == T::revolute && to == T::revolute && planar_loop({g_in, c_in, c_out, g_out}))
          add(c_in, c_out, C, true);
      }
    }
  return loops;
}

double spatial_transmission_index(const Model& model, const SpatialTransmissionLoop& l,
                                  const VecX& q) {
  const SpatialJoint& c_in = *spatial_joint(model, l.joints[1]);
  const SpatialJoint& c_out = *spatial_joint(model, l.joints[2]);
  const SpatialJoint& g_out = *spatial_joint(model, l.joints[3]);
  // The coupler line: from its input-end point to its output-end point p (on the output link).
  const Vec3 p_in = spatial_world(model, spatial_side_on(c_in, l.bodies[0]), q);
  const Vec3 p = spatial_world(model, spatial_side_on(c_out, l.bodies[2]), q);
  const Vec3 a = spatial_axis(model, g_out, q);  // output axis (unit)
  Vec3 s = p - p_in;
  if (l.planar) {  // the force lies in the plane of motion, normal n: the revolutes' axis
    const Vec3 n = spatial_axis(model, c_in, q);
    s -= s.dot(n) * n;
  }
  const double ls = s.norm();
  if (!(ls > 0.0)) return 0.0;
  s /= ls;
  if (l.prismatic_output) return std::abs(a.dot(s));  // [Sutherland & Roth 1973]: |a·s|
  const Vec3 o = spatial_world(model, g_out.pi.body == kGround ? g_out.pi : g_out.pj, q);
  const Vec3 r = p - o;
  const double lever = a.cross(r).norm();  // the largest |a·(r × s)| over unit s
  if (!(lever > 1e-12 * std::max(1.0, r.norm()))) return 0.0;
  return std::min(1.0, std::abs(a.dot(r.cross(s))) / lever);  // [Sutherland & Roth 1973]
}

namespace {

// The design's assembly mode at the locks, limits ignored: assemble's continuation (follow_locks)
// from the design pose in steps of at most 2° (revolute) or 2 % of the mechanism's size
// (prismatic), each step projected from the previous position (mass-metric Gauss–Newton). Small
// steps keep the mode of the design (the same branch, as `cycle` follows it); a projection of the
// design pose straight onto the locks may land on another mode. Empty when a step does not
// converge (a dead point in between). With `secant`, each step is predicted along the previous
// one before the projection: through a change point, where two branches cross, it stays on the
// branch it came along (a projection from the previous position alone may turn onto the other
// one).
std::optional<VecX> continue_to_locks(const Model& model, const VecX& q_guess,
                                      const std::vector<JointLock>& locks, bool secant = false) {
  return follow_locks(model, q_guess, locks, 1e-12, {secant, length_scale(model)});
}

// A spatial joint's coordinate at q, an angle taken modulo 2π nearest the middle of its limits.
double spatial_limit_coordinate(const Model& model, int joint, const VecX& q) {
  const Joint& j = model.joints[static_cast<size_t>(joint)];
  const double x = joint_coordinate(model, joint, q);
  if (!is_revolute(model, joint) || !j.limits) return x;
  const double mid = 0.5 * (j.limits->x() + j.limits->y());
  return x - kTwoPi * std::round((x - mid) / kTwoPi);
}

// A spatial design position (docs/spatial.md §6.3–6.4): (A1) without the inputs (assemble: Ipopt in
// local coordinates, limits not applied), then the inputs reached by continuation from that
// pose on its assembly mode and branch (continue_to_locks with the secant predictor: the
// mass-metric Gauss–Newton in velocity space, q ⊕ δu), else by one projection onto the inputs.
// `assemble` takes no locks on spatial joints, so this is the spatial counterpart of
// assemble(model, q_design, {locks}).
AssemblyResult assemble_spatial_at(const Model& model, const VecX& q_design,
                                   const std::vector<JointLock>& locks) {
  AssemblyOptions free;
  free.use_limits = false;
  AssemblyResult a = assemble(model, q_design, free);
  const bool closed =
      a.status == AssemblyStatus::assembled || a.status == AssemblyStatus::unchanged;
  if (!closed || locks.empty()) return a;
  double lock_residual = 0.0;
  for (const JointLock& l : locks) {
    const double s = joint_coordinate(model, l.joint, a.q) - l.value;
    lock_residual = std::max(lock_residual, std::abs(is_revolute(model, l.joint) ? wrap(s) : s));
  }
  if (lock_residual <= 1e-12) return a;  // the design pose is at the inputs
  AssemblyResult r = a;
  std::optional<VecX> q = continue_to_locks(model, a.q, locks, true);
  std::string how = "continued from there to the inputs";
  if (!q) {
    VecX x = a.q;
    if (project_with_locks(model, x, locks, 1e-12, 200)) {
      q = x;
      how = "projected from there onto the inputs (the continuation did not reach them)";
    }
  }
  if (!q) {
    r.status = AssemblyStatus::cannot_close;
    r.message =
        "no position at the inputs: from the assembled design pose neither the "
        "continuation nor a projection onto the inputs converges";
    return r;
  }
  r.status = AssemblyStatus::assembled;
  r.q = *q;
  r.message = "design pose: " + a.message + "; " + how;
  return r;
}

}  // namespace

std::vector<LimitBlock> find_limit_blocks(const Model& model, const VecX& q_guess,
                                          const AssemblyOptions& options) {
  std::vector<LimitBlock> out;
  if (!options.use_limits) return out;
  AssemblyOptions free = options;
  free.use_limits = false;
  // On the design's assembly mode when the continuation reaches the locks; otherwise the
  // mass-metric projection of the design pose.
  const std::optional<VecX> on_branch = continue_to_locks(model, q_guess, options.locks);
  const AssemblyResult a = assemble(model, on_branch ? *on_branch : q_guess, free);
  if (a.status != AssemblyStatus::assembled && a.status != AssemblyStatus::unchanged) return out;
  for (size_t j = 0; j < model.joints.size(); ++j)
    if (outside_limits(model, static_cast<int>(j), a.q))
      out.push_back({static_cast<int>(j), limit_coordinate(model, static_cast<int>(j), a.q),
                     is_revolute(model, static_cast<int>(j))});
  return out;
}

SingularityMeasures singularity_measures(const Model& model, const VecX& q,
                                         const std::vector<int>& input_joints, int generic_rank,
                                         const std::vector<int>& idle_bodies) {
  SingularityMeasures out;
  const MatX idle = idle_rows(model, q, idle_bodies);
  const int ni = static_cast<int>(input_joints.size()) + static_cast<int>(idle.rows());
  MatX J(model.nc + ni, model.n);
  MatX Et(model.nc, model.n), A(model.n, model.n);
  compute_constraint_jacobian(model, q, Et);
  compute_inverse_mass_matrix(model, q, A);
  J.topRows(model.nc) = Et;
  VecX d(model.n);
  for (size_t k = 0; k < input_joints.size(); ++k) {
    compute_scalar(model, JointCoordinate{input_joints[k]}, q, nullptr, d);
    J.row(model.nc + static_cast<int>(k)) = d.transpose();
  }
  J.bottomRows(idle.rows()) = idle;  // idle bodies' own motions held (mass-orthogonal)
  // Mass-metric column scaling (u = √A ũ) and unit rows: unit-free.
  const VecX sqrtA = A.diagonal().cwiseSqrt();
  J = J * sqrtA.asDiagonal();
  for (Eigen::Index r = 0; r < J.rows(); ++r) {
    const double n = J.row(r).norm();
    if (n > 0.0) J.row(r) /= n;
  }
  {
    const Eigen::JacobiSVD<MatX> svd(J.topRows(model.nc));
    const VecX& s = svd.singularValues();
    out.sigma_min = generic_rank > 0 && generic_rank <= s.size() && s(0) > 0.0
                        ? s(generic_rank - 1) / s(0)
                        : 0.0;
  }
  if (!input_joints.empty() && J.rows() >= model.n) {
    const Eigen::JacobiSVD<MatX> svd(J);
    const VecX& s = svd.singularValues();
    out.eta = s(0) > 0.0 ? s(model.n - 1) / s(0) : 0.0;
  }
  return out;
}

bool ValidationReport::pass() const {
  if (stop != StopReason::none) return false;  // checks did not run
  if (circuit_defect || branch_defect || order_defect) return false;
  return std::all_of(positions.begin(), positions.end(),
                     [](const PositionReport& p) { return p.pass(); });
}

namespace {

// What every step of validate_design_positions reads: the model, the options and what is found
// once for all positions (units of the messages, length scale, design pose, loops, idle bodies).
struct ValidationContext {
  const Model& model;
  const ValidateOptions& opt;
  UnitSystem file_units;  // messages quote values in the file's declared units (in code: SI)
  double L = 1.0;         // length scale of the mechanism
  VecX q_design{};
  bool spatial = false;
  int input = -1;  // the common input joint (−1: none)
  std::vector<FourBarLoop> loops{};
  std::vector<SliderCrankLoop> slider_cranks{};
  std::vector<SpatialTransmissionLoop> transmission_loops{};
  std::vector<int> idle_bodies{};  // idle bodies at the assembled design pose
  RunWatch* bounds = nullptr;      // the run's bounds (validate_design_positions owns them)
};

// The common input: the single joint every position locks (circuits, order, η need it); −1 if
// the positions lock different joints or more than one.
int find_common_input(const Model& model) {
  int input = -1;
  bool common = !model.design_positions.empty();
  for (const DesignPosition& p : model.design_positions) {
    if (p.inputs.size() != 1 || (input >= 0 && p.inputs[0].first != input)) common = false;
    if (!p.inputs.empty() && input < 0) input = p.inputs[0].first;
  }
  return common ? input : -1;
}

// The loops whose quality is checked at every position (four-bars and slider-cranks: planar
// only; Sutherland–Roth transmission loops), and what does not apply to this mechanism.
void find_checked_loops(ValidationContext& c, ValidationReport& rep) {
  if (c.spatial) {
    rep.not_applicable = {"Grashof type: planar four-bar loops only",
                          "four-bar transmission angle: planar four-bar loops only",
                          "slider-crank pressure angle: planar slider-crank loops only"};
  }
  if (!c.spatial) {
    c.loops = find_four_bar_loops(c.model, c.input);
    c.slider_cranks = find_slider_crank_loops(c.model);
  }
  c.transmission_loops = find_spatial_transmission_loops(c.model, c.input);
  rep.transmission_index_bound =
      c.opt.min_transmission_index.value_or(std::sin(c.opt.min_transmission));
  if (c.spatial && c.transmission_loops.empty())
    rep.not_applicable.emplace_back(
        "transmission index (Sutherland & Roth 1973): no loop ground -R/P- link -S/U- binary "
        "coupler -S/U- link -R/P- ground (or a distance row, or parallel revolutes)");
}

// Generic rank: at the assembled design pose (the positions raise it to their max later). Idle
// bodies (docs/spatial.md §4.1): those mobility finds at the assembled design pose.
void design_pose_mobility(ValidationContext& c, ValidationReport& rep) {
  VecX q = c.q_design;
  AssemblyOptions ao;
  ao.use_limits = !c.spatial;  // spatial limits are checked per position
  const AssemblyResult a = assemble(c.model, c.q_design, ao);
  if (a.status == AssemblyStatus::assembled || a.status == AssemblyStatus::unchanged) q = a.q;
  const Mobility mob = compute_mobility(c.model, q);
  rep.generic_rank = mob.rank;
  for (const Mobility::Idle& i : mob.idle) c.idle_bodies.push_back(c.model.find_body(i.body));
}

// Assembly with the position's inputs locked: pr.assembly, pr.assembles and (spatial: checked
// at the assembled position; planar: the limits the assembly ran into) pr.limit_blocks. When it
// does not assemble, the failures say why. Returns the assembly.
AssemblyResult assemble_design_position(const ValidationContext& c, const AssemblyOptions& ao,
                                        PositionReport& pr) {
  const Model& model = c.model;
  AssemblyResult a = c.spatial ? assemble_spatial_at(model, c.q_design, ao.locks)
                               : assemble(model, c.q_design, ao);
  pr.assembly = a.status;
  pr.assembly_message = a.message;
  pr.assembles = a.status == AssemblyStatus::assembled || a.status == AssemblyStatus::unchanged;
  if (c.spatial && pr.assembles) {  // limits: checked at the position (assemble takes none)
    for (size_t j = 0; j < model.joints.size(); ++j) {
      const Joint& jt = model.joints[j];
      if (!jt.limits) continue;
      const double x = spatial_limit_coordinate(model, static_cast<int>(j), a.q);
      if (x < jt.limits->x() - 1e-9 || x > jt.limits->y() + 1e-9)
        pr.limit_blocks.push_back(
            {static_cast<int>(j), x, is_revolute(model, static_cast<int>(j))});
    }
    if (!pr.limit_blocks.empty()) {
      pr.assembles = false;
      pr.assembly = AssemblyStatus::cannot_close;
    }
  }
  if (pr.assembles) return a;
  if (!c.spatial) pr.limit_blocks = find_limit_blocks(model, c.q_design, ao);
  for (const LimitBlock& b : pr.limit_blocks) {
    const Joint& jt = model.joints[static_cast<size_t>(b.joint)];
    const bool rev = is_revolute(model, b.joint);
    pr.failures.push_back("joint '" + jt.name + "' would need " +
                          format_input(b.needed, rev, c.file_units) + ", outside its limits [" +
                          format_input(jt.limits->x(), rev, c.file_units) + ", " +
                          format_input(jt.limits->y(), rev, c.file_units) + "]");
  }
  pr.failures.push_back(pr.limit_blocks.empty() || !c.spatial
                            ? "does not assemble: " + a.message
                            : "does not assemble within the joint limits");
  return a;
}

// How far a position misses its target, relative: planar, the target point's distance (m);
// spatial, the larger of the distance and the angle errors, each over its tolerance.
double target_error(const ValidationContext& c, const DesignTarget& t, const VecX& q) {
  if (c.spatial) {
    const SpatialTargetErrors e = spatial_target_errors(c.model, t, q);
    return std::max(e.distance / t.tolerance,
                    e.angle ? *e.angle / t.angle_tolerance.value_or(t.tolerance / c.L) : 0.0);
  }
  double e = (world(c.model, t.point, q) - t.position).norm();
  return e;
}

// The position among the assembly modes (with a target, the mode that meets it best; else the
// projection of the design pose, modes[0]), and its number among the modes sorted by signature,
// then by coordinates: pr.q, pr.modes, pr.mode, pr.mode_signature.
void choose_mode(const ValidationContext& c, const DesignPosition& dp,
                 const std::vector<int>& inputs, const std::vector<VecX>& modes,
                 PositionReport& pr) {
  const Model& model = c.model;
  size_t chosen = 0;
  if (dp.target)
    for (size_t k = 1; k < modes.size(); ++k)
      if (target_error(c, *dp.target, modes[k]) <
          target_error(c, *dp.target, modes[chosen]) - 1e-12)
        chosen = k;
  pr.q = modes[chosen];
  // Spatial: the sign of det [Eᵀ_R; d] over the independent rows R at the position (redundant
  // rows are the norm in spatial linkages); not with idle bodies (the matrix is singular).
  std::vector<int> rows;
  if (c.spatial) {
    const Mobility mob = compute_mobility(model, pr.q);
    for (int r = 0; r < model.nc; ++r)
      if (std::find(mob.redundant_rows.begin(), mob.redundant_rows.end(), r) ==
          mob.redundant_rows.end())
        rows.push_back(r);
  }
  std::vector<std::pair<std::string, size_t>> order;
  for (size_t k = 0; k < modes.size(); ++k)
    order.emplace_back(
        mode_signature(model, modes[k], c.loops, inputs, rows, c.idle_bodies.empty()), k);
  std::sort(order.begin(), order.end(), [&](const auto& x, const auto& y) {
    if (x.first != y.first) return x.first < y.first;
    const VecX& a1 = modes[x.second];
    const VecX& b1 = modes[y.second];
    for (Eigen::Index i = 0; i < a1.size(); ++i)
      if (std::abs(a1(i) - b1(i)) > 1e-9) return a1(i) < b1(i);
    return false;
  });
  pr.modes = static_cast<int>(modes.size());
  for (size_t k = 0; k < order.size(); ++k)
    if (order[k].second == chosen) {
      pr.mode = static_cast<int>(k) + 1;
      pr.mode_signature = order[k].first;
    }
}

// How far the position is from the design pose: the kinetic-energy distance √(dqᵀ M dq) and the
// largest translation of a body frame's origin.
void measure_displacement(const ValidationContext& c, PositionReport& pr) {
  const Model& model = c.model;
  MatX M(model.n, model.n);
  compute_mass_matrix(model, c.q_design, M);
  const VecX dq = difference(model, pr.q, c.q_design);  // velocity-sized: q_design ⊕ dq = q
  pr.distance = std::sqrt(std::max(0.0, dq.dot(M * dq)));
  for (size_t b = 0; b < model.bodies.size(); ++b) {
    const Body& body = model.bodies[b];
    const int bi = static_cast<int>(b);
    if (body.kind == BodyKind::spatial) {  // the body frame's origin
      const Vec3 o = -body.spatial.com_local;
      pr.max_translation = std::max(
          pr.max_translation, (spatial_point(spatial_frame(model, bi, pr.q, nullptr), o).r -
                               spatial_point(spatial_frame(model, bi, c.q_design, nullptr), o).r)
                                  .norm());
      continue;
    }
    const PointRef origin{bi, -body.com_local, body.name};
    pr.max_translation = std::max(
        pr.max_translation, (world(model, origin, pr.q) - world(model, origin, c.q_design)).norm());
  }
}

// The target at the chosen position: its distance and angle errors against their tolerances.
void check_target(const ValidationContext& c, const DesignTarget& t, PositionReport& pr) {
  const Model& model = c.model;
  const UnitSystem& u = c.file_units;
  if (c.spatial) {
    const SpatialTargetErrors e = spatial_target_errors(model, t, pr.q);
    pr.target_error = e.distance;
    pr.target_met = e.distance <= t.tolerance;
    if (!pr.target_met)
      pr.failures.push_back("target missed by " +
                            format_quantity(e.distance, Dimension::length, u) + " (tolerance " +
                            format_quantity(t.tolerance, Dimension::length, u) + ")");
    if (e.angle) {
      pr.target_angle_error = e.angle;
      const double tol_angle = t.angle_tolerance.value_or(t.tolerance / c.L);
      if (*e.angle > tol_angle) {
        pr.target_met = false;
        pr.failures.push_back(
            std::string(t.orientation ? "target orientation" : "target direction") + " missed by " +
            format_quantity(*e.angle, Dimension::angle, u) + " (tolerance " +
            format_quantity(tol_angle, Dimension::angle, u) + ")");
      }
    }
    return;
  }
  pr.target_error = target_error(c, t, pr.q);
  pr.target_met = *pr.target_error <= t.tolerance;
  if (!pr.target_met)
    pr.failures.push_back("target missed by " +
                          format_quantity(*pr.target_error, Dimension::length, u) + " (tolerance " +
                          format_quantity(t.tolerance, Dimension::length, u) + ")");
  if (t.angle) {
    // Angle targets: the body angle of the target point's body, within
    // tolerance / L (rad): the tolerance at the mechanism's size (docs/theory.md).
    pr.target_angle_error = std::abs(wrap(body_angle(model, t.point.body, pr.q) - *t.angle));
    const double tol_angle = t.tolerance / c.L;
    if (*pr.target_angle_error > tol_angle) {
      pr.target_met = false;
      pr.failures.push_back("target angle missed by " +
                            format_quantity(*pr.target_angle_error, Dimension::angle, u) +
                            " (tolerance " + format_quantity(tol_angle, Dimension::angle, u) + ")");
    }
  }
}

// Pass 1 for one design position: assembly, its modes, the position's mode, displacement,
// target, mobility. Raises rep.generic_rank to the position's rank.
PositionReport report_position(const ValidationContext& c, const DesignPosition& dp,
                               std::mt19937& gen, ValidationReport& rep) {
  PositionReport pr;
  pr.name = dp.name;
  AssemblyOptions ao;
  std::vector<int> inputs;
  for (const auto& [j, v] : dp.inputs) {
    ao.locks.push_back({j, v});
    inputs.push_back(j);
  }
  const AssemblyResult a = assemble_design_position(c, ao, pr);
  if (!pr.assembles) return pr;
  const std::vector<VecX> modes =
      assembly_modes(c.model, ao.locks, a.q, c.q_design, c.L, c.opt, gen, c.idle_bodies, *c.bounds);
  choose_mode(c, dp, inputs, modes, pr);
  measure_displacement(c, pr);
  if (dp.target) check_target(c, *dp.target, pr);
  const Mobility mob = compute_mobility(c.model, pr.q);
  pr.dof = mob.dof;
  pr.rank = mob.rank;
  pr.redundant = mob.redundant;
  pr.idle = mob.idle;
  for (const Mobility::Idle& i : mob.idle) pr.idle_dof += i.count;
  rep.generic_rank = std::max(rep.generic_rank, mob.rank);
  return pr;
}

// Joint names of a loop, "A-B-C-D" (a joint shared by two sides named once when `skip_repeat`).
template <class Loop>
std::string loop_joint_names(const Model& model, const Loop& l, bool skip_repeat = false) {
  std::string names;
  for (int j = 0; j < 4; ++j)
    if (!skip_repeat || j != 2 || l.joints[2] != l.joints[1])
      names += (j ? "-" : "") + model.joints[static_cast<size_t>(l.joints[j])].name;
  return names;
}

// Pass 2 for one assembled position: singularity measures (σ_min, η), whether the inputs fix the
// position, and the quality of every checked loop (transmission angle, pressure angle,
// transmission index; the smallest index over all positions into rep).
void check_singularity_and_loops(const ValidationContext& c, const std::vector<int>& inputs,
                                 PositionReport& pr, ValidationReport& rep) {
  const Model& model = c.model;
  const ValidateOptions& opt = c.opt;
  const UnitSystem& u = c.file_units;
  pr.singular = singularity_measures(model, pr.q, inputs, rep.generic_rank, c.idle_bodies);
  if (pr.singular.sigma_min < opt.min_sigma)
    pr.failures.push_back("singular: sigma_min of the constraint Jacobian " +
                          fmt(pr.singular.sigma_min) + " (a change point)");
  if (pr.dof - pr.idle_dof > static_cast<int>(inputs.size())) {
    // The inputs leave the mechanism free to move: η is 0 by construction, not a dead point.
    pr.singular.eta.reset();
    pr.failures.push_back("the inputs do not fix the position: DOF " + std::to_string(pr.dof) +
                          (pr.idle_dof ? " (" + std::to_string(pr.idle_dof) + " idle)" : "") +
                          ", " + std::to_string(inputs.size()) + " input(s)");
  } else if (pr.singular.eta && *pr.singular.eta < opt.min_sigma) {
    pr.failures.push_back("dead point of the inputs: transmission index " + fmt(*pr.singular.eta));
  }
  for (const FourBarLoop& l : c.loops) {
    FourBarReport fb;
    fb.joints = loop_joint_names(model, l);
    fb.type = l.type;
    fb.transmission = transmission_angle(model, l, pr.q);
    fb.ok = std::min(fb.transmission, kPi - fb.transmission) >= opt.min_transmission;
    if (!fb.ok)
      pr.failures.push_back("transmission angle " +
                            format_quantity(fb.transmission, Dimension::angle, u) + " in loop " +
                            fb.joints + " (needs " +
                            format_quantity(opt.min_transmission, Dimension::angle, u) + " ... " +
                            format_quantity(kPi - opt.min_transmission, Dimension::angle, u) + ")");
    pr.four_bars.push_back(fb);
  }
  for (const SliderCrankLoop& l : c.slider_cranks) {
    SliderCrankReport sc;
    sc.joints = loop_joint_names(model, l);
    sc.pressure = pressure_angle(model, l, pr.q);
    sc.ok = sc.pressure <= kPi / 2.0 - opt.min_transmission;
    if (!sc.ok)
      pr.failures.push_back("pressure angle " + format_quantity(sc.pressure, Dimension::angle, u) +
                            " in slider-crank loop " + sc.joints + " (needs at most " +
                            format_quantity(kPi / 2.0 - opt.min_transmission, Dimension::angle, u) +
                            ")");
    pr.slider_cranks.push_back(sc);
  }
  for (const SpatialTransmissionLoop& l : c.transmission_loops) {
    SpatialLoopReport lr;
    lr.joints = loop_joint_names(model, l, true);
    lr.type = l.type;
    lr.index = spatial_transmission_index(model, l, pr.q);
    lr.ok = lr.index >= rep.transmission_index_bound;
    if (!lr.ok)
      pr.failures.push_back("transmission index " + fmt(lr.index) + " in loop " + lr.joints + " (" +
                            lr.type + ", Sutherland & Roth; needs at least " +
                            fmt(rep.transmission_index_bound) + ")");
    if (!rep.min_transmission_index || lr.index < *rep.min_transmission_index) {
      rep.min_transmission_index = lr.index;
      rep.min_transmission_index_at = pr.name;
    }
    pr.spatial_loops.push_back(lr);
  }
}

// Order defect: the input must move monotonically through the positions, in the given order
// (revolute steps taken the short way round, less than one turn in total).
void check_order(const ValidationContext& c, ValidationReport& rep) {
  const Model& model = c.model;
  const bool rev = is_revolute(model, c.input);
  double total = 0.0;
  int sign = 0;
  for (size_t k = 1; k < model.design_positions.size(); ++k) {
    double ds =
        model.design_positions[k].inputs[0].second - model.design_positions[k - 1].inputs[0].second;
    if (rev) ds = wrap(ds);
    total += ds;
    const int sk = ds > 0.0 ? 1 : ds < 0.0 ? -1 : 0;
    if (sign == 0 && k == 1) sign = sk;
    if (sk == 0 || sk != sign) {
      rep.order_defect = true;
      const std::string msg = "order defect: input '" + rep.input + "' goes " +
                              (sk == 0  ? "nowhere"
                               : sk > 0 ? "up"
                                        : "down") +
                              " from '" + model.design_positions[k - 1].name + "' to '" +
                              model.design_positions[k].name + "' but " +
                              (sign > 0 ? "up" : "down") + " before";
      rep.defects.push_back(msg);
      rep.positions[k].failures.push_back(msg);
    }
  }
  if (rev && std::abs(total) >= kTwoPi) {
    rep.order_defect = true;
    rep.defects.emplace_back("order defect: the positions span more than one turn of the input");
  }
}

// Circuits: each position is located on a circuit already traced, else a new one is traced from
// it (at most 8); its branch, and the nearest singular point of its circuit. Returns the
// circuits.
std::vector<Circuit> trace_circuits(const ValidationContext& c, ValidationReport& rep) {
  const Model& model = c.model;
  Tracer tracer(model, c.input, rep.generic_rank, c.opt, c.idle_bodies, *c.bounds);
  std::vector<Circuit> circuits;
  std::vector<std::optional<double>> where(rep.positions.size());
  for (size_t k = 0; k < rep.positions.size(); ++k) {
    PositionReport& pr = rep.positions[k];
    for (size_t ci = 0; ci < circuits.size() && pr.circuit < 0; ++ci)
      if (auto l = tracer.locate(circuits[ci], pr.q)) {
        pr.circuit = static_cast<int>(ci) + 1;
        where[k] = l;
      }
    if (pr.circuit < 0 && circuits.size() < 8) {
      circuits.push_back(tracer.trace(pr.q));
      pr.circuit = static_cast<int>(circuits.size());
      where[k] = 0.0;
      for (const SingularPoint& sp : circuits.back().singular)
        rep.singular_points.push_back(
            sp.kind + " of input '" + rep.input + "' at " +
            format_input(sp.s, is_revolute(model, c.input), c.file_units) + " on circuit " +
            std::to_string(pr.circuit));
    }
    if (pr.circuit < 0) continue;
    const Circuit& circuit = circuits[static_cast<size_t>(pr.circuit - 1)];
    pr.branch = circuit.branch_at(*where[k]);
    const double sk = joint_coordinate(model, c.input, pr.q);
    for (const SingularPoint& sp : circuit.singular) {
      double d = sp.s - sk;
      if (is_revolute(model, c.input)) d = wrap(d);
      if (!pr.singular_distance || std::abs(d) < *pr.singular_distance) {
        pr.singular_distance = std::abs(d);
        pr.singular_kind = sp.kind;
        pr.singular_input = sk + d;
      }
    }
  }
  return circuits;
}

// Circuit and branch defects between consecutive positions: every position on the first one's
// circuit, and no singular position between two on the same circuit.
void check_circuits_and_branches(ValidationReport& rep) {
  for (size_t k = 1; k < rep.positions.size(); ++k) {
    PositionReport& a = rep.positions[k - 1];
    PositionReport& b = rep.positions[k];
    if (b.circuit != rep.positions[0].circuit) {
      rep.circuit_defect = true;
      const std::string msg = "circuit defect: '" + b.name + "' is on circuit " +
                              std::to_string(b.circuit) + ", '" + rep.positions[0].name +
                              "' on circuit " + std::to_string(rep.positions[0].circuit) +
                              " (the linkage must be taken apart to go from one to the other)";
      rep.defects.push_back(msg);
      b.failures.push_back(msg);
    } else if (a.circuit == b.circuit && a.branch != b.branch) {
      rep.branch_defect = true;
      const std::string msg = "branch defect: a singular position lies between '" + a.name +
                              "' (branch " + std::to_string(a.branch) + ") and '" + b.name +
                              "' (branch " + std::to_string(b.branch) + ")";
      rep.defects.push_back(msg);
      b.failures.push_back(msg);
    }
  }
}

}  // namespace

namespace {

// A report whose checks a bound stopped at `where`: the checks from there on did not run.
void mark_stopped(const RunWatch& bounds, const std::string& where, ValidationReport& rep) {
  rep.stop = bounds.stop();
  rep.stop_message = bounds.message() + "; the checks from " + where + " on did not run";
}

}  // namespace

ValidationReport validate_design_positions(const Model& model, const ValidateOptions& opt) {
  ValidationReport rep;
  // Step 1: what every position shares: the common input, the loops, the design pose's rank.
  ValidationContext c{model, opt, unit_system(model.units)};
  RunWatch bounds(opt.control);
  c.bounds = &bounds;
  c.L = length_scale(model);
  c.q_design = model.design_q();
  c.spatial = model.dimension == 3;
  c.input = find_common_input(model);
  if (c.input >= 0) {
    rep.input = model.joints[static_cast<size_t>(c.input)].name;
    rep.input_angular = is_revolute(model, c.input);
  }
  find_checked_loops(c, rep);
  design_pose_mobility(c, rep);

  // Step 2 (pass 1): every position's assembly, modes, mode, target and mobility. The run's
  // fraction: a share per position, the circuits' trace the last one.
  std::mt19937 gen(opt.seed);
  const double shares = static_cast<double>(model.design_positions.size() + 1);
  for (const DesignPosition& dp : model.design_positions) {
    bounds.set_fraction(static_cast<double>(rep.positions.size()) / shares);
    rep.positions.push_back(report_position(c, dp, gen, rep));
    if (bounds.stopped()) {
      mark_stopped(bounds, "position '" + dp.name + "'", rep);
      return rep;
    }
  }

  // Step 3 (pass 2): singularity measures and loop quality at every assembled position (with
  // the generic rank over all positions).
  for (size_t k = 0; k < rep.positions.size(); ++k) {
    PositionReport& pr = rep.positions[k];
    if (!pr.assembles) continue;
    std::vector<int> inputs;
    for (const auto& [j, v] : model.design_positions[k].inputs) inputs.push_back(j);
    check_singularity_and_loops(c, inputs, pr, rep);
  }

  // Step 4: order defect (a common input, two positions or more).
  if (c.input >= 0 && rep.positions.size() >= 2) check_order(c, rep);

  // Step 5: circuits and branches (1-DOF mechanisms with one common input).
  const bool traceable =
      c.input >= 0 && std::all_of(rep.positions.begin(), rep.positions.end(), [](const auto& p) {
        return p.assembles && p.dof - p.idle_dof == 1;
      });
  if (traceable && !rep.positions.empty()) {
    bounds.set_fraction((shares - 1.0) / shares);
    rep.circuits = static_cast<int>(trace_circuits(c, rep).size());
    if (bounds.stopped()) {
      mark_stopped(bounds, "the circuits' trace", rep);
      return rep;
    }
    check_circuits_and_branches(rep);
  }
  return rep;
}

}  // namespace orthomech
