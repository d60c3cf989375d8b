// The unit check (lang/elab_units.h): each rule with a model that passes and one that fails
// with its exact diagnostic; the false alarms other tools raise (angles against numbers,
// N.m against J) pass; --set values with a unit are converted; every example is unit-clean
// and every example with one unit changed is caught. If one of these fails, a unit mistake
// runs silently, or a correct model is refused.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "lang/diagnostics.h"
#include "lang/elaborate.h"
#include "lang/units.h"
#include "stdlib/stdlib.h"

namespace kanesim::lang {
namespace {

namespace fs = std::filesystem;

struct Checked {
  std::string errors;  // every error rendered; "" when the model is clean
  flat::Mechanism mech;
};

Checked Check(const std::string& text, std::vector<ParamOverride> sets = {}, const std::string& name = "m.mech") {
  Program program;
  Diagnostics diags(&program.sources);
  Checked c;
  if (LoadProgramFromText(name, text, stdlib::Files(), &program, diags)) {
    ElaborateOptions o;
    o.overrides = std::move(sets);
    Elaborate(program, o, &c.mech, diags);
  }
  for (const auto& d : diags.All())
    if (d.severity == Severity::Error) c.errors += diags.Render(d);
  return c;
}

// A pendulum whose declarations and equations are the test's: `decls` go before the
// components, `eqs` after the connections.
std::string Pendulum(const std::string& decls, const std::string& rod = "Rod rod(L = 1);", const std::string& eqs = "") {
  return "model M\n" + decls + "\n  World world;\n  Revolute j;\n  " + rod +
         "\nequation\n  connect(world.frame_b, j.frame_a);\n  connect(j.frame_b, rod.frame_a);\n" + eqs + "\nend M;\n";
}

// The first line of the first error: "m.mech:L:C: error[E237]: message".
std::string FirstLine(const std::string& errors) { return errors.substr(0, errors.find('\n')); }

TEST(UnitParser, ReadsModelicaUnitStrings) {
  Unit u;
  std::string error;
  ASSERT_TRUE(ParseUnit("N.m/rad", &u, &error)) << error;
  EXPECT_EQ(u.ToString(), "m2.kg/(s2.rad)");
  ASSERT_TRUE(ParseUnit("kN/mm", &u, &error));
  EXPECT_DOUBLE_EQ(u.scale, 1e6);
  ASSERT_TRUE(ParseUnit("deg", &u, &error));
  EXPECT_DOUBLE_EQ(u.scale, std::numbers::pi / 180);
  Unit one;
  ASSERT_TRUE(ParseUnit("1", &one, &error));
  Unit rad;
  ASSERT_TRUE(ParseUnit("rad", &rad, &error));
  EXPECT_TRUE(rad.Agrees(one));   // rad = 1 for the check
  EXPECT_FALSE(u.Agrees(rad));    // deg is pi/180 rad
  EXPECT_EQ(rad.ToString(), "rad");  // but kept for display
  EXPECT_FALSE(ParseUnit("N..m", &u, &error));
  EXPECT_EQ(error, "expected a unit symbol at character 3");
}

TEST(UnitCheck, TheStandardLibraryAndEveryExampleAreUnitClean) {
  int n = 0;
  for (const auto& e : fs::directory_iterator(fs::path(KANESIM_SOURCE_DIR) / "examples")) {
    if (e.path().extension() != ".mech") continue;
    std::ifstream in(e.path());
    std::stringstream ss;
    ss << in.rdbuf();
    EXPECT_EQ(Check(ss.str(), {}, e.path().string()).errors, "") << e.path();
    ++n;
  }
  EXPECT_GE(n, 11);
  for (const char* model : {"Rod rod(L = 1);", "Box rod(lx = 1);", "Cylinder rod(length = 1);",
                                   "Sphere rod(radius = 0.1);"})
    EXPECT_EQ(Check(Pendulum("", model)).errors, "") << model;
}


// Every model of the standard library, each instantiated on its own beside a World (the
// examples leave some out): its declarations, modifiers and equations raise no unit error.
// Elaboration must succeed, else the check's messages would not be reported at all.
TEST(UnitCheck, EveryStandardLibraryModelIsUnitClean) {
  const std::string mesh = (fs::path(KANESIM_SOURCE_DIR) / "examples" / "meshes" / "rod.stl").string();
  int n = 0;
  for (const auto& [path, text] : stdlib::Files()) {
    std::istringstream lines(text);
    for (std::string line; std::getline(lines, line);) {
      if (line.rfind("model ", 0) != 0) continue;  // "partial model" and connectors are not instances
      const std::string name = line.substr(6, line.find_first_of(" \"", 6) - 6);
      const std::string mods = name == "MeshBody" || name == "BodyShape" ? "(file = \"" + mesh + "\")" : "";
      std::string model = name == "World" ? "model M\n  World world;\nend M;\n"
                                          : "model M\n  World world;\n  " + name + " x" + mods + ";\nend M;\n";
      if (name == "JointCoupling")  // it must join two joints' drives (E212)
        model = "model M\n  World world;\n  Revolute a;\n  Revolute b;\n  JointCoupling x(ratio = 2);\nequation\n"
                "  connect(a.drive, x.flange_a);\n  connect(b.drive, x.flange_b);\nend M;\n";
      EXPECT_EQ(Check(model).errors, "") << path << ": " << name;
      ++n;
    }
  }
  EXPECT_GE(n, 28);
}

// One rule: a model that passes, and one that fails with this first line.
struct Rule {
  const char* name;
  std::string pass, fail, message;
};

class UnitRule : public ::testing::TestWithParam<Rule> {};

TEST_P(UnitRule, PassesTheRightModelAndReportsTheWrongOne) {
  const Rule& r = GetParam();
  EXPECT_EQ(Check(r.pass).errors, "") << r.name;
  const std::string errors = Check(r.fail).errors;
  EXPECT_EQ(FirstLine(errors), r.message) << errors;
}

const std::string kSine = "  parameter Real w(unit = \"rad/s\") = 1;\n  parameter Real T(unit = \"N.m\") = 1;";
const std::string kTorques = "  parameter Real T(unit = \"N.m\") = 1;\n  parameter Real F(unit = \"N\") = 1;\n";

INSTANTIATE_TEST_SUITE_P(
    Rules, UnitRule,
    ::testing::Values(
        // A modifier's value against the component's declared unit.
        Rule{"Modifier", Pendulum("  parameter Real len(unit = \"m\") = 1;", "Rod rod(L = len);"),
             Pendulum("  parameter Real len(unit = \"kg\") = 1;", "Rod rod(L = len);"),
             "m.mech:5:15: error[E237]: 'rod.L' has unit \"m\" but its value has unit \"kg\""},
        // A declaration's binding against its own unit.
        Rule{"Binding", Pendulum("  parameter Real a(unit = \"m\") = 1;\n  parameter Real b(unit = \"m\") = a + 1;"),
             Pendulum("  parameter Real a(unit = \"m\") = 1;\n  parameter Real b(unit = \"s\") = a + 1;"),
             "m.mech:3:34: error[E237]: 'b' has unit \"s\" but its value has unit \"m\""},
        // An equation's two sides; N.m and J are one unit (a false alarm elsewhere).
        Rule{"Equation", Pendulum("  parameter Real E(unit = \"J\") = 1;", "Rod rod(L = 1);", "  j.tau = E;"),
             Pendulum(kTorques, "Rod rod(L = 1);", "  j.tau = F;"),
             "m.mech:11:3: error[E237]: the two sides of the equation have different units: 'j.tau' is \"N.m\", the "
             "right side \"N\""},
        // The operands of + and -; a number added to a length is a length.
        Rule{"Sum", Pendulum("  parameter Real a(unit = \"m\") = 1;", "Rod rod(L = a + 1);"),
             Pendulum("  parameter Real a(unit = \"m\") = 1;\n  parameter Real b(unit = \"rad\") = 1;", "Rod rod(L = a - b);"),
             "m.mech:6:15: error[E237]: the operands of '-' have different units: \"m\" and \"rad\""},
        // In an equation a number times a quantity may carry any unit (0.3 N.m/rad); the sum
        // it is part of is still checked.
        Rule{"NumberInAnEquation", Pendulum(kTorques, "Rod rod(L = 1);", "  j.tau = -0.3 * j.q;"),
             Pendulum(kTorques, "Rod rod(L = 1);", "  j.tau = -0.3 * j.q + F;"),
             "m.mech:11:3: error[E237]: the two sides of the equation have different units: 'j.tau' is \"N.m\", the "
             "right side \"N\""},
        // In a binding or modifier a number beside a quantity is a plain factor (Modelica's
        // rule): twice a length is a length, twice a mass is not one.
        Rule{"NumberInABinding", Pendulum("  parameter Real len(unit = \"m\") = 1;", "Rod rod(L = 2 * len);"),
             Pendulum("  parameter Real mass(unit = \"kg\") = 1;", "Rod rod(L = 2 * mass);"),
             "m.mech:5:15: error[E237]: 'rod.L' has unit \"m\" but its value has unit \"kg\""},
        // A number over a quantity: its inverse (2 / T is a rate, not a time).
        Rule{"NumberOverAQuantity",
             Pendulum("  parameter Real T(unit = \"s\") = 1;\n  parameter Real w(unit = \"rad/s\") = 2 / T;"),
             Pendulum("  parameter Real T(unit = \"s\") = 1;\n  parameter Real w(unit = \"s\") = 2 / T;"),
             "m.mech:3:34: error[E237]: 'w' has unit \"s\" but its value has unit \"1/s\""},
        // sin takes an angle in rad or a number; w * time is one (rad/s times s).
        Rule{"Sine", Pendulum(kSine, "Rod rod(L = 1);", "  j.tau = T * sin(w * time);"),
             Pendulum(kSine, "Rod rod(L = 1);", "  j.tau = T * sin(w);"),
             "m.mech:10:19: error[E237]: 'sin' needs a dimensionless argument (an angle in rad is one), but this has unit "
             "\"rad/s\""},
        // sin of time alone (a test signal reading time as a number) is still a number: a
        // length times it is a length, a mass times it is not.
        Rule{"SineOfTime", Pendulum("  parameter Real len(unit = \"m\") = 1;\n  output Real y(unit = \"m\") = len * sin(time);"),
             Pendulum("  parameter Real mass(unit = \"kg\") = 1;\n  output Real y(unit = \"m\") = mass * sin(time);"),
             "m.mech:3:31: error[E237]: 'y' has unit \"m\" but its value has unit \"kg\""},
        // An angle and a number agree (rad = 1, a false alarm elsewhere); an angle in deg is
        // not an angle in rad.
        Rule{"Angles", Pendulum("  parameter Real a(unit = \"1\") = 0.3;", "Revolute k(q(start = a));\n  Rod rod(L = 1);"),
             Pendulum("  parameter Real a(unit = \"deg\") = 30;", "Revolute k(q(start = a));\n  Rod rod(L = 1);"),
             "m.mech:5:24: error[E237]: the start value of 'k.q' has unit \"deg\", not \"rad\""},
        // An angle's rate (a joint's u, its q's derivative: rad/s) is a frequency (1/s), a
        // false alarm elsewhere for der(phi); the angle itself is not one.
        Rule{"AngleRate", Pendulum("  output Real rate(unit = \"1/s\") = j.u;"),
             Pendulum("  output Real rate(unit = \"1/s\") = j.q;"),
             "m.mech:2:36: error[E237]: 'rate' has unit \"1/s\" but its value has unit \"rad\""},
        // sqrt halves exponents.
        Rule{"Sqrt", Pendulum("  parameter Real area(unit = \"m2\") = 1;", "Rod rod(L = sqrt(area));"),
             Pendulum("  parameter Real area(unit = \"m3\") = 1;", "Rod rod(L = sqrt(area));"),
             "m.mech:5:15: error[E237]: 'rod.L' has unit \"m\" but its value has unit \"m1.5\""},
        // A frame's motion: r in m, v in m/s.
        Rule{"FrameMotion", Pendulum("  output Real h(unit = \"m\") = rod.frame_b.r[2];"),
             Pendulum("  output Real h(unit = \"m\") = rod.frame_b.v[2];"),
             "m.mech:2:31: error[E237]: 'h' has unit \"m\" but its value has unit \"m/s\""},
        // A comparison's two sides.
        Rule{"Comparison",
             Pendulum("  parameter Real a(unit = \"m\") = 1;", "Rod rod(L = if a > 0.5 then a else 1);"),
             Pendulum("  parameter Real a(unit = \"m\") = 1;\n  parameter Real t(unit = \"s\") = 1;",
                      "Rod rod(L = if a > t then a else 1);"),
             "m.mech:6:18: error[E237]: the compared values have different units: \"m\" and \"s\""},
        // Same dimension, another scale: a stiffness in N/mm is not one in N/m.
        Rule{"Scale",
             "model M\n  parameter Real k(unit = \"N/m\") = 50;\n  World world;\n  Prismatic p;\n  Body b(m = 1);\n"
             "  Spring s(c = k);\nequation\n  connect(world.frame_b, p.frame_a);\n  connect(p.frame_b, b.frame_a);\n"
             "  connect(world.frame_b, s.frame_a);\n  connect(p.frame_b, s.frame_b);\nend M;\n",
             "model M\n  parameter Real k(unit = \"N/mm\") = 50;\n  World world;\n  Prismatic p;\n  Body b(m = 1);\n"
             "  Spring s(c = k);\nequation\n  connect(world.frame_b, p.frame_a);\n  connect(p.frame_b, b.frame_a);\n"
             "  connect(world.frame_b, s.frame_a);\n  connect(p.frame_b, s.frame_b);\nend M;\n",
             "m.mech:6:16: error[E237]: 's.c' has unit \"N/m\" but its value has unit \"N/mm\""},
        // A spring on a joint's flanges is in the joint's units: N.m/rad on a revolute.
        Rule{"FlangeSpring",
             Pendulum("  parameter Real k(unit = \"N.m/rad\") = 1;", "Rod rod(L = 1);\n  TorsionSpring s(c = k);",
                      "  connect(s.flange_a, j.support);\n  connect(s.flange_b, j.drive);"),
             Pendulum("  parameter Real k(unit = \"N/m\") = 1;", "Rod rod(L = 1);\n  TorsionSpring s(c = k);",
                      "  connect(s.flange_a, j.support);\n  connect(s.flange_b, j.drive);"),
             "m.mech:6:23: error[E237]: 's.c' has unit \"N.m/rad\" but its value has unit \"N/m\""},
        // A free joint's start speeds: three in m/s, then three in rad/s.
        Rule{"JointCoordinates",
             Pendulum("  parameter Real v(unit = \"m/s\") = 1;",
                      "Rod rod(L = 1);\n  FreeMotion f(u(start = {v, 0, 0, 0, 0, 0}));"),
             Pendulum("  parameter Real v(unit = \"m/s\") = 1;",
                      "Rod rod(L = 1);\n  FreeMotion f(u(start = {0, 0, 0, v, 0, 0}));"),
             "m.mech:6:36: error[E237]: the start value of 'f.u[4]' has unit \"m/s\", not \"rad/s\""},
        // A variable without a unit takes one from its first use; a second, different use is
        // reported, not guessed.
        Rule{"Inference",
             Pendulum("  parameter Real a(unit = \"m\") = 1;\n  parameter Real k = 0.5;", "Rod rod(L = a + k);",
                      "  j.tau = 0 * k;"),
             Pendulum("  parameter Real a(unit = \"m\") = 1;\n  parameter Real b(unit = \"rad\") = 1;\n"
                      "  parameter Real k = 0.5;\n  Revolute i(q(start = b + k));",
                      "Rod rod(L = a + k);"),
             "m.mech:8:15: error[E238]: 'k' has no unit and is used here as \"m\", but earlier as \"rad\""},
        // The use may be inside a sum or a branch given a unit as a whole: `L2 = 1 + k` bound
        // to a length makes k a length, so k as an angle afterwards is a conflict.
        Rule{"InferenceThroughASum",
             Pendulum("  parameter Real k = 0.5;\n  parameter Real L2(unit = \"m\") = 1 + k;\n"
                      "  parameter Real L3(unit = \"m\") = if L2 > 1 then -k else k + 2;"),
             Pendulum("  parameter Real b(unit = \"rad\") = 1;\n  parameter Real k = 0.5;\n"
                      "  parameter Real L2(unit = \"m\") = 1 + k;\n  Revolute i(q(start = b + k));"),
             "m.mech:5:24: error[E238]: 'k' has no unit and is used here as \"rad\", but earlier as \"m\""}),
    [](const ::testing::TestParamInfo<Rule>& i) { return std::string(i.param.name); });

TEST(UnitCheck, AMismatchNamesBothDeclarations) {
  const std::string errors =
      Check(Pendulum("  parameter Real len(unit = \"kg\") = 1;", "Rod rod(L = len);")).errors;
  EXPECT_NE(errors.find("note: 'rod.L' is declared with unit \"m\" here"), std::string::npos) << errors;
  EXPECT_NE(errors.find("m.mech:2:18: note: 'len' has unit \"kg\""), std::string::npos) << errors;
}

TEST(UnitCheck, AnOutputTakesTheUnitOfItsExpression) {
  Checked c = Check(Pendulum("  output Real h = rod.frame_b.r[2];\n  output Real speed = j.u;"));
  ASSERT_EQ(c.errors, "");
  ASSERT_EQ(c.mech.outputs.size(), 2u);
  EXPECT_EQ(c.mech.outputs[0].unit, "m");
  EXPECT_EQ(c.mech.outputs[1].unit, "rad/s");
}

double ParamValue(const flat::Mechanism& m, const std::string& name) {
  if (const int i = m.FindParam(name); i >= 0) return m.params[static_cast<size_t>(i)].value;
  ADD_FAILURE() << "no parameter " << name;
  return 0;
}

TEST(UnitCheck, SetValuesWithAUnitAreConverted) {
  const std::string model = Pendulum("  parameter Real k(unit = \"N/m\") = 50;", "Rod rod(L = 1);");
  Checked c = Check(model, {{"k", "5[N/mm]"}});
  ASSERT_EQ(c.errors, "");
  EXPECT_DOUBLE_EQ(ParamValue(c.mech, "k"), 5000);
  c = Check(model, {{"rod.L", "250[mm]"}});
  ASSERT_EQ(c.errors, "");
  EXPECT_DOUBLE_EQ(ParamValue(c.mech, "rod.L"), 0.25);
  c = Check(model, {{"k", "5[kg]"}});
  EXPECT_EQ(FirstLine(c.errors),
            "<--set k unit>:1:1: error[E237]: --set k: 'k' has unit \"N/m\", which \"kg\" cannot be converted to")
      << c.errors;
}

// Elements 2..n of an array are copies of element 1 and the check reads a binding once for
// all of them (lang/elab_units.cpp, BoundOnce): each element's mistake must still be reported,
// with notes naming that element's declarations, and a unit that differs between elements
// (a spring's stiffness takes the unit of the joint it acts on) must be read in each.
TEST(UnitCheck, EachArrayElementIsCheckedWithItsOwnNames) {
  const std::string cells =
      "model P\n  parameter Real a(unit = \"m\") = 1;\n  parameter Real b(unit = \"s\") = a;\nend P;\n"
      "model M\n  P p[3];\n  World world;\nend M;\n";
  const std::string errors = Check(cells).errors;
  for (const char* k : {"1", "2", "3"}) {
    const std::string e = std::string("p[") + k + "]";
    EXPECT_NE(errors.find("m.mech:3:34: error[E237]: '" + e + ".b' has unit \"s\" but its value has unit \"m\""),
              std::string::npos) << errors;
    EXPECT_NE(errors.find("m.mech:2:18: note: '" + e + ".a' has unit \"m\""), std::string::npos) << errors;
    EXPECT_NE(errors.find("hint: the value must be in \"s\"; check the unit of '" + e + ".a'"), std::string::npos)
        << errors;
  }
  const std::string springs =
      "model Cell\n  TorsionSpring s(c = 10);\n  parameter Real check(unit = \"N.m/rad\") = s.c;\nend Cell;\n"
      "model M\n  World world;\n  Revolute r1(axis = {0, 0, 1});\n  Revolute r2(axis = {0, 1, 0});\n"
      "  Prismatic p(axis = {1, 0, 0});\n  Body b1(m = 1, I = identity(3));\n  Body b2(m = 1, I = identity(3));\n"
      "  Body b3(m = 1, I = identity(3));\n  Cell cells[3];\nequation\n  connect(world.frame_b, r1.frame_a);\n"
      "  connect(r1.frame_b, b1.frame_a);\n  connect(b1.frame_a, r2.frame_a);\n  connect(r2.frame_b, b2.frame_a);\n"
      "  connect(b2.frame_a, p.frame_a);\n  connect(p.frame_b, b3.frame_a);\n"
      "  connect(cells[1].s.flange_b, r1.drive);\n  connect(cells[2].s.flange_b, r2.drive);\n"
      "  connect(cells[3].s.flange_b, p.drive);\nend M;\n";
  const std::string spring_errors = Check(springs).errors;
  EXPECT_EQ(FirstLine(spring_errors),
            "m.mech:3:44: error[E237]: 'cells[3].check' has unit \"N.m/rad\" but its value has unit \"N/m\"")
      << spring_errors;
  EXPECT_EQ(spring_errors.find("cells[1]"), std::string::npos) << spring_errors;
  EXPECT_EQ(spring_errors.find("cells[2]"), std::string::npos) << spring_errors;
}

// A binding written in a class is read once for all its instances whose variables take
// their units from the class's text (lang/elab_units.cpp, BoundOnce): an instance given
// another unit from outside, by a short class definition, or on an array of no unit, is
// read again, and a mismatch there names its own declarations.
TEST(UnitCheck, AnInstanceGivenAnotherUnitFromOutsideIsCheckedOnItsOwn) {
  const std::string errors =
      Check("model P\n  parameter Real a(unit = \"m\") = 1;\n  parameter Real b(unit = \"m\") = 2 * a;\n"
            "  parameter Real[2] v = {1, 2};\n  parameter Real[2] w(each unit = \"m\") = v;\nend P;\n"
            "model P2 = P(a(unit = \"kg\"));\n"
            "model M\n  P p1;\n  P p2;\n  P p3(a(unit = \"s\"));\n  P p4;\n  P p5(v(each unit = \"N\"));\n  P2 q;\n"
            "  World world;\nend M;\n")
          .errors;
  std::string firsts;
  for (size_t at = errors.find("m.mech:"); at != std::string::npos; at = errors.find("\nm.mech:", at + 1)) {
    const size_t b = errors[at] == '\n' ? at + 1 : at;
    const std::string line = errors.substr(b, errors.find('\n', b) - b);
    if (line.find(": error[") != std::string::npos) firsts += line + "\n";
  }
  EXPECT_EQ(firsts,
            "m.mech:3:34: error[E237]: 'p3.b' has unit \"m\" but its value has unit \"s\"\n"
            "m.mech:5:42: error[E237]: 'p5.w' has unit \"m\" but its value has unit \"N\"\n"
            "m.mech:3:34: error[E237]: 'q.b' has unit \"m\" but its value has unit \"kg\"\n")
      << errors;
  EXPECT_NE(errors.find("note: 'p3.a' has unit \"s\""), std::string::npos) << errors;
  EXPECT_NE(errors.find("check the unit of 'q.a'"), std::string::npos) << errors;
}

// A declaration of literals only is shared by its instances (Instantiator::DeclarationMod);
// a value given from outside over it (Node::mod_over_decl) is checked in each.
TEST(UnitCheck, AValueGivenOverASharedDeclarationIsChecked) {
  const std::string errors = Check("model P\n  parameter Real a(unit = \"m\") = 1;\nend P;\nmodel M\n"
                                   "  parameter Real b(unit = \"s\") = 2;\n  P p1(a = b);\n  P p2;\n  P p3(a = b);\n"
                                   "  World world;\nend M;\n")
                                 .errors;
  EXPECT_NE(errors.find("m.mech:6:12: error[E237]: 'p1.a' has unit \"m\" but its value has unit \"s\""),
            std::string::npos) << errors;
  EXPECT_NE(errors.find("m.mech:8:12: error[E237]: 'p3.a' has unit \"m\" but its value has unit \"s\""),
            std::string::npos) << errors;
  EXPECT_EQ(errors.find("p2.a"), std::string::npos) << errors;
}

// The check reads declared units as the emitter shows each variable and the values in
// batches (lang/elab_units.cpp, UnitChecker::Flush): the messages still come in the order
// of the declarations, a unit string's own error (E236) where it is first read.
TEST(UnitCheck, MessagesComeInTheOrderOfTheDeclarations) {
  const std::string errors =
      Check("model M\n  parameter Real a(unit = \"m\") = 1;\n  parameter Real b(unit = \"s\") = a;\n"
            "  parameter Real c(unit = \"furlong\") = 1;\n  parameter Real d(unit = \"kg\") = a + e;\n"
            "  parameter Real e(unit = \"parsec\") = 2;\n  parameter Real f(unit = \"kg\") = a;\n"
            "  World world;\nend M;\n")
          .errors;
  std::string firsts;
  for (size_t at = errors.find("m.mech:"); at != std::string::npos; at = errors.find("\nm.mech:", at + 1)) {
    const size_t b = errors[at] == '\n' ? at + 1 : at;
    const std::string line = errors.substr(b, errors.find('\n', b) - b);
    if (line.find(": error[") != std::string::npos) firsts += line.substr(0, line.find(']') + 1) + "\n";
  }
  EXPECT_EQ(firsts,
            "m.mech:3:34: error[E237]\nm.mech:4:27: error[E236]\nm.mech:6:27: error[E236]\nm.mech:5:35: error[E237]\n"
            "m.mech:7:35: error[E237]\n")
      << errors;
}

// Every example with one declared unit changed (to another dimension, or for a plain symbol
// to another scale: m -> mm) is refused with a unit error.
TEST(UnitCheck, EveryExampleWithOneUnitChangedIsCaught) {
  int mutations = 0;
  for (const auto& e : fs::directory_iterator(fs::path(KANESIM_SOURCE_DIR) / "examples")) {
    if (e.path().extension() != ".mech") continue;
    std::ifstream in(e.path());
    std::stringstream ss;
    ss << in.rdbuf();
    const std::string text = ss.str();
    const std::string key = "unit = \"";
    for (size_t at = text.find(key); at != std::string::npos; at = text.find(key, at + 1)) {
      const size_t b = at + key.size(), end = text.find('"', b);
      const std::string unit = text.substr(b, end - b);
      std::vector<std::string> changed{unit == "kg" ? "s" : "kg"};
      if (unit == "m") changed.push_back("mm");
      if (unit == "rad") changed.push_back("deg");
      if (unit == "kg") changed.push_back("g");
      for (const std::string& to : changed) {
        std::string mutated = text;
        mutated.replace(b, end - b, to);
        const std::string errors = Check(mutated, {}, e.path().string()).errors;
        const bool caught = errors.find("error[E237]") != std::string::npos || errors.find("error[E238]") != std::string::npos;
        EXPECT_TRUE(caught) << e.path().filename() << ": unit \"" << unit << "\" -> \"" << to << "\" at offset " << b
                            << " not caught";
        ++mutations;
      }
    }
  }
  EXPECT_GE(mutations, 60);
}
}  // namespace
}  // namespace kanesim::lang
