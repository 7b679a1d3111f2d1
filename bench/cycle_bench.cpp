// Benchmarks of the driven sweep (issue 3 §7): the whole cycle at 3600 positions — assembly,
// continuation (predictor + locked-input Newton corrector), velocities, accelerations, drive and
// minimum-norm reactions, measures and energies at every position. Reported per position
// (items_per_second = positions per second). Run: build/bench/orthomech_bench
// --benchmark_filter=Cycle
#include <benchmark/benchmark.h>

#include "orthomech/analysis/cycle.hpp"
#include "orthomech/io/mechanism_file.hpp"

namespace {
using namespace orthomech;

void cycle(benchmark::State& bs, const std::string& name) {
  const Model model =
      load_mechanism(std::string(ORTHOMECH_SOURCE_DIR) + "/mechanisms/" + name + ".yaml");
  CycleOptions o;
  o.driver = model.drivers.at(0);
  o.steps = 3600;
  for (auto _ : bs) {
    const CycleResult r = run_cycle(model, o);
    if (r.status != CycleStatus::completed) bs.SkipWithError(r.message.c_str());
    benchmark::DoNotOptimize(r.points.data());
  }
  bs.SetItemsProcessed(bs.iterations() * o.steps);
  bs.counters["us_per_position"] =
      benchmark::Counter(static_cast<double>(bs.iterations() * o.steps),
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

}  // namespace

BENCHMARK_CAPTURE(cycle, CycleCrankRocker3600, std::string("crank-rocker"))
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(cycle, CycleAndrews3600, std::string("andrews-squeezer"))
    ->Unit(benchmark::kMillisecond);
