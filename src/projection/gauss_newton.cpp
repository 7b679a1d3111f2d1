#include "orthomech/projection/gauss_newton.hpp"

#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <cmath>
#include <limits>

#include "orthomech/constraints/joints.hpp"
#include "orthomech/model/free_system.hpp"

namespace orthomech {

namespace {

double max_abs(const VecX& x) { return x.size() ? x.cwiseAbs().maxCoeff() : 0.0; }

double finite_or_infinity(double r) {
  return std::isfinite(r) ? r : std::numeric_limits<double>::infinity();
}

// The rows c = [f_rows; g] and, with gradients, C = [E_rowsᵀ; G] at q.
class Rows {
 public:
  Rows(const Model& model, const ExtraRows& extra, const GaussNewtonOptions& options)
      : model_(model),
        extra_(extra),
        options_(options),
        f_(model.nc),
        g_(extra.count),
        G_(extra.count, model.n) {
    if (options.f_rows.empty()) {
      rows_.resize(static_cast<size_t>(model.nc));
      for (int k = 0; k < model.nc; ++k) rows_[static_cast<size_t>(k)] = k;
    } else {
      rows_ = options.f_rows;
    }
  }

  // f and g at q; the residual that decides descent and convergence.
  double evaluate(const VecX& q) {
    compute_constraint_residual(model_, q, f_);
    if (extra_.count > 0) extra_.evaluate(q, g_, G_);
    f_max_ = max_abs(f_);
    g_max_ = max_abs(g_);
    return finite_or_infinity(options_.residual ? options_.residual(q) : std::max(f_max_, g_max_));
  }

  [[nodiscard]] bool converged(double residual) const {
    if (options_.extra_tolerance < 0.0) return residual <= options_.tolerance;
    return f_max_ <= options_.tolerance && g_max_ <= options_.extra_tolerance;
  }

  [[nodiscard]] double f_max() const { return f_max_; }

  // C and c at q (the last q evaluated); false when choose_f_rows chose no row.
  bool assemble(const VecX& q, const MatX& A) {
    // Sized at the first step: a start that already satisfies the rows (a closed drawing of a
    // 2400-body chain: n_c × n = 830 MB) never forms Eᵀ.
    if (Et_.rows() != model_.nc || Et_.cols() != model_.n) Et_.resize(model_.nc, model_.n);
    compute_constraint_jacobian(model_, q, Et_);
    if (options_.choose_f_rows) options_.choose_f_rows(Et_, G_, A, rows_);
    if (options_.choose_f_rows && rows_.empty()) return false;
    const auto nf = static_cast<Eigen::Index>(rows_.size());
    C_.resize(nf + extra_.count, model_.n);
    c_.resize(nf + extra_.count);
    for (Eigen::Index k = 0; k < nf; ++k) {
      const int row = rows_[static_cast<size_t>(k)];
      C_.row(k) = Et_.row(row);
      c_(k) = f_(row);
    }
    C_.bottomRows(extra_.count) = G_;
    c_.tail(extra_.count) = g_;
    return true;
  }

  [[nodiscard]] const MatX& C() const { return C_; }
  [[nodiscard]] const VecX& c() const { return c_; }

 private:
  const Model& model_;
  const ExtraRows& extra_;
  const GaussNewtonOptions& options_;
  std::vector<int> rows_;  // the rows of f in the step
  VecX f_, g_;
  MatX G_, Et_;
  VecX c_;
  MatX C_;
  double f_max_ = 0.0, g_max_ = 0.0;
};

// A = M⁻¹ (eq. (6)) at the start q, formed once (a q that holds needs none).
void ensure_inverse_mass(const Model& model, const VecX& q, MatX& A) {
  if (A.size() > 0) return;
  A.resize(model.n, model.n);
  compute_inverse_mass_matrix(model, q, A);
}

// The minimum-norm solution x with q ⊕ (−x) the step: x = W Cᵀ (C W Cᵀ)⁺ c. False when the
// rows are chosen independent and a pivot of C W Cᵀ is below options.dependent_below.
bool minimum_norm_step(const MatX& C, const VecX& c, const MatX& A,
                       const GaussNewtonOptions& options, VecX& x) {
  if (options.metric == GaussNewtonOptions::Metric::euclidean) {
    x = Eigen::CompleteOrthogonalDecomposition<MatX>(C).solve(c);  // C⁺ c
    return true;
  }
  const MatX ACt = A * C.transpose();
  if (!options.choose_f_rows) {
    const Eigen::CompleteOrthogonalDecomposition<MatX> cod(C * ACt);
    x = ACt * cod.solve(c);
    return true;
  }
  const Eigen::LDLT<MatX> ldlt(C * ACt);  // eq. (42) on the chosen rows
  if (options.dependent_below > 0.0) {
    const VecX D = ldlt.vectorD().cwiseAbs();
    if (!(D.minCoeff() > options.dependent_below * D.maxCoeff())) return false;
  }
  x = ACt * ldlt.solve(c);
  return true;
}

}  // namespace

GaussNewtonResult gauss_newton_positions(const Model& model, VecX& q, const ExtraRows& extra,
                                         const GaussNewtonOptions& options) {
  using Descent = GaussNewtonOptions::Descent;
  using Stop = GaussNewtonResult::Stop;
  GaussNewtonResult result;
  Rows rows(model, extra, options);
  MatX A;
  VecX x, trial;
  double r = rows.evaluate(q);
  double previous = std::numeric_limits<double>::infinity();
  int stalled = 0;
  auto stop = [&](Stop why) {
    result.stop = why;
    result.converged = why == Stop::converged;
    return result;
  };
  for (int it = 0;; ++it) {
    result.residual = r;
    if (!std::isfinite(r)) return stop(Stop::not_finite);
    if (rows.converged(r)) return stop(Stop::converged);
    stalled = r > 0.5 * previous ? stalled + 1 : 0;
    if (options.stall_limit > 0 && stalled >= options.stall_limit) return stop(Stop::stalled);
    if (it >= options.max_iterations) break;
    previous = r;
    const bool mass_metric = options.metric == GaussNewtonOptions::Metric::mass;
    if (mass_metric || options.choose_f_rows) ensure_inverse_mass(model, q, A);
    if (!rows.assemble(q, A)) return stop(Stop::no_rows);
    if (!minimum_norm_step(rows.C(), rows.c(), A, options, x)) return stop(Stop::dependent_rows);
    if (!x.allFinite()) return stop(Stop::not_finite);
    if (options.descent == Descent::free) {
      integrate_positions(model, q, x, -1.0);  // q ⊕ (−x)
      r = rows.evaluate(q);
      ++result.steps;
      continue;
    }
    double step = 1.0;
    trial = q;
    integrate_positions(model, trial, x, -step);
    double rt = rows.evaluate(trial);
    // Backtracking on the residual keeps wild starts (multi-start) from diverging.
    for (int k = 0; options.descent == Descent::backtrack && k < 8 && !(rt < r); ++k) {
      step *= 0.5;
      trial = q;
      integrate_positions(model, trial, x, -step);
      rt = rows.evaluate(trial);
    }
    if (!(rt < r)) {
      rows.evaluate(q);  // the rows at the q returned
      return stop(Stop::no_descent);
    }
    q = trial;
    r = rt;
    ++result.steps;
  }
  if (options.accept >= 0.0 && rows.f_max() <= options.accept) return stop(Stop::converged);
  return stop(Stop::iterations);
}

}  // namespace orthomech
