// Benchmarks of the driven sweep (issue 3 §7; spatial files: issue 13 item 7): the whole cycle at
// 3600 positions — assembly, continuation (predictor + locked-input Newton corrector), velocities,
// accelerations, drive and minimum-norm reactions, measures and energies at every position.
// Reported per position (items_per_second = positions per second). Run: build/bench/orthomech_bench
// --benchmark_filter=Cycle. The driven N-four-bar at 360 positions (cycle/CycleNFourBar360/N): the
// cycle of large models.
#include <benchmark/benchmark.h>
#include <malloc.h>

#include <numbers>
#include <string>

#include "orthomech/analysis/cycle.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "unit/analysis/large_mechanisms.hpp"

namespace {
using namespace orthomech;

// The cycle of the model's first driver at `steps` positions, timed; per-position counters.
void sweep(benchmark::State& bs, const Model& model, int steps) {
  CycleOptions o;
  o.driver = model.drivers.at(0);
  o.steps = steps;
  for (auto _ : bs) {
    const CycleResult r = run_cycle(model, o);
    if (r.status != CycleStatus::completed) bs.SkipWithError(r.message.c_str());
    benchmark::DoNotOptimize(r.points.size());
  }
  bs.SetItemsProcessed(bs.iterations() * o.steps);
  bs.counters["us_per_position"] =
      benchmark::Counter(static_cast<double>(bs.iterations() * o.steps),
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

void cycle(benchmark::State& bs, const std::string& name, bool keep_heap) {
  // keep_heap: glibc returns the freed result storage to the OS after every sweep and the next
  // sweep page-faults it in again; with the trim threshold raised the benchmark measures the
  // computation alone (a single CLI run pays the faults once).
  if (keep_heap) {
    mallopt(M_TRIM_THRESHOLD, 256 << 20);
    mallopt(M_MMAP_THRESHOLD, 256 << 20);
  }
  const Model model =
      load_mechanism(std::string(ORTHOMECH_SOURCE_DIR) + "/mechanisms/" + name + ".yaml");
  sweep(bs, model, 3600);
}

}  // namespace

BENCHMARK_CAPTURE(cycle, CycleCrankRocker3600, std::string("crank-rocker"), false)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(cycle, CycleAndrews3600, std::string("andrews-squeezer"), false)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(cycle, CycleCrankRocker3600KeepHeap, std::string("crank-rocker"), true)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(cycle, CycleAndrews3600KeepHeap, std::string("andrews-squeezer"), true)
    ->Unit(benchmark::kMillisecond);
// Spatial cycles (issue 13 item 7): RSSR (target ≤ 5 µs per position) and the double wishbone.
BENCHMARK_CAPTURE(cycle, CycleRssr3600, std::string("rssr"), true)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(cycle, CycleDoubleWishbone3600, std::string("double-wishbone"), true)
    ->Unit(benchmark::kMillisecond);

namespace {

// The driven N-four-bar (IFToMM A02 with a motor at O0, 60 rpm), 360 positions: the cycle of a
// large model (issue 18 item 2). From n = 300 (N = 50) its chart block is on the rated sparse
// path (ChartFactorisation::rated_sparse_when_large); N = 40 stays dense. Reported per position.
void cycle_n_four_bar(benchmark::State& bs) {
  const int N = static_cast<int>(bs.range(0));
  const Model model = parse_mechanism(test::n_four_bar_yaml(N, std::numbers::pi / 2) +
                                          "drivers:\n  - {name: motor, joint: O0, speed: 60 rpm}\n",
                                      "n-four-bar (bench)");
  sweep(bs, model, 360);
}

}  // namespace

BENCHMARK(cycle_n_four_bar)
    ->Name("cycle/CycleNFourBar360")
    ->Arg(40)
    ->Arg(100)
    ->Arg(200)
    ->Unit(benchmark::kMillisecond);
