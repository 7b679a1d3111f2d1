// Proof that the projection hot paths allocate nothing after set-up (issue 2 §9): global
// operator new is replaced by a counting one; the counter must not move across evaluations.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "orthomech/analysis/mobility.hpp"
#include "orthomech/analysis/positions.hpp"
#include "orthomech/projection/dual.hpp"
#include "orthomech/projection/primal.hpp"
#include "support/fixtures.hpp"

namespace {
std::atomic<long> g_allocations{0};
}

void* operator new(std::size_t size) {
  ++g_allocations;
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) { return operator new(size); }
void* operator new(std::size_t size, std::align_val_t al) {
  ++g_allocations;
  const std::size_t a = static_cast<std::size_t>(al);
  if (void* p = std::aligned_alloc(a, (size + a - 1) / a * a)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }

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
  const long before = g_allocations.load();
  for (int k = 0; k < 100; ++k) {
    s.q(0) = q(0) + 1e-9 * k;  // move a little: real work, same chart
    (void)evaluate_dual(model, s, ws);
    if (primal_ok) (void)evaluate_primal(model, s, ws);
    q_work = q;
    (void)correct_positions_in_chart(model, q_work, ws);
  }
  EXPECT_EQ(g_allocations.load() - before, 0) << "heap allocations in the hot path";
  EXPECT_EQ(ws.dual.switch_count, 0);
}

INSTANTIATE_TEST_SUITE_P(Bundled, NoAllocation,
                         ::testing::Values("crank-rocker", "andrews-squeezer", "triple-crank"));

}  // namespace
}  // namespace orthomech
