// The event root finder (sim/regula_falsi.h): if these fail, an event time is not located to
// its tolerance around a closed-form zero, the returned end is on the wrong side of the zero,
// or the search spends its evaluations halving a bracket the secant had already closed in on.
#include "sim/regula_falsi.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

namespace kanesim::sim {
namespace {

constexpr double kEps = 2.220446049250313e-16;
constexpr double kRel = 4.0 * kEps;  // DOP853's stopping tolerance (sim/integrator_dop853.cpp)
// Evaluations allowed per zero on smooth g: the secant needs 4-6 from a bracket of 2e-3 s;
// the halving this file guards against took 9-31 on the same cases.
constexpr int kMaxEvals = 8;

struct Case {
  const char* what;
  double (*g)(double x);  // g as a function of x = t - r: positive before the zero, negative after
};

const Case kCases[] = {
    {"near-linear", [](double x) { return -x * (1.0 + 50.0 * x); }},
    {"curved", [](double x) { return -std::sin(40.0 * x) - 30.0 * x * x; }},
    {"exponential", [](double x) { return -std::expm1(x); }},
    {"steep", [](double x) { return -std::tanh(2000.0 * x); }},
};

TEST(RegulaFalsiRoot, LocatesClosedFormZerosToTheToleranceInFewEvaluations) {
  for (const Case& c : kCases) {
    for (double r : {0.13536583407612074, 0.17149795448816346, 0.2439524505945283, 0.75, 1.2345678901234567, 3.3}) {
      const double a = r - 1.3e-3, b = r + 0.7e-3;
      auto g = [&](double t) { return c.g(t - r); };
      int evals = 0;
      auto eval = [&](double t, double* gt) {
        ++evals;
        *gt = g(t);
        return true;
      };
      bool failed = true;
      const double root = RegulaFalsiRoot(a, g(a), b, g(b), kRel, eval, &failed);
      SCOPED_TRACE(testing::Message() << c.what << " r = " << r);
      EXPECT_FALSE(failed);
      EXPECT_LE(g(root), 0.0);  // the right end of the bracket
      EXPECT_LE(std::abs(root - r), kRel * r);
      EXPECT_LE(evals, kMaxEvals);
    }
  }
}

// g with round-off: a slope of 1e-3 and a deterministic noise of +-1e-17 make g's sign random
// within 1e-14 s of the zero (~100 ulp at t = 0.3), as the warm-started friction forces do.
TEST(RegulaFalsiRoot, NoisyFunctionEndsInsideItsNoiseBand) {
  const double r = 0.2439524505945283, slope = 1e-3, noise = 1e-17;
  uint64_t state = 88172645463325252ull;  // fixed seed (xorshift64)
  auto g = [&](double t) {
    state ^= state << 13, state ^= state >> 7, state ^= state << 17;
    const double u = static_cast<double>(state >> 11) * 0x1.0p-53 * 2.0 - 1.0;
    return slope * (r - t) + noise * u;
  };
  int evals = 0;
  auto eval = [&](double t, double* gt) {
    ++evals;
    *gt = g(t);
    return true;
  };
  bool failed = true;
  const double root = RegulaFalsiRoot(r - 1e-3, g(r - 1e-3), r + 1e-3, g(r + 1e-3), kRel, eval, &failed);
  EXPECT_FALSE(failed);
  EXPECT_LE(std::abs(root - r), noise / slope + kRel * r);
  EXPECT_LE(evals, 30) << "evaluations";  // the move off an end doubles: a noise band of ~50 tol costs ~log2(50) more
}

TEST(RegulaFalsiRoot, FailedEvaluationStopsWithTheBracketSoFar) {
  int evals = 0;
  auto eval = [&](double t, double* gt) {
    *gt = 0.5 - t;
    return ++evals < 2;
  };
  bool failed = false;
  const double root = RegulaFalsiRoot(0.0, 0.5, 2.0, -1.5, kRel, eval, &failed);
  EXPECT_TRUE(failed);
  EXPECT_EQ(evals, 2);
  EXPECT_LT(root, 2.0);  // the first point (0.5 exactly, g = 0) became the right end
}

}  // namespace
}  // namespace kanesim::sim
