// SimulateOptions::on_sample (issue 18 item 2): every output sample is handed to the sink once,
// in time order, the outputs inside change-point passages included and the outputs of steps
// undone by a rewind excluded; with record_samples false the result keeps none of them. Oracle:
// the same run with record_samples = true (the samples it keeps), and the output grid.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "orthomech/dynamics/simulate.hpp"
#include "support/fixtures.hpp"

namespace orthomech {
namespace {

bool same(const VecX& a, const VecX& b) { return a.size() == b.size() && a == b; }

void expect_same_sample(const SimulationSample& a, const SimulationSample& b, size_t k) {
  EXPECT_EQ(a.t, b.t) << "sample " << k;
  EXPECT_TRUE(same(a.q, b.q)) << "sample " << k;
  EXPECT_TRUE(same(a.u, b.u)) << "sample " << k;
  EXPECT_TRUE(same(a.udot, b.udot)) << "sample " << k;
  EXPECT_TRUE(same(a.lambda, b.lambda)) << "sample " << k;
  EXPECT_EQ(a.measures, b.measures) << "sample " << k;
  EXPECT_EQ(a.reactions, b.reactions) << "sample " << k;
  EXPECT_EQ(a.kinetic, b.kinetic) << "sample " << k;
  EXPECT_EQ(a.potential, b.potential) << "sample " << k;
  EXPECT_EQ(a.work, b.work) << "sample " << k;
  EXPECT_EQ(a.residual, b.residual) << "sample " << k;
  EXPECT_EQ(a.velocity_residual, b.velocity_residual) << "sample " << k;
}

struct Streamed {
  SimulateResult result;
  std::vector<SimulationSample> received;
};

Streamed run_streamed(const Model& model, SimulateOptions o) {
  Streamed s;
  o.record_samples = false;
  o.on_sample = [&s](const SimulationSample& smp) { s.received.push_back(smp); };
  s.result = simulate(model, o);
  return s;
}

// The streamed run against the recorded one: the same samples, none kept, the same summary.
// Returns both runs.
struct Runs {
  SimulateResult recorded;
  Streamed streamed;
};
Runs expect_streamed_equals_recorded(const Model& model, const SimulateOptions& o) {
  SimulateOptions rec = o;
  rec.record_samples = true;
  const SimulateResult ref = simulate(model, rec);
  const Streamed s = run_streamed(model, o);
  EXPECT_TRUE(s.result.samples.empty());
  EXPECT_EQ(s.result.status, ref.status);
  EXPECT_EQ(s.result.message, ref.message);
  EXPECT_EQ(s.result.steps, ref.steps);
  EXPECT_EQ(s.result.rewinds, ref.rewinds);
  EXPECT_EQ(s.result.passages.size(), ref.passages.size());
  EXPECT_EQ(s.result.max_velocity_residual, ref.max_velocity_residual);
  EXPECT_EQ(s.result.energy_max_drift, ref.energy_max_drift);
  expect_same_sample(s.result.final, ref.final, 9999);
  EXPECT_EQ(s.received.size(), ref.samples.size());
  for (size_t k = 0; k < std::min(s.received.size(), ref.samples.size()); ++k)
    expect_same_sample(s.received[k], ref.samples[k], k);
  return {ref, s};
}

// The sink sees every output time t = k dt_out, k = 0 … t_end/dt_out, once and in order.
void expect_output_grid(const std::vector<SimulationSample>& samples, double dt_out, size_t n) {
  ASSERT_EQ(samples.size(), n);
  for (size_t k = 0; k < n; ++k)
    EXPECT_NEAR(samples[k].t, static_cast<double>(k) * dt_out, 1e-12) << "sample " << k;
}

TEST(SimulateStream, CrankRocker_SinkGetsEveryOutput_ResultKeepsNone) {
  const Model model = test::load_bundled("crank-rocker");
  SimulateOptions o;
  o.t_end = 0.5;
  o.dt_out = 1e-3;
  const Runs runs = expect_streamed_equals_recorded(model, o);
  ASSERT_EQ(runs.recorded.status, SimulateStatus::completed);
  expect_output_grid(runs.streamed.received, o.dt_out, 501);
}

// Change points passed (outputs inside the passage steps from the step's Hermite) and steps
// undone by rewinds (C2', C2''; their outputs withdrawn before they reach the sink): the
// N = 2 bar at rtol 1e-6 with dopri5 (10 passages, 9 rewinds in 10 s; outputs every 1 ms, so
// the undone steps had outputs).
TEST(SimulateStream, NFourBar2_PassagesAndRewinds_EveryOutputOnceInOrder) {
  const Model model = test::load_bundled("n-four-bar-2");
  SimulateOptions o;
  o.t_end = 10.0;
  o.dt_out = 1e-3;
  o.rtol = 1e-6;
  o.atol = 1e-12;
  o.initial_rates = {{model.find_measure("B0_x"), 1.0}};
  const Runs runs = expect_streamed_equals_recorded(model, o);
  const SimulateResult& ref = runs.recorded;
  ASSERT_EQ(ref.status, SimulateStatus::completed) << ref.message;
  EXPECT_GT(ref.passages.size(), 0u);
  EXPECT_GT(ref.rewinds, 0);  // the case covers outputs withdrawn by a rewind
  expect_output_grid(runs.streamed.received, o.dt_out, 10001);
}

// A run that stops (primal form before the first change point, status singular): the sink has
// every output up to the stop, and `final` is the stop's state as with the recorded run.
TEST(SimulateStream, StoppedRun_SinkHasEveryOutputUpToTheStop) {
  const Model model = test::load_bundled("n-four-bar-40");
  SimulateOptions o;
  o.form = DynamicsForm::primal;
  o.t_end = 1.0;
  o.dt_out = 1e-2;
  const SimulateResult ref = expect_streamed_equals_recorded(model, o).recorded;
  ASSERT_EQ(ref.status, SimulateStatus::singular);
  ASSERT_FALSE(ref.samples.empty());
  EXPECT_LT(ref.samples.back().t, 1.0);
}

// Without a sink and without record_samples, nothing is sampled (the summary and final only).
TEST(SimulateStream, NoSinkNoRecord_NoSamples) {
  const Model model = test::load_bundled("crank-rocker");
  SimulateOptions o;
  o.t_end = 0.1;
  o.record_samples = false;
  const SimulateResult r = simulate(model, o);
  ASSERT_EQ(r.status, SimulateStatus::completed);
  EXPECT_TRUE(r.samples.empty());
  EXPECT_NEAR(r.final.t, 0.1, 1e-12);
}

}  // namespace
}  // namespace orthomech
