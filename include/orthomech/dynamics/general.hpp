#pragma once
// Free systems given by functions (design §2: "a general free system with configuration-
// dependent M(q) ... must fit the same interface"), e.g. a tree in joint coordinates such as
// Andrews' squeezer in the test set's relative coordinates. Holonomic velocities (q̇ = u).
//
// This is the dense path of the equations of motion with every Ṁ term (eqs. (81)–(82), (91),
// (97)–(99)); the mechanism-file engine (simulate) has Ṁ = 0 for its absolute coordinates.
// NOTE: it is a second evaluator of the same equations, not the mechanism-file engine behind an
// interface (that refactor of model/free_system and the projection workspace is future work).
#include <functional>
#include <string>

#include "orthomech/model/model.hpp"

namespace orthomech {

struct GeneralSystem {
  int n = 0;                                         // coordinates = velocities
  int nc = 0;                                        // constraint rows
  std::function<void(const VecX& q, MatX& M)> mass;  // M(q), eq. (4)
  std::function<void(const VecX& q, const VecX& u, MatX& Mdot)> mass_rate;      // Ṁ along u
  std::function<void(const VecX& q, const VecX& u, double t, VecX& Q)> forces;  // Q̂, eq. (17)
  std::function<void(const VecX& q, VecX& f)> residual;                         // f, eq. (20)
  std::function<void(const VecX& q, MatX& Et)> jacobian;                        // Eᵀ, eq. (23)
  std::function<void(const VecX& q, const VecX& u, VecX& Dtu)> convective;      // Dᵀu, eq. (76)
};

struct GeneralDynamics {
  VecX udot, pdot, R, lambda, J;
};

// Primal form, Theorem 7 with Ṁ: ṗ = αᵀQ̂ − Ωu + βᵀṀu (eq. (99)), u̇ = A(ṗ − Ṁu);
// R from Theorem 5 with Ṁ_βα = βᵀṀα (eq. (91)); λ = G⁻¹EᵀA R; J = EᵀAp (eq. (105)).
// Returns false when G is singular.
bool compute_general_primal(const GeneralSystem& sys, const VecX& q, const VecX& u, double t,
                            GeneralDynamics& out);
// Dual form with Ṁ: F an orthonormal basis of null(Eᵀ), w with Eᵀ w = −Dᵀu (minimum norm),
// H v̇ = Fᵀ(Q̂ − Ṁu − M w) (eq. (68)), u̇ = F v̇ + w; R = M u̇ + Ṁu − Q̂.
bool compute_general_dual(const GeneralSystem& sys, const VecX& q, const VecX& u, double t,
                          GeneralDynamics& out);

struct GeneralSimulateOptions {
  bool primal = false;
  double t_end = 1.0, rtol = 1e-10, atol = 1e-12;
  double position_tolerance = 1e-13;
};
struct GeneralSimulateResult {
  bool completed = false;
  std::string message;
  double t = 0.0;
  VecX q, u;
  GeneralDynamics final;
  double max_residual = 0.0;  // max |f| left by a step before its correction
  long steps = 0;
};
// Dormand–Prince 5(4) on (q, p) (primal) or (q, u) (dual, u̇ from compute_general_dual); after
// every accepted step: mass-metric Gauss–Newton onto f = 0 and u ← α u (eq. (70)).
[[nodiscard]] GeneralSimulateResult simulate_general(const GeneralSystem& sys, const VecX& q0,
                                                     const VecX& u0,
                                                     const GeneralSimulateOptions& options);

}  // namespace orthomech
