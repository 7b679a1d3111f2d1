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

// Body b's columns of Eᵀ scaled by √A_kk (the scales in `sa`), rows normalised, as the rank test
// of the chart selector: its null space is b's own motions (every other body at rest), in scaled
// coordinates.
Eigen::FullPivLU<MatX> own_motion_lu(const Body& b, const MatX& Et, const VecX& A_diag,
                                     double tolerance, VecX& sa) {
  sa.resize(b.nu());
  for (int k = 0; k < b.nu(); ++k) sa(k) = std::sqrt(A_diag(b.u_offset + k));
  MatX cols = Et.middleCols(b.u_offset, b.nu()) * sa.asDiagonal();
  for (Eigen::Index r = 0; r < cols.rows(); ++r) {
    const double norm = Et.row(r).norm();
    if (norm > 0.0) cols.row(r) /= norm;
  }
  Eigen::FullPivLU<MatX> lu(cols);
  lu.setThreshold(tolerance);
  return lu;
}

int own_motions(const Body& b, const MatX& Et, const VecX& A_diag, double tolerance) {
  VecX sa;
  return b.nu() - static_cast<int>(own_motion_lu(b, Et, A_diag, tolerance, sa).rank());
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

std::vector<int> idle_body_indices(const Model& model, const Mobility& m) {
  std::vector<int> out;
  for (const Mobility::Idle& i : m.idle) out.push_back(model.find_body(i.body));
  return out;
}

MatX idle_motions(const Model& model, const VecX& q, const std::vector<int>& idle) {
  if (idle.empty()) return MatX(model.n, 0);
  MatX Et(model.nc, model.n), A(model.n, model.n);
  compute_constraint_jacobian(model, q, Et);
  compute_inverse_mass_matrix(model, q, A);
  const VecX A_diag = A.diagonal();
  std::vector<VecX> motions;
  for (const int b : idle) {
    const Body& body = model.bodies[static_cast<size_t>(b)];
    VecX sa;
    const Eigen::FullPivLU<MatX> lu =
        own_motion_lu(body, Et, A_diag, ChartOptions{}.rank_tolerance, sa);
    if (lu.rank() == body.nu()) continue;
    const MatX K = lu.kernel();
    // The rotation components of the body's velocity (planar φ̇; spatial ω).
    const int rot_at = body.kind == BodyKind::spatial ? 3 : 2;
    const int rot_count = body.kind == BodyKind::spatial ? 3 : body.kind == BodyKind::rigid ? 1 : 0;
    for (Eigen::Index c = 0; c < K.cols(); ++c) {
      VecX v = VecX::Zero(model.n);
      v.segment(body.u_offset, body.nu()) = sa.asDiagonal() * K.col(c);
      const double turn = v.segment(body.u_offset + rot_at, rot_count).norm();
      motions.emplace_back(v / (turn > 0.0 ? turn : v.norm()));
    }
  }
  MatX V(model.n, static_cast<Eigen::Index>(motions.size()));
  for (size_t k = 0; k < motions.size(); ++k) V.col(static_cast<Eigen::Index>(k)) = motions[k];
  return V;
}

MatX idle_rows(const Model& model, const VecX& q, const std::vector<int>& idle, MatX* motions) {
  MatX V = idle_motions(model, q, idle);
  MatX R(V.cols(), model.n);
  if (motions) *motions = V;
  if (V.cols() == 0) return R;
  MatX M(model.n, model.n);
  compute_mass_matrix(model, q, M);
  for (Eigen::Index k = 0; k < V.cols(); ++k) {
    const VecX row = M * V.col(k);
    R.row(k) = row.transpose() / row.norm();
  }
  return R;
}

}  // namespace orthomech
