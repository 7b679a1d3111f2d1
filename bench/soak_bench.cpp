// Soak runs (issue 17, item 6): long runs that must keep their memory flat and their constraints
// closed. Too long for the test suite (tens of seconds), so benchmarks with checks: a check that
// fails ends the benchmark with an error (SkipWithError), so a run shows it.
//   Pendulum, 1e4 periods, twice (after a 1e3-period run): simulate (dual, dopri5) with only the
//     final sample kept; the second run leaves the heap where the first left it (no leak), the
//     peak resident set grows by less than 8 B per extra step from 1e3 to 1e4 periods (nothing
//     stored per step; the chart-switch log grows, by design); max |f| over every accepted step
//     < 1e-9 m.
//   Triple-crank, 1e5 positions, twice: run_cycle; |f(q)| < 1e-9 at every position; the second
//     sweep leaves the heap where the first left it and does not raise the peak resident set.
// Run: build/bench/orthomech_bench --benchmark_filter=Soak
#include <benchmark/benchmark.h>
#include <malloc.h>
#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "orthomech/analysis/cycle.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/dynamics/simulate.hpp"
#include "orthomech/io/mechanism_file.hpp"

namespace {
using namespace orthomech;

constexpr double kClosure = 1e-9;      // m (or rad): the bound on the residual
constexpr long kRssGrowth = 1L << 20;  // bytes: "flat" (1 MB of allocator noise)

Model bundled(const std::string& name) {
  return load_mechanism(std::string(ORTHOMECH_SOURCE_DIR) + "/mechanisms/" + name + ".yaml");
}

long heap_in_use() { return static_cast<long>(mallinfo2().uordblks); }

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

struct Memory {
  long heap_run1 = 0, heap_run2 = 0;  // heap in use after each run, minus before the first
  long rss_growth_run2 = 0;           // peak resident set after run 2 minus after run 1
};

// Runs `run` twice and reports the memory as above.
template <class Run>
Memory twice(Run&& run) {
  Memory m;
  const long heap0 = heap_in_use();
  run();
  m.heap_run1 = heap_in_use() - heap0;
  const long rss1 = peak_rss_bytes();
  run();
  m.heap_run2 = heap_in_use() - heap0;
  m.rss_growth_run2 = peak_rss_bytes() - rss1;
  return m;
}

void check_memory(benchmark::State& bs, const Memory& m) {
  bs.counters["rss_growth_run2"] = static_cast<double>(m.rss_growth_run2);
  if (m.heap_run2 != m.heap_run1) bs.SkipWithError("heap in use grew from run 1 to run 2");
  if (m.rss_growth_run2 >= kRssGrowth) bs.SkipWithError("resident set grew in run 2");
}

// The pendulum switches charts four times a period and the result lists every switch, so its
// memory grows with time by design (about 100 B a switch). What must not grow is anything per
// step: from a 1e3- to a 1e4-period run the peak resident set may grow by less than
// kBytesPerStep per extra step (storing a state, 2 coordinates and 2 velocities, would be
// 32 B a step).
constexpr double kBytesPerStep = 8.0;

void SoakPendulum1e4Periods(benchmark::State& bs) {
  const Model model = bundled("pendulum");
  for (auto _ : bs) {
    const long short_steps = pendulum_run(model, 1e3).steps;
    const long rss_short = peak_rss_bytes();
    long steps = 0;
    size_t switches = 0;
    double residual = 0.0;
    bool completed = true;
    const Memory m = twice([&] {
      const SimulateResult r = pendulum_run(model, 1e4);
      steps = r.steps;
      switches = r.chart_switches.size();
      residual = std::max(residual, r.max_constraint_residual);
      completed = completed && r.status == SimulateStatus::completed;
    });
    const double per_step = static_cast<double>(peak_rss_bytes() - rss_short) /
                            static_cast<double>(steps - short_steps);
    std::fprintf(stderr,
                 "pendulum: %ld steps, %zu chart switches, max |f| %.3g, heap after run 1 %+ld B, "
                 "after run 2 %+ld B, peak RSS: +%ld B from 1e3 to 1e4 periods (%.2f B per extra "
                 "step), %+ld B in run 2\n",
                 steps, switches, residual, m.heap_run1, m.heap_run2, peak_rss_bytes() - rss_short,
                 per_step, m.rss_growth_run2);
    bs.counters["steps"] = static_cast<double>(steps);
    bs.counters["max_residual"] = residual;
    bs.counters["rss_bytes_per_step"] = per_step;
    if (!completed) bs.SkipWithError("the simulation did not complete");
    if (!(residual < kClosure)) bs.SkipWithError("closure residual above 1e-9");
    if (m.heap_run2 != m.heap_run1) bs.SkipWithError("heap in use grew from run 1 to run 2");
    if (!(per_step < kBytesPerStep)) bs.SkipWithError("memory grows with the number of steps");
  }
}

void SoakTripleCrank1e5Positions(benchmark::State& bs) {
  const Model model = bundled("triple-crank");
  CycleOptions o;
  o.driver = model.drivers.at(0);
  o.steps = 100000;
  for (auto _ : bs) {
    double worst = 0.0;
    bool completed = true;
    size_t positions = 0;
    const Memory m = twice([&] {
      const CycleResult r = run_cycle(model, o);
      completed = completed && r.status == CycleStatus::completed;
      positions = r.points.size();
      VecX f(model.nc);
      for (const DrivenPointView& p : r.points) {
        compute_constraint_residual(model, VecX(p.q), f);
        worst = std::max(worst, f.cwiseAbs().maxCoeff());
      }
    });
    std::fprintf(stderr,
                 "triple-crank: %zu positions, max |f| %.3g, heap after run 1 %+ld B, after "
                 "run 2 %+ld B, peak RSS growth in run 2 %+ld B\n",
                 positions, worst, m.heap_run1, m.heap_run2, m.rss_growth_run2);
    bs.counters["positions"] = static_cast<double>(positions);
    bs.counters["max_residual"] = worst;
    if (!completed) bs.SkipWithError("the sweep did not complete");
    if (!(worst < kClosure)) bs.SkipWithError("closure residual above 1e-9");
    check_memory(bs, m);
  }
}

}  // namespace

BENCHMARK(SoakPendulum1e4Periods)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK(SoakTripleCrank1e5Positions)->Unit(benchmark::kSecond)->Iterations(1);
