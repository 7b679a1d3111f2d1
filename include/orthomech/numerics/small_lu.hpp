#pragma once
// LU with partial pivoting, in place, for the small dense blocks of linkages (n ≲ 20): the chart's
// dependent block E_RDᵀ and the locked-input Jacobian of the cycle corrector. The unblocked,
// column-oriented loop is about twice as fast as Eigen's PartialPivLU at n = 8–9 (measured in
// bench: cycle and dual benchmarks), whose blocked driver has a fixed cost per call. Row
// interchanges are stored LAPACK-style: at step k rows k and piv(k) were swapped.
// Blocks of order ≤ kFixedLuMax run kernels instantiated for their order (loops of known length,
// unrolled: the solves keep the right-hand side in registers, where the general loop's chain of
// stores and reloads made a random 8 × 8 solve 4× slower: 88 against 22 ns in a micro-benchmark;
// docs/performance.md has their share in the cycle benchmarks). They perform the same operations in
// the same order as the general loops below, so the factors and solutions are the same.
// Header-only; allocation-free.
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>
#include <utility>

namespace orthomech {

inline constexpr int kFixedLuMax = 16;

namespace small_lu_detail {

// f(std::integral_constant<int, n>) for 1 ≤ n ≤ kFixedLuMax; false (f not called) otherwise.
template <class F, int... Ks>
bool with_fixed_order(Eigen::Index n, F&& f, std::integer_sequence<int, Ks...>) {
  return ((n == Ks + 1 ? (f(std::integral_constant<int, Ks + 1>{}), true) : false) || ...);
}
template <class F>
bool with_fixed_order(Eigen::Index n, F&& f) {
  return with_fixed_order(n, std::forward<F>(f), std::make_integer_sequence<int, kFixedLuMax>{});
}

// lu_factor for order N (leading dimension ld).
template <int N>
double factor(double* __restrict a, Eigen::Index ld, int* __restrict piv) {
  double u_min = std::numeric_limits<double>::infinity(), u_max = 0.0;
#pragma GCC unroll 16
  for (int k = 0; k < N; ++k) {
    double* __restrict ck = a + k * ld;
    int p = k;
    double big = std::abs(ck[k]);
#pragma GCC unroll 16
    for (int i = k + 1; i < N; ++i) {
      const double v = std::abs(ck[i]);
      if (v > big) {
        big = v;
        p = i;
      }
    }
    piv[k] = p;
    if (p != k)
#pragma GCC unroll 16
      for (int j = 0; j < N; ++j) std::swap(a[k + j * ld], a[p + j * ld]);
    if (big == 0.0) return 0.0;
    u_min = std::min(u_min, big);
    u_max = std::max(u_max, big);
    const double inv = 1.0 / ck[k];
    ck[k] = inv;
#pragma GCC unroll 16
    for (int i = k + 1; i < N; ++i) ck[i] *= inv;
#pragma GCC unroll 16
    for (int j = k + 1; j < N; ++j) {
      double* __restrict cj = a + j * ld;
      const double f = cj[k];
      if (f == 0.0) continue;  // blocks of linkages are sparse (and the pattern repeats)
#pragma GCC unroll 16
      for (int i = k + 1; i < N; ++i) cj[i] -= ck[i] * f;
    }
  }
  return u_min / u_max;
}

// lu_solve for order N: the interchanges applied in memory, then the substitutions on a local
// copy that the unrolled loops keep in registers.
template <int N>
void solve(const double* __restrict a, Eigen::Index ld, const int* __restrict piv,
           double* __restrict b) {
  for (int k = 0; k < N; ++k)
    if (piv[k] != k) std::swap(b[k], b[piv[k]]);
  double x[N];
#pragma GCC unroll 16
  for (int k = 0; k < N; ++k) x[k] = b[k];
#pragma GCC unroll 16
  for (int k = 0; k < N; ++k) {
    if (x[k] == 0.0) continue;  // right-hand sides are often columns of Eᵀ: mostly zeros
    const double* col = a + k * ld;
#pragma GCC unroll 16
    for (int i = k + 1; i < N; ++i) x[i] -= col[i] * x[k];
  }
#pragma GCC unroll 16
  for (int k = N - 1; k >= 0; --k) {
    const double* col = a + k * ld;
    x[k] *= col[k];
#pragma GCC unroll 16
    for (int i = 0; i < k; ++i) x[i] -= col[i] * x[k];
  }
#pragma GCC unroll 16
  for (int k = 0; k < N; ++k) b[k] = x[k];
}

// lu_solve_transposed for order N.
template <int N>
void solve_transposed(const double* __restrict a, Eigen::Index ld, const int* __restrict piv,
                      double* __restrict b) {
  double x[N];
#pragma GCC unroll 16
  for (int k = 0; k < N; ++k) x[k] = b[k];
#pragma GCC unroll 16
  for (int k = 0; k < N; ++k) {
    const double* col = a + k * ld;
    double s = x[k];
#pragma GCC unroll 16
    for (int i = 0; i < k; ++i) s -= col[i] * x[i];
    x[k] = s * col[k];
  }
#pragma GCC unroll 16
  for (int k = N - 1; k >= 0; --k) {
    const double* col = a + k * ld;
    double s = x[k];
#pragma GCC unroll 16
    for (int i = k + 1; i < N; ++i) s -= col[i] * x[i];
    x[k] = s;
  }
#pragma GCC unroll 16
  for (int k = 0; k < N; ++k) b[k] = x[k];
  for (int k = N - 1; k >= 0; --k)
    if (piv[k] != k) std::swap(b[k], b[piv[k]]);
}

}  // namespace small_lu_detail

// A ← its LU factors: unit-lower L below the diagonal, U above it, and 1/U_kk on it. Returns
// min|U_kk| / max|U_kk|, 0 when a pivot is exactly zero (the factorisation stops there).
template <class Matrix>
double lu_factor(Matrix& A, Eigen::VectorXi& piv) {
  const Eigen::Index n = A.rows(), ld = A.outerStride();
  double* __restrict a = A.data();
  double fixed = 0.0;
  if (small_lu_detail::with_fixed_order(n, [&](auto order) {
        fixed = small_lu_detail::factor<decltype(order)::value>(a, ld, piv.data());
      }))
    return fixed;
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
  if (small_lu_detail::with_fixed_order(n, [&](auto order) {
        small_lu_detail::solve<decltype(order)::value>(a, ld, piv.data(), x);
      }))
    return;
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
  if (small_lu_detail::with_fixed_order(n, [&](auto order) {
        small_lu_detail::solve_transposed<decltype(order)::value>(a, ld, piv.data(), x);
      }))
    return;
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
