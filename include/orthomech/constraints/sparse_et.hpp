#pragma once
// Eᵀ (n_c × n, eq. (23)) stored on its structural pattern (issue 18: the sparse dual form).
// The pattern is recorded once from the joints' own writers (SparseEt(model)): every entry a
// writer can touch is in it, whatever q, so no write ever falls outside it, and no entry is
// guessed from sample positions. Refreshing the values costs O(non-zeros): nothing of size
// n_c · n is zeroed or stored (the dense Eᵀ of the N = 400 four-bar is 46 MB, zeroed at every
// evaluation), which keeps a large mechanism's evaluation linear in its size.
// Planar and spatial models (joints, knife edges, rolling discs) get their structural pattern; a
// general system (Eᵀ given by a function, model/general_system.hpp) has no structure to record and
// gets the full n_c × n pattern (its values copied from the function's dense Eᵀ).
#include <Eigen/SparseCore>
#include <span>
#include <utility>
#include <vector>

#include "orthomech/model/free_system.hpp"
#include "orthomech/model/model.hpp"
#include "orthomech/model/state.hpp"

namespace orthomech {

class SparseEt {
 public:
  using Matrix = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;
  // An entry of a column: its row and the position of its value in values().
  struct Entry {
    int row;
    int index;
  };
  // The writers' view of one row: row(j) += x adds into entry (i, j). j must be in the row's
  // pattern (it always is for the writers that recorded it; anything else throws
  // std::logic_error). Linear search over the row's columns (≤ 6 planar, ≤ 12 spatial).
  struct Row {
    double* values;
    const int* columns;
    int count;
    double& operator()(Eigen::Index j) const {  // inline: the writers' hot path (simulate)
      for (int k = 0; k < count; ++k)
        if (columns[k] == j) return values[k];
      outside_pattern(j);
    }
    [[noreturn]] static void outside_pattern(Eigen::Index j);  // throws std::logic_error
  };

  SparseEt() = default;
  // Records the pattern of the model's Eᵀ; the values are zero.
  explicit SparseEt(const Model& model);

  [[nodiscard]] int rows() const { return static_cast<int>(m_.rows()); }
  [[nodiscard]] int cols() const { return static_cast<int>(m_.cols()); }
  [[nodiscard]] int nonZeros() const { return static_cast<int>(m_.nonZeros()); }
  // n_c × n, row-major, compressed; the values of the last evaluation (zeros of the pattern
  // kept). Products: matrix() * u = Eᵀu, matrix().transpose() * λ = E λ.
  [[nodiscard]] const Matrix& matrix() const { return m_; }
  // Row i's columns, ascending, and its values (same order).
  [[nodiscard]] std::span<const int> row_columns(int i) const;
  [[nodiscard]] std::span<const double> row_values(int i) const;
  // Column j's entries, rows ascending.
  [[nodiscard]] std::span<const Entry> column(int j) const;
  [[nodiscard]] const double* values() const { return m_.valuePtr(); }
  // Entry (i, j); 0 outside the pattern.
  [[nodiscard]] double coeff(int i, int j) const;
  // Zeroes the values (the writers accumulate), keeps the pattern. Named as Eigen's, so one
  // writer serves a dense MatX and a SparseEt.
  void setZero();
  // A general system: the values ← its jacobian(q), through a dense scratch kept here.
  void set_from_general(const Model& model, const VecX& q);
  // Et (resized to n_c × n) ← this matrix, zeros outside the pattern.
  void to_dense(MatX& Et) const;
  // Et's entries on the pattern ← this matrix's; the others are not touched (O(non-zeros)): for a
  // dense Eᵀ (n_c × n) whose entries outside the pattern are zero, as every evaluation leaves
  // them.
  void copy_values_to(MatX& Et) const;
  [[nodiscard]] Row row(int i) {
    const int b = m_.outerIndexPtr()[i];
    const int e = m_.outerIndexPtr()[i + 1];
    return {m_.valuePtr() + b, m_.innerIndexPtr() + b, e - b};
  }

 private:
  Matrix m_;
  std::vector<int> column_start_;      // n + 1: column j's entries are column_entries_[start…)
  std::vector<Entry> column_entries_;  // non-zeros, by column
  MatX general_;                       // a general system's dense Eᵀ (empty otherwise)
};

// Records the entries the writers touch (SparseEt(model) builds its pattern with it): the same
// writers as for a dense Eᵀ, with row(i)(j) noting (i, j) and returning a sink for the value.
class EtRecorder {
 public:
  struct Row {
    EtRecorder* recorder;
    int i;
    double& operator()(Eigen::Index j) const {
      recorder->entries.emplace_back(i, static_cast<int>(j));
      return recorder->sink;
    }
  };
  void setZero() {}
  [[nodiscard]] Row row(int i) { return {this, i}; }
  std::vector<std::pair<int, int>> entries;  // (row, column), in writing order, repeats kept
  double sink = 0.0;
};

// The writers of every joint, knife edge and rolling disc at the design q, recorded.
void record_constraint_pattern(const Model& model, EtRecorder& recorder);

// Eᵀ(q) into its pattern (Et from SparseEt(model)). Allocation-free.
void compute_constraint_jacobian(const Model& model, const VecX& q, SparseEt& Et);
// f(q) and Eᵀ(q) in one pass. Allocation-free.
void compute_constraint_residual_and_jacobian(const Model& model, const VecX& q, VecX& f,
                                              SparseEt& Et);
// The same with the bodies' rotations at q already computed (rotations.update(model, q)).
void compute_constraint_residual_and_jacobian(const Model& model, const VecX& q,
                                              const BodyPoses& rotations, VecX& f, SparseEt& Et);
// Dᵀu only (size n_c), each row's product with u formed directly (no n_c × n storage).
void compute_constraint_rate(const Model& model, const State& state, const BodyPoses& rotations,
                             VecX& Dtu);

}  // namespace orthomech
