#pragma once
// LU with partial pivoting, in place, for the small dense blocks of linkages (n ≲ 20): the chart's
// dependent block E_RDᵀ and the locked-input Jacobian of the cycle corrector. The unblocked,
// column-oriented loop is about twice as fast as Eigen's PartialPivLU at n = 8–9 (measured in
// bench: cycle and dual benchmarks), whose blocked driver has a fixed cost per call. Row
// interchanges are stored LAPACK-style: at step k rows k and piv(k) were swapped.
// Header-only; allocation-free.
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace orthomech {

// A ← its LU factors: unit-lower L below the diagonal, U above it, and 1/U_kk on it. Returns
// min|U_kk| / max|U_kk|, 0 when a pivot is exactly zero (the factorisation stops there).
template <class Matrix>
double lu_factor(Matrix& A, Eigen::VectorXi& piv) {
  const Eigen::Index n = A.rows(), ld = A.outerStride();
  double* __restrict a = A.data();
  double u_min = std::numeric_limits<double>::infinity(), u_max = 0.0;  // of |U_kk|
  for (Eigen::Index k = 0; k < n; ++k) {
    double* __restrict ck = a + k * ld;
    Eigen::Index p = k;
    double big = std::abs(ck[k]);
    for (Eigen::Index i = k + 1; i < n; ++i) {
      if (std::abs(ck[i]) > big) {
        big = std::abs(ck[i]);
        p = i;
      }
    }
    piv(k) = static_cast<int>(p);
    if (p != k)
      for (Eigen::Index j = 0; j < n; ++j) std::swap(a[k + j * ld], a[p + j * ld]);
    if (big == 0.0) return 0.0;
    u_min = std::min(u_min, big);
    u_max = std::max(u_max, big);
    // The diagonal keeps 1/U_kk: the solves multiply instead of dividing (a division costs as
    // much as a whole row of multiply-adds here).
    const double inv = 1.0 / ck[k];
    ck[k] = inv;
    for (Eigen::Index i = k + 1; i < n; ++i) ck[i] *= inv;
    for (Eigen::Index j = k + 1; j < n; ++j) {  // column by column: contiguous storage
      double* __restrict cj = a + j * ld;
      const double f = cj[k];
      if (f == 0.0) continue;
      for (Eigen::Index i = k + 1; i < n; ++i) cj[i] -= ck[i] * f;
    }
  }
  return n == 0 ? 1.0 : u_min / u_max;
}

// b ← A⁻¹ b from the factors of lu_factor (P A = L U). b: a vector with contiguous storage.
template <class Matrix, class Vector>
void lu_solve(const Matrix& LU, const Eigen::VectorXi& piv, Vector&& b) {
  const Eigen::Index n = LU.rows(), ld = LU.outerStride();
  const double* __restrict a = LU.data();
  double* __restrict x = b.data();
  for (Eigen::Index k = 0; k < n; ++k)
    if (piv(k) != k) std::swap(x[k], x[piv(k)]);
  for (Eigen::Index k = 0; k < n; ++k) {  // L y = P b, column by column
    const double xk = x[k];
    if (xk == 0.0) continue;  // right-hand sides are often columns of Eᵀ: mostly zeros
    const double* col = a + k * ld;
    for (Eigen::Index i = k + 1; i < n; ++i) x[i] -= col[i] * xk;
  }
  for (Eigen::Index k = n - 1; k >= 0; --k) {  // U x = y
    const double* col = a + k * ld;
    const double xk = x[k] * col[k];  // col[k] = 1/U_kk
    x[k] = xk;
    for (Eigen::Index i = 0; i < k; ++i) x[i] -= col[i] * xk;
  }
}

// b ← A⁻ᵀ b: Aᵀ = Uᵀ Lᵀ P, so Uᵀ z = b, Lᵀ y = z, b = Pᵀ y (interchanges in reverse order).
template <class Matrix, class Vector>
void lu_solve_transposed(const Matrix& LU, const Eigen::VectorXi& piv, Vector&& b) {
  const Eigen::Index n = LU.rows(), ld = LU.outerStride();
  const double* __restrict a = LU.data();
  double* __restrict x = b.data();
  for (Eigen::Index k = 0; k < n; ++k) {  // Uᵀ: column k of U is row k of Uᵀ
    const double* col = a + k * ld;
    double s = x[k];
    for (Eigen::Index i = 0; i < k; ++i) s -= col[i] * x[i];
    x[k] = s * col[k];  // col[k] = 1/U_kk
  }
  for (Eigen::Index k = n - 1; k >= 0; --k) {
    const double* col = a + k * ld;
    double s = x[k];
    for (Eigen::Index i = k + 1; i < n; ++i) s -= col[i] * x[i];
    x[k] = s;
  }
  for (Eigen::Index k = n - 1; k >= 0; --k)
    if (piv(k) != k) std::swap(x[k], x[piv(k)]);
}

}  // namespace orthomech
