// The elaborator's evaluation against closed forms and against an independent evaluator:
// sums of comprehensions (Faulhaber's formulas, the geometric series), nested
// comprehension sums N^2 (N+1)^2 / 4, and seeded random expression trees evaluated here
// by a recursive evaluator written for the test (small depth, so recursion is fine).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "tests/elab/elab_text.h"

namespace kanesim::lang::test {
namespace {

double Value1(const std::string& decls, const std::string& name = "x") {
  auto e = ElaborateText(ModelWith(decls));
  EXPECT_TRUE(e->ok) << e->errors.substr(0, 2000);
  return e->ok ? e->P(name) : NAN;
}

// If this fails, comprehensions, ranges or sum() produce wrong values.
TEST(ClosedForm, ComprehensionSums) {
  for (long n : {1L, 2L, 5L, 10L, 50L, 300L}) {
    const std::string N = "  parameter Integer N = " + std::to_string(n) + ";\n";
    const double t = n * (n + 1) / 2.0;
    EXPECT_DOUBLE_EQ(Value1(N + "  parameter Real x = sum({sum({i * j for j in 1:N}) for i in 1:N});"), t * t) << n;
    EXPECT_DOUBLE_EQ(Value1(N + "  parameter Real x = sum({i ^ 2 for i in 1:N});"), n * (n + 1) * (2 * n + 1) / 6.0)
        << n;
    EXPECT_DOUBLE_EQ(Value1(N + "  parameter Real x = sum(1:N);"), t) << n;
    // Geometric series with ratio 1/2: sum_{k=0}^{n} 2^-k = 2 - 2^-n (exact in binary).
    EXPECT_DOUBLE_EQ(Value1(N + "  parameter Real x = sum({0.5 ^ k for k in 0:N});"), 2 - std::pow(0.5, n)) << n;
  }
}

// A random expression over + - * / with leaves that are small integers or the parameters
// a = 3 and b = -2, written fully parenthesized or as left-deep chains; Eval computes its
// value independently.
struct RandomExpr {
  std::mt19937 rng;
  explicit RandomExpr(unsigned seed) : rng(seed) {}
  int Pick(int n) { return std::uniform_int_distribution<int>(0, n - 1)(rng); }
  // Returns the text; *value receives the value.
  std::string Make(int depth, double* value) {
    if (depth == 0 || Pick(4) == 0) {
      switch (Pick(3)) {
        case 0: *value = 3; return "a";
        case 1: *value = -2; return "b";
        default: {
          int k = 1 + Pick(9);
          *value = k;
          return std::to_string(k);
        }
      }
    }
    if (Pick(3) == 0) {  // a left-deep chain of several terms with one operator
      const char* op = "+-*"[Pick(3)] == '+' ? "+" : (Pick(2) ? "-" : "*");
      int terms = 2 + Pick(6);
      double acc = 0;
      std::string s = "(" + Make(depth - 1, &acc);
      for (int i = 1; i < terms; ++i) {
        double v = 0;
        s += std::string(" ") + op + " " + Make(depth - 1, &v);
        acc = op[0] == '+' ? acc + v : op[0] == '-' ? acc - v : acc * v;
      }
      *value = acc;
      return s + ")";
    }
    double x = 0, y = 0;
    std::string l = Make(depth - 1, &x), r = Make(depth - 1, &y);
    switch (Pick(5)) {
      case 0: *value = x + y; return "(" + l + " + " + r + ")";
      case 1: *value = x - y; return "(" + l + " - " + r + ")";
      case 2: *value = x * y; return "(" + l + " * " + r + ")";
      case 3: *value = -x; return "(-" + l + ")";
      default:
        if (y == 0) {
          *value = x;
          return l;
        }
        *value = x / y;
        return "(" + l + " / " + r + ")";
    }
  }
};

// If this fails, the explicit-stack evaluation of operators combines operands in the
// wrong order or with the wrong operator: 200 seeded random expressions, each evaluated
// as a constant and through parameters, against the test's own evaluator.
TEST(ClosedForm, RandomExpressionsMatchAnIndependentEvaluator) {
  RandomExpr gen(20240611);
  for (int k = 0; k < 200; ++k) {
    double want = 0;
    const std::string text = gen.Make(6, &want);
    if (!std::isfinite(want) || std::fabs(want) > 1e12) continue;
    const double got = Value1("  parameter Real a = 3;\n  parameter Real b = -2;\n  parameter Real x = " + text + ";");
    EXPECT_NEAR(got, want, 1e-12 * std::max(1.0, std::fabs(want))) << text;
  }
}

}  // namespace
}  // namespace kanesim::lang::test
