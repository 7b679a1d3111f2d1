#include "orthomech/dynamics/general.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/QR>
#include <cmath>

#include "integrator.hpp"

namespace orthomech {

namespace {

struct Eval {
  MatX M, A, Mdot, Et;
  VecX Q, Dtu;
  void at(const GeneralSystem& s, const VecX& q, const VecX& u, double t) {
    M.resize(s.n, s.n);
    Mdot.resize(s.n, s.n);
    Et.resize(s.nc, s.n);
    Q.resize(s.n);
    Dtu.resize(s.nc);
    s.mass(q, M);
    A = M.llt().solve(MatX::Identity(s.n, s.n));  // eq. (6)
    s.mass_rate(q, u, Mdot);
    s.forces(q, u, t, Q);
    s.jacobian(q, Et);
    s.convective(q, u, Dtu);
  }
};

}  // namespace

bool compute_general_primal(const GeneralSystem& sys, const VecX& q, const VecX& u, double t,
                            GeneralDynamics& out) {
  Eval e;
  e.at(sys, q, u, t);
  const MatX E = e.Et.transpose();
  const MatX G = e.Et * e.A * E;  // eq. (42)
  const Eigen::LLT<MatX> llt(G);
  if (llt.info() != Eigen::Success) return false;
  const MatX pi = E * llt.solve(e.Et);                     // eq. (43)
  const MatX beta = e.A * pi;                              // eq. (44)
  const MatX alpha = MatX::Identity(sys.n, sys.n) - beta;  // eq. (44)
  // Ω from Dᵀ: only Ω u = E G⁻¹ Dᵀu and ω u are needed; ω u = Ω α u + αᵀ Ωᵀ u (eq. (79)) with
  // Ω = E G⁻¹ Dᵀ. Dᵀ itself is linear in u: Ω u needs Dᵀu only, and for ω u we use (102):
  // ω u = Ω u on admissible u, which is checked separately (crosscheck) for the mechanism engine.
  const VecX Omega_u = E * llt.solve(e.Dtu);  // eq. (78) applied to u
  const VecX Mdot_u = e.Mdot * u;
  out.pdot = alpha.transpose() * e.Q - Omega_u + beta.transpose() * Mdot_u;  // eq. (99)
  out.udot = e.A * (out.pdot - Mdot_u);  // ṗ = M u̇ + Ṁ u, eq. (100)
  // eq. (91): R = −βᵀQ̂ − ωu + Ṁ_βα u, Ṁ_βα = βᵀṀα (eq. (104)); ωu = Ωu (eq. (102)).
  out.R = -beta.transpose() * e.Q - Omega_u + beta.transpose() * e.Mdot * (alpha * u);
  out.lambda = llt.solve(e.Et * (e.A * out.R));
  out.J = e.Et * u;  // eq. (105): J = EᵀAp with p = Mu
  return true;
}

bool compute_general_dual(const GeneralSystem& sys, const VecX& q, const VecX& u, double t,
                          GeneralDynamics& out) {
  Eval e;
  e.at(sys, q, u, t);
  // F: orthonormal basis of null(Eᵀ) from a full QR of E (columns beyond the rank).
  const MatX E = e.Et.transpose();
  const Eigen::ColPivHouseholderQR<MatX> qr(E);
  const int r = static_cast<int>(qr.rank());
  const MatX Qfull = qr.householderQ() * MatX::Identity(sys.n, sys.n);
  const MatX F = Qfull.rightCols(sys.n - r);
  // w: minimum-norm solution of Eᵀ w = −Dᵀu (Ḟ v of the design, for this F up to a null part).
  const VecX w = e.Et.completeOrthogonalDecomposition().solve(-e.Dtu);
  const MatX H = F.transpose() * e.M * F;  // eq. (68)
  const VecX Mdot_u = e.Mdot * u;
  const VecX vdot = H.llt().solve(F.transpose() * (e.Q - Mdot_u - e.M * w));
  out.udot = F * vdot + w;
  out.pdot = e.M * out.udot + Mdot_u;
  out.R = out.pdot - e.Q;
  out.lambda = E.completeOrthogonalDecomposition().solve(out.R);
  out.J = e.Et * u;
  return true;
}

GeneralSimulateResult simulate_general(const GeneralSystem& sys, const VecX& q0, const VecX& u0,
                                       const GeneralSimulateOptions& options) {
  GeneralSimulateResult res;
  const int n = sys.n;
  MatX M(n, n), Et(sys.nc, n);
  VecX f(sys.nc);
  // Mass-metric Gauss–Newton onto f = 0 and the velocity projection u ← α u (eq. (70)).
  auto project = [&](VecX& q, VecX& u) -> bool {
    for (int it = 0; it < 20; ++it) {
      sys.residual(q, f);
      if (f.cwiseAbs().maxCoeff() <= options.position_tolerance) break;
      sys.mass(q, M);
      sys.jacobian(q, Et);
      const MatX AE = M.llt().solve(MatX(Et.transpose()));
      q -= AE * (Et * AE).llt().solve(f);
      if (it == 19) return false;
    }
    sys.mass(q, M);
    sys.jacobian(q, Et);
    const MatX AE = M.llt().solve(MatX(Et.transpose()));
    u -= AE * (Et * AE).llt().solve(Et * u);  // u ← α u = u − A E G⁻¹ Eᵀ u, eq. (44)
    return true;
  };
  VecX q = q0, u = u0;
  if (!project(q, u)) {
    res.message = "the initial position does not assemble";
    return res;
  }
  VecX x(2 * n);
  x.head(n) = q;
  sys.mass(q, M);
  x.tail(n) = options.primal ? VecX(M * u) : u;
  GeneralDynamics d;
  bool failed = false;
  detail::OdeProblem prob;
  prob.rhs = [&](const VecX& y, VecX& dy, double t) {
    dy.resize(2 * n);
    VecX uu = y.tail(n);
    if (options.primal) {
      sys.mass(y.head(n), M);
      uu = M.llt().solve(VecX(y.tail(n)));  // u = A p, eq. (100)
      failed = !compute_general_primal(sys, y.head(n), uu, t, d) || failed;
      dy.tail(n) = d.pdot;
    } else {
      failed = !compute_general_dual(sys, y.head(n), uu, t, d) || failed;
      dy.tail(n) = d.udot;
    }
    dy.head(n) = uu;
  };
  prob.accept = [&](double, VecX& y) {
    VecX qq = y.head(n), uu = y.tail(n);
    if (options.primal) {
      sys.mass(qq, M);
      uu = M.llt().solve(uu);
    }
    sys.residual(qq, f);
    res.max_residual = std::max(res.max_residual, f.cwiseAbs().maxCoeff());
    if (!project(qq, uu)) return false;
    y.head(n) = qq;
    if (options.primal) {
      sys.mass(qq, M);
      y.tail(n) = M * uu;
    } else {
      y.tail(n) = uu;
    }
    ++res.steps;
    return !failed;
  };
  prob.output = [](double, const VecX&) {};
  detail::OdeOptions oo;
  oo.rtol = options.rtol;
  oo.atol = options.atol;
  oo.t_end = options.t_end;
  oo.dt_out = options.t_end;
  const detail::OdeStats st = detail::integrate_ode(prob, x, oo);
  res.t = st.t;
  res.q = x.head(n);
  res.u = x.tail(n);
  if (options.primal) {
    sys.mass(res.q, M);
    res.u = M.llt().solve(VecX(x.tail(n)));
  }
  (void)compute_general_dual(sys, res.q, res.u, res.t, res.final);
  res.completed = st.completed && !failed;
  res.message = failed ? "singular G" : st.message;
  return res;
}

}  // namespace orthomech
