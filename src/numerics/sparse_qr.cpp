#include "orthomech/numerics/sparse_qr.hpp"

#include <cmath>
#include <new>
#include <stdexcept>
#include <string>
#include <suitesparse/SuiteSparseQR.hpp>

namespace orthomech {

namespace {
using Long = SuiteSparse_long;
[[noreturn]] void fail(const char* what, int status) {
  if (status == CHOLMOD_OUT_OF_MEMORY) throw std::bad_alloc();  // the environment's limit
  throw std::runtime_error(std::string("SuiteSparseQR: ") + what + " failed (CHOLMOD status " +
                           std::to_string(status) + ")");
}
}  // namespace

struct SparseRankQr::Spqr {
  cholmod_common cc{};
  cholmod_sparse* H = nullptr;  // Householder vectors, m × nh
  cholmod_dense* HTau = nullptr;
  Long* HPinv = nullptr;  // row permutation of H
  Long m = 0;

  Spqr() {
    cholmod_l_start(&cc);
    cc.print = 0;  // errors are thrown here, never printed (stdout carries results)
  }
  ~Spqr() {
    cholmod_l_free_sparse(&H, &cc);
    cholmod_l_free_dense(&HTau, &cc);
    cholmod_l_free(static_cast<size_t>(m), sizeof(Long), HPinv, &cc);
    cholmod_l_finish(&cc);
  }
  Spqr(const Spqr&) = delete;
  Spqr& operator=(const Spqr&) = delete;

  // Y = Qᵀ X (method SPQR_QTX) or Q X (SPQR_QX), X dense m × k.
  Eigen::MatrixXd apply(int method, const Eigen::MatrixXd& X) {
    if (X.rows() != m) throw std::invalid_argument("SparseRankQr: X must have m rows");
    if (X.cols() == 0 || m == 0) return X;
    cholmod_dense view{};
    view.nrow = static_cast<size_t>(X.rows());
    view.ncol = static_cast<size_t>(X.cols());
    view.nzmax = view.nrow * view.ncol;
    view.d = view.nrow;
    view.x = const_cast<double*>(X.data());  // read only (qmult's inputs are not modified)
    view.xtype = CHOLMOD_REAL;
    view.dtype = CHOLMOD_DOUBLE;
    cholmod_dense* Y = SuiteSparseQR_qmult<double>(method, H, HTau, HPinv, &view, &cc);
    if (!Y) fail("qmult", cc.status);
    Eigen::MatrixXd out =
        Eigen::Map<const Eigen::MatrixXd>(static_cast<const double*>(Y->x), X.rows(), X.cols());
    cholmod_l_free_dense(&Y, &cc);
    return out;
  }
};

// (L1) S as CHOLMOD sees it: a packed, sorted compressed-column matrix with 64-bit indices.
// (L2) [Q, R, P] = qr(S) in COLAMD order with Heath's rank detection at `tolerance`; R's first
//      `rank` rows, Q as Householder vectors (kept for apply_Q/apply_Qt).
// (L3) kept_pivots = |R_kk|, k < rank.
SparseRankQr::SparseRankQr(const Eigen::SparseMatrix<double>& S, double tolerance)
    : spqr_(std::make_unique<Spqr>()) {
  if (!S.isCompressed()) throw std::invalid_argument("SparseRankQr: S must be compressed");
  Spqr& q = *spqr_;
  q.m = S.rows();
  const Long k = S.cols();
  std::vector<Long> p(S.outerIndexPtr(), S.outerIndexPtr() + k + 1);  // (L1)
  std::vector<Long> i(S.innerIndexPtr(), S.innerIndexPtr() + S.nonZeros());
  cholmod_sparse A{};
  A.nrow = static_cast<size_t>(q.m);
  A.ncol = static_cast<size_t>(k);
  A.nzmax = static_cast<size_t>(S.nonZeros());
  A.p = p.data();
  A.i = i.data();
  A.x = const_cast<double*>(S.valuePtr());  // read only
  A.stype = 0;
  A.itype = CHOLMOD_LONG;
  A.xtype = CHOLMOD_REAL;
  A.dtype = CHOLMOD_DOUBLE;
  A.sorted = 1;
  A.packed = 1;
  cholmod_sparse* R = nullptr;
  Long* E = nullptr;
  const Long rank = SuiteSparseQR<double>(SPQR_ORDERING_COLAMD, tolerance, 0, &A, &R, &E, &q.H,
                                          &q.HPinv, &q.HTau, &q.cc);  // (L2)
  if (rank < 0 || !R) {
    cholmod_l_free_sparse(&R, &q.cc);
    cholmod_l_free(static_cast<size_t>(k), sizeof(Long), E, &q.cc);
    fail("factorisation", q.cc.status);
  }
  rank_ = static_cast<int>(rank);
  order_.resize(static_cast<size_t>(k));
  for (Long j = 0; j < k; ++j) order_[static_cast<size_t>(j)] = static_cast<int>(E ? E[j] : j);
  pivots_ = Eigen::VectorXd::Zero(rank_);  // (L3)
  const auto* Rp = static_cast<const Long*>(R->p);
  const auto* Ri = static_cast<const Long*>(R->i);
  const auto* Rx = static_cast<const double*>(R->x);
  for (Long j = 0; j < rank; ++j)
    for (Long e = Rp[j]; e < Rp[j + 1]; ++e)
      if (Ri[e] == j) pivots_(j) = std::abs(Rx[e]);
  cholmod_l_free_sparse(&R, &q.cc);
  cholmod_l_free(static_cast<size_t>(k), sizeof(Long), E, &q.cc);
}

SparseRankQr::~SparseRankQr() = default;

Eigen::MatrixXd SparseRankQr::apply_Qt(const Eigen::MatrixXd& X) const {
  return spqr_->apply(SPQR_QTX, X);
}

Eigen::MatrixXd SparseRankQr::apply_Q(const Eigen::MatrixXd& X) const {
  return spqr_->apply(SPQR_QX, X);
}

Eigen::MatrixXd SparseRankQr::trailing_Q() const {
  const Eigen::Index m = spqr_->m;
  Eigen::MatrixXd X = Eigen::MatrixXd::Zero(m, m - rank_);
  X.bottomRows(m - rank_).setIdentity();
  return apply_Q(X);
}

}  // namespace orthomech
