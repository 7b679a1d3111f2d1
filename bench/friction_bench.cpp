// Benchmarks of `cycle` with pin friction (issue 49, Performance: "cycle with friction on every
// joint costs no more than 2× the frictionless cycle, same run"): the sweep of 3600 positions
// and the friction series over it (friction_series: moments, powers, energies; for a redundant
// mechanism the least friction over the admissible splits), with friction in every pin and with
// every coefficient set to 0 (the same file: the frictionless twin). Run:
// build/bench/orthomech_bench --benchmark_filter=Friction.
#include <benchmark/benchmark.h>
#include <malloc.h>

#include <string>
#include <vector>

#include "orthomech/analysis/cycle.hpp"
#include "orthomech/analysis/cycle_friction.hpp"
#include "orthomech/io/mechanism_file.hpp"

namespace {
using namespace orthomech;

// `name` with every pin in `pins` given `friction` (the file's own friction when empty).
Model with_pins(const std::string& name, const std::vector<std::string>& pins,
                const std::string& friction) {
  std::vector<FileChange> changes;
  for (const std::string& j : pins)
    changes.push_back(parse_file_change("joints." + j + ".friction=" + friction));
  return load_mechanism(std::string(ORTHOMECH_SOURCE_DIR) + "/mechanisms/" + name + ".yaml",
                        changes);
}

void sweep(benchmark::State& bs, const Model& model) {
  mallopt(M_TRIM_THRESHOLD, 256 << 20);  // (as cycle_bench's KeepHeap: the computation alone)
  mallopt(M_MMAP_THRESHOLD, 256 << 20);
  CycleOptions o;
  o.driver = model.drivers.at(0);
  o.steps = 3600;
  for (auto _ : bs) {
    const CycleResult r = run_cycle(model, o);
    if (r.status != CycleStatus::completed) bs.SkipWithError(r.message.c_str());
    const FrictionSeries f = friction_series(model, r, o.driver.joint, true);
    benchmark::DoNotOptimize(f.dissipated);
  }
  bs.SetItemsProcessed(bs.iterations() * o.steps);
}

void friction(benchmark::State& bs, const std::string& name, const std::vector<std::string>& pins,
              const std::string& coefficient) {
  sweep(bs, with_pins(name, pins, "{coefficient: " + coefficient + ", radius: 5}"));
}

const std::vector<std::string> kWiper = {"A0", "A", "B", "B0"};
const std::vector<std::string> kPress = {"O", "K", "K_rod", "P", "C"};
const std::vector<std::string> kTriple = {"O1", "O2", "O3", "A1", "A2", "A3"};

}  // namespace

BENCHMARK_CAPTURE(friction, FrictionWiper3600_Frictionless, std::string("wiper-drive"), kWiper,
                  std::string("0"))
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(friction, FrictionWiper3600_EveryPin, std::string("wiper-drive"), kWiper,
                  std::string("0.15"))
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(friction, FrictionPress3600_Frictionless, std::string("knuckle-press"), kPress,
                  std::string("0"))
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(friction, FrictionPress3600_EveryPin, std::string("knuckle-press"), kPress,
                  std::string("0.1"))
    ->Unit(benchmark::kMillisecond);
// The redundant triple crank: with friction, also the least friction over its splits.
BENCHMARK_CAPTURE(friction, FrictionTripleCrank3600_Frictionless, std::string("triple-crank"),
                  kTriple, std::string("0"))
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(friction, FrictionTripleCrank3600_EveryPin, std::string("triple-crank"), kTriple,
                  std::string("0.2"))
    ->Unit(benchmark::kMillisecond);
