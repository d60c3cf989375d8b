// Closed-form single-degree-of-freedom cases: the simple (physical) pendulum.
#include <gtest/gtest.h>

#include <cmath>

#include "runtime/engine.h"
#include "tests/runtime/builders.h"

namespace kanesim {
namespace {

// Closed forms evaluated in double precision: a few ulps of the largest term.
constexpr double kClosedFormTol = 1e-12;

TEST(Pendulum, AccelerationMatchesClosedForm) {
  // If this fails, Kane's equations for one revolute joint (gravity projected on the
  // tangent basis, or the inertia term I_O) are wrong.
  const double m = 1.3, L = 0.7, g = 9.81;
  auto r = rt::Compile(test::Pendulum(m, L, g), {});
  ASSERT_TRUE(r.errors.empty()) << r.errors[0].message;
  auto ws = rt::MakeWorkspace(*r.program);
  for (double q : {0.0, 0.3, 1.2, 2.9, -2.0}) {
    double y[2] = {q, 0.7}, yd[2];
    ASSERT_EQ(rt::Derivative(*r.program, *ws, 0.0, y, yd), 0) << rt::ErrorMessage(*ws);
    const double I_O = m * L * L / 3.0;
    EXPECT_NEAR(yd[0], 0.7, kClosedFormTol);
    EXPECT_NEAR(yd[1], -g * std::sin(q) * (m * L / 2) / I_O, kClosedFormTol);
  }
}

}  // namespace
}  // namespace kanesim
