// The integration loop allocates nothing per step on the C++ side: if this fails, the
// right-hand-side wrapper (GuardedRhs, the solvers' callbacks) or the driver's loop
// between output rows allocates, which costs time on every evaluation.
// (SUNDIALS itself allocates only at setup, with malloc, which this does not count.)
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>
#include <string>

#include "sim/integrator.h"

namespace {
std::atomic<long> g_news{0};
}  // namespace

// Every replaceable form, so that no allocation pairs with a sanitizer's own operator.
static void* CountedAlloc(std::size_t n) noexcept {
  g_news.fetch_add(1, std::memory_order_relaxed);
  return std::malloc(n ? n : 1);
}
void* operator new(std::size_t n) {
  if (void* p = CountedAlloc(n)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) {
  if (void* p = CountedAlloc(n)) return p;
  throw std::bad_alloc();
}
void* operator new(std::size_t n, const std::nothrow_t&) noexcept { return CountedAlloc(n); }
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept { return CountedAlloc(n); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }

namespace kanesim::sim {
namespace {

class Oscillator final : public OdeSystem {
 public:
  int Size() const override { return 2; }
  int Rhs(double, const double* y, double* yd) override {
    yd[0] = y[1];
    yd[1] = -y[0];
    return 0;
  }
};

TEST(SimAlloc, NoAllocationBetweenOutputRows) {
  for (rt::Integrator m : {rt::Integrator::IDA, rt::Integrator::CvodeAdams, rt::Integrator::CvodeBdf, rt::Integrator::ArkodeErk, rt::Integrator::Dop853}) {
    Oscillator ode;
    const double y0[2] = {1.0, 0.0};
    long at_row2 = -1, at_last = -1;
    long row = 0;
    RowCallback cb = [&](double, const double*, std::string*) {
      ++row;
      if (row == 2) at_row2 = g_news.load();
      at_last = g_news.load();
      return 0;
    };
    IntegratorOptions opt;
    opt.method = m;
    opt.rtol = opt.atol = 1e-8;
    IntegrateResult r = Integrate(ode, y0, OutputGrid{0.0, 20.0, 0.5}, opt, cb);
    ASSERT_TRUE(r.ok) << r.cause;
    ASSERT_EQ(row, 41);
    EXPECT_EQ(at_last - at_row2, 0) << MethodName(m) << ": operator new called while integrating";
  }
}

}  // namespace
}  // namespace kanesim::sim
