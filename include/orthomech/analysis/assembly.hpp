#pragma once
// Initial conditions (docs/design.md §5, issue 4): the user's design position is only a guess.
//
// Positions. `assemble` projects the guess q₀ onto the constraint manifold with Ipopt:
//   min ½ (q − q₀)ᵀ W (q − q₀)   s.t.  f(q) = 0 (eq. (20)),  s_k(q) = value_k (locked inputs),
//                                       min_j ≤ s_j(q) ≤ max_j (joint limits),             (A1)
// with W = M the mass matrix (eq. (4)): the kinetic-energy metric, the paper's natural metric.
// Exact first and second derivatives: ∂f/∂q = Eᵀ (B̃ = I for planar bodies, eq. (19)) and the
// Hessian of the Lagrangian W + Σλ_i ∇²f_i, whose column k is W e_k + Dᵀ(q, e_k)ᵀ λ because
// Dᵀ(q, u) = Σ_k ∂Eᵀ/∂q_k u_k (eq. (76)) — docs/theory.md, "Assembly". A guess that already
// satisfies everything is returned bit-for-bit unchanged. When Ipopt finds no feasible point,
// the best least-squares pose min ½‖f(q)‖² (locks and limits kept) names the joints that cannot
// close and by how much.
//
// Velocities. u = α u₀ (eq. (44)), the admissible velocity closest to u₀ in the mass metric;
// the kinetic energy removed is ½ (βu₀)ᵀ M (βu₀) = T(u₀) − T(u) (mass-orthogonality).
//
// Results are data (house style): never an exception for a numerical outcome.
#include <optional>
#include <string>
#include <vector>

#include "orthomech/model/model.hpp"
#include "orthomech/run_control.hpp"

namespace orthomech {

struct JointLock {
  int joint = -1;      // a joint with a coordinate (joint_coordinate_kind: planar revolute or
                       // prismatic; spatial revolute, cylindrical, screw, prismatic)
  double value = 0.0;  // joint coordinate, SI (planar revolute: matched modulo 2π nearest the
                       // guess; spatial angle: modulo 2π)
  int measure = -1;    // ≥ 0: lock this measure's position quantity instead (joint ignored;
                       // assemble and project_with_locks only; a measure's value is not wrapped)
};

struct AssemblyOptions {
  std::vector<JointLock> locks;
  bool use_limits = true;    // bounds from Joint::limits
  double tolerance = 1e-12;  // max |f_k|, |s_k − value_k| of an assembled position (m, rad)
  int max_iterations = 300;  // Ipopt iterations
  // The run's bounds (orthomech/run_control.hpp), asked after every Ipopt iteration: a time
  // limit, an interrupt flag, a progress callback (the fraction of max_iterations). A bound met
  // ends the projection with status `stopped`.
  RunControl control;
};

enum class AssemblyStatus {
  unchanged,      // the guess already satisfied f = 0, the locks and the limits
  assembled,      // projected onto the manifold, residual ≤ tolerance
  cannot_close,   // no feasible pose: see `gaps`
  not_converged,  // the solver stopped without a feasible pose and the gap is within tolerance
  failed,         // solver error (see message / solver_status)
  stopped,        // a bound of AssemblyOptions::control was met (AssemblyResult::stop)
};
[[nodiscard]] const char* to_string(AssemblyStatus s);

struct BodyMove {
  std::string body;
  double translation = 0.0;  // |Δr| of the body frame origin, m
  double rotation = 0.0;     // Δφ, rad (0 for particles)
};

struct JointResidual {
  std::string joint;
  double residual = 0.0;     // max |f_k| over the joint's rows (m or rad)
  double gap = 0.0;          // Euclidean norm of the joint's length rows (m), 0 if none
  std::vector<double> rows;  // f_k per component (Joint::component_names)
};

struct AssemblyResult {
  AssemblyStatus status = AssemblyStatus::failed;
  StopReason stop = StopReason::none;  // which bound, when status is stopped
  std::string message;
  std::string solver_status;  // Ipopt's return status ("" when Ipopt was not needed)
  int iterations = 0;         // Ipopt iterations (+ Newton polish steps)
  double residual = 0.0;      // max |f_k| and lock violation at q (m, rad)
  // The same split by kind: the length rows of f and the locks/limits of prismatic joints (m);
  // the angular rows (angle, gear ratio) and the locks/limits of revolutes (rad).
  double residual_length = 0.0, residual_angle = 0.0;
  VecX q;  // assembled position (the guess when unchanged; the best least-squares pose when
           // cannot_close; the solver's last iterate otherwise). bodies/joints/residual are at q.
  double distance = 0.0;  // √((q − q₀)ᵀ W (q − q₀)), the mass-metric distance (√kg·m)
  std::vector<BodyMove> bodies;
  std::vector<JointResidual> joints;
  // cannot_close: the best least-squares pose and the joints that stay open there (gap > tol),
  // largest first; total_gap = Σ gap (m).
  VecX q_least_squares;
  std::vector<JointResidual> gaps;
  double total_gap = 0.0;
};

// (A1). q0 has size model.nq. Never throws for numerical trouble; an exception raised inside a
// solver callback (a bug) is rethrown after the solve.
[[nodiscard]] AssemblyResult assemble(const Model& model, const VecX& q0,
                                      const AssemblyOptions& options = {});

// Max |f_k| over the length rows of f (m) and over its angular rows (rad, joint components
// "angle" and "ratio"), with the violations of `options`' locks and limits (prismatic: m,
// revolute: rad) at q.
struct ResidualSplit {
  double length = 0.0, angle = 0.0;
};
[[nodiscard]] ResidualSplit split_residual(const Model& model, const VecX& q,
                                           const AssemblyOptions& options);
// f alone: no locks, no limits.
[[nodiscard]] ResidualSplit split_residual(const Model& model, const VecX& q);
// Whether a joint component (Joint::component_names) is an angular row of f (rad).
[[nodiscard]] bool is_angular_row(const std::string& component);

// Per-joint residuals at q (names, max |f_k|, gap).
[[nodiscard]] std::vector<JointResidual> joint_residuals(const Model& model, const VecX& q);

struct VelocityProjection {
  VecX u;                  // α u₀
  double kinetic_initial;  // T(u₀)
  double kinetic;          // T(u)
  double kinetic_removed;  // T(β u₀) = T(u₀) − T(u)
  bool ok = true;          // false when no chart of the rank at q is regular (u = 0 then)
};
// Mass-orthogonal projection of a velocity guess, u = α u₀ = F H⁻¹ Fᵀ M u₀: the dual form's
// projection (project_velocity in projection/dual.hpp, the one simulate uses) in a chart of the
// rank of Eᵀ at q, so that redundant constraints are handled. α is the same operator as the
// primal form's I − A π (eq. (44)); the tests check it against an SVD null-space projection.
[[nodiscard]] VelocityProjection project_velocities(const Model& model, const VecX& q,
                                                    const VecX& u0);

// Mass-metric Gauss–Newton with locked inputs (Eigen only, no Ipopt): the cheap projection used
// by multi-start and continuation. Returns true when max residual ≤ tolerance.
bool project_with_locks(const Model& model, VecX& q, const std::vector<JointLock>& locks,
                        double tolerance = 1e-12, int max_iterations = 50);

// The locks reached by continuation from q_guess on its branch (assembly.cpp, docs/theory.md):
// q_guess closed without the locks (project_with_locks), then each locked coordinate moved from
// its value there to the lock (an angle the short way round) in equal steps of at most 2° or 2 %
// of the length scale, each corrected by project_with_locks at the step's values. Empty when a
// step does not converge. Used by `assemble` (spatial) and `validate`.
struct LockContinuation {
  bool secant = true;  // predict each step along the previous one (q_k ⊕ (q_k ⊖ q_{k−1}))
  double length_scale = 0.0;  // m, for the 2 % slide step; 0: the largest joint-point offset
};
[[nodiscard]] std::optional<VecX> follow_locks(const Model& model, const VecX& q_guess,
                                               const std::vector<JointLock>& locks,
                                               double tolerance = 1e-12,
                                               const LockContinuation& how = {});

// Joint coordinate s(q) of a revolute (φ_j − φ_i) or prismatic (slide) joint.
[[nodiscard]] double joint_coordinate(const Model& model, int joint, const VecX& q);
// Its Hessian ∇²s (nq × nq), exact (polarisation of the convective term ḋu = uᵀ∇²s u, see
// docs/theory.md "Assembly"); zero for a revolute joint. Used in the Hessian of the Lagrangian
// of locks and limits.
[[nodiscard]] MatX joint_coordinate_hessian(const Model& model, int joint, const VecX& q);

}  // namespace orthomech
