#pragma once
// A Jacobian row that is never stored (library-internal): `row(i) += x` accumulates x·w(i), so
// the helpers that write a row (add_point_jacobian, add_point_jacobian_rate, …) give its product
// with a vector w directly: Dᵀu row by row, or d·u̇ of a measure, without a row buffer.
#include <Eigen/Core>

#include "orthomech/model/model.hpp"

namespace orthomech {

struct DotRow {
  const VecX& w;
  double sum = 0.0;
  struct Entry {
    DotRow& row;
    Eigen::Index i;
    void operator+=(double x) { row.sum += x * row.w(i); }
  };
  Entry operator()(Eigen::Index i) { return {*this, i}; }
};

}  // namespace orthomech
