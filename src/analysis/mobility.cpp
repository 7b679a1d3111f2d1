#include "orthomech/analysis/mobility.hpp"

#include <Eigen/LU>
#include <algorithm>

#include "orthomech/constraints/joints.hpp"
#include "orthomech/model/free_system.hpp"

namespace orthomech {

namespace {

// The number of joints that connect body b.
int joints_at(const Model& model, int b) {
  int count = 0;
  for (const Joint& j : model.joints)
    std::visit(
        [&](const auto& k) {
          if constexpr (requires { k.pi.body; })
            if (k.pi.body == b || k.pj.body == b) ++count;
        },
        j.kind);
  return count;
}

// Motions of body b alone: the null space of Eᵀ restricted to its columns (every other body at
// rest), columns scaled by √A_kk and rows normalised as the rank test of the chart selector.
int own_motions(const Body& b, const MatX& Et, const VecX& A_diag, double tolerance) {
  MatX cols = Et.middleCols(b.u_offset, b.nu());
  for (int k = 0; k < b.nu(); ++k) cols.col(k) *= std::sqrt(A_diag(b.u_offset + k));
  for (Eigen::Index r = 0; r < cols.rows(); ++r) {
    const double norm = Et.row(r).norm();
    if (norm > 0.0) cols.row(r) /= norm;
  }
  Eigen::FullPivLU<MatX> lu(cols);
  lu.setThreshold(tolerance);
  return b.nu() - static_cast<int>(lu.rank());
}

}  // namespace

Mobility compute_mobility(const Model& model, const VecX& q, const ChartOptions& options) {
  Mobility m;
  m.nq = model.nq;
  m.n = model.n;
  m.nc = model.nc;
  m.grubler = model.n - model.nc;
  m.tolerance = options.rank_tolerance;
  MatX Et(model.nc, model.n);
  compute_constraint_jacobian(model, q, Et);
  MatX A(model.n, model.n);
  compute_inverse_mass_matrix(model, q, A);
  ChartSelector selector(model.nc, model.n);
  Chart chart;
  m.rank = selector.select(Et, A.diagonal(), options, chart);
  m.dof = model.n - m.rank;
  const auto& order = selector.row_order();
  const VecX& piv = selector.row_pivots();
  m.smallest_pivot = m.rank > 0 ? piv(m.rank - 1) : 0.0;
  for (int k = m.rank; k < model.nc; ++k) {
    m.redundant_rows.push_back(order[static_cast<size_t>(k)]);
    m.largest_dropped = std::max(m.largest_dropped, piv(k));
  }
  std::sort(m.redundant_rows.begin(), m.redundant_rows.end());
  for (int row : m.redundant_rows) m.redundant.push_back(model.constraint_row_name(row));
  if (!model.general)
    for (size_t b = 0; b < model.bodies.size(); ++b) {
      if (joints_at(model, static_cast<int>(b)) < 2) continue;
      const int count = own_motions(model.bodies[b], Et, A.diagonal(), options.rank_tolerance);
      if (count > 0) m.idle.push_back({model.bodies[b].name, count});
    }
  return m;
}

}  // namespace orthomech
