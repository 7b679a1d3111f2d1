#include "orthomech/projection/primal.hpp"

#include <stdexcept>

#include "orthomech/model/free_system.hpp"
#include "orthomech/model/loads.hpp"

namespace orthomech {

const char* to_string(ProjectionStatus s) {
  switch (s) {
    case ProjectionStatus::ok:
      return "ok";
    case ProjectionStatus::singular_G:
      return "G is singular (redundant constraints or a singular position)";
    case ProjectionStatus::singular_chart:
      return "no chart has a regular dependent block (change point)";
    case ProjectionStatus::singular_H:
      return "H is not positive definite";
  }
  return "?";
}

FreeSystemWorkspace::FreeSystemWorkspace(const Model& model)
    : M(MatX::Zero(model.n, model.n)),
      A(MatX::Zero(model.n, model.n)),
      A_diag(VecX::Zero(model.n)),
      A_sqrt(VecX::Zero(model.n)),
      M_diag(VecX::Zero(model.n)),
      Mdot(MatX::Zero(model.n, model.n)),
      Q(VecX::Zero(model.n)),
      constant_mass(mass_matrix_is_constant(model)) {}

PrimalWorkspace::PrimalWorkspace(const Model& model)
    : AE(model.n, model.nc),
      G(model.nc, model.nc),
      G_llt(model.nc),
      GinvEt(model.nc, model.n),
      pi(model.n, model.n),
      alpha(model.n, model.n),
      beta(model.n, model.n),
      GinvDt(model.nc, model.n),
      Omega(model.n, model.n),
      omega(model.n, model.n) {}

Workspace::Workspace(const Model& m, int rank)
    : free(m), constraints(m), primal(m), dual(m, rank), model(&m) {
  if (rank < 0 || rank > m.nc || rank > m.n)
    throw std::invalid_argument("Workspace: rank out of range");
}

void compute_free_system(const Model& model, const State& state, Workspace& ws) {
  if (ws.model != &model) throw std::invalid_argument("Workspace built for another Model");
  auto& fs = ws.free;
  if (!fs.constant_mass || !fs.mass_ready) {
    compute_mass_matrix(model, state.q, fs.M);          // eq. (4)
    compute_inverse_mass_matrix(model, state.q, fs.A);  // eq. (6)
    fs.A_diag = fs.A.diagonal();
    fs.A_sqrt = fs.A_diag.cwiseSqrt();
    fs.M_diag = fs.M.diagonal();
    fs.diagonal_mass = (fs.M - MatX(fs.M_diag.asDiagonal())).cwiseAbs().maxCoeff() == 0.0;
    fs.mass_ready = true;
  }
  if (!fs.constant_mass) compute_mass_matrix_rate(model, state.q, state.u, fs.Mdot);
  compute_applied_forces(model, state, fs.Q);  // eq. (17)
}

ProjectionStatus compute_primal(const Model& /*model*/, const State& /*state*/, Workspace& ws) {
  auto& p = ws.primal;
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
