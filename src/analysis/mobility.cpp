#include "orthomech/analysis/mobility.hpp"

#include <algorithm>

#include "orthomech/constraints/joints.hpp"
#include "orthomech/model/free_system.hpp"

namespace orthomech {

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
  return m;
}

}  // namespace orthomech
