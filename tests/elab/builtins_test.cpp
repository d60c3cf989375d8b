// The built-in functions (lang/elab_builtins.cpp) against values computed here with
// <cmath> and by hand, and their argument-count and shape diagnostics word for word, so
// that the one table {name, arity, lowering} keeps every function and every message.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "tests/elab/elab_text.h"

namespace kanesim::lang::test {
namespace {

// The value of `x` after `declarations` (which define it).
double X(const std::string& declarations) {
  auto e = ElaborateText(ModelWith(declarations));
  EXPECT_TRUE(e->ok) << declarations << "\n" << e->errors.substr(0, 2000);
  return e->ok ? e->P("x") : std::nan("");
}

double Of(const std::string& expr) { return X("  parameter Real x = " + expr + ";"); }

// If this fails, a unary built-in lowers to the wrong operation.
TEST(Builtins, UnaryFunctionsMatchCmath) {
  const double a = 0.3;
  EXPECT_DOUBLE_EQ(Of("sin(0.3)"), std::sin(a));
  EXPECT_DOUBLE_EQ(Of("cos(0.3)"), std::cos(a));
  EXPECT_DOUBLE_EQ(Of("tan(0.3)"), std::tan(a));
  EXPECT_DOUBLE_EQ(Of("asin(0.3)"), std::asin(a));
  EXPECT_DOUBLE_EQ(Of("acos(0.3)"), std::acos(a));
  EXPECT_DOUBLE_EQ(Of("atan(0.3)"), std::atan(a));
  EXPECT_DOUBLE_EQ(Of("sinh(0.3)"), std::sinh(a));
  EXPECT_DOUBLE_EQ(Of("cosh(0.3)"), std::cosh(a));
  EXPECT_DOUBLE_EQ(Of("tanh(0.3)"), std::tanh(a));
  EXPECT_DOUBLE_EQ(Of("exp(0.3)"), std::exp(a));
  EXPECT_DOUBLE_EQ(Of("log(0.3)"), std::log(a));
  EXPECT_DOUBLE_EQ(Of("sqrt(0.3)"), std::sqrt(a));
  EXPECT_EQ(Of("abs(-3)"), 3);
  EXPECT_EQ(Of("sign(-2.5)"), -1);
  EXPECT_EQ(Of("floor(-1.5)"), -2);
  EXPECT_EQ(Of("ceil(-1.5)"), -1);
  EXPECT_EQ(Of("integer(2.7)"), 2);
  EXPECT_DOUBLE_EQ(Of("atan2(1, -2)"), std::atan2(1.0, -2.0));
}

// If this fails, min/max with two arguments and with one (over its elements) are mixed up.
TEST(Builtins, MinMaxSumTakeOneOrTwoArguments) {
  EXPECT_EQ(Of("min(3, 2)"), 2);
  EXPECT_EQ(Of("max(3, 2)"), 3);
  EXPECT_EQ(Of("min({4, 1, 3})"), 1);
  EXPECT_EQ(Of("max({4, 1, 3})"), 4);
  EXPECT_EQ(Of("sum({4, 1, 3})"), 8);
  EXPECT_EQ(Of("mod(7, 3)"), 1);
}

// If this fails, a vector or matrix built-in puts an element in the wrong place.
TEST(Builtins, VectorsAndMatricesByHand) {
  // cross({1,2,3}, {4,5,6}) = (2*6 - 3*5, 3*4 - 1*6, 1*5 - 2*4) = (-3, 6, -3)
  EXPECT_EQ(X("  parameter Real v[3] = cross({1, 2, 3}, {4, 5, 6});\n  parameter Real x = v[2];"), 6);
  EXPECT_EQ(Of("dot({1, 2, 3}, {4, 5, 6})"), 32);
  EXPECT_EQ(Of("norm({3, 4})"), 5);
  // skew(a) b = cross(a, b): row 1 of skew({1,2,3}) is (0, -3, 2).
  EXPECT_EQ(X("  parameter Real S[3, 3] = skew({1, 2, 3});\n  parameter Real x = S[1, 2];"), -3);
  EXPECT_EQ(X("  parameter Real S[3, 3] = skew({1, 2, 3});\n  parameter Real x = S[3, 1];"), -2);
  EXPECT_EQ(X("  parameter Real P[2, 3] = outerProduct({1, 2}, {3, 4, 5});\n  parameter Real x = P[2, 3];"), 10);
  EXPECT_EQ(X("  parameter Real T[3, 2] = transpose([1, 2, 3; 4, 5, 6]);\n  parameter Real x = T[1, 2];"), 4);
  EXPECT_EQ(X("  parameter Real I[3, 3] = identity(3);\n  parameter Real x = I[2, 2] + 10 * I[2, 3];"), 1);
  EXPECT_EQ(X("  parameter Real D[2, 2] = diagonal({7, 8});\n  parameter Real x = D[2, 2] + 10 * D[1, 2];"), 8);
  EXPECT_EQ(X("  parameter Real Z[2, 3] = zeros(2, 3);\n  parameter Real x = Z[2, 3];"), 0);
  EXPECT_EQ(X("  parameter Real O[2] = ones(2);\n  parameter Real x = O[2];"), 1);
  EXPECT_EQ(X("  parameter Real F[2, 2] = fill(4.5, 2, 2);\n  parameter Real x = F[2, 1];"), 4.5);
  EXPECT_EQ(Of("size(zeros(2, 3), 2)"), 3);
  EXPECT_EQ(X("  parameter Integer s[2] = size(zeros(2, 3));\n  parameter Real x = s[1];"), 2);
  EXPECT_EQ(Of("size(vector([1, 2; 3, 4]), 1)"), 4);
}

struct BadCall {
  const char* expr;
  const char* code;
  const char* text;
};

// If this fails, a built-in's diagnostic changed its code or its words.
TEST(Builtins, WrongArgumentsAreDiagnosedWordForWord) {
  const BadCall cases[] = {
      {"sin(1, 2)", "E214", "'sin' takes 1 argument(s), got 2"},
      {"atan2(1)", "E214", "'atan2' takes 2 argument(s), got 1"},
      {"min(1, 2, 3)", "E214", "'min' takes 1 argument(s), got 3"},
      {"sum(1, 2)", "E214", "'sum' takes 1 argument(s), got 2"},
      {"norm({1, 2}, {3, 4})", "E214", "'norm' takes 1 argument(s), got 2"},
      {"size({1, 2}, 1, 1)", "E214", "'size' takes 2 argument(s), got 3"},
      {"zeros()", "E214", "'zeros' needs dimensions"},
      {"fill(1)", "E214", "'fill' needs dimensions"},
      {"meshVolume(\"a.stl\")", "E214", "'meshVolume' takes 2 argument(s) (file, scale), got 1"},
      {"cat(1)", "E214", "'cat' needs a dimension and at least one array, got 1 argument(s)"},
      {"sin(x = 1)", "E214", "'sin' takes no named arguments"},
      {"sine(1)", "E214", "did you mean 'sin'?"},
      {"der(1)", "E214", "derivatives are not written by hand"},
      {"dot({1, 2}, {1, 2, 3})", "E205", "'dot' needs vectors of equal length"},
      {"cross({1, 2}, {1, 2})", "E205", "'cross' needs 3-vectors, got [2]"},
      {"sqrt(\"a\")", "E204", "'sqrt' needs numbers"},
  };
  for (const auto& c : cases) {
    auto e = ElaborateText(ModelWith(std::string("  parameter Real y = ") + c.expr + ";"));
    EXPECT_FALSE(e->ok) << c.expr;
    EXPECT_TRUE(e->HasCode(c.code)) << c.expr << "\n" << e->errors;
    EXPECT_NE(e->errors.find(c.text), std::string::npos) << c.expr << "\n" << e->errors;
  }
}

}  // namespace
}  // namespace kanesim::lang::test
