// Soak runs (issue 17, item 6): long runs that must keep their memory flat and their constraints
// closed. Too long for the test suite (tens of seconds), so benchmarks with checks: a check that
// fails ends the benchmark with an error (SkipWithError), so a run shows it.
//   Pendulum, 1e4 periods: simulate (dual, dopri5) with only the final sample kept; the heap in
//     use after the run equals the heap before it (no leak), and the peak resident set of the
//     1e4-period run exceeds that of a 1e3-period run by less than 1 MB (no growth with time).
//     max |f| over every accepted step < 1e-9 m.
//   Triple-crank, 1e5 positions: run_cycle; |f(q)| < 1e-9 at every position; the heap in use
//     after the result is destroyed equals the heap before the sweep.
// Run: build/bench/orthomech_bench --benchmark_filter=Soak
#include <benchmark/benchmark.h>
#include <malloc.h>
#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "orthomech/analysis/cycle.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/dynamics/simulate.hpp"
#include "orthomech/io/mechanism_file.hpp"

namespace {
using namespace orthomech;

constexpr double kClosure = 1e-9;           // m (or rad): the bound on the residual
constexpr double kRssGrowth = 1024 * 1024;  // bytes: "flat" (one page table's worth of noise)

Model bundled(const std::string& name) {
  return load_mechanism(std::string(ORTHOMECH_SOURCE_DIR) + "/mechanisms/" + name + ".yaml");
}

size_t heap_in_use() { return mallinfo2().uordblks; }

long peak_rss_bytes() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss * 1024L;
}

// The pendulum of mechanisms/pendulum.yaml starts horizontal at rest: amplitude 90°, period
// T = 4 sqrt(L/g) K(sin 45°) = 2.3680 s for L = 1 m, g = 9.81 m/s² (complete elliptic integral
// K(1/√2) = 1.854075). The number of periods only sets t_end; the checks do not depend on it.
SimulateResult pendulum_run(const Model& model, double periods) {
  SimulateOptions o;
  o.t_end = periods * 4.0 * std::sqrt(1.0 / 9.81) * 1.854075;
  o.dt_out = o.t_end;  // two output times: the memory of the samples is not what is measured
  o.record_samples = false;
  o.max_steps = 100'000'000;
  return simulate(model, o);
}

void SoakPendulum1e4Periods(benchmark::State& bs) {
  const Model model = bundled("pendulum");
  for (auto _ : bs) {
    (void)pendulum_run(model, 1e3);  // warm: the 1e3-period run sets the peak to compare with
    const long rss_short = peak_rss_bytes();
    const size_t heap_before = heap_in_use();
    long steps = 0;
    double residual = 0.0;
    bool completed = false;
    {
      const SimulateResult r = pendulum_run(model, 1e4);
      steps = r.steps;
      residual = r.max_constraint_residual;
      completed = r.status == SimulateStatus::completed;
    }
    const size_t heap_after = heap_in_use();
    const long rss_growth = peak_rss_bytes() - rss_short;
    bs.counters["steps"] = static_cast<double>(steps);
    bs.counters["max_residual"] = residual;
    bs.counters["rss_growth_bytes"] = static_cast<double>(rss_growth);
    bs.counters["heap_delta_bytes"] =
        static_cast<double>(heap_after) - static_cast<double>(heap_before);
    if (!completed) bs.SkipWithError("the simulation did not complete");
    if (!(residual < kClosure)) bs.SkipWithError("closure residual above 1e-9");
    if (heap_after != heap_before) bs.SkipWithError("heap in use grew (a leak)");
    if (static_cast<double>(rss_growth) >= kRssGrowth) bs.SkipWithError("resident set grew");
  }
}

void SoakTripleCrank1e5Positions(benchmark::State& bs) {
  const Model model = bundled("triple-crank");
  CycleOptions o;
  o.driver = model.drivers.at(0);
  o.steps = 100000;
  CycleOptions warm = o;
  warm.steps = 360;
  for (auto _ : bs) {
    (void)run_cycle(model, warm);  // first-use allocations (if any) before the measurement
    const size_t heap_before = heap_in_use();
    double worst = 0.0;
    bool completed = false;
    size_t positions = 0;
    {
      const CycleResult r = run_cycle(model, o);
      completed = r.status == CycleStatus::completed;
      positions = r.points.size();
      VecX f(model.nc);
      for (const DrivenPointView& p : r.points) {
        compute_constraint_residual(model, VecX(p.q), f);
        worst = std::max(worst, f.cwiseAbs().maxCoeff());
      }
    }
    const size_t heap_after = heap_in_use();
    bs.counters["positions"] = static_cast<double>(positions);
    bs.counters["max_residual"] = worst;
    bs.counters["heap_delta_bytes"] =
        static_cast<double>(heap_after) - static_cast<double>(heap_before);
    if (!completed) bs.SkipWithError("the sweep did not complete");
    if (!(worst < kClosure)) bs.SkipWithError("closure residual above 1e-9");
    if (heap_after != heap_before) bs.SkipWithError("heap in use grew (a leak)");
  }
}

}  // namespace

BENCHMARK(SoakPendulum1e4Periods)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK(SoakTripleCrank1e5Positions)->Unit(benchmark::kSecond)->Iterations(1);
