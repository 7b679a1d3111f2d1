#pragma once
// Private to src/synthesis: the Levenberg–Marquardt polish of path generation (L23), shared by
// the four-bar (path_generation.cpp) and the slider-crank (slider_crank.cpp) searches.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace orthomech::synthesis::detail {

// (L23) Levenberg–Marquardt on a residual vector res(x, r) of size m, central-difference
// Jacobian, steps clamped to the box; a step is kept only when it lowers F = |r|². Adds its
// evaluations of res to `evaluations`.
template <typename Residuals>
Eigen::VectorXd levenberg_marquardt(const Residuals& res_raw, int m, Eigen::VectorXd x,
                                    const Eigen::VectorXd& lo, const Eigen::VectorXd& hi,
                                    int max_iterations, int& evaluations) {
  const auto res = [&](const Eigen::VectorXd& y, Eigen::VectorXd& r_out) {
    ++evaluations;
    res_raw(y, r_out);
  };
  Eigen::VectorXd r(m), rp(m), rm(m), r_try(m);
  Eigen::MatrixXd J(m, x.size());
  res(x, r);
  double F = r.squaredNorm(), lambda = 1e-3;
  for (int iter = 0; iter < max_iterations && F > 1e-30; ++iter) {
    for (Eigen::Index j = 0; j < x.size(); ++j) {  // central differences
      const double h = 1e-7 * (1.0 + std::abs(x(j)));
      Eigen::VectorXd xp = x, xm = x;
      xp(j) += h;
      xm(j) -= h;
      res(xp, rp);
      res(xm, rm);
      J.col(j) = (rp - rm) / (2.0 * h);
    }
    const Eigen::MatrixXd JtJ = J.transpose() * J;
    const Eigen::VectorXd g = J.transpose() * r;
    bool improved = false;
    for (int tries = 0; tries < 12 && !improved; ++tries) {
      Eigen::MatrixXd A = JtJ;
      A.diagonal() += lambda * (JtJ.diagonal().array() + 1e-12).matrix();
      const Eigen::VectorXd x_try = (x - A.ldlt().solve(g)).cwiseMax(lo).cwiseMin(hi);
      res(x_try, r_try);
      const double F_try = r_try.squaredNorm();
      if (F_try < F) {
        improved = F - F_try > 1e-15 * F;
        x = x_try, r = r_try, F = F_try;
        lambda = std::max(lambda / 3.0, 1e-12);
        if (!improved) return x;  // stalled
      } else {
        lambda *= 4.0;
      }
    }
    if (!improved) break;
  }
  return x;
}

}  // namespace orthomech::synthesis::detail
