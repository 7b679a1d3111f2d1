#include "orthomech/dynamics/equations.hpp"

#include <Eigen/QR>

#include "orthomech/projection/dual.hpp"
#include "orthomech/projection/primal.hpp"

namespace orthomech {

void compute_multipliers(const MatX& Et, const VecX& R, VecX& lambda) {
  if (Et.rows() == 0) {  // no constraint, no multiplier (Eigen's QR fails on empty matrices)
    lambda.resize(0);
    return;
  }
  const MatX E = Et.transpose();
  const Eigen::CompleteOrthogonalDecomposition<MatX> cod(E);
  lambda = cod.solve(R);
}

// Dual dynamics (docs/design.md §4). From ṗ = Q̂ + R with ṗ = M u̇ + Ṁ u and Fᵀ R = 0 (eq. (64)):
//   (L1) u = F v, u̇ = F v̇ + Ḟ v,
//   (L2) Fᵀ M F v̇ = Fᵀ (Q̂ − Ṁ u − M Ḟ v), i.e. H v̇ = … with H from eq. (68).
ProjectionStatus compute_dual_dynamics(const Model& model, const State& state, Workspace& ws,
                                       DynamicsPoint& out) {
  const ProjectionStatus status = evaluate_dual(model, state, ws);
  if (status != ProjectionStatus::ok) return status;
  const auto& d = ws.dual;
  const auto& fs = ws.free;
  VecX v(d.na);
  for (int k = 0; k < d.na; ++k)
    v(k) = state.u(d.engine.chart().independent[static_cast<size_t>(k)]);
  const VecX Fdot_v = d.Fdot * v;                                                 // (L1)
  const VecX rhs = d.F.transpose() * (fs.Q - fs.Mdot * state.u - fs.M * Fdot_v);  // (L2)
  const VecX vdot = d.H_llt.solve(rhs);  // eq. (68): H v̇ = …
  out.udot = d.F * vdot + Fdot_v;
  out.pdot = fs.M * out.udot + fs.Mdot * state.u;
  out.R = out.pdot - fs.Q;
  out.J = ws.constraints.Et * state.u;
  compute_multipliers(ws.constraints.Et, out.R, out.lambda);
  return status;
}

ProjectionStatus compute_primal_dynamics(const Model& model, const State& state, Workspace& ws,
                                         DynamicsPoint& out) {
  const ProjectionStatus status = evaluate_primal(model, state, ws);
  if (status != ProjectionStatus::ok) return status;
  const auto& pr = ws.primal;
  const auto& fs = ws.free;
  const VecX p = fs.M * state.u;  // eq. (5)
  const VecX Mdot_u = fs.Mdot * state.u;
  out.pdot =
      pr.alpha.transpose() * fs.Q - pr.Omega * state.u + pr.beta.transpose() * Mdot_u;  // eq. (99)
  out.udot = fs.A * (out.pdot - Mdot_u);  // eq. (100) differentiated: ṗ = M u̇ + Ṁ u
  out.R = -pr.beta.transpose() * fs.Q - pr.omega * state.u +
          pr.beta.transpose() * fs.Mdot * (pr.alpha * state.u);  // eq. (91)
  out.J = ws.constraints.Et * (fs.A * p);                        // eq. (105)
  // λ from E λ = R: Eᵀ A E λ = Eᵀ A R, i.e. λ = G⁻¹ Eᵀ A R (eq. (42)).
  out.lambda = pr.G_llt.solve(ws.constraints.Et * (fs.A * out.R));
  return status;
}

}  // namespace orthomech
