#pragma once
// G = B diag(a) Bᵀ for a sparse B whose pattern is fixed while its values and the weights a
// change, and G's LDLᵀ factorisation: the primal form's G = Eᵀ A E (eq. (42) with A diagonal) of
// large mechanisms in `simulate`, formed at every right-hand-side evaluation.
//
// analyze records, once, every product B_ik a_k B_jk that adds to an entry of G's upper triangle
// in a fill-reducing order (AMD on G's pattern, Eigen's AMDOrdering), so that factorize writes G's
// values in place (no sparse product, no permuted copy) and hands them to Eigen's SimplicialLDLT
// in that order. Allocation-free after analyze but for the one small pointer array Eigen's
// SimplicialLDLT::factorize allocates.
#include <Eigen/OrderingMethods>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <vector>

namespace orthomech {

class WeightedGram {
 public:
  using RowMajorMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor>;

  // B's pattern (compressed; its values are not read): G's pattern, the order, the products.
  void analyze(const RowMajorMatrix& B);
  // G = B diag(a) Bᵀ from B's values (on the pattern given to analyze) and a (size B.cols()), and
  // its LDLᵀ. False when G is not numerically positive definite, min D_kk ≤ kSingular · max D_kk
  // (B has dependent rows; the dense path's test in simulate and projection/primal.cpp).
  bool factorize(const RowMajorMatrix& B, const Eigen::VectorXd& a);
  // x = G⁻¹ b (x and b of size B.rows(); x may not be b).
  void solve(const Eigen::VectorXd& b, Eigen::VectorXd& x);

  static constexpr double kSingular = 1e-12;

  // G's upper triangle in the factorisation's order, P G Pᵀ, P = order() (tests).
  [[nodiscard]] const Eigen::SparseMatrix<double>& permuted_upper() const { return G_; }
  // Row i of G is row order()[i] of P G Pᵀ.
  [[nodiscard]] const std::vector<int>& order() const { return position_; }

 private:
  struct Product {
    int slot;  // index in G_'s values
    int u, v;  // indices of B_ik and B_jk in B's values
    int k;     // the weight's index
  };
  std::vector<Product> products_;
  std::vector<int> position_;  // row i of G → row position_[i] of P G Pᵀ
  Eigen::SparseMatrix<double> G_;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Upper, Eigen::NaturalOrdering<int>>
      ldlt_;
  Eigen::VectorXd work_;
};

}  // namespace orthomech
