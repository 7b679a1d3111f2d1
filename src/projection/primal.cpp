#include "orthomech/projection/primal.hpp"

#include <stdexcept>

#include "orthomech/projection/free_system_stage.hpp"

namespace orthomech {

PrimalWorkspace::PrimalWorkspace(const Model& model, bool allocate)
    : AE(allocate ? model.n : 0, allocate ? model.nc : 0),
      G(allocate ? model.nc : 0, allocate ? model.nc : 0),
      G_llt(allocate ? model.nc : 0),
      GinvEt(allocate ? model.nc : 0, allocate ? model.n : 0),
      pi(allocate ? model.n : 0, allocate ? model.n : 0),
      alpha(allocate ? model.n : 0, allocate ? model.n : 0),
      beta(allocate ? model.n : 0, allocate ? model.n : 0),
      GinvDt(allocate ? model.nc : 0, allocate ? model.n : 0),
      Omega(allocate ? model.n : 0, allocate ? model.n : 0),
      omega(allocate ? model.n : 0, allocate ? model.n : 0) {}

ProjectionStatus compute_primal(const Model& model, const State& /*state*/, Workspace& ws) {
  auto& p = ws.primal;
  if (p.pi.rows() != model.n)
    throw std::logic_error("compute_primal: the Workspace was built without the primal stage");
  const MatX& Et = ws.constraints.Et;
  const MatX& A = ws.free.A;
  p.AE.noalias() = A * Et.transpose();
  p.G.noalias() = Et * p.AE;  // eq. (42): G = Eᵀ A E
  p.G_llt.compute(p.G);
  // G is singular exactly when Eᵀ loses rank (redundant rows or a change point); a Cholesky
  // pivot ratio (squared) below kSingularG flags it: rounding leaves ~1e-16 on a truly
  // singular G, so 1e-12 separates singular from merely ill-conditioned (docs/theory.md).
  constexpr double kSingularG = 1e-12;
  const auto Ld = p.G_llt.matrixLLT().diagonal();
  p.G_pivot_ratio =
      Ld.size() > 0 ? (Ld.minCoeff() * Ld.minCoeff()) / (Ld.maxCoeff() * Ld.maxCoeff()) : 1.0;
  if (p.G_llt.info() != Eigen::Success || !(p.G_pivot_ratio > kSingularG)) {
    p.status = ProjectionStatus::singular_G;
    return p.status;
  }
  p.GinvEt = Et;
  p.G_llt.solveInPlace(p.GinvEt);
  p.pi.noalias() = Et.transpose() * p.GinvEt;  // eq. (43): π = E G⁻¹ Eᵀ
  p.beta.noalias() = A * p.pi;                 // eq. (44): β = A π
  p.alpha = -p.beta;                           // eq. (44): α = I − A π
  p.alpha.diagonal().array() += 1.0;
  p.GinvDt = ws.constraints.Dt;
  p.G_llt.solveInPlace(p.GinvDt);
  p.Omega.noalias() = Et.transpose() * p.GinvDt;  // eq. (78): Ω = E G⁻¹ Dᵀ
  p.omega.noalias() = p.Omega * p.alpha;          // eq. (79): ω = Ω α + αᵀ Ωᵀ
  p.omega.noalias() += p.alpha.transpose() * p.Omega.transpose();
  p.status = ProjectionStatus::ok;
  return p.status;
}

ProjectionStatus evaluate_primal(const Model& model, const State& state, Workspace& ws) {
  compute_free_system(model, state, ws);
  compute_constraints(model, state, ws.constraints);
  return compute_primal(model, state, ws);
}

}  // namespace orthomech
