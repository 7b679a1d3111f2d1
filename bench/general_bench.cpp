// Andrews' squeezer in the test set's relative coordinates (M(q), every Ṁ term live) through the
// same engine as the mechanism files (model/general_system.hpp), to t = 0.03 s at rtol 1e-10:
// wall time, and the error against the published state (max relative error of the 7 angles,
// rates and multipliers) and the energy drift T − W (relative). Run:
// build/bench/orthomech_bench --benchmark_filter=AndrewsRelative
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>

#include "orthomech/dynamics/simulate.hpp"
#include "support/andrews_reference.hpp"
#include "support/andrews_relative.hpp"

namespace {
using namespace orthomech;

void AndrewsRelative(benchmark::State& bs, DynamicsForm form, Integrator integrator) {
  const Model model = test::andrews_relative();
  const SimulateOptions o = test::andrews::reference_run(form, integrator);
  SimulateResult r;
  for (auto _ : bs) {
    r = simulate(model, o);
    benchmark::DoNotOptimize(r.final.q.data());
  }
  namespace ref = test::andrews;
  double eq = 0.0, eu = 0.0, el = 0.0;
  for (size_t k = 0; k < 7; ++k) {
    const auto K = static_cast<Eigen::Index>(k);
    eq = std::max(eq, std::abs(r.final.q(K) - ref::kAnglesT003[k]) / std::abs(ref::kAnglesT003[k]));
    eu = std::max(eu, std::abs(r.final.u(K) - ref::kRatesT003[k]) / std::abs(ref::kRatesT003[k]));
  }
  for (size_t k = 0; k < 6; ++k)
    el =
        std::max(el, std::abs(-r.final.lambda(static_cast<Eigen::Index>(k)) - ref::kLambdaT003[k]) /
                         std::abs(ref::kLambdaT003[k]));
  bs.counters["err_q"] = eq;
  bs.counters["err_u"] = eu;
  bs.counters["err_lambda"] = el;
  bs.counters["drift"] = r.energy_max_drift / std::max(r.energy_scale, 1e-300);
  bs.counters["steps"] = static_cast<double>(r.steps);
  bs.counters["evals"] = static_cast<double>(r.evaluations);
}
BENCHMARK_CAPTURE(AndrewsRelative, dual_dopri5, DynamicsForm::dual, Integrator::dopri5)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(AndrewsRelative, primal_dopri5, DynamicsForm::primal, Integrator::dopri5)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(AndrewsRelative, dual_rkf78, DynamicsForm::dual, Integrator::rkf78)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(AndrewsRelative, primal_rkf78, DynamicsForm::primal, Integrator::rkf78)
    ->Unit(benchmark::kMillisecond);

}  // namespace
