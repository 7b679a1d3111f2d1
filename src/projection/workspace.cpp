#include "orthomech/projection/workspace.hpp"

#include <sstream>
#include <stdexcept>

#include "orthomech/model/free_system.hpp"
#include "orthomech/model/loads.hpp"
#include "orthomech/projection/free_system_stage.hpp"

namespace orthomech {

const char* to_string(ProjectionStatus s) {
  switch (s) {
    case ProjectionStatus::ok:
      return "ok";
    case ProjectionStatus::singular_G:
      return "G is singular (redundant constraints or a singular position)";
    case ProjectionStatus::singular_chart:
      return "no chart has a regular dependent block (change point)";
    case ProjectionStatus::singular_H:
      return "H is not positive definite";
  }
  return "?";
}

namespace {
bool holds_dense_mass(const Model& model, MassStorage storage) {
  return storage == MassStorage::dense || !mass_matrix_is_diagonal(model);
}
MatX square_if(bool dense, int n) { return dense ? MatX::Zero(n, n) : MatX(); }

// True when every off-diagonal entry of M is exactly 0.
bool is_diagonal(const MatX& M) {
  for (Eigen::Index j = 0; j < M.cols(); ++j)
    for (Eigen::Index i = 0; i < M.rows(); ++i)
      if (i != j && M(i, j) != 0.0) return false;
  return true;
}

// M, A and their diagonals, as n × n matrices.
void fill_dense_mass(const Model& model, const State& state, FreeSystemWorkspace& fs) {
  compute_mass_matrix(model, state.q, fs.M);          // eq. (4)
  compute_inverse_mass_matrix(model, state.q, fs.A);  // eq. (6)
  fs.A_diag = fs.A.diagonal();
  fs.M_diag = fs.M.diagonal();
  fs.diagonal_mass = is_diagonal(fs.M);
}

// The diagonals alone (mass_matrix_is_diagonal(model): M and A are diag(M_diag), diag(A_diag)).
void fill_diagonal_mass(const Model& model, const State& state, FreeSystemWorkspace& fs) {
  fs.M_diag = mass_matrix_diagonal(model, state.q);
  fs.A_diag = inverse_mass_diagonal(model, state.q);
  fs.diagonal_mass = true;
}
}  // namespace

FreeSystemWorkspace::FreeSystemWorkspace(const Model& model, MassStorage storage)
    : M(square_if(holds_dense_mass(model, storage), model.n)),
      A(square_if(holds_dense_mass(model, storage), model.n)),
      A_diag(VecX::Zero(model.n)),
      A_sqrt(VecX::Zero(model.n)),
      M_diag(VecX::Zero(model.n)),
      dense_mass(holds_dense_mass(model, storage)),
      Mdot(square_if(holds_dense_mass(model, storage), model.n)),
      Q(VecX::Zero(model.n)),
      constant_mass(mass_matrix_is_constant(model)) {}

void check_dense_workspace_size(const Model& m, const WorkspaceStages& stages) {
  const double bytes = dense_workspace_bytes(m, stages);
  if (bytes > kMaxDenseWorkspaceBytes) {
    std::ostringstream text;
    text.precision(2);
    text << std::fixed << (m.file.empty() ? m.name : m.file) << ": " << m.n
         << " velocity components and " << m.nc
         << " constraint rows: this command forms dense n × n matrices (" << bytes / 1e9
         << " GB, more than its limit of " << kMaxDenseWorkspaceBytes / 1e9
         << " GB); simulate and info work on sparse matrices without this limit";
    throw ModelTooLarge(text.str());
  }
}

namespace {
// The model, once the size of the whole workspace is checked (ModelTooLarge), before its first
// stage allocates anything.
const Model& checked_size(const Model& m, const WorkspaceStages& stages) {
  check_dense_workspace_size(m, stages);
  return m;
}

// The rank, checked before any matrix is sized by it (a negative size is not a matrix).
int checked_rank(const Model& m, int rank) {
  if (rank < 0 || rank > m.nc || rank > m.n)
    throw std::invalid_argument("Workspace: rank out of range");
  return rank;
}
}  // namespace

double dense_workspace_bytes(const Model& model, const WorkspaceStages& stages) {
  const double n = model.n, nc = model.nc;
  double matrices = stages.constraint_matrices ? 2.0 * nc * n : 0.0;  // Eᵀ, Dᵀ
  if (holds_dense_mass(model, stages.mass)) matrices += 3.0 * n * n;  // M, A, Ṁ
  if (stages.primal) matrices += 5.0 * n * n + 3.0 * nc * n + nc * nc;
  if (stages.dual_projections) matrices += 5.0 * n * n;  // ψ, α, β, Θ, θ
  return 8.0 * matrices;
}

Workspace::Workspace(const Model& m, int rank, ChartFactorisation factorisation,
                     const WorkspaceStages& stages)
    : free(checked_size(m, stages), stages.mass),
      constraints(m, stages.constraint_matrices),
      primal(m, stages.primal),
      dual(m, checked_rank(m, rank), factorisation, stages.dual_projections),
      model(&m) {}

void compute_free_system(const Model& model, const State& state, Workspace& ws) {
  if (ws.model != &model) throw std::invalid_argument("Workspace built for another Model");
  compute_free_system(model, state, ws.free);
}

void compute_free_system(const Model& model, const State& state, FreeSystemWorkspace& fs) {
  if (!fs.constant_mass || !fs.mass_ready) {
    if (fs.dense_mass)
      fill_dense_mass(model, state, fs);
    else
      fill_diagonal_mass(model, state, fs);
    fs.A_sqrt = fs.A_diag.cwiseSqrt();
    fs.mass_ready = true;
  }
  if (!fs.constant_mass) compute_mass_matrix_rate(model, state.q, state.u, fs.Mdot);
  compute_applied_forces(model, state, fs.Q);  // eq. (17)
}

}  // namespace orthomech
