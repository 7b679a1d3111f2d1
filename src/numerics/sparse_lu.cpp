#include "orthomech/numerics/sparse_lu.hpp"

#include <suitesparse/klu.h>

namespace orthomech {

struct SparseLu::Klu {
  klu_common common{};
  klu_symbolic* symbolic = nullptr;
  klu_numeric* numeric = nullptr;
  int n = 0;

  Klu() {
    klu_defaults(&common);
    // Partial pivoting (KLU's default 0.001 prefers the diagonal down to a thousandth of the
    // column's largest entry). No row scaling: the owner scales the block (the chart engine, to
    // the mass metric). No check of the input's indices either (scale −1; the check took 3 % of
    // an N = 40 run): an Eigen matrix in compressed form has sorted, unique row indices.
    common.tol = 1.0;
    common.scale = -1;
  }
  ~Klu() {
    free_numeric();
    if (symbolic) klu_free_symbolic(&symbolic, &common);
  }
  Klu(const Klu&) = delete;
  Klu& operator=(const Klu&) = delete;
  void free_numeric() {
    if (numeric) klu_free_numeric(&numeric, &common);
  }
};

namespace {
// KLU's C interface takes its inputs through non-const pointers and does not write them.
int* pointers(const Eigen::SparseMatrix<double>& A) { return const_cast<int*>(A.outerIndexPtr()); }
int* indices(const Eigen::SparseMatrix<double>& A) { return const_cast<int*>(A.innerIndexPtr()); }
double* values(const Eigen::SparseMatrix<double>& A) { return const_cast<double*>(A.valuePtr()); }
}  // namespace

SparseLu::SparseLu() : klu_(std::make_unique<Klu>()) {}
SparseLu::~SparseLu() = default;

bool SparseLu::analyze(const Eigen::SparseMatrix<double>& A) {
  Klu& k = *klu_;
  k.free_numeric();
  if (k.symbolic) klu_free_symbolic(&k.symbolic, &k.common);
  k.n = static_cast<int>(A.cols());
  if (!A.isCompressed() || A.rows() != A.cols()) return false;
  k.symbolic = klu_analyze(k.n, pointers(A), indices(A), &k.common);
  return k.symbolic != nullptr;
}

bool SparseLu::factor_fresh(const Eigen::SparseMatrix<double>& A) {
  Klu& k = *klu_;
  k.free_numeric();
  ++fresh_;
  k.numeric = klu_factor(pointers(A), indices(A), values(A), k.symbolic, &k.common);
  return k.numeric != nullptr && k.common.status == KLU_OK;
}

bool SparseLu::factorize(const Eigen::SparseMatrix<double>& A) {
  Klu& k = *klu_;
  if (!k.symbolic) return false;
  if (!k.numeric) return factor_fresh(A);
  // The last fresh factorisation's pivots, kept while they stay good.
  ++refactored_;
  if (klu_refactor(pointers(A), indices(A), values(A), k.symbolic, k.numeric, &k.common) != 0 &&
      k.common.status == KLU_OK &&
      klu_rgrowth(pointers(A), indices(A), values(A), k.symbolic, k.numeric, &k.common) != 0 &&
      k.common.rgrowth * kMaxGrowth >= 1.0)
    return true;
  return factor_fresh(A);
}

double SparseLu::pivot_ratio() {
  Klu& k = *klu_;
  if (!k.numeric || klu_rcond(k.symbolic, k.numeric, &k.common) == 0) return 0.0;
  return k.common.rcond;
}

namespace {
// (−1)^(n − number of cycles) of the permutation p of 0 … n−1. seen: n flags of work space.
int permutation_sign(const int* p, int n, std::vector<char>& seen) {
  seen.assign(static_cast<size_t>(n), 0);
  int sign = 1;
  for (int i = 0; i < n; ++i) {
    if (seen[static_cast<size_t>(i)]) continue;
    int length = 0;
    for (int j = i; !seen[static_cast<size_t>(j)]; j = p[j]) {
      seen[static_cast<size_t>(j)] = 1;
      ++length;
    }
    if (length % 2 == 0) sign = -sign;  // a cycle of even length is an odd permutation
  }
  return sign;
}
}  // namespace

int SparseLu::determinant_sign() const {
  const Klu& k = *klu_;
  if (!k.numeric) return 0;
  // P A Q = L U (KLU's block triangular form with the blocks' pivoting folded into Pnum):
  // det A = sign(P) sign(Q) Π U_kk.
  const auto* u = static_cast<const double*>(k.numeric->Udiag);
  int sign = 1;
  for (int i = 0; i < k.n; ++i)
    if (u[i] < 0.0) sign = -sign;
  return sign * permutation_sign(k.numeric->Pnum, k.n, seen_) *
         permutation_sign(k.symbolic->Q, k.n, seen_);
}

void SparseLu::solve_in_place(double* x) {
  Klu& k = *klu_;
  klu_solve(k.symbolic, k.numeric, k.n, 1, x, &k.common);
}

void SparseLu::solve_transposed_in_place(double* x) {
  Klu& k = *klu_;
  klu_tsolve(k.symbolic, k.numeric, k.n, 1, x, &k.common);
}

}  // namespace orthomech
