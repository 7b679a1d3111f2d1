// Benchmarks of issue 18 item 2: mobility (rank of E, DOF, redundant equations, idle bodies) of
// large generated planar models by the sparse QR, and of the N = 40 four-bar by both methods.
// Run: build/bench/orthomech_bench --benchmark_filter=Mobility
#include <benchmark/benchmark.h>

#include <numbers>

#include "orthomech/analysis/mobility.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "unit/analysis/large_mechanisms.hpp"

namespace {
using namespace orthomech;

void run(benchmark::State& bs, const Model& m, RankMethod method, int expected_dof) {
  const VecX q = m.design_q();
  for (auto _ : bs) {
    const Mobility mob = compute_mobility(m, q, {}, method);
    if (mob.dof != expected_dof) bs.SkipWithError("wrong DOF");
    benchmark::DoNotOptimize(mob.rank);
  }
  bs.counters["n"] = m.n;
  bs.counters["nc"] = m.nc;
}

// The 1000-link pendulum chain (n = 3000, n_c = 2000, DOF 1000).
void BM_MobilityPendulumChain(benchmark::State& bs) {
  const int N = static_cast<int>(bs.range(0));
  run(bs, parse_mechanism(test::pendulum_chain_yaml(N), "chain.yaml"), RankMethod::sparse, N);
}
BENCHMARK(BM_MobilityPendulumChain)->Arg(250)->Arg(1000)->Unit(benchmark::kMillisecond);

// The N-four-bar at a general position (DOF 1).
void BM_MobilityNFourBar(benchmark::State& bs) {
  const int N = static_cast<int>(bs.range(0));
  run(bs, parse_mechanism(test::n_four_bar_yaml(N, std::numbers::pi / 2 - 0.3), "nfb.yaml"),
      RankMethod::sparse, 1);
}
BENCHMARK(BM_MobilityNFourBar)->Arg(100)->Arg(499)->Unit(benchmark::kMillisecond);

// Dense and sparse on the same models, for the threshold kSparseMobilityFrom.
void BM_MobilityChainDense(benchmark::State& bs) {
  const int N = static_cast<int>(bs.range(0));
  run(bs, parse_mechanism(test::pendulum_chain_yaml(N), "chain.yaml"), RankMethod::dense, N);
}
BENCHMARK(BM_MobilityChainDense)
    ->Arg(50)
    ->Arg(100)
    ->Arg(200)
    ->Arg(250)
    ->Unit(benchmark::kMillisecond);
void BM_MobilityChainSparse(benchmark::State& bs) {
  const int N = static_cast<int>(bs.range(0));
  run(bs, parse_mechanism(test::pendulum_chain_yaml(N), "chain.yaml"), RankMethod::sparse, N);
}
BENCHMARK(BM_MobilityChainSparse)
    ->Arg(50)
    ->Arg(100)
    ->Arg(200)
    ->Arg(250)
    ->Unit(benchmark::kMillisecond);

}  // namespace
