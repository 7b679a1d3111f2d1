#include "orthomech/projection/dual.hpp"

#include <algorithm>
#include <stdexcept>

#include "orthomech/numerics/small_lu.hpp"
#include "orthomech/projection/free_system_stage.hpp"
#include "orthomech/projection/primal.hpp"

namespace orthomech {

DualWorkspace::DualWorkspace(const Model& model, int rank, ChartFactorisation factorisation,
                             bool projections)
    : na(model.n - rank),
      r(rank),
      engine(model, rank, factorisation),
      rhs(rank, std::max(1, model.n - rank)),
      F(MatX::Zero(model.n, model.n - rank)),
      MF(model.n, model.n - rank),
      H(model.n - rank, model.n - rank),
      H_llt(model.n - rank),
      HinvFt(model.n - rank, projections ? model.n : 0),
      psi(projections ? model.n : 0, projections ? model.n : 0),
      alpha(projections ? model.n : 0, projections ? model.n : 0),
      beta(projections ? model.n : 0, projections ? model.n : 0),
      DtF(model.nc, model.n - rank),
      MFdot(model.n, model.n - rank),
      betaFdot(model.n, model.n - rank),
      small(model.n - rank, model.n - rank),
      Fdot(MatX::Zero(model.n, model.n - rank)),
      Theta(projections ? model.n : 0, projections ? model.n : 0),
      theta(projections ? model.n : 0, projections ? model.n : 0),
      dq(VecX::Zero(model.n)) {}

void reset_chart(Workspace& ws) { ws.dual.engine.reset(); }

VecX project_velocity(const MatX& MF, const Eigen::LLT<MatX>& H_llt, const VecX& u0) {
  return H_llt.solve(MF.transpose() * u0);  // eq. (70): α u₀ = F (H⁻¹ Fᵀ M u₀)
}

namespace {
// Entry (i, j) of Eᵀ, dense or on its pattern.
double entry(const MatX& Et, int i, int j) { return Et(i, j); }
double entry(const SparseEt& Et, int i, int j) { return Et.coeff(i, j); }

template <typename Jacobian>
ProjectionStatus basis_at(const State& state, Workspace& ws, const Jacobian& Et) {
  auto& d = ws.dual;

  // 1. Chart: kept while its block is well conditioned, switched with hysteresis otherwise
  //    (the chart engine's policy, projection/chart_engine.hpp).
  if (!(d.engine.update(Et, ws.free.A_diag, ws.free.A_sqrt, state.t) > 0.0)) {
    d.status = ProjectionStatus::singular_chart;
    return d.status;
  }
  const Chart& c = d.engine.chart();

  // 2. F = P [I; −(E_RDᵀ)⁻¹ E_RIᵀ]: Eᵀ F = 0 on the independent rows, hence on all rows.
  for (int k = 0; k < d.na; ++k) {
    const int ik = c.independent[static_cast<size_t>(k)];
    d.F.row(ik).setZero();
    d.F(ik, k) = 1.0;
    for (int i = 0; i < d.r; ++i) d.rhs(i, k) = entry(Et, c.rows[static_cast<size_t>(i)], ik);
  }
  d.rhs *= -1.0;
  d.engine.solve_dependent(d.rhs, d.F);
  d.status = ProjectionStatus::ok;
  return d.status;
}
}  // namespace

ProjectionStatus compute_basis(const Model& /*model*/, const State& state, Workspace& ws) {
  return basis_at(state, ws, ws.constraints.Et);
}

ProjectionStatus compute_basis(const Model& model, const State& state, Workspace& ws,
                               const SparseEt& Et) {
  if (Et.rows() != model.nc || Et.cols() != model.n)
    throw std::invalid_argument("compute_basis: Eᵀ is not of this model");
  return basis_at(state, ws, Et);
}

ProjectionStatus compute_dual(const Model& model, const State& state, Workspace& ws) {
  if (ws.dual.psi.rows() != model.n)
    throw std::logic_error("compute_dual: the Workspace was built without the dual projections");
  if (compute_basis(model, state, ws) != ProjectionStatus::ok) return ws.dual.status;
  auto& d = ws.dual;
  const Chart& c = d.engine.chart();
  const MatX& M = ws.free.M;
  const bool diagonal = ws.free.diagonal_mass;

  // 3. H = Fᵀ M F, eq. (68), and ψ = F H⁻¹ Fᵀ, eq. (69). Every product below is O(n² n_a) or
  //    less: ψ, α, Θ have rank n_a, and products with a diagonal M are scalings.
  if (diagonal)
    d.MF = ws.free.M_diag.asDiagonal() * d.F;
  else
    d.MF.noalias() = M * d.F;
  d.H.noalias() = d.F.transpose() * d.MF;  // eq. (68)
  d.H_llt.compute(d.H);
  if (d.H_llt.info() != Eigen::Success) {
    d.status = ProjectionStatus::singular_H;
    return d.status;
  }
  d.HinvFt = d.F.transpose();
  for (Eigen::Index k = 0; k < d.HinvFt.cols(); ++k) {  // vector solves: cheap for small n_a
    auto col = d.HinvFt.col(k);
    d.H_llt.solveInPlace(col);
  }
  d.psi.noalias() = d.F * d.HinvFt;  // eq. (69): ψ = F H⁻¹ Fᵀ

  // 4. α = ψ M, β = I − ψ M, eq. (70).
  if (diagonal)
    d.alpha = d.psi * ws.free.M_diag.asDiagonal();  // eq. (70)
  else
    d.alpha.noalias() = d.psi * M;  // eq. (70)
  d.beta = -d.alpha;                // eq. (70)
  d.beta.diagonal().array() += 1.0;

  // 5. Ḟ: differentiating Eᵀ F = 0 gives Eᵀ Ḟ = −Dᵀ F; the independent rows of Ḟ are zero.
  d.DtF.noalias() = ws.constraints.Dt * d.F;
  for (int k = 0; k < d.na; ++k) d.Fdot.row(c.independent[static_cast<size_t>(k)]).setZero();
  for (int i = 0; i < d.r; ++i) d.rhs.row(i) = -d.DtF.row(c.rows[static_cast<size_t>(i)]);
  d.engine.solve_dependent(d.rhs, d.Fdot);

  // 6. Θ = Ḟ H⁻¹ Fᵀ, eq. (83); θ = β Θ + Θᵀ βᵀ = (β Ḟ)(H⁻¹ Fᵀ) + transpose, eq. (84), with
  //    β Ḟ = Ḟ − F (H⁻¹ Fᵀ)(M Ḟ).
  d.Theta.noalias() = d.Fdot * d.HinvFt;  // eq. (83)
  if (diagonal)
    d.MFdot = ws.free.M_diag.asDiagonal() * d.Fdot;
  else
    d.MFdot.noalias() = M * d.Fdot;
  d.small.noalias() = d.HinvFt * d.MFdot;
  d.betaFdot = d.Fdot;
  d.betaFdot.noalias() -= d.F * d.small;
  d.theta.noalias() = d.betaFdot * d.HinvFt;           // eq. (84): β Θ
  for (Eigen::Index j = 0; j < d.theta.cols(); ++j) {  // eq. (84): + Θᵀ βᵀ = (β Θ)ᵀ
    for (Eigen::Index i = 0; i < j; ++i)
      d.theta(i, j) = d.theta(j, i) = d.theta(i, j) + d.theta(j, i);
    d.theta(j, j) *= 2.0;
  }
  d.status = ProjectionStatus::ok;
  return d.status;
}

double refactor_chart(Workspace& ws) {
  ChartEngine& engine = ws.dual.engine;
  if (!engine.ready() && !engine.select(ws.constraints.Et, ws.free.A_diag)) return 0.0;
  return engine.factor(ws.constraints.Et, ws.free.A_sqrt);
}

void solve_chart(Workspace& ws, const VecX& b, VecX& x) { ws.dual.engine.solve(b, x); }

void solve_chart_transposed(Workspace& ws, const VecX& b, Eigen::Ref<VecX> x) {
  ws.dual.engine.solve_transposed(b, x);
}

ChartCorrectionResult correct_positions_in_chart(const Model& model, VecX& q, Workspace& ws,
                                                 const ChartCorrection& options) {
  if (!ws.free.mass_ready) {  // the chart's scaling A
    State s(model);
    s.q = q;
    compute_free_system(model, s, ws);
  }
  ChartEngine& engine = ws.dual.engine;
  VecX& f = ws.constraints.f;
  MatX& Et = ws.constraints.Et;
  compute_constraint_residual_and_jacobian(model, q, f, Et);
  if ((!engine.ready() && !engine.select(Et, ws.free.A_diag)) ||
      !(engine.factor(Et, ws.free.A_sqrt) > 0.0)) {
    ChartCorrectionResult result;
    result.status = SolveStatus::singular;
    result.residual = f.size() ? f.cwiseAbs().maxCoeff() : 0.0;
    result.message = "the chart's dependent block is singular";
    return result;
  }
  ChartCorrection prepared = options;
  prepared.start = ChartCorrection::Start::prepared;
  return engine.correct_positions(q, Et, f, ws.dual.dq, prepared);
}

ProjectionStatus evaluate_dual(const Model& model, const State& state, Workspace& ws) {
  compute_free_system(model, state, ws);
  compute_constraints(model, state, ws.constraints);
  return compute_dual(model, state, ws);
}

}  // namespace orthomech
