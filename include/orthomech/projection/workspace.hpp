#pragma once
// Workspace (house style): every matrix the projections need, allocated once in the
// constructor, grouped by stage, each field with its equation. Algorithms are free functions
// compute_x(const Model&, const State&, Workspace&).
#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <stdexcept>
#include <vector>

#include "orthomech/constraints/joints.hpp"
#include "orthomech/model/model.hpp"
#include "orthomech/projection/chart_engine.hpp"

namespace orthomech {

// How the free-system stage stores M and A: always as n × n matrices (`dense`, what the
// projections' n × n products need), or, when the model's M is diagonal whatever q
// (mass_matrix_is_diagonal), as their diagonals alone (`diagonal_if_possible`: M, A and Ṁ are
// then 0 × 0, so a large planar model holds no n × n matrix; simulate, issue 18).
enum class MassStorage { dense, diagonal_if_possible };

// The stages a command uses (issue 18: only those are allocated). Every command that projects
// (compute_primal, compute_dual) keeps the default; `cycle` needs the free system (its
// diagonal when M is diagonal) and the chart with F (compute_basis) only, with Eᵀ and Dᵀ as
// n_c × n matrices for a small model and neither for a large one (its Eᵀ on its pattern, in
// DrivenWorkspace; Dᵀ never formed): at N = 1000 of the N-four-bar the dense pair took 576 MB.
struct WorkspaceStages {
  MassStorage mass = MassStorage::dense;
  bool primal = true;            // PrimalWorkspace's matrices (compute_primal)
  bool dual_projections = true;  // DualWorkspace's n × n matrices ψ, α, β, Θ, θ (compute_dual)
  bool constraint_matrices = true;  // ConstraintWorkspace's Eᵀ, Dᵀ (n_c × n; compute_constraints)
};

// Stage 1: the free system at q (paper §2).
struct FreeSystemWorkspace {
  MatX M;                      // n × n: mass matrix, eq. (4) (0 × 0 unless dense_mass)
  MatX A;                      // n × n: A = M⁻¹, eq. (6) (0 × 0 unless dense_mass)
  VecX A_diag;                 // n: diagonal of A (chart scaling)
  VecX A_sqrt;                 // n: √A_kk (chart scaling)
  VecX M_diag;                 // n: diagonal of M
  bool diagonal_mass = false;  // M diagonal (planar bodies): products with M become scalings
  bool dense_mass = true;      // M, A, Ṁ held as n × n matrices (else only the diagonals)
  MatX Mdot;                   // n × n: Ṁ along u (0 × 0 unless dense_mass)
  VecX Q;                      // n: applied generalized forces Q̂, eq. (17)
  bool constant_mass = true;
  bool mass_ready = false;  // M, A filled (once, when constant)
  explicit FreeSystemWorkspace(const Model& model, MassStorage storage = MassStorage::dense);
};

enum class ProjectionStatus {
  ok,
  singular_G,      // primal: G = EᵀAE singular (redundant constraints or a singular position)
  singular_chart,  // dual: the dependent block is singular in every chart (a change point)
  singular_H,      // dual: H not positive definite (cannot happen for M > 0; reported anyway)
};
[[nodiscard]] const char* to_string(ProjectionStatus s);

// Stage 2a: primal (E-based) projections, eq. (42), eq. (43), eq. (44), eq. (78), eq. (79).
struct PrimalWorkspace {
  MatX AE;  // n × nc: A E
  MatX G;   // nc × nc: fundamental matrix G = EᵀAE, eq. (42)
  Eigen::LLT<MatX> G_llt;
  MatX GinvEt;                 // nc × n: G⁻¹ Eᵀ
  MatX pi;                     // n × n: π = M β = E G⁻¹ Eᵀ, eq. (43)
  MatX alpha;                  // n × n: α = I − A π, eq. (44)
  MatX beta;                   // n × n: β = A π, eq. (44)
  MatX GinvDt;                 // nc × n: G⁻¹ Dᵀ
  MatX Omega;                  // n × n: Ω = E G⁻¹ Dᵀ, eq. (78)
  MatX omega;                  // n × n: ω = π̇ = Ω α + αᵀ Ωᵀ, eq. (79)
  double G_pivot_ratio = 0.0;  // min/max diagonal of the Cholesky factor, squared
  ProjectionStatus status = ProjectionStatus::ok;
  // allocate: false leaves every matrix 0 × 0 (compute_primal then throws std::logic_error).
  explicit PrimalWorkspace(const Model& model, bool allocate = true);
};

// Stage 2b: dual (F-based) projections, eq. (68), eq. (69), eq. (70), eq. (83), eq. (84), in charts
// (eq. (71), eq. (72) and eq. (85) follow from these and are checked in tests, not stored).
struct DualWorkspace {
  int na;              // admissible DOF n_a, eq. (25)
  int r;               // rank of Eᵀ
  ChartEngine engine;  // the chart, its factorised block, the switching policy (chart_engine.hpp)
  MatX rhs;            // r × n_a: scratch (right-hand sides of the dependent block)
  MatX F;              // n × n_a: basis of admissible velocities, Eᵀ F = 0
  MatX MF;             // n × n_a: M F
  MatX H;              // n_a × n_a: H = Fᵀ M F, eq. (68)
  Eigen::LLT<MatX> H_llt;
  MatX HinvFt;    // n_a × n: H⁻¹ Fᵀ
  MatX psi;       // n × n: ψ = α A = F H⁻¹ Fᵀ, eq. (69)
  MatX alpha;     // n × n: α = ψ M, eq. (70)
  MatX beta;      // n × n: β = I − ψ M, eq. (70)
  MatX DtF;       // nc × n_a: Dᵀ F
  MatX MFdot;     // n × n_a: M Ḟ
  MatX betaFdot;  // n × n_a: β Ḟ = Ḟ − F H⁻¹ Fᵀ M Ḟ
  MatX small;     // n_a × n_a: scratch
  MatX Fdot;      // n × n_a: Ḟ from Eᵀ Ḟ = −Dᵀ F (docs/design.md §4)
  MatX Theta;     // n × n: Θ = Ḟ H⁻¹ Fᵀ, eq. (83)
  MatX theta;     // n × n: θ = ψ̇ = β Θ + Θᵀ βᵀ, eq. (84)
  VecX dq;        // n: scratch of the chart position corrector
  ProjectionStatus status = ProjectionStatus::ok;
  // factorisation: the engine's (chart_engine.hpp); the cycle asks for rated_sparse_when_large.
  // projections: false leaves the n × n matrices (and H⁻¹Fᵀ, Ḟ's products) 0 × 0: compute_basis
  // only (compute_dual then throws std::logic_error).
  DualWorkspace(const Model& model, int rank,
                ChartFactorisation factorisation = ChartFactorisation::dense,
                bool projections = true);
};

// The dense projections' matrices (13 of n × n, 5 of n_c × n, G) take 8 (13 n² + 5 n_c n + n_c²)
// bytes with every stage; a Workspace larger than kMaxDenseWorkspaceBytes is refused with
// ModelTooLarge before anything is allocated (a 2500-body planar model would need 8.6 GB: the
// system would kill the process instead of reporting). Commands on the sparse path (simulate,
// info) build none; `cycle` builds only Eᵀ, Dᵀ (2 n_c n) below kSparseJacobianFrom velocities
// and, unless M is diagonal, M, A, Ṁ.
inline constexpr double kMaxDenseWorkspaceBytes = 4.0 * 1024 * 1024 * 1024;
[[nodiscard]] double dense_workspace_bytes(const Model& model, const WorkspaceStages& stages = {});
class ModelTooLarge : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
// Throws ModelTooLarge (the message names the file, n, n_c and the bytes) when a Workspace of
// this model would exceed kMaxDenseWorkspaceBytes: what the Workspace constructor checks, for a
// command to refuse before it does other work (crosscheck: before simulating the motion).
void check_dense_workspace_size(const Model& model, const WorkspaceStages& stages = {});

struct Workspace {
  FreeSystemWorkspace free;
  ConstraintWorkspace constraints;
  PrimalWorkspace primal;
  DualWorkspace dual;
  const Model* model;  // the Model it was sized for (API misuse check)
  // rank: rank of Eᵀ on the branch (from compute_mobility); sizes F and H.
  Workspace(const Model& model, int rank,
            ChartFactorisation factorisation = ChartFactorisation::dense,
            const WorkspaceStages& stages = {});
};

}  // namespace orthomech
