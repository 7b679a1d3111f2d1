#pragma once
// The rolling disc (docs/spatial.md §3), a nonholonomic constraint of a spatial body: its three
// rows t1, t2, n (model.hpp: RollingDisc), defined here in one place. With a = R a′ the symmetry
// axis, c = k·a, s = |k × a| = √(1 − c²), m = (k − c a)/s (in the disc plane, from the contact
// point P up to the centre), ρ_P = ρ_c − ρ_d m the contact point from the centre of mass
// (ρ_c = R c′ the disc centre):
//   Eᵀ row  [ nᵀ | (Rᵀ(ρ_P × n))ᵀ ]                                              (D0)
//   Dᵀ row  [ 0  | (Rᵀ(ρ̇_P × n − w × (ρ_P × n)))ᵀ ],   Dᵀu = (ρ̇_P × n)·w
// for n = t1, t2, k, with ρ̇_P = w × ρ_c − ρ_d ṁ (the contact point moves on the disc:
// ṁ ≠ w × m). Rows t1, t2 have f = 0 (nonholonomic); row n has f = k·(r_C − O) − ρ_d s, the
// height of the lowest rim point above the plane, whose ∂f/∂q·B̃ is its Eᵀ row. Undefined for a
// disc lying flat (s = 0).
#include "orthomech/model/model.hpp"
#include "orthomech/model/spatial.hpp"

namespace orthomech {

// The contact geometry of a disc at (q, u) (u may be null: rates zero).
struct RollingDiscKinematics {
  SpatialFrame frame;
  Vec3 rho_p = Vec3::Zero();      // contact point P from the centre of mass, world
  Vec3 rho_p_dot = Vec3::Zero();  // its rate (not w × ρ_P)
  double height = 0.0;            // f of row n: k·(r_C − O) − ρ_d s
};
[[nodiscard]] RollingDiscKinematics rolling_disc_kinematics(const Model& model,
                                                            const RollingDisc& disc, const VecX& q,
                                                            const VecX* u);

// The disc's rows (from disc.row_offset): f (if f), Eᵀ (if Et), Dᵀ (if Dt), Dᵀu (if Dtu, needs u).
// Its rows of Eᵀ and Dᵀ are added into: they must be zero on entry (compute_constraints zeroes
// the matrices once). Allocation-free.
// EtT: MatX, SparseEt or EtRecorder (constraints/sparse_et.hpp; instantiated for the three).
template <typename EtT>
void evaluate_rolling_disc(const Model& model, const RollingDisc& disc, const VecX& q,
                           const VecX* u, VecX* f, EtT* Et, MatX* Dt, VecX* Dtu);

// The contact force of the ground on the disc (world), from the multipliers of its three rows
// (t1, t2, n): λ_t1 t1 + λ_t2 t2 + λ_n k, acting at the contact point.
[[nodiscard]] Vec3 rolling_disc_contact_force(const RollingDisc& disc,
                                              const Eigen::Ref<const VecX>& lambda);

}  // namespace orthomech
