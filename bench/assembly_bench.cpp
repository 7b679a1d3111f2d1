// Benchmarks of issue 4: `assemble` (Ipopt projection + Newton polish) of the Andrews squeezer
// from rough poses with β locked, and `validate` of a 10-position design set of the crank-rocker
// (assembly, multi-start modes, measures, circuit trace with NLopt refinement).
// Run: build/bench/orthomech_bench --benchmark_filter='Assemble|Validate'
#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>

#include "orthomech/analysis/assembly.hpp"
#include "orthomech/analysis/validate.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "support/andrews_reference.hpp"

namespace {
using namespace orthomech;

Model bundled(const std::string& name) {
  return load_mechanism(std::string(ORTHOMECH_SOURCE_DIR) + "/mechanisms/" + name + ".yaml");
}

// Andrews with every pose angle rounded to 0.1 rad and every position to 1 mm (as the test).
void BM_AssembleAndrewsFromRoughAngles(benchmark::State& bs) {
  Model m = bundled("andrews-squeezer");
  test::andrews::round_design_poses(m);
  const VecX q0 = m.design_q();
  AssemblyOptions o;
  o.locks.push_back({m.find_joint("O"), test::andrews::kAnglesT0[0]});
  int iterations = 0;
  for (auto _ : bs) {
    const AssemblyResult r = assemble(m, q0, o);
    if (r.status != AssemblyStatus::assembled) bs.SkipWithError("did not assemble");
    iterations = r.iterations;
    benchmark::DoNotOptimize(r.q.data());
  }
  bs.counters["iterations"] = iterations;
}
BENCHMARK(BM_AssembleAndrewsFromRoughAngles)->Unit(benchmark::kMillisecond);

// Andrews from rough poses without any lock (mass-metric projection only).
void BM_AssembleAndrewsFromRoughAnglesNoLock(benchmark::State& bs) {
  Model m = bundled("andrews-squeezer");
  for (Body& b : m.bodies) b.design_pose.z() = std::round(b.design_pose.z() * 10.0) / 10.0;
  const VecX q0 = m.design_q();
  for (auto _ : bs) benchmark::DoNotOptimize(assemble(m, q0).q.data());
}
BENCHMARK(BM_AssembleAndrewsFromRoughAnglesNoLock)->Unit(benchmark::kMillisecond);

// The crank-rocker with ten design positions, crank 0°, 36°, …, 324° (inputs only).
void BM_ValidateTenPositions(benchmark::State& bs) {
  Model m = bundled("crank-rocker");
  m.design_positions.clear();
  for (int k = 0; k < 10; ++k) {
    DesignPosition p;
    p.name = "p" + std::to_string(k + 1);
    p.inputs.push_back({m.find_joint("A0"), k * 36.0 * std::numbers::pi / 180.0});
    m.design_positions.push_back(p);
  }
  for (auto _ : bs) {
    const ValidationReport r = validate_design_positions(m);
    if (r.positions.size() != 10) bs.SkipWithError("wrong report");
    benchmark::DoNotOptimize(r.positions.data());
  }
}
BENCHMARK(BM_ValidateTenPositions)->Unit(benchmark::kMillisecond);

}  // namespace
