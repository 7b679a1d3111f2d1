#include "orthomech/constraints/rolling_disc.hpp"

#include <cmath>

#include "orthomech/constraints/sparse_et.hpp"

namespace orthomech {

RollingDiscKinematics rolling_disc_kinematics(const Model& model, const RollingDisc& disc,
                                              const VecX& q, const VecX* u) {
  RollingDiscKinematics x;
  x.frame = spatial_frame(model, disc.body, q, u);
  const Vec3& k = disc.normal;
  const Vec3& w = x.frame.w;
  const Vec3 a = x.frame.R * disc.axis_local;
  const Vec3 adot = w.cross(a);
  const double c = k.dot(a);
  const double s = k.cross(a).norm();  // √(1 − c²), accurate near c = 0
  const Vec3 m = (k - c * a) / s;      // from P up to the centre, in the disc plane
  const double cdot = k.dot(adot);
  const double sdot = -c * cdot / s;
  const Vec3 mdot = (-cdot * a - c * adot) / s - m * (sdot / s);
  const Vec3 rho_c = x.frame.R * disc.centre_local;
  x.rho_p = rho_c - disc.radius * m;
  x.rho_p_dot = w.cross(rho_c) - disc.radius * mdot;
  x.height = k.dot(x.frame.r + rho_c - disc.plane_point) - disc.radius * s;
  return x;
}

template <typename EtT>
void evaluate_rolling_disc(const Model& model, const RollingDisc& disc, const VecX& q,
                           const VecX* u, VecX* f, EtT* Et, MatX* Dt, VecX* Dtu) {
  const RollingDiscKinematics x = rolling_disc_kinematics(model, disc, q, u);
  const Vec3 t2 = disc.normal.cross(disc.t1);
  const Vec3* directions[3] = {&disc.t1, &t2, &disc.normal};
  for (int k = 0; k < 3; ++k) {
    const int r = disc.row_offset + k;
    const Vec3& n = *directions[k];
    const Vec3 h = x.rho_p.cross(n);           // (R1) with g = n, h = ρ_P × n
    if (f) (*f)(r) = k == 2 ? x.height : 0.0;  // eq. (20): rows t1, t2 nonholonomic
    if (Et) {
      auto e = Et->row(r);
      add_spatial_row(x.frame, n, h, 1.0, e);  // (D0), eq. (23)
    }
    const Vec3 hdot = x.rho_p_dot.cross(n);
    if (Dt) {
      auto e = Dt->row(r);
      add_spatial_row_rate(x.frame, Vec3::Zero(), h, hdot, 1.0, e);  // (D0), eq. (76)
    }
    if (Dtu) (*Dtu)(r) = hdot.dot(x.frame.w);  // (R3): ġ = 0
  }
}

// The three targets of the writers (constraints/sparse_et.hpp).
template void evaluate_rolling_disc<MatX>(const Model&, const RollingDisc&, const VecX&,
                                          const VecX*, VecX*, MatX*, MatX*, VecX*);
template void evaluate_rolling_disc<SparseEt>(const Model&, const RollingDisc&, const VecX&,
                                              const VecX*, VecX*, SparseEt*, MatX*, VecX*);
template void evaluate_rolling_disc<EtRecorder>(const Model&, const RollingDisc&, const VecX&,
                                                const VecX*, VecX*, EtRecorder*, MatX*, VecX*);

Vec3 rolling_disc_contact_force(const RollingDisc& disc, const Eigen::Ref<const VecX>& lambda) {
  return lambda(0) * disc.t1 + lambda(1) * disc.normal.cross(disc.t1) + lambda(2) * disc.normal;
}

}  // namespace orthomech
