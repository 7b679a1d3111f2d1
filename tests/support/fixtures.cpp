#include "support/fixtures.hpp"

#include <gtest/gtest.h>

#include <Eigen/SVD>
#include <random>
#include <stdexcept>

#include "orthomech/analysis/positions.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/model/free_system.hpp"

namespace orthomech::test {

std::string source_path(const std::string& relative) {
  return std::string(ORTHOMECH_SOURCE_DIR) + "/" + relative;
}

Model load_bundled(const std::string& name) {
  return load_mechanism(source_path("mechanisms/" + name + ".yaml"));
}

VecX assembled_q(const Model& model) {
  VecX q = model.design_q();
  const SolveResult r = project_positions(model, q);
  EXPECT_EQ(r.status, SolveStatus::converged) << model.name << ": " << r.message;
  return q;
}

VecX admissible_velocity(const Model& model, const VecX& q, unsigned seed) {
  MatX Et(model.nc, model.n);
  compute_constraint_jacobian(model, q, Et);
  // Null space of Eᵀ from the SVD (an oracle independent of charts and QR).
  Eigen::JacobiSVD<MatX> svd(Et, Eigen::ComputeFullV);
  const int r = static_cast<int>(svd.rank());
  const MatX N = svd.matrixV().rightCols(model.n - r);
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> dist(-1.0, 1.0);
  VecX c(N.cols());
  for (Eigen::Index k = 0; k < c.size(); ++k) c(k) = dist(gen);
  return N * c;
}

int svd_rank(const Model& model, const VecX& q, double rel_tol) {
  MatX Et(model.nc, model.n);
  compute_constraint_jacobian(model, q, Et);
  Eigen::JacobiSVD<MatX> svd(Et);
  svd.setThreshold(rel_tol);
  return static_cast<int>(svd.rank());
}

CycleResult full_cycle(const Model& model, int steps) {
  CycleOptions o;
  o.driver = model.drivers.at(0);
  o.steps = steps;
  return run_cycle(model, o);
}

size_t measure_index(const Model& model, const std::string& name) {
  for (size_t i = 0; i < model.measures.size(); ++i)
    if (model.measures[i].name == name) return i;
  throw std::invalid_argument("no measure " + name);
}

}  // namespace orthomech::test
