#include "orthomech/projection/dual.hpp"

#include <algorithm>

#include "orthomech/numerics/small_lu.hpp"
#include "orthomech/projection/primal.hpp"

namespace orthomech {

namespace {
// Chart switches kept in DualWorkspace::switches (the count goes on beyond it).
constexpr size_t kMaxRecordedSwitches = 1024;
}  // namespace

DualWorkspace::DualWorkspace(const Model& model, int rank)
    : na(model.n - rank),
      r(rank),
      selector(model.nc, model.n),
      Ert_D(rank, rank),
      Ert_D_piv(rank),
      rhs(rank, std::max(1, model.n - rank)),
      sol(rank, std::max(1, model.n - rank)),
      F(MatX::Zero(model.n, model.n - rank)),
      MF(model.n, model.n - rank),
      H(model.n - rank, model.n - rank),
      H_llt(model.n - rank),
      HinvFt(model.n - rank, model.n),
      psi(model.n, model.n),
      alpha(model.n, model.n),
      beta(model.n, model.n),
      DtF(model.nc, model.n - rank),
      MFdot(model.n, model.n - rank),
      betaFdot(model.n, model.n - rank),
      small(model.n - rank, model.n - rank),
      Fdot(MatX::Zero(model.n, model.n - rank)),
      Theta(model.n, model.n),
      theta(model.n, model.n),
      Fdot_scratch(MatX::Zero(model.n, std::max(1, model.n - rank))),
      dq(VecX::Zero(model.n)) {
  switches.reserve(kMaxRecordedSwitches);
}

void reset_chart(Workspace& ws) { ws.dual.chart_ready = false; }

namespace {

// LU of the scaled dependent block S_r E_RDᵀ S_d (S_d = diag √A_D) of a chart; returns its
// quality min |U_kk| / max |U_kk| (0 if singular).
double factor_chart(const MatX& Et, const VecX& A_sqrt, const Chart& c, DualWorkspace& d) {
  const int r = c.rank();
  for (int k = 0; k < r; ++k) {
    const int dk = c.dependent[static_cast<size_t>(k)];
    for (int i = 0; i < r; ++i)
      d.Ert_D(i, k) = c.row_scale(i) * Et(c.rows[static_cast<size_t>(i)], dk) * A_sqrt(dk);
  }
  if (r == 0) return 1.0;
  return lu_factor(d.Ert_D, d.Ert_D_piv);  // in place: Ert_D holds the factors
}

// X = −(E_RDᵀ)⁻¹ B_R for B = rhs rows (r × n_a), using the scaled LU:
// (E_RDᵀ)⁻¹ = S_d (S_r E_RDᵀ S_d)⁻¹ S_r. Writes X into the dependent rows of `out`.
void solve_dependent(const VecX& A_sqrt, const Chart& c, DualWorkspace& d, MatX& out) {
  const int r = c.rank();
  if (r == 0) return;
  for (int i = 0; i < r; ++i) d.rhs.row(i) *= -c.row_scale(i);
  // Column by column (vector solves are far cheaper than blocked matrix paths for the small
  // blocks of linkages): sol = (S_r E_RDᵀ S_d)⁻¹ rhs.
  for (Eigen::Index k = 0; k < out.cols(); ++k) {
    d.sol.col(k).head(r) = d.rhs.col(k).head(r);
    lu_solve(d.Ert_D, d.Ert_D_piv, d.sol.col(k).head(r));
  }
  for (int k = 0; k < r; ++k) {
    const int dk = c.dependent[static_cast<size_t>(k)];
    out.row(dk) = A_sqrt(dk) * d.sol.row(k).head(out.cols());
  }
}

}  // namespace

ProjectionStatus compute_basis(const Model& /*model*/, const State& state, Workspace& ws) {
  auto& d = ws.dual;
  const MatX& Et = ws.constraints.Et;
  const VecX& A_diag = ws.free.A_diag;
  const VecX& A_sqrt = ws.free.A_sqrt;

  // 1. Chart: keep it while its dependent block is well conditioned; otherwise re-select with
  //    the rank-revealing QR and switch if the new one is better by the hysteresis factor.
  if (!d.chart_ready) {
    d.selector.select(Et, A_diag, d.options, d.chart);
    d.chart_ready = true;
    d.quality = factor_chart(Et, A_sqrt, d.chart, d);
  } else {
    d.quality = factor_chart(Et, A_sqrt, d.chart, d);
    if (d.quality < d.options.switch_below) {
      Chart candidate = d.chart;  // NOTE: allocates, but only when the chart degrades
      d.selector.select(Et, A_diag, d.options, candidate);
      const double old_quality = d.quality;
      const double q_new = candidate.rank() == d.r ? factor_chart(Et, A_sqrt, candidate, d) : 0.0;
      if (q_new > d.options.hysteresis * old_quality) {
        d.chart = std::move(candidate);
        d.quality = q_new;
        ++d.switch_count;
        if (d.switches.size() < kMaxRecordedSwitches)
          d.switches.push_back({state.t, old_quality, q_new});
      } else {
        d.quality = factor_chart(Et, A_sqrt, d.chart, d);  // restore the LU of the chart kept
      }
    }
  }
  if (d.chart.rank() != d.r || !(d.quality > 0.0)) {
    d.status = ProjectionStatus::singular_chart;
    return d.status;
  }
  const Chart& c = d.chart;

  // 2. F = P [I; −(E_RDᵀ)⁻¹ E_RIᵀ]: Eᵀ F = 0 on the independent rows, hence on all rows.
  for (int k = 0; k < d.na; ++k) {
    const int ik = c.independent[static_cast<size_t>(k)];
    d.F.row(ik).setZero();
    d.F(ik, k) = 1.0;
    for (int i = 0; i < d.r; ++i) d.rhs(i, k) = Et(c.rows[static_cast<size_t>(i)], ik);
  }
  solve_dependent(A_sqrt, c, d, d.F);
  d.status = ProjectionStatus::ok;
  return d.status;
}

ProjectionStatus compute_dual(const Model& model, const State& state, Workspace& ws) {
  if (compute_basis(model, state, ws) != ProjectionStatus::ok) return ws.dual.status;
  auto& d = ws.dual;
  const Chart& c = d.chart;
  const VecX& A_sqrt = ws.free.A_sqrt;
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
  for (int i = 0; i < d.r; ++i) d.rhs.row(i) = d.DtF.row(c.rows[static_cast<size_t>(i)]);
  solve_dependent(A_sqrt, c, d, d.Fdot);

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
  if (!ws.dual.chart_ready) {
    ws.dual.selector.select(ws.constraints.Et, ws.free.A_diag, ws.dual.options, ws.dual.chart);
    ws.dual.chart_ready = true;
  }
  ws.dual.quality = factor_chart(ws.constraints.Et, ws.free.A_sqrt, ws.dual.chart, ws.dual);
  return ws.dual.quality;
}

void solve_chart(Workspace& ws, const VecX& b, VecX& x) {
  auto& d = ws.dual;
  const Chart& c = d.chart;
  x.setZero();
  for (int i = 0; i < d.r; ++i) x(i) = b(c.rows[static_cast<size_t>(i)]);  // scratch
  for (int i = 0; i < d.r; ++i) d.rhs(i, 0) = -x(i);
  solve_dependent(ws.free.A_sqrt, c, d, d.Fdot_scratch);
  x.setZero();
  for (int k = 0; k < d.r; ++k) {
    const int dk = c.dependent[static_cast<size_t>(k)];
    x(dk) = d.Fdot_scratch(dk, 0);
  }
}

void solve_chart_transposed(Workspace& ws, const VecX& b, Eigen::Ref<VecX> x) {
  // (E_RDᵀ)ᵀ = S_d⁻¹ Sᵀ S_r⁻¹ with S = S_r E_RDᵀ S_d, so Sᵀ (S_r⁻¹ x) = S_d b_D.
  auto& d = ws.dual;
  const Chart& c = d.chart;
  const int r = d.r;
  if (r == 0) return;
  auto w = d.sol.col(0);
  for (int k = 0; k < r; ++k) {
    const int dk = c.dependent[static_cast<size_t>(k)];
    w(k) = ws.free.A_sqrt(dk) * b(dk);
  }
  lu_solve_transposed(d.Ert_D, d.Ert_D_piv, w.head(r));
  for (int i = 0; i < r; ++i) x(i) = c.row_scale(i) * w(i);
}

ProjectionStatus evaluate_dual(const Model& model, const State& state, Workspace& ws) {
  compute_free_system(model, state, ws);
  compute_constraints(model, state, ws.constraints);
  return compute_dual(model, state, ws);
}

}  // namespace orthomech
