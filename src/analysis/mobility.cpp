#include "orthomech/analysis/mobility.hpp"

#include <Eigen/LU>
#include <Eigen/SparseCore>
#include <algorithm>
#include <stdexcept>
#include <string>
#include <utility>

#include "orthomech/constraints/constraint_system.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/constraints/sparse_et.hpp"
#include "orthomech/model/free_system.hpp"

namespace orthomech {

namespace {

using SparseMat = Eigen::SparseMatrix<double>;  // column-major

// The number of joints that connect each body (a joint from a body to itself counts once).
std::vector<int> joints_per_body(const Model& model) {
  std::vector<int> count(model.bodies.size(), 0);
  for (const Joint& j : model.joints)
    std::visit(
        [&](const auto& k) {
          if constexpr (requires { k.pi.body; }) {
            if (k.pi.body != kGround) ++count[static_cast<size_t>(k.pi.body)];
            if (k.pj.body != kGround && k.pj.body != k.pi.body)
              ++count[static_cast<size_t>(k.pj.body)];
          }
        },
        j.kind);
  return count;
}

// Eᵀ at q (eq. (23)) and its sparse copy (n_c × n, column-major: column k lists the constraint
// rows that involve velocity component k), with ‖row‖ of every constraint row.
struct SparseJacobian {
  SparseMat Et;
  VecX row_norm;
};

// ‖row‖ of every constraint row of J.Et.
void compute_row_norms(SparseJacobian& J) {
  J.row_norm = VecX::Zero(J.Et.rows());
  for (Eigen::Index k = 0; k < J.Et.outerSize(); ++k)
    for (SparseMat::InnerIterator it(J.Et, k); it; ++it)
      J.row_norm(it.row()) += it.value() * it.value();
  J.row_norm = J.row_norm.cwiseSqrt();
}

SparseJacobian sparse_jacobian(const MatX& Et) {
  SparseJacobian J;
  J.Et = Et.sparseView(0.0, 0.0);  // exact zeros only: every computed entry is kept
  J.Et.makeCompressed();
  compute_row_norms(J);
  return J;
}

// The same from the joints' writers into Eᵀ's structural pattern (SparseEt; the values are those
// of the dense Eᵀ bit for bit), without the dense n_c × n matrix (46 MB at N-four-bar-400).
// Exact zeros of the pattern are dropped, as sparseView drops them above.
SparseJacobian sparse_jacobian(const Model& model, const VecX& q) {
  SparseEt pattern(model);
  compute_constraint_jacobian(model, q, pattern);
  SparseJacobian J;
  J.Et = pattern.matrix();  // row-major to column-major
  J.Et.prune([](Eigen::Index, Eigen::Index, double v) { return v != 0.0; });
  J.Et.makeCompressed();
  compute_row_norms(J);
  return J;
}

// The constraint rows with a nonzero in body b's columns, ascending.
std::vector<int> rows_at(const Body& b, const SparseMat& Et) {
  std::vector<int> rows;
  for (int k = 0; k < b.nu(); ++k)
    for (SparseMat::InnerIterator it(Et, b.u_offset + k); it; ++it)
      rows.push_back(static_cast<int>(it.row()));
  std::sort(rows.begin(), rows.end());
  rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
  return rows;
}

// Body b's columns of Eᵀ scaled by √A_kk (the scales in `sa`), rows normalised, as the rank test
// of the chart selector: its null space is b's own motions (every other body at rest), in scaled
// coordinates. Only the rows that involve b (rows_at) are formed: the others are zero in these
// columns and change neither the rank nor the kernel of the full-pivoting LU (a zero row is never
// a pivot while a nonzero entry is left, and the order of the other rows is kept).
Eigen::FullPivLU<MatX> own_motion_lu(const Body& b, const SparseJacobian& J, const VecX& A_diag,
                                     double tolerance, VecX& sa) {
  sa.resize(b.nu());
  for (int k = 0; k < b.nu(); ++k) sa(k) = std::sqrt(A_diag(b.u_offset + k));
  const std::vector<int> rows = rows_at(b, J.Et);
  MatX cols = MatX::Zero(static_cast<Eigen::Index>(rows.size()), b.nu());
  for (int k = 0; k < b.nu(); ++k)
    for (SparseMat::InnerIterator it(J.Et, b.u_offset + k); it; ++it) {
      const auto at = std::lower_bound(rows.begin(), rows.end(), static_cast<int>(it.row()));
      cols(at - rows.begin(), k) = it.value() * sa(k);
    }
  for (size_t r = 0; r < rows.size(); ++r) {
    const double norm = J.row_norm(rows[r]);
    if (norm > 0.0) cols.row(static_cast<Eigen::Index>(r)) /= norm;
  }
  Eigen::FullPivLU<MatX> lu(cols);
  lu.setThreshold(tolerance);
  return lu;
}

int own_motions(const Body& b, const SparseJacobian& J, const VecX& A_diag, double tolerance) {
  VecX sa;
  return b.nu() - static_cast<int>(own_motion_lu(b, J, A_diag, tolerance, sa).rank());
}

// Rank and redundant rows by the dense, column-pivoted QR of the chart selector.
void dense_rank(const Model& model, const MatX& Et, const VecX& A_diag, const ChartOptions& options,
                Mobility& m) {
  ChartSelector selector(model.nc, model.n);
  m.rank = selector.select(Et, A_diag, options, m.chart);
  const auto& order = selector.row_order();
  const VecX& piv = selector.row_pivots();
  m.smallest_pivot = m.rank > 0 ? piv(m.rank - 1) : 0.0;
  for (int k = m.rank; k < model.nc; ++k) {
    m.redundant_rows.push_back(order[static_cast<size_t>(k)]);
    m.largest_dropped = std::max(m.largest_dropped, piv(k));
  }
}

// Rank and redundant rows by the sparse QR (projection/chart.hpp: sparse_row_rank).
void sparse_rank(const Model& model, const SparseJacobian& J, const VecX& A_diag,
                 const ChartOptions& options, Mobility& m) {
  m.sparse = true;
  if (model.nc == 0) return;
  SparseRowRank s = sparse_row_rank(J.Et, A_diag, options.rank_tolerance, {});
  m.rank = s.rank;
  m.smallest_pivot = s.smallest_pivot;
  m.largest_dropped = s.largest_dropped;
  m.redundant_rows = std::move(s.redundant_rows);
}

}  // namespace

Mobility compute_mobility(const Model& model, const VecX& q, const ChartOptions& options,
                          RankMethod method) {
  Mobility m;
  m.nq = model.nq;
  m.n = model.n;
  m.nc = model.nc;
  m.grubler = model.n - model.nc;
  m.tolerance = options.rank_tolerance;
  if (method == RankMethod::automatic)
    method = constraint_system(model).structurally_sparse() && model.n >= kSparseMobilityFrom
                 ? RankMethod::sparse
                 : RankMethod::dense;
  const VecX A_diag = inverse_mass_diagonal(model, q);
  SparseJacobian J;
  if (method == RankMethod::sparse) {  // no dense Eᵀ
    J = sparse_jacobian(model, q);
    sparse_rank(model, J, A_diag, options, m);
  } else {
    MatX Et(model.nc, model.n);
    compute_constraint_jacobian(model, q, Et);
    J = sparse_jacobian(Et);
    dense_rank(model, Et, A_diag, options, m);
  }
  m.dof = model.n - m.rank;
  std::sort(m.redundant_rows.begin(), m.redundant_rows.end());
  for (int row : m.redundant_rows) m.redundant.push_back(model.constraint_row_name(row));
  const std::vector<int> joints = joints_per_body(model);  // none for a general system
  for (size_t b = 0; b < model.bodies.size(); ++b) {
    if (joints[b] < 2) continue;
    const int count = own_motions(model.bodies[b], J, A_diag, options.rank_tolerance);
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
  const SparseJacobian J = sparse_jacobian(model, q);
  const VecX A_diag = inverse_mass_diagonal(model, q);
  std::vector<VecX> motions;
  for (const int b : idle) {
    const Body& body = model.bodies[static_cast<size_t>(b)];
    VecX sa;
    const Eigen::FullPivLU<MatX> lu =
        own_motion_lu(body, J, A_diag, ChartOptions{}.rank_tolerance, sa);
    if (lu.rank() == body.nu()) continue;
    const MatX K = lu.kernel();
    // The rotation components of the body's velocity (planar φ̇; spatial ω).
    const int rot_at = body.translations();
    const int rot_count = body.rotations();
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
