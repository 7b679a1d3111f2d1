#pragma once
// The power balance of a spatial sweep (tests): d/dt of kinetic plus potential energy.
#include "orthomech/analysis/cycle.hpp"
#include "orthomech/model/model.hpp"

namespace orthomech::test {

// Σ over the spatial bodies of (m v·v̇ + ωᵀ J ω̇) − m g·v at a driven position (body-frame ω: the
// gyroscopic term does no work), for a uniform gravity g.
inline double spatial_energy_rate(const Model& model, const DrivenPointView& p, const Vec3& g) {
  double sum = 0.0;
  for (const Body& b : model.bodies) {
    const Vec3 v = p.u.segment<3>(b.u_offset), vdot = p.udot.segment<3>(b.u_offset);
    const Vec3 w = p.u.segment<3>(b.u_offset + 3), wdot = p.udot.segment<3>(b.u_offset + 3);
    sum += b.mass * v.dot(vdot) + w.dot(b.spatial.inertia * wdot) - b.mass * g.dot(v);
  }
  return sum;
}

}  // namespace orthomech::test
