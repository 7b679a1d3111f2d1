// Design studies (issue 15 item 5): variants per second of a Monte Carlo tolerance study of the
// crank-rocker's cycle (360 positions per variant, examples/tolerance-study.yaml's laws) on 1 and
// 2 OpenMP threads — run_variants, the loop `sweep` runs, without the database (its cost per row is
// measured by the whole command: docs/benchmarks.md). The MPI figure is a whole-command timing
// (`mpirun -n 2|3 orthomech sweep …`), in docs/benchmarks.md.
#include <benchmark/benchmark.h>

#include <fstream>
#include <numeric>
#include <sstream>
#include <string>

#include "orthomech/study/study.hpp"

namespace orthomech {
namespace {

std::string text_of(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void BM_StudyVariants(benchmark::State& state) {
  const std::string root = ORTHOMECH_SOURCE_DIR;
  const std::string file = root + "/mechanisms/crank-rocker.yaml";
  const std::string mechanism = text_of(file);
  const Study study = load_study(root + "/examples/tolerance-study.yaml", mechanism, file);
  std::vector<long> pending(static_cast<size_t>(state.range(0)));
  std::iota(pending.begin(), pending.end(), 0L);
  const int threads = static_cast<int>(state.range(1));
  long completed = 0;
  for (auto _ : state) {
    run_variants(mechanism, file, study, pending, threads,
                 [&](const VariantResult& r) { completed += r.status == "completed" ? 1 : 0; });
  }
  state.counters["variants_per_s"] = benchmark::Counter(
      static_cast<double>(state.iterations()) * static_cast<double>(pending.size()),
      benchmark::Counter::kIsRate);
  state.counters["completed"] =
      static_cast<double>(completed) / static_cast<double>(state.iterations());
}
BENCHMARK(BM_StudyVariants)
    ->Args({200, 1})
    ->Args({200, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace orthomech
