// Arrays of components of one class (lang/elab_share.cpp): elements 2..n may be copies of
// element 1's instance tree bound to their own slice of the modifier, or instantiated each
// when they may differ. Either way an array must elaborate to the same flat mechanism as
// the same components written out one by one; that written-out form is the independent
// reference here (it never takes the array path).
#include <gtest/gtest.h>

#include <string>

#include "flat/mechanism.h"
#include "tests/elab/elab_text.h"

namespace kanesim::lang::test {
namespace {

// The flat mechanism of `text` as `kanesim check --emit flat` prints it, or the errors.
std::string Flat(const std::string& text) {
  auto e = ElaborateText(text);
  return e->ok ? flat::DumpFlat(e->mech) : "errors:\n" + e->errors;
}

// `text` with every "name_k" (k one digit) renamed "name[k]", as the array form names it.
std::string Indexed(std::string text, const std::string& name) {
  for (size_t at = text.find(name + "_"); at != std::string::npos; at = text.find(name + "_", at)) {
    const size_t digit = at + name.size() + 1;
    text.replace(at + name.size(), 2, "[" + text.substr(digit, 1) + "]");
    at = digit + 2;
  }
  return text;
}

// Three joints and three parts of class `part`, connected in a chain.
std::string Chain(const std::string& classes, const std::string& joints, const std::string& parts,
                  const std::string& part_name) {
  std::string s = classes + "model M\n  World world;\n" + joints + parts + "equation\n";
  s += "  connect(world.frame_b, j_1.frame_a);\n";
  for (int i = 1; i <= 3; ++i) {
    const std::string k = std::to_string(i);
    s += "  connect(j_" + k + ".frame_b, " + part_name + "_" + k + ".frame_a);\n";
    if (i > 1) s += "  connect(" + part_name + "_" + std::to_string(i - 1) + ".frame_b, j_" + k + ".frame_a);\n";
  }
  return s + "end M;\n";
}

// The same chain with arrays `j[3]` and `<part_name>[3]` (connections in for loops).
std::string ArrayChain(const std::string& classes, const std::string& joints, const std::string& parts,
                       const std::string& p) {
  return classes + "model M\n  World world;\n" + joints + parts +
         "equation\n  connect(world.frame_b, j[1].frame_a);\n"
         "  for i in 1:3 loop\n    connect(j[i].frame_b, " + p + "[i].frame_a);\n  end for;\n"
         "  for i in 2:3 loop\n    connect(" + p + "[i - 1].frame_b, j[i].frame_a);\n  end for;\nend M;\n";
}

const char* kJoints =
    "  Revolute j[3](axis = {{0, 0, 1}, {0, 1, 0}, {1, 0, 0}}, q(start = {0.1, 0.2, 0.3}), each u(start = 0.5));\n";
const char* kJointsWritten =
    "  Revolute j_1(axis = {0, 0, 1}, q(start = 0.1), u(start = 0.5));\n"
    "  Revolute j_2(axis = {0, 1, 0}, q(start = 0.2), u(start = 0.5));\n"
    "  Revolute j_3(axis = {1, 0, 0}, q(start = 0.3), u(start = 0.5));\n";

void ExpectSame(const std::string& array_form, const std::string& written, const std::string& part) {
  const std::string a = Flat(array_form);
  const std::string w = Indexed(Indexed(Flat(written), "j"), part);
  EXPECT_EQ(a.rfind("errors", 0), std::string::npos) << a;
  EXPECT_EQ(a, w);
}

// If this fails, an element of a shared array took element 1's value of a modifier given
// per element (axis, q's start, a part's length, a sub-component's inertia).
TEST(ArrayShare, PerElementModifiersAsWrittenOut) {
  const std::string parts =
      "  Rod links[3](L = {0.5, 0.7, 0.9}, m = {1, 2, 3}, each color = \"red\",\n"
      "               body(I = {diagonal({1, 1, 1}), diagonal({2, 2, 2}), diagonal({3, 3, 3})}));\n";
  const std::string written =
      "  Rod links_1(L = 0.5, m = 1, color = \"red\", body(I = diagonal({1, 1, 1})));\n"
      "  Rod links_2(L = 0.7, m = 2, color = \"red\", body(I = diagonal({2, 2, 2})));\n"
      "  Rod links_3(L = 0.9, m = 3, color = \"red\", body(I = diagonal({3, 3, 3})));\n";
  ExpectSame(ArrayChain("", kJoints, parts, "links"), Chain("", kJointsWritten, written, "links"), "links");
}

// If this fails, a component present in some elements only (a condition on a parameter
// given per element, and an if-equation on it) is present or absent in the wrong ones.
TEST(ArrayShare, ConditionalComponentPerElement) {
  const std::string arm =
      "model Arm\n  parameter Boolean heavy = false;\n  Frame frame_a, frame_b;\n  Rod rod(L = 0.5);\n"
      "  Body extra(m = 2) if heavy;\nequation\n  connect(frame_a, rod.frame_a);\n"
      "  connect(rod.frame_b, frame_b);\n  if heavy then\n    connect(frame_a, extra.frame_a);\n  end if;\nend Arm;\n";
  const std::string parts = "  Arm arms[3](heavy = {true, false, true});\n";
  const std::string written =
      "  Arm arms_1(heavy = true);\n  Arm arms_2(heavy = false);\n  Arm arms_3(heavy = true);\n";
  ExpectSame(ArrayChain(arm, kJoints, parts, "arms"), Chain(arm, kJointsWritten, written, "arms"), "arms");
}

// If this fails, an array inside the class took element 1's size, or nested slices of a
// modifier (an array of arrays) reached the wrong inner element.
TEST(ArrayShare, InnerArraysSizedAndSlicedPerElement) {
  const std::string multi =
      "model Multi\n  parameter Integer k = 1;\n  Frame frame_a, frame_b;\n  Body b[k](each m = 1);\n"
      "  Rod r[2](L = {0.1, 0.2});\nequation\n  for i in 1:k loop\n    connect(frame_a, b[i].frame_a);\n"
      "  end for;\n  connect(frame_a, r[1].frame_a);\n  connect(r[1].frame_b, r[2].frame_a);\n"
      "  connect(r[2].frame_b, frame_b);\nend Multi;\n";
  const std::string parts = "  Multi ms[3](k = {1, 2, 3}, r(m = {{1, 2}, {3, 4}, {5, 6}}));\n";
  const std::string written =
      "  Multi ms_1(k = 1, r(m = {1, 2}));\n  Multi ms_2(k = 2, r(m = {3, 4}));\n  Multi ms_3(k = 3, r(m = {5, 6}));\n";
  ExpectSame(ArrayChain(multi, kJoints, parts, "ms"), Chain(multi, kJointsWritten, written, "ms"), "ms");
}

// If this fails, shared elements lost their per-element identity in the equations: a
// torque given to one joint by an if-equation on the loop index, and a --set on one element.
TEST(ArrayShare, IndexDependentEquationsAndSetOnOneElement) {
  const std::string parts = "  Rod links[3](each L = 0.5);\n";
  std::string arrays = ArrayChain("", kJoints, parts, "links");
  arrays.replace(arrays.find("end M;"), 6,
                 "  for i in 1:3 loop\n    if i == 2 then\n      j[i].tau = 1;\n    else\n      j[i].tau = 0;\n"
                 "    end if;\n  end for;\nend M;");
  std::string written = Chain("", kJointsWritten,
                              "  Rod links_1(L = 0.5);\n  Rod links_2(L = 0.5);\n  Rod links_3(L = 0.5);\n", "links");
  written.replace(written.find("end M;"), 6, "  j_1.tau = 0;\n  j_2.tau = 1;\n  j_3.tau = 0;\nend M;");
  ExpectSame(arrays, written, "links");
  auto e = ElaborateText(arrays, {{"links[2].L", "0.8"}});
  ASSERT_TRUE(e->ok) << e->errors;
  EXPECT_DOUBLE_EQ(e->P("links[2].L"), 0.8);
  EXPECT_DOUBLE_EQ(e->P("links[1].L"), 0.5);
  EXPECT_DOUBLE_EQ(e->P("links[3].body.r_CM[1]"), 0.25);
  EXPECT_DOUBLE_EQ(e->P("links[2].body.r_CM[1]"), 0.4);
}

// If this fails, an element's variable read element 1's modifiers where they depend on the
// element (a start value and a length from the element's own parameter), or the
// attributes the elements share (literals: unit, start = 0) were lost in a copy.
TEST(ArrayShare, ModifiersReadingTheElementAsWrittenOut) {
  const std::string link =
      "model Link\n  parameter Real a = 1;\n  parameter Real b(unit = \"m\", min = 0) = 2 * a;\n"
      "  Frame frame_a, frame_b;\n  Revolute pin(q(start = a / 10), u(start = 0));\n  Rod rod(L = b);\n"
      "equation\n  connect(frame_a, pin.frame_a);\n  connect(pin.frame_b, rod.frame_a);\n"
      "  connect(rod.frame_b, frame_b);\nend Link;\n";
  const std::string parts = "  Link ls[3](a = {1, 2, 3});\n";
  const std::string written = "  Link ls_1(a = 1);\n  Link ls_2(a = 2);\n  Link ls_3(a = 3);\n";
  ExpectSame(ArrayChain(link, kJoints, parts, "ls"), Chain(link, kJointsWritten, written, "ls"), "ls");
  auto e = ElaborateText(ArrayChain(link, kJoints, parts, "ls"));
  ASSERT_TRUE(e->ok) << e->errors;
  EXPECT_DOUBLE_EQ(e->P("ls[3].rod.L"), 6.0);
}

// If this fails, a bound (min) that reads the element's own parameter was taken from
// element 1: only element 3's value is below its own bound.
TEST(ArrayShare, BoundReadingTheElementCheckedPerElement) {
  const std::string part =
      "model P\n  parameter Real a = 1;\n  parameter Real b(min = a) = 2.5;\n  Frame frame_a, frame_b;\n"
      "  Rod rod(L = b);\nequation\n  connect(frame_a, rod.frame_a);\n  connect(rod.frame_b, frame_b);\nend P;\n";
  auto e = ElaborateText(ArrayChain(part, kJoints, "  P ps[3](a = {1, 2, 3});\n", "ps"));
  EXPECT_FALSE(e->ok);
  EXPECT_NE(e->errors.find("'ps[3].b' = 2.5"), std::string::npos) << e->errors;
  EXPECT_EQ(e->errors.find("'ps[2].b'"), std::string::npos) << e->errors;
  EXPECT_EQ(e->errors.find("'ps[1].b'"), std::string::npos) << e->errors;
}

// If this fails, leaving the elaboration's instance tree to the process's exit (what
// `kanesim check` and `run` ask for, ElaborateOptions::leave_to_exit) changed the flat
// mechanism: the same model elaborated both ways, arrays shared and not, must print alike.
TEST(LeaveToExit, SameMechanismAsFreeingTheTree) {
  const std::string parts =
      "  Rod links[3](L = {0.5, 0.7, 0.9}, m = {1, 2, 3}, each color = \"red\",\n"
      "               body(I = {diagonal({1, 1, 1}), diagonal({2, 2, 2}), diagonal({3, 3, 3})}));\n";
  const std::string text = ArrayChain("", kJoints, parts, "links");
  std::string flat[2];
  for (int keep = 0; keep < 2; ++keep) {
    Program program;
    flat::Mechanism mech;
    Diagnostics diags(&program.sources);
    ElaborateOptions options;
    options.leave_to_exit = keep == 1;
    ASSERT_TRUE(LoadProgramFromText("test.mech", text, stdlib::Files(), &program, diags));
    ASSERT_TRUE(Elaborate(program, options, &mech, diags)) << diags.RenderAll();
    flat[keep] = flat::DumpFlat(mech);
  }
  EXPECT_EQ(flat[0], flat[1]);
  EXPECT_NE(flat[0].find("links[3].L"), std::string::npos) << flat[0];
}

// If this fails, a wrong attribute of a declaration shared by every instance (checked once
// when sound, Instantiator::CheckVarAttributes) was reported in one instance only.
TEST(LeaveToExit, WrongAttributeOfASharedDeclarationInEveryInstance) {
  const std::string cls = "model P\n  parameter Real c(bogus = 1) = 2;\nend P;\n";
  auto e = ElaborateText(cls + ModelWith("  P p1;\n  P p2;\n  P p3;\n"));
  EXPECT_FALSE(e->ok);
  size_t count = 0;
  for (size_t at = e->errors.find("'bogus' is not an attribute"); at != std::string::npos;
       at = e->errors.find("'bogus' is not an attribute", at + 1))
    ++count;
  EXPECT_EQ(count, 3u) << e->errors;
}

}  // namespace
}  // namespace kanesim::lang::test
