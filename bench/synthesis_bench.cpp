// Benchmarks of issue 50 item 1: closed-form four-bar positions (src/synthesis/four_bar.cpp),
// the inner loop of path synthesis. Target ≥ 10⁶ positions/s on one core.
// Run: build/bench/orthomech_bench --benchmark_filter=FourBar
#include <benchmark/benchmark.h>

#include <numbers>

#include "orthomech/synthesis/four_bar.hpp"

namespace {
using namespace orthomech::synthesis;

// One crank turn of the crank-rocker of mechanisms/crank-rocker.yaml in 360 steps per iteration;
// items/s is positions per second.
void BM_FourBarPosition(benchmark::State& bs) {
  FourBar fb;
  fb.A0 = {0, 0};
  fb.B0 = {70, 0};
  fb.a = 30;
  fb.b = 80;
  fb.c = 60;
  fb.coupler_point = {40, 20};
  constexpr int kSteps = 360;
  constexpr double kStep = 2 * std::numbers::pi / kSteps;
  for (auto _ : bs) {
    for (int k = 0; k < kSteps; ++k) {
      const FourBarPosition p = calc_position(fb, k * kStep);
      benchmark::DoNotOptimize(p.P);
    }
  }
  bs.SetItemsProcessed(bs.iterations() * kSteps);
}
BENCHMARK(BM_FourBarPosition);

void BM_SliderCrankPosition(benchmark::State& bs) {
  SliderCrank sc;
  sc.r = 50;
  sc.l = 200;
  sc.offset = 10;
  constexpr int kSteps = 360;
  constexpr double kStep = 2 * std::numbers::pi / kSteps;
  for (auto _ : bs) {
    for (int k = 0; k < kSteps; ++k) {
      const SliderCrankPosition p = calc_position(sc, k * kStep);
      benchmark::DoNotOptimize(p.P);
    }
  }
  bs.SetItemsProcessed(bs.iterations() * kSteps);
}
BENCHMARK(BM_SliderCrankPosition);

}  // namespace
