#include "orthomech/projection/workspace.hpp"

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

FreeSystemWorkspace::FreeSystemWorkspace(const Model& model)
    : M(MatX::Zero(model.n, model.n)),
      A(MatX::Zero(model.n, model.n)),
      A_diag(VecX::Zero(model.n)),
      A_sqrt(VecX::Zero(model.n)),
      M_diag(VecX::Zero(model.n)),
      Mdot(MatX::Zero(model.n, model.n)),
      Q(VecX::Zero(model.n)),
      constant_mass(mass_matrix_is_constant(model)) {}

namespace {
// The rank, checked before any matrix is sized by it (a negative size is not a matrix).
int checked_rank(const Model& m, int rank) {
  if (rank < 0 || rank > m.nc || rank > m.n)
    throw std::invalid_argument("Workspace: rank out of range");
  return rank;
}
}  // namespace

Workspace::Workspace(const Model& m, int rank)
    : free(m), constraints(m), primal(m), dual(m, checked_rank(m, rank)), model(&m) {}

void compute_free_system(const Model& model, const State& state, Workspace& ws) {
  if (ws.model != &model) throw std::invalid_argument("Workspace built for another Model");
  compute_free_system(model, state, ws.free);
}

void compute_free_system(const Model& model, const State& state, FreeSystemWorkspace& fs) {
  if (!fs.constant_mass || !fs.mass_ready) {
    compute_mass_matrix(model, state.q, fs.M);          // eq. (4)
    compute_inverse_mass_matrix(model, state.q, fs.A);  // eq. (6)
    fs.A_diag = fs.A.diagonal();
    fs.A_sqrt = fs.A_diag.cwiseSqrt();
    fs.M_diag = fs.M.diagonal();
    fs.diagonal_mass = (fs.M - MatX(fs.M_diag.asDiagonal())).cwiseAbs().maxCoeff() == 0.0;
    fs.mass_ready = true;
  }
  if (!fs.constant_mass) compute_mass_matrix_rate(model, state.q, state.u, fs.Mdot);
  compute_applied_forces(model, state, fs.Q);  // eq. (17)
}

}  // namespace orthomech
