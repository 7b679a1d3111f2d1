// Proof that the projection hot paths allocate nothing after set-up (issue 2 §9): malloc and
// friends are interposed by counting versions; the counter must not move across evaluations.
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <string>
#include <vector>

#include "../../src/dynamics/integrator.hpp"
#include "orthomech/analysis/cycle.hpp"
#include "orthomech/analysis/mobility.hpp"
#include "orthomech/analysis/positions.hpp"
#include "orthomech/constraints/joints.hpp"
#include "orthomech/constraints/sparse_et.hpp"
#include "orthomech/io/mechanism_file.hpp"
#include "orthomech/model/free_system.hpp"
#include "orthomech/model/measures.hpp"
#include "orthomech/projection/chart.hpp"
#include "orthomech/projection/chart_engine.hpp"
#include "orthomech/projection/dual.hpp"
#include "orthomech/projection/primal.hpp"
#include "support/fixtures.hpp"
#include "support/spatial_fixtures.hpp"

namespace {
std::atomic<long> g_allocations{0};
std::atomic<long long> g_bytes{0};  // bytes asked for (never decreases)
}  // namespace

// Every heap allocation of the process goes through malloc/calloc/realloc (Eigen's
// aligned_malloc uses std::malloc; libstdc++'s operator new calls malloc). This binary interposes
// them, counts, and forwards to glibc's implementations.
extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void* __libc_memalign(std::size_t, std::size_t);
void* malloc(std::size_t size) {
  ++g_allocations;
  g_bytes += static_cast<long long>(size);
  return __libc_malloc(size);
}
void* calloc(std::size_t n, std::size_t size) {
  ++g_allocations;
  g_bytes += static_cast<long long>(n * size);
  return __libc_calloc(n, size);
}
void* realloc(void* p, std::size_t size) {
  ++g_allocations;
  g_bytes += static_cast<long long>(size);
  return __libc_realloc(p, size);
}
void* aligned_alloc(std::size_t alignment, std::size_t size) {
  ++g_allocations;
  g_bytes += static_cast<long long>(size);
  return __libc_memalign(alignment, size);
}
int posix_memalign(void** out, std::size_t alignment, std::size_t size) {
  ++g_allocations;
  g_bytes += static_cast<long long>(size);
  *out = __libc_memalign(alignment, size);
  return *out ? 0 : 12;  // ENOMEM
}
}

namespace orthomech {
namespace {

class NoAllocation : public ::testing::TestWithParam<const char*> {};

TEST_P(NoAllocation, DualPrimalAndCorrectorAllocateNothingAfterSetUp) {
  const Model model = test::load_bundled(GetParam());
  const VecX q = test::assembled_q(model);
  const Mobility mob = compute_mobility(model, q);
  Workspace ws(model, mob.rank);
  State s(model);
  s.q = q;
  s.u = test::admissible_velocity(model, q, 7);
  // Set-up: first evaluations size everything and choose the chart.
  ASSERT_EQ(evaluate_dual(model, s, ws), ProjectionStatus::ok);
  const bool primal_ok = evaluate_primal(model, s, ws) == ProjectionStatus::ok;
  VecX q_work = q;
  {  // the counter sees Eigen's heap allocations (else this test could not fail)
    const long c0 = g_allocations.load();
    const VecX probe = VecX::Ones(64);
    ASSERT_GT(g_allocations.load() - c0, 0);
    ASSERT_EQ(probe.sum(), 64.0);
  }
  const long before = g_allocations.load();
  for (int k = 0; k < 100; ++k) {
    s.q(0) = q(0) + 1e-9 * k;  // move a little: real work, same chart
    (void)evaluate_dual(model, s, ws);
    if (primal_ok) (void)evaluate_primal(model, s, ws);
    q_work = q;
    (void)correct_positions_in_chart(model, q_work, ws);
  }
  EXPECT_EQ(g_allocations.load() - before, 0) << "heap allocations in the hot path";
  EXPECT_EQ(ws.dual.engine.switch_count(), 0);
}

// The driven computation of every cycle position, (C1)–(C4) with minimum-norm multipliers.
TEST_P(NoAllocation, DrivenKinetostaticsAllocatesNothingAfterSetUp) {
  const Model model = test::load_bundled(GetParam());
  const VecX q = test::assembled_q(model);
  const Mobility mob = compute_mobility(model, q);
  Workspace ws(model, mob.rank);
  DrivenWorkspace dws(model, mob.rank);
  State s(model);
  s.q = q;
  DrivenPoint p;
  const int joint = model.drivers.at(0).joint;
  ASSERT_TRUE(compute_driven(model, joint, 10.0, 1.0, s, ws, dws, p));  // set-up
  std::vector<double> values;
  compute_reactions(model, q, p.lambda, values);
  double measure_sum = 0.0;
  std::vector<Measure> accelerations = model.measures;  // every measure at order 2 too
  for (Measure& m : accelerations) m.derivative = 2;
  const long before = g_allocations.load();
  for (int k = 0; k < 100; ++k) {
    s.q = q;
    s.q(0) += 1e-9 * k;
    (void)compute_driven(model, joint, 10.0, 1.0, s, ws, dws, p);
    compute_reactions(model, q, p.lambda, values);
    // What the sweep stores per position: reactions and measures from compute_driven's rotation
    // table (acceleration measures included), and the rate term on its own.
    compute_reactions(model, s.q, dws.rotations, p.lambda, values);
    for (const Measure& m : model.measures)
      measure_sum += evaluate_measure(model, m, s.q, &s.u, &p.udot, dws.rotations);
    for (const Measure& m : accelerations)
      measure_sum += evaluate_measure(model, m, s.q, &s.u, &p.udot);
    compute_constraint_rate(model, s, dws.rotations, ws.constraints);
    dws.rotations.update(model, s.q);
    // The determinacy test of the sweep: reactions of a null-space column, without a copy.
    for (Eigen::Index j = 0; j < dws.N.cols(); ++j)
      compute_reactions(model, q, dws.N.col(j), values);
  }
  EXPECT_EQ(g_allocations.load() - before, 0)
      << "heap allocations in compute_driven, compute_reactions, evaluate_measure or "
         "compute_constraint_rate";
  EXPECT_TRUE(std::isfinite(measure_sum));
}

// The Rosenbrock stepper (src/dynamics/integrator.cpp, written here) allocates per run, not per
// step: a run of 1000 fixed steps allocates as much as a run of 100 (a non-allocating right-hand
// side, x'' = −x). odeint's own steppers do allocate per step, in its Eigen algebra (measured
// with this function: 3 per step for dopri5 and rkf78, ~11 for Bulirsch–Stoer;
// docs/architecture.md).
long allocations_of_run(detail::OdeStepper stepper, long steps) {
  detail::OdeProblem p;
  p.rhs = [](const VecX& x, VecX& f, double) {
    f.resize(2);
    f(0) = x(1);
    f(1) = -x(0);
  };
  p.accept = [](double, VecX&) { return true; };
  p.output = [](double, const VecX&) {};
  detail::OdeOptions o;
  o.stepper = stepper;
  o.rtol = o.atol = 1e6;        // every step accepted …
  o.dt_init = o.max_dt = 1e-3;  // … at the fixed step
  o.t_end = 1e-3 * static_cast<double>(steps);
  o.dt_out = o.t_end;
  VecX x(2);
  x << 1.0, 0.0;
  const long before = g_allocations.load();
  const detail::OdeStats s = detail::integrate_ode(p, x, o);
  const long used = g_allocations.load() - before;
  EXPECT_TRUE(s.completed) << s.message;
  return used;
}

// Spatial models (issue 12 item 8): quaternion bodies, the spatial joint rows, the gyroscopic
// term and the corrector's ⊕ allocate nothing either.
TEST(NoAllocationSpatial, DualPrimalAndCorrectorAllocateNothingAfterSetUp) {
  for (SpatialJointType type : {SpatialJointType::revolute, SpatialJointType::universal,
                                SpatialJointType::screw, SpatialJointType::distance}) {
    const Model model = testing::spatial::two_body_model(type, 0);
    const VecX q = model.design_q();
    const Mobility mob = compute_mobility(model, q);
    Workspace ws(model, mob.rank);
    State s(model);
    s.q = q;
    s.u = test::admissible_velocity(model, q, 7);
    ASSERT_EQ(evaluate_dual(model, s, ws), ProjectionStatus::ok);
    ASSERT_EQ(evaluate_primal(model, s, ws), ProjectionStatus::ok);
    VecX q_work = q;
    const long before = g_allocations.load();
    for (int k = 0; k < 100; ++k) {
      s.q(0) = q(0) + 1e-9 * k;
      (void)evaluate_dual(model, s, ws);
      (void)evaluate_primal(model, s, ws);
      q_work = q;
      (void)correct_positions_in_chart(model, q_work, ws);
    }
    EXPECT_EQ(g_allocations.load() - before, 0) << spatial_joint_spec(type).type;
  }
}

// The rolling disc's rows (a nonholonomic constraint of a spatial body) allocate nothing either.
TEST(NoAllocationSpatial, RollingDiscAllocatesNothingAfterSetUp) {
  const Model model = test::load_bundled("rolling-disc");
  const VecX q = model.design_q();
  Workspace ws(model, compute_mobility(model, q).rank);
  State s(model);
  s.q = q;
  s.u = test::admissible_velocity(model, q, 7);
  ASSERT_EQ(evaluate_dual(model, s, ws), ProjectionStatus::ok);
  ASSERT_EQ(evaluate_primal(model, s, ws), ProjectionStatus::ok);
  VecX q_work = q;
  const long before = g_allocations.load();
  for (int k = 0; k < 100; ++k) {
    s.q(0) = q(0) + 1e-9 * k;
    (void)evaluate_dual(model, s, ws);
    (void)evaluate_primal(model, s, ws);
    q_work = q;
    (void)correct_positions_in_chart(model, q_work, ws);
  }
  EXPECT_EQ(g_allocations.load() - before, 0);
}

// Eᵀ on its structural pattern (simulate's Eᵀ, issue 18): f, Eᵀ and Dᵀu allocate nothing after
// the pattern is recorded, planar (four-bar chain) and spatial (rolling disc, Bennett).
TEST(NoAllocationSparseEt, EvaluationsAllocateNothingAfterSetUp) {
  for (const char* name : {"n-four-bar-40", "rolling-disc", "bennett", "andrews-squeezer"}) {
    const Model model = test::load_bundled(name);
    const VecX q = model.design_q();
    SparseEt Et(model);
    BodyPoses rotations(model);
    VecX f(model.nc), Dtu(model.nc);
    State s(model);
    s.q = q;
    s.u = VecX::Ones(model.n);
    const long before = g_allocations.load();
    for (int k = 0; k < 100; ++k) {
      s.q(0) = q(0) + 1e-9 * k;
      rotations.update(model, s.q);
      compute_constraint_residual_and_jacobian(model, s.q, rotations, f, Et);
      compute_constraint_jacobian(model, s.q, Et);
      compute_constraint_rate(model, s, rotations, Dtu);
    }
    EXPECT_EQ(g_allocations.load() - before, 0) << name;
    EXPECT_TRUE(f.allFinite() && Dtu.allFinite()) << name;
  }
}

// The sparse chart engine (simulate's on large mechanisms): after the chart's first
// factorisation, factorisations at new positions (KLU reusing its pivots) and the solves
// allocate nothing.
TEST(NoAllocationSparseEngine, FactorisationsAndSolvesAllocateNothingAfterTheFirst) {
  const Model model = test::load_bundled("n-four-bar-40");
  SparseEt Et(model);
  VecX q = model.design_q();
  compute_constraint_jacobian(model, q, Et);
  const int r = static_cast<int>(Eigen::FullPivLU<MatX>(MatX(Et.matrix())).rank());
  ChartEngine engine(model, r, ChartFactorisation::sparse_when_large);
  ASSERT_TRUE(engine.sparse());
  const VecX ones = VecX::Ones(model.n);
  ASSERT_TRUE(engine.select(Et, ones));
  ASSERT_EQ(engine.factor(Et, ones), 1.0);
  const VecX b = VecX::Ones(model.nc), c = VecX::Ones(model.n);
  VecX x(model.n), lambda(r);
  const double q0 = q(0);
  const long before = g_allocations.load();
  for (int k = 1; k <= 100; ++k) {
    q(0) = q0 + 1e-4 * k;
    compute_constraint_jacobian(model, q, Et);
    EXPECT_EQ(engine.factor(Et, ones), 1.0);
    engine.solve(b, x);
    engine.solve_transposed(c, lambda);
  }
  EXPECT_EQ(g_allocations.load() - before, 0);
  EXPECT_TRUE(x.allFinite() && lambda.allFinite());
}

TEST(NoAllocationIntegrators, RosenbrockStepsAllocateNothing) {
  EXPECT_EQ(allocations_of_run(detail::OdeStepper::rosenbrock4, 1000),
            allocations_of_run(detail::OdeStepper::rosenbrock4, 100));
}

// A 2400-body spatial chain of spherical joints (n = 14400, n_c = 7200), drawn closed. Its chart
// selector and the position projection of a start that already closes reserved the dense n × n_c
// blocks they never touch (3.3 GB per selector, 830 MB for Eᵀ: `simulate` ended in exit 4 under
// `ulimit -v 4000000`, issue 47); they are sized at their first dense use.
Model spatial_chain(int bodies) {
  std::string text =
      "orthomech: 1\ndimension: 3\nname: chain\nunits: {length: m, angle: deg, mass: kg, time: "
      "s, force: N}\nbodies:\n";
  for (int i = 0; i < bodies; ++i)
    text += "  - {name: b" + std::to_string(i) +
            ", mass: 1, inertia: [0.01, 0.01, 0.01], pose: {position: [" + std::to_string(i) +
            ".5, 0, 0]}, points: {L: [-0.5, 0, 0], R: [0.5, 0, 0]}}\n";
  text += "joints:\n  - {name: j0, type: spherical, connects: [ground.origin, b0.L]}\n";
  for (int i = 1; i < bodies; ++i)
    text += "  - {name: j" + std::to_string(i) + ", type: spherical, connects: [b" +
            std::to_string(i - 1) + ".R, b" + std::to_string(i) + ".L]}\n";
  return parse_mechanism(text, "chain.yaml");
}

TEST(NoAllocationLargeModels, SelectorAndAClosedStartReserveNoDenseBlocks) {
  const Model model = spatial_chain(2400);
  ASSERT_EQ(model.n, 14400);
  ASSERT_EQ(model.nc, 7200);
  const long long dense = 8LL * model.n * model.nc;  // one n × n_c block: 830 MB
  long long before = g_bytes.load();
  { const ChartSelector selector(model.nc, model.n); }
  EXPECT_LT(g_bytes.load() - before, 1LL << 20);  // its row bookkeeping only
  VecX q = model.design_q();
  before = g_bytes.load();
  const SolveResult closed = project_positions(model, q);
  EXPECT_EQ(closed.status, SolveStatus::converged);
  // The closed start forms nothing n × n_c: what it allocates is O(n) (f, the selector's
  // bookkeeping), far below a tenth of one dense block (83 MB); before, 4.1 GB.
  EXPECT_LT(g_bytes.load() - before, dense / 10);
  // The counter sees large blocks (else this test could not fail).
  before = g_bytes.load();
  { const MatX block(model.nc, model.n); }
  EXPECT_GE(g_bytes.load() - before, dense);
}

INSTANTIATE_TEST_SUITE_P(Bundled, NoAllocation,
                         ::testing::Values("crank-rocker", "andrews-squeezer", "triple-crank"));

}  // namespace
}  // namespace orthomech
