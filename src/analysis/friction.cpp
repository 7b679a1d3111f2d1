#include "orthomech/analysis/friction.hpp"

#include <cmath>
#include <cstddef>
#include <variant>

namespace orthomech {

namespace {

// The u entry of a body's angle (−1: the ground).
int angle_entry(const Model& model, int body) {
  if (body == kGround) return -1;
  return model.bodies[static_cast<std::size_t>(body)].u_offset + 2;
}

double rate(const Eigen::Ref<const VecX>& u, int entry) { return entry < 0 ? 0.0 : u(entry); }

double sign(double x) { return x > 0.0 ? 1.0 : x < 0.0 ? -1.0 : 0.0; }

// μ r |F| of a pin at λ.
double moment_size(const FrictionPin& p, const Eigen::Ref<const VecX>& lambda) {
  return p.coefficient * p.radius * std::hypot(lambda(p.row), lambda(p.row + 1));
}

}  // namespace

std::vector<FrictionPin> friction_pins(const Model& model) {
  std::vector<FrictionPin> pins;
  for (std::size_t j = 0; j < model.joints.size(); ++j) {
    const Joint& joint = model.joints[j];
    const auto* rev = std::get_if<Revolute>(&joint.kind);
    if (!joint.friction || !rev || joint.friction->coefficient == 0.0) continue;
    FrictionPin p;
    p.joint = static_cast<int>(j);
    p.row = joint.row_offset;
    p.u_first = angle_entry(model, rev->pi.body);
    p.u_second = angle_entry(model, rev->pj.body);
    p.coefficient = joint.friction->coefficient;
    p.radius = joint.friction->radius;
    pins.push_back(p);
  }
  return pins;
}

void add_friction_forces(const std::vector<FrictionPin>& pins, const VecX& u, const VecX& lambda,
                         VecX& Q) {
  for (const FrictionPin& p : pins) {
    const double t = moment_size(p, lambda) * sign(rate(u, p.u_second) - rate(u, p.u_first));
    if (p.u_second >= 0) Q(p.u_second) -= t;
    if (p.u_first >= 0) Q(p.u_first) += t;
  }
}

double friction_moments(const std::vector<FrictionPin>& pins, const Eigen::Ref<const VecX>& u,
                        const Eigen::Ref<const VecX>& lambda, std::vector<double>& moments) {
  moments.resize(pins.size());
  double power = 0.0;
  for (std::size_t i = 0; i < pins.size(); ++i) {
    const FrictionPin& p = pins[i];
    const double w = rate(u, p.u_second) - rate(u, p.u_first);
    const double size = moment_size(p, lambda);
    moments[i] = -size * sign(w);
    power += size * std::abs(w);
  }
  return power;
}

}  // namespace orthomech
