#pragma once
// LU with partial pivoting, in place, for the small dense blocks of linkages (n ≲ 20): the chart's
// dependent block E_RDᵀ and the locked-input Jacobian of the cycle corrector. The unblocked,
// column-oriented loop is about twice as fast as Eigen's PartialPivLU at n = 8–9 (measured in
// bench: cycle and dual benchmarks), whose blocked driver has a fixed cost per call. Row
// interchanges are stored LAPACK-style: at step k rows k and piv(k) were swapped.
// Header-only; allocation-free.
#include <Eigen/Core>
#include <cmath>
#include <utility>

namespace orthomech {

// A ← its LU factors (unit-lower L below the diagonal, U on and above). Returns
// min|U_kk| / max|U_kk|, 0 when a pivot is exactly zero (the factorisation stops there).
template <class Matrix>
double lu_factor(Matrix& A, Eigen::VectorXi& piv) {
  const Eigen::Index n = A.rows();
  for (Eigen::Index k = 0; k < n; ++k) {
    Eigen::Index p = k;
    double big = std::abs(A(k, k));
    for (Eigen::Index i = k + 1; i < n; ++i) {
      if (std::abs(A(i, k)) > big) {
        big = std::abs(A(i, k));
        p = i;
      }
    }
    piv(k) = static_cast<int>(p);
    if (p != k) A.row(k).swap(A.row(p));
    if (big == 0.0) return 0.0;
    const double inv = 1.0 / A(k, k);
    for (Eigen::Index i = k + 1; i < n; ++i) A(i, k) *= inv;
    for (Eigen::Index j = k + 1; j < n; ++j) {  // column by column: contiguous in Eigen's storage
      const double a = A(k, j);
      if (a == 0.0) continue;
      for (Eigen::Index i = k + 1; i < n; ++i) A(i, j) -= A(i, k) * a;
    }
  }
  if (n == 0) return 1.0;
  const auto U = A.diagonal().cwiseAbs();
  const double mx = U.maxCoeff();
  return mx > 0.0 ? U.minCoeff() / mx : 0.0;
}

// b ← A⁻¹ b from the factors of lu_factor (P A = L U).
template <class Matrix, class Vector>
void lu_solve(const Matrix& LU, const Eigen::VectorXi& piv, Vector&& b) {
  const Eigen::Index n = LU.rows();
  for (Eigen::Index k = 0; k < n; ++k)
    if (piv(k) != k) std::swap(b(k), b(piv(k)));
  for (Eigen::Index k = 0; k < n; ++k)
    for (Eigen::Index i = k + 1; i < n; ++i) b(i) -= LU(i, k) * b(k);
  for (Eigen::Index k = n - 1; k >= 0; --k) {
    b(k) /= LU(k, k);
    for (Eigen::Index i = 0; i < k; ++i) b(i) -= LU(i, k) * b(k);
  }
}

// b ← A⁻ᵀ b: Aᵀ = Uᵀ Lᵀ P, so Uᵀ z = b, Lᵀ y = z, b = Pᵀ y (interchanges in reverse order).
template <class Matrix, class Vector>
void lu_solve_transposed(const Matrix& LU, const Eigen::VectorXi& piv, Vector&& b) {
  const Eigen::Index n = LU.rows();
  for (Eigen::Index k = 0; k < n; ++k) {
    double s = b(k);
    for (Eigen::Index i = 0; i < k; ++i) s -= LU(i, k) * b(i);
    b(k) = s / LU(k, k);
  }
  for (Eigen::Index k = n - 1; k >= 0; --k) {
    double s = b(k);
    for (Eigen::Index i = k + 1; i < n; ++i) s -= LU(i, k) * b(i);
    b(k) = s;
  }
  for (Eigen::Index k = n - 1; k >= 0; --k)
    if (piv(k) != k) std::swap(b(k), b(piv(k)));
}

}  // namespace orthomech
