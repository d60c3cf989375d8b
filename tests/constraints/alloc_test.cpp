// The closed-loop right-hand side allocates nothing (projection by Newton, partition,
// reduced Kane's equations): a global operator-new counter around rt::Derivative and
// rt::EvalSignals (with loop residuals and the drive torque) on the examples.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "runtime/program.h"
#include "tests/constraints/load_util.h"

namespace {
std::atomic<long> g_allocations{0};
}  // namespace

void* operator new(std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }

namespace kanesim::test {
namespace {

void Check(const std::string& example, const std::vector<std::string>& signals) {
  auto l = LoadModel(kRoot + "/examples/" + example);
  ASSERT_TRUE(l && l->prog);
  const rt::Program& p = *l->prog;
  auto ws = rt::MakeWorkspace(p);
  std::vector<double> y(static_cast<size_t>(rt::StateSize(p))), yd(y.size()), out(signals.size());
  rt::InitialState(p, y.data());
  std::string err;
  auto plan = rt::PlanSignals(p, signals, &err);
  ASSERT_TRUE(plan) << err;
  ASSERT_EQ(rt::Derivative(p, *ws, 0.0, y.data(), yd.data()), 0);  // first call may size nothing lazily
  for (size_t i = 0; i < y.size(); ++i) y[i] += 1e-4;                // off the manifold: Newton iterates
  const long before = g_allocations.load();
  for (int k = 0; k < 5; ++k) {
    ASSERT_EQ(rt::Derivative(p, *ws, 0.01 * k, y.data(), yd.data()), 0) << rt::ErrorMessage(*ws);
    ASSERT_EQ(rt::EvalSignals(p, *plan, *ws, 0.01 * k, y.data(), out.data()), 0) << rt::ErrorMessage(*ws);
  }
  EXPECT_EQ(g_allocations.load() - before, 0) << example << ": operator new called in the right-hand side";
}

TEST(ConstraintsAlloc, FourBarRightHandSideAllocatesNothing) {
  // If this fails, the projection or the reduced solve allocates on every evaluation.
  Check("fourbar.mech", {"crank_coupler.q", "coupler_rocker.constraint_residual", "coupler_rocker.constraint_drift",
                         "coupler_rocker.constraint_residual_velocity"});
}

TEST(ConstraintsAlloc, ReactionsAndConstraintPowerAllocateNothing) {
  // If this fails, the constraint forces computed on request allocate per output row.
  Check("fourbar.mech", {"crank_pivot.reaction_force[1]", "coupler_rocker.reaction_torque[3]", "constraint_power"});
}

TEST(ConstraintsAlloc, SliderCrankDriveAllocatesNothing) {
  // If this fails, the zero-DOF path or the loop drive torque allocates.
  Check("slider_crank.mech", {"slide.q", "crank_pivot.drive"});
}

}  // namespace
}  // namespace kanesim::test
