#include "orthomech/constraints/sparse_et.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "orthomech/constraints/joints.hpp"
#include "orthomech/model/general_system.hpp"

namespace orthomech {

void SparseEt::Row::outside_pattern(Eigen::Index j) {
  throw std::logic_error("SparseEt: column " + std::to_string(j) +
                         " is outside the recorded pattern of its row");
}

namespace {

// The (row, column) pairs of the model's Eᵀ, sorted by row then column, without repeats.
std::vector<std::pair<int, int>> structural_entries(const Model& model) {
  EtRecorder recorder;
  record_constraint_pattern(model, recorder);
  std::vector<std::pair<int, int>>& e = recorder.entries;
  std::sort(e.begin(), e.end());
  e.erase(std::unique(e.begin(), e.end()), e.end());
  return std::move(e);
}

}  // namespace

SparseEt::SparseEt(const Model& model) {
  const std::vector<std::pair<int, int>> entries = structural_entries(model);
  m_.resize(model.nc, model.n);
  m_.reserve(static_cast<Eigen::Index>(entries.size()));
  int current = -1;
  for (const auto& [i, j] : entries) {  // sorted: rows, then columns ascending
    while (current < i) m_.startVec(++current);
    m_.insertBack(i, j) = 0.0;
  }
  m_.finalize();
  m_.makeCompressed();
  // Column access: the entries of column j, rows ascending (row-major storage, read by rows).
  const int n = model.n;
  column_start_.assign(static_cast<size_t>(n) + 1, 0);
  for (Eigen::Index k = 0; k < m_.nonZeros(); ++k)
    ++column_start_[static_cast<size_t>(m_.innerIndexPtr()[k]) + 1];
  for (int j = 0; j < n; ++j)
    column_start_[static_cast<size_t>(j) + 1] += column_start_[static_cast<size_t>(j)];
  column_entries_.resize(static_cast<size_t>(m_.nonZeros()));
  std::vector<int> next(column_start_.begin(), column_start_.end() - 1);
  for (int i = 0; i < model.nc; ++i)
    for (int k = m_.outerIndexPtr()[i]; k < m_.outerIndexPtr()[i + 1]; ++k)
      column_entries_[static_cast<size_t>(next[static_cast<size_t>(m_.innerIndexPtr()[k])]++)] = {
          i, k};
}

std::span<const int> SparseEt::row_columns(int i) const {
  const int b = m_.outerIndexPtr()[i];
  const int e = m_.outerIndexPtr()[i + 1];
  return {m_.innerIndexPtr() + b, static_cast<size_t>(e - b)};
}

std::span<const double> SparseEt::row_values(int i) const {
  const int b = m_.outerIndexPtr()[i];
  const int e = m_.outerIndexPtr()[i + 1];
  return {m_.valuePtr() + b, static_cast<size_t>(e - b)};
}

std::span<const SparseEt::Entry> SparseEt::column(int j) const {
  const int b = column_start_[static_cast<size_t>(j)];
  const int e = column_start_[static_cast<size_t>(j) + 1];
  return {column_entries_.data() + b, static_cast<size_t>(e - b)};
}

double SparseEt::coeff(int i, int j) const { return m_.coeff(i, j); }

void SparseEt::setZero() { std::fill(m_.valuePtr(), m_.valuePtr() + m_.nonZeros(), 0.0); }

void SparseEt::set_from_general(const Model& model, const VecX& q) {
  general_.resize(model.nc, model.n);  // allocates on the first call only
  model.general->jacobian(q, general_);
  // The full pattern, row-major: values in the order of general_'s rows.
  double* v = m_.valuePtr();
  for (int i = 0; i < rows(); ++i)
    for (int j = 0; j < cols(); ++j) *v++ = general_(i, j);
}

void SparseEt::to_dense(MatX& Et) const { Et = MatX(m_); }

void SparseEt::copy_values_to(MatX& Et) const {
  for (int i = 0; i < rows(); ++i) {
    const auto cols = row_columns(i);
    const auto vals = row_values(i);
    for (size_t t = 0; t < cols.size(); ++t) Et(i, cols[t]) = vals[t];
  }
}

}  // namespace orthomech
