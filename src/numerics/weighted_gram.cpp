#include "orthomech/numerics/weighted_gram.hpp"

#include <algorithm>
#include <utility>

namespace orthomech {

namespace {
struct Entry {
  int row;    // the row of B
  int value;  // its index in B's values
};

// B's entries by column: the rows that share a column k meet in G through a_k.
std::vector<std::vector<Entry>> entries_by_column(const WeightedGram::RowMajorMatrix& B) {
  std::vector<std::vector<Entry>> columns(static_cast<size_t>(B.cols()));
  const int* start = B.outerIndexPtr();
  const int* col = B.innerIndexPtr();
  for (int i = 0; i < B.rows(); ++i)
    for (int t = start[i]; t < start[i + 1]; ++t)
      columns[static_cast<size_t>(col[t])].push_back({i, t});
  return columns;
}

// G's pattern, upper triangle, with row i of G at row position[i] (the diagonal always: G is
// then structurally regular).
std::vector<Eigen::Triplet<double>> upper_pattern(const std::vector<std::vector<Entry>>& columns,
                                                  const std::vector<int>& position) {
  std::vector<Eigen::Triplet<double>> upper;
  size_t pairs = 0;
  for (const auto& c : columns) pairs += c.size() * c.size();
  upper.reserve(position.size() + pairs);
  for (int i = 0; i < static_cast<int>(position.size()); ++i) upper.emplace_back(i, i, 1.0);
  for (const auto& c : columns)
    for (const Entry& x : c)
      for (const Entry& y : c) {
        const int r = position[static_cast<size_t>(x.row)];
        const int s = position[static_cast<size_t>(y.row)];
        if (r <= s) upper.emplace_back(r, s, 1.0);
      }
  return upper;
}

// The fill-reducing order of G's pattern: position[i] is row i's place.
std::vector<int> amd_positions(int m, const std::vector<std::vector<Entry>>& columns) {
  std::vector<int> identity(static_cast<size_t>(m));
  for (int i = 0; i < m; ++i) identity[static_cast<size_t>(i)] = i;
  const auto upper = upper_pattern(columns, identity);
  Eigen::SparseMatrix<double> S(m, m);
  S.setFromTriplets(upper.begin(), upper.end());
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> order;
  Eigen::AMDOrdering<int>()(S,
                            order);  // (on the pattern of S + Sᵀ) order(j): the row eliminated j-th
  std::vector<int> position(static_cast<size_t>(m));
  for (int j = 0; j < m; ++j) position[static_cast<size_t>(order.indices()(j))] = j;
  return position;
}
}  // namespace

void WeightedGram::analyze(const RowMajorMatrix& B) {
  const int m = static_cast<int>(B.rows());
  const auto columns = entries_by_column(B);
  position_ = amd_positions(m, columns);
  const auto upper = upper_pattern(columns, position_);  // of P G Pᵀ
  G_.resize(m, m);
  G_.setFromTriplets(upper.begin(), upper.end());
  G_.makeCompressed();
  const auto slot = [this](int r, int s) {
    const int* begin = G_.innerIndexPtr() + G_.outerIndexPtr()[s];
    const int* end = G_.innerIndexPtr() + G_.outerIndexPtr()[s + 1];
    return static_cast<int>(std::lower_bound(begin, end, r) - G_.innerIndexPtr());
  };
  products_.clear();
  for (int k = 0; k < static_cast<int>(columns.size()); ++k) {
    const auto& c = columns[static_cast<size_t>(k)];
    for (size_t x = 0; x < c.size(); ++x)
      for (size_t y = x; y < c.size(); ++y) {  // each pair once; G is symmetric
        int r = position_[static_cast<size_t>(c[x].row)];
        int s = position_[static_cast<size_t>(c[y].row)];
        if (r > s) std::swap(r, s);
        products_.push_back({slot(r, s), c[x].value, c[y].value, k});
      }
  }
  ldlt_.analyzePattern(G_);
  work_.resize(m);
}

bool WeightedGram::factorize(const RowMajorMatrix& B, const Eigen::VectorXd& a) {
  double* g = G_.valuePtr();
  std::fill(g, g + G_.nonZeros(), 0.0);
  const double* v = B.valuePtr();
  for (const Product& p : products_) g[p.slot] += v[p.u] * a(p.k) * v[p.v];  // eq. (42)
  ldlt_.factorize(G_);
  if (ldlt_.info() != Eigen::Success) return false;
  const auto& D = ldlt_.vectorD();
  return D.minCoeff() > kSingular * D.maxCoeff();  // (also false on NaN)
}

void WeightedGram::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) {
  const auto m = static_cast<Eigen::Index>(position_.size());
  for (Eigen::Index i = 0; i < m; ++i) work_(position_[static_cast<size_t>(i)]) = b(i);
  x = ldlt_.solve(work_);  // (P G Pᵀ) (P x) = P b
  work_ = x;
  for (Eigen::Index i = 0; i < m; ++i) x(i) = work_(position_[static_cast<size_t>(i)]);
}

}  // namespace orthomech
