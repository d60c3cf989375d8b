// A parameter's min, max and unit reach its flat parameter, and a value outside [min, max]
// is E213, whether the attribute is written as a literal (read from the syntax) or as an
// expression (evaluated).
#include <gtest/gtest.h>

#include <string>

#include "tests/elab/elab_text.h"

namespace kanesim::lang::test {
namespace {

const flat::Param& ParamOf(const Elaborated& e, const std::string& name) {
  const int i = e.mech.FindParam(name);
  EXPECT_GE(i, 0) << name;
  return e.mech.params[static_cast<size_t>(i < 0 ? 0 : i)];
}

std::string Model(const std::string& x, const std::string& y) {
  return ModelWith("  parameter Real lo = 0.5;\n  parameter Real x(min = 0, max = 2, unit = \"m\") = " + x +
                   ";\n  parameter Real y(min = lo * 2, unit = \"k\" + \"g\") = " + y +
                   ";\n  parameter Real v[2](each min = -1, each unit = \"s\") = {-0.5, 1};");
}

// If this fails, a literal attribute was read wrong (or not at all) where the evaluated
// one was right, or the reverse: the range, the unit, or the range check differ.
TEST(Attributes, LiteralAndEvaluatedAlike) {
  auto ok = ElaborateText(ModelWith("  parameter Real lo = 0.5;\n"
                                    "  parameter Real x(min = 0, max = 2, unit = \"m\") = 1.5;\n"
                                    "  parameter Real y(min = lo * 2, max = 3 - 0.5, unit = \"kg\") = 1.1;\n"
                                    "  parameter Real v[2](each min = -1, each unit = \"s\") = {-0.5, 1};"));
  ASSERT_TRUE(ok->ok) << ok->errors;
  EXPECT_EQ(ParamOf(*ok, "x").unit, "m");
  EXPECT_DOUBLE_EQ(ParamOf(*ok, "x").min, 0);
  EXPECT_DOUBLE_EQ(ParamOf(*ok, "x").max, 2);
  EXPECT_EQ(ParamOf(*ok, "y").unit, "kg");
  EXPECT_DOUBLE_EQ(ParamOf(*ok, "y").min, 1);
  EXPECT_DOUBLE_EQ(ParamOf(*ok, "y").max, 2.5);
  EXPECT_EQ(ParamOf(*ok, "v[2]").unit, "s");
  EXPECT_DOUBLE_EQ(ParamOf(*ok, "v[1]").min, -1);

  auto above = ElaborateText(Model("3", "1.1"));
  EXPECT_TRUE(above->HasCode("E213")) << above->errors;
  EXPECT_NE(above->errors.find("parameter 'x' = 3.000000 is outside its range [0.000000, 2.000000]"),
            std::string::npos)
      << above->errors;
  auto below = ElaborateText(ModelWith("  parameter Real lo = 0.5;\n  parameter Real y(min = lo * 2) = 0.9;"));
  EXPECT_TRUE(below->HasCode("E213")) << below->errors;
  // A unit that is not a String is an error of its expression, not a unit.
  EXPECT_TRUE(above->HasCode("E204")) << above->errors;
}

}  // namespace
}  // namespace kanesim::lang::test
