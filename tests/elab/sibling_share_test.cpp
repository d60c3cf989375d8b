// Scalar components of one class side by side (lang/elab_share.cpp): a later sibling
// whose modifier has the first's form may be a copy of the first's instance tree holding
// its own values. Either way a model must elaborate to the same flat mechanism as with
// every component instantiated (ElaborateOptions::share_siblings off), the independent
// reference here, and each component must have the values written for it.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "flat/mechanism.h"
#include "tests/elab/elab_text.h"

namespace kanesim::lang::test {
namespace {

// The flat mechanism as `kanesim check --emit flat` prints it, or the errors.
std::string Flat(const Elaborated& e) { return e.ok ? flat::DumpFlat(e.mech) : "errors:\n" + e.errors; }

// Elaborates `text` with and without sibling sharing, expects the same flat mechanism,
// and returns the shared one (for value checks).
std::unique_ptr<Elaborated> SameBothWays(const std::string& text, std::vector<ParamOverride> sets = {}) {
  auto shared = ElaborateText(text, sets, true);
  auto each = ElaborateText(text, sets, false);
  EXPECT_EQ(Flat(*shared), Flat(*each));
  return shared;
}

// A chain of three revolute joints and three rods, each modified alike (one form) with
// its own values: joints 2 and 3 and rods 2 and 3 are copies of the first ones.
const char* kChain =
    "model M\n  World world;\n"
    "  Revolute j1(axis = {0, 0, 1}, q(start = 0.1), u(start = 0.5));\n"
    "  Revolute j2(axis = {0, 1, 0}, q(start = 0.2), u(start = -0.5));\n"
    "  Revolute j3(axis = {1, 0, 0}, q(start = 0.3), u(start = 0.25));\n"
    "  Rod r1(L = 0.5, m = 1, body(I = diagonal({1, 1, 1})));\n"
    "  Rod r2(L = 0.7, m = 2, body(I = diagonal({2, 2, 2})));\n"
    "  Rod r3(L = 0.9, m = 3, body(I = diagonal({3, 3, 3})));\n"
    "equation\n"
    "  connect(world.frame_b, j1.frame_a);\n  connect(j1.frame_b, r1.frame_a);\n"
    "  connect(r1.frame_b, j2.frame_a);\n  connect(j2.frame_b, r2.frame_a);\n"
    "  connect(r2.frame_b, j3.frame_a);\n  connect(j3.frame_b, r3.frame_a);\n"
    "end M;\n";

// If this fails, a copied sibling took the first's value of a modifier written for it
// (an axis, a start value, a length, a sub-component's inertia).
TEST(SiblingShare, OwnValuesAsInstantiated) {
  auto e = SameBothWays(kChain);
  ASSERT_TRUE(e->ok) << e->errors;
  EXPECT_EQ(e->P("r2.L"), 0.7);
  EXPECT_EQ(e->P("r3.m"), 3);
  EXPECT_EQ(e->P("r3.body.m"), 3);
  EXPECT_EQ(e->P("r2.body.I[2,2]"), 2);
  EXPECT_EQ(e->P("j2.axis[2]"), 1);
  EXPECT_EQ(e->P("j3.axis[1]"), 1);
  EXPECT_EQ(e->P("j3.axis[3]"), 0);
}

// --set values, named whole or by element, are bound as the user wrote them (a set
// sibling is never a copy; an element set turns sharing off for the model).
TEST(SiblingShare, SetValuesAsInstantiated) {
  auto whole = SameBothWays(kChain, {{"r2.L", "1.5"}, {"j3.axis", "{0, 1, 0}"}});
  ASSERT_TRUE(whole->ok) << whole->errors;
  EXPECT_EQ(whole->P("r2.L"), 1.5);
  EXPECT_EQ(whole->P("r3.L"), 0.9);
  EXPECT_EQ(whole->P("j3.axis[2]"), 1);
  auto element = SameBothWays(kChain, {{"j2.axis[1]", "1"}, {"r3.body.I[1,1]", "7"}});
  ASSERT_TRUE(element->ok) << element->errors;
  EXPECT_EQ(element->P("j2.axis[1]"), 1);
  EXPECT_EQ(element->P("j3.axis[1]"), 1);
  EXPECT_EQ(element->P("r3.body.I[1,1]"), 7);
  EXPECT_EQ(element->P("r2.body.I[1,1]"), 2);
}

// Values that read names are evaluated where they were written, in the copy as in the
// first: a sibling's length from another's, a mass from the model's parameter.
TEST(SiblingShare, ValuesReadingNamesAsInstantiated) {
  const std::string text =
      "model M\n  World world;\n  parameter Real k = 3;\n"
      "  Revolute j1(axis = {0, 0, 1});\n  Revolute j2(axis = {0, 0, 1});\n"
      "  Rod r1(L = 0.5, m = k);\n  Rod r2(L = r1.L * 2, m = 2 * k);\n"
      "equation\n  connect(world.frame_b, j1.frame_a);\n  connect(j1.frame_b, r1.frame_a);\n"
      "  connect(r1.frame_b, j2.frame_a);\n  connect(j2.frame_b, r2.frame_a);\nend M;\n";
  auto e = SameBothWays(text);
  ASSERT_TRUE(e->ok) << e->errors;
  EXPECT_EQ(e->P("r2.L"), 1.0);
  EXPECT_EQ(e->P("r2.m"), 6);
  EXPECT_EQ(e->P("r1.m"), 3);
}

// A sibling whose structure depends on its own parameters (an array size read while
// instantiating the first) is instantiated, not copied: the second has three elements.
TEST(SiblingShare, StructureFromParametersInstantiatedEach) {
  const std::string text =
      "model P\n  parameter Integer n = 1;\n  parameter Real x[n] = fill(1.5, n);\nend P;\n" +
      ModelWith("  P p1(n = 2);\n  P p2(n = 3);\n");
  auto e = SameBothWays(text);
  ASSERT_TRUE(e->ok) << e->errors;
  EXPECT_EQ(e->P("p2.x[3]"), 1.5);
  EXPECT_TRUE(std::isnan(e->P("p1.x[3]")));
}

// A value given from two levels up reaches a sibling copied inside a copied component:
// a2 is a copy of a1 whose b2 is a copy of b1. Each b2 must keep the value written for it.
// (A copy that duplicated the moved value and freed the original let a later value take
// the freed address, and a2's copy then put 7 in the wrong place: b2.x of a2 was 5.)
TEST(SiblingShare, AValueThroughTwoLevelsOfCopies) {
  const std::string text =
      "model B\n  parameter Real x = 0;\n  parameter Real y = 1;\nend B;\n"
      "model A\n  parameter Real p = 1;\n  B b1(x = p, y = 3);\n  B b2(x = 2, y = 4);\nend A;\n" +
      ModelWith("  A a1(p = 10, b2(x = 5));\n  A a2(p = 20, b2(x = 7));\n  A a3(p = 30, b2(x = 9));\n");
  auto e = SameBothWays(text);
  ASSERT_TRUE(e->ok) << e->errors;
  EXPECT_EQ(e->P("a1.b2.x"), 5);
  EXPECT_EQ(e->P("a2.b2.x"), 7);
  EXPECT_EQ(e->P("a3.b2.x"), 9);
  EXPECT_EQ(e->P("a2.b1.x"), 20);
  EXPECT_EQ(e->P("a3.b1.y"), 3);
  EXPECT_EQ(e->P("a3.b2.y"), 4);
}

// Mistakes are reported as without sharing: in a copied sibling's own value (a unit
// mismatch found after instantiation), and in the first's.
TEST(SiblingShare, DiagnosticsAsInstantiated) {
  const std::string text =
      "model M\n  World world;\n  parameter Real len(unit = \"m\") = 1;\n  parameter Real t(unit = \"s\") = 1;\n"
      "  Revolute j1(axis = {0, 0, 1});\n  Revolute j2(axis = {0, 0, 1});\n"
      "  Rod r1(L = len, m = 1);\n  Rod r2(L = t, m = 2);\n"
      "equation\n  connect(world.frame_b, j1.frame_a);\n  connect(j1.frame_b, r1.frame_a);\n"
      "  connect(r1.frame_b, j2.frame_a);\n  connect(j2.frame_b, r2.frame_a);\nend M;\n";
  auto shared = ElaborateText(text, {}, true);
  auto each = ElaborateText(text, {}, false);
  EXPECT_FALSE(each->ok);
  EXPECT_EQ(shared->errors, each->errors);
  EXPECT_NE(shared->errors.find("test.mech:8:"), std::string::npos) << shared->errors;
}

}  // namespace
}  // namespace kanesim::lang::test
