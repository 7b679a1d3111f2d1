// Eᵀ of the N-four-bar (eq. (23)) evaluated dense (n_c × n MatX: zeroed and written whole) and on
// its structural pattern (SparseEt, issue 18): the sparse cost is O(non-zeros), the dense one
// O(n_c · n). `build/bench/orthomech_bench --benchmark_filter=EtEvaluation`.
#include <benchmark/benchmark.h>

#include "orthomech/constraints/joints.hpp"
#include "orthomech/constraints/sparse_et.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/model/free_system.hpp"
#include "unit/analysis/large_mechanisms.hpp"

namespace orthomech {
namespace {

Model four_bar(int N) { return parse_mechanism(test::n_four_bar_yaml(N, 0.3), "n-four-bar"); }

void EtEvaluationDense(benchmark::State& bs) {
  const Model model = four_bar(static_cast<int>(bs.range(0)));
  const VecX q = model.design_q();
  VecX f(model.nc);
  MatX Et(model.nc, model.n);
  for (auto _ : bs) {
    compute_constraint_residual_and_jacobian(model, q, f, Et);
    benchmark::DoNotOptimize(Et.data());
  }
  bs.counters["n"] = model.n;
}

void EtEvaluationSparse(benchmark::State& bs) {
  const Model model = four_bar(static_cast<int>(bs.range(0)));
  const VecX q = model.design_q();
  VecX f(model.nc);
  SparseEt Et(model);
  for (auto _ : bs) {
    compute_constraint_residual_and_jacobian(model, q, f, Et);
    benchmark::DoNotOptimize(Et.values());
  }
  bs.counters["n"] = model.n;
  bs.counters["nnz"] = Et.nonZeros();
}

BENCHMARK(EtEvaluationDense)->Arg(10)->Arg(40)->Arg(100)->Arg(400)->Unit(benchmark::kMicrosecond);
BENCHMARK(EtEvaluationSparse)->Arg(10)->Arg(40)->Arg(100)->Arg(400)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace orthomech
