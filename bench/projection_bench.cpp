// Benchmarks of one projection evaluation (issue 2 §9): dual (F-based, eqs. (68)–(70),
// (83)–(84)) and primal (E-based, eqs. (42)–(44), (78)–(79)), each including the free-system and
// constraint evaluation that precede it. Run: build/bench/orthomech_bench
#include <benchmark/benchmark.h>

#include "orthomech/analysis/mobility.hpp"
#include "orthomech/analysis/positions.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/projection/dual.hpp"
#include "orthomech/projection/primal.hpp"

namespace {
using namespace orthomech;

struct Setup {
  Model model;
  State state;
  int rank = 0;
  explicit Setup(const std::string& name)
      : model(load_mechanism(std::string(ORTHOMECH_SOURCE_DIR) + "/mechanisms/" + name + ".yaml")) {
    state = State(model);
    state.q = model.design_q();
    (void)project_positions(model, state.q);
    rank = compute_mobility(model, state.q).rank;
    // An admissible velocity: the first column of F (dual) times 10.
    Workspace ws(model, rank);
    (void)evaluate_dual(model, state, ws);
    state.u = 10.0 * ws.dual.F.col(0);
  }
};

void dual(benchmark::State& bs, const std::string& name) {
  Setup s(name);
  Workspace ws(s.model, s.rank);
  for (auto _ : bs) {
    benchmark::DoNotOptimize(evaluate_dual(s.model, s.state, ws));
    benchmark::DoNotOptimize(ws.dual.theta.data());
  }
}
void primal(benchmark::State& bs, const std::string& name) {
  Setup s(name);
  Workspace ws(s.model, s.rank);
  for (auto _ : bs) {
    benchmark::DoNotOptimize(evaluate_primal(s.model, s.state, ws));
    benchmark::DoNotOptimize(ws.primal.omega.data());
  }
}
void corrector(benchmark::State& bs, const std::string& name) {
  Setup s(name);
  Workspace ws(s.model, s.rank);
  (void)evaluate_dual(s.model, s.state, ws);
  VecX q = s.state.q;
  for (auto _ : bs) {
    q = s.state.q;
    q(0) += 1e-6;
    benchmark::DoNotOptimize(correct_positions_in_chart(s.model, q, ws));
  }
}

BENCHMARK_CAPTURE(dual, crank_rocker, std::string("crank-rocker"));
BENCHMARK_CAPTURE(primal, crank_rocker, std::string("crank-rocker"));
BENCHMARK_CAPTURE(dual, andrews, std::string("andrews-squeezer"));
BENCHMARK_CAPTURE(primal, andrews, std::string("andrews-squeezer"));
BENCHMARK_CAPTURE(corrector, crank_rocker, std::string("crank-rocker"));
BENCHMARK_CAPTURE(corrector, andrews, std::string("andrews-squeezer"));
// Spatial models (issue 12 item 8): quaternion bodies, spatial joint rows, the gyroscopic term.
BENCHMARK_CAPTURE(dual, rssr, std::string("rssr"));
BENCHMARK_CAPTURE(primal, rssr, std::string("rssr"));
BENCHMARK_CAPTURE(dual, bricard, std::string("bricard"));
BENCHMARK_CAPTURE(corrector, rssr, std::string("rssr"));
BENCHMARK_CAPTURE(corrector, bricard, std::string("bricard"));

}  // namespace

BENCHMARK_MAIN();
