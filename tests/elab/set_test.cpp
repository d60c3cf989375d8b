// --set: names with 1-based indices reach the element they name, and every bad target is
// a diagnostic with a stable code pointing into "<--set>" (issue 24, "Clear messages").
#include <gtest/gtest.h>

#include "tests/elab/elab_text.h"

namespace kanesim::lang::test {
namespace {

const char* kModel = R"(model M
  parameter Integer N = 3;
  parameter Real I[2, 3] = {{1, 2, 3}, {4, 5, 6}};
  parameter Real s = 1;
  World world;
  Rod links[N];
end M;
)";

// If this fails, a --set with indices changes another element than the one named (the
// old parser read "I[2,3]" as I[2]), or a plain one does not reach its parameter.
TEST(Set, IndicesReachTheElementNamed) {
  struct Case {
    const char* name;
    const char* value;
    const char* param;
    double want;
  };
  const Case cases[] = {
      {"I[2,3]", "7", "I[2,3]", 7},          {"I[1,2]", "-1", "I[1,2]", -1},
      {"world.g[2]", "-1.6", "world.g[2]", -1.6}, {"links[2].L", "0.3", "links[2].L", 0.3},
      {"s", "2.5", "s", 2.5},
  };
  for (const auto& c : cases) {
    auto e = ElaborateText(kModel, {{c.name, c.value}});
    ASSERT_TRUE(e->ok) << c.name << "\n" << e->errors;
    EXPECT_DOUBLE_EQ(e->P(c.param), c.want) << c.name;
    // Neighbours keep their values.
    EXPECT_DOUBLE_EQ(e->P("I[1,3]"), 3) << c.name;
    EXPECT_DOUBLE_EQ(e->P("I[2,2]"), 5) << c.name;
    EXPECT_DOUBLE_EQ(e->P("links[1].L"), 1) << c.name;
  }
}

// If this fails, a bad --set target is accepted silently, crashes, or is reported with a
// misleading message: every class of mistake in the name and in the value.
TEST(Set, BadTargetsAreDiagnostics) {
  struct Case {
    const char* assignment;  // name=value
    const char* code;
    const char* text;        // in the rendered diagnostic
    bool first = true;       // the first error has `code` (else: one of the errors)
  };
  const Case cases[] = {
      {"world.g[0]=1", "E219", "<--set>:1:9: error[E219]: --set world.g[0]: index 0 is out of range 1..3"},
      {"world.g[4]=1", "E219", "index 4 is out of range 1..3 of 'world.g'"},
      {"world.g[-1]=1", "E219", "index -1 is out of range 1..3"},
      {"links[0].L=1", "E219", "index 0 is out of range 1..3 of 'links'"},
      {"links[4].L=1", "E219", "index 4 is out of range 1..3 of 'links'"},
      {"I[3,1]=1", "E219", "index 3 is out of range 1..2 of 'I'"},
      {"s[1]=2", "E210", "'s' is a scalar and takes no index"},
      {"I[1]=2", "E210", "'I' has 2 dimension(s) but 1 indices are given"},
      {"world.g[1,2]=1", "E210", "'world.g' has 1 dimension(s) but 2 indices"},
      {"world.g[1][2]=1", "E210", "expected '.' or '='"},
      {"world.g[x]=1", "E210", "expected an integer index"},
      {"world.g[1.5]=1", "E210", "expected ',' or ']'"},
      {"world.g[1=2", "E210", "expected ',' or ']'"},
      {"N.=1", "E210", "expected a name"},
      {".N=1", "E210", "expected a name"},
      {"world..g=1", "E210", "expected a name"},
      {"world.g[99999999999999999999]=1", "E210", "the index is too large"},
      {"nosuch=1", "E201", "--set nosuch: no such parameter"},
      {"world.nosuch=1", "E201", "'world' has no element 'nosuch'"},
      {"wrld.g=1", "E201", "did you mean 'world'?"},
      {"world.g.x=1", "E201", "'world.g' is a variable and has no member 'x'"},
      {"links=1", "E211", "'links' is not a parameter", false},
      {"s=abc", "E201", "unknown name 'abc'"},
      {"world.g=1", "E210", "has size [3] but its value has size scalar"},
      {"N=1.5", "E210", "'N' is Integer but its value is Real"},
      {"s=\"text\"", "E210", "'s' is Real but its value is String"},
  };
  for (const auto& c : cases) {
    std::string a = c.assignment;
    size_t eq = a.find('=');
    auto e = ElaborateText(kModel, {{a.substr(0, eq), a.substr(eq + 1)}});
    EXPECT_FALSE(e->ok) << a;
    ASSERT_FALSE(e->codes.empty()) << a;
    if (c.first) {
      EXPECT_EQ(e->codes[0], c.code) << a << "\n" << e->errors;
    }
    EXPECT_TRUE(e->HasCode(c.code)) << a << "\n" << e->errors;
    EXPECT_NE(e->errors.find(c.text), std::string::npos) << a << "\n" << e->errors;
  }
}


const char* kJoints = R"(model J
  parameter Real a = 0.25;
  World world;
  Revolute j(axis = {0, 0, 1}, q(start = 0.1), u(start = 0.2));
  Rod rod(L = 1, m = 1);
  Revolute k[2](each axis = {0, 0, 1});
  Rod r[2](each L = 1, each m = 1);
equation
  connect(world.frame_b, j.frame_a);
  connect(j.frame_b, rod.frame_a);
  connect(rod.frame_b, k[1].frame_a);
  connect(k[1].frame_b, r[1].frame_a);
  connect(r[1].frame_b, k[2].frame_a);
  connect(k[2].frame_b, r[2].frame_a);
end J;
)";

// The start expressions of every joint, as text: what Emit made of them.
std::string Starts(const Elaborated& e) {
  std::string s;
  for (const auto& j : e.mech.joints) {
    s += j.name + ":";
    for (auto x : j.q_start) s += " q=" + e.mech.exprs.ToString(x);
    for (auto x : j.u_start) s += " u=" + e.mech.exprs.ToString(x);
    s += "\n";
  }
  return s;
}

// If this fails, `--set j.q.start=...` is refused (E201 before issue 40) or gives another
// start than the same value written in the file: plain, on an array element, an expression.
TEST(Set, StartValuesActAsIfWritten) {
  struct Case {
    std::vector<ParamOverride> sets;
    std::pair<std::string, std::string> edit;  // the same start written in the file
  };
  const Case cases[] = {
      {{{"j.q.start", "0.3"}}, {"q(start = 0.1)", "q(start = 0.3)"}},
      {{{"j.u.start", "-2*a"}}, {"u(start = 0.2)", "u(start = -2*a)"}},
      {{{"k[2].q.start", "0.7"}}, {"Revolute k[2](each axis = {0, 0, 1});",
                                   "Revolute k[2](each axis = {0, 0, 1}, q(start = {0, 0.7}));"}},
  };
  for (const auto& c : cases) {
    auto got = ElaborateText(kJoints, c.sets);
    ASSERT_TRUE(got->ok) << c.sets[0].name << "\n" << got->errors;
    std::string text = kJoints;
    text.replace(text.find(c.edit.first), c.edit.first.size(), c.edit.second);
    auto want = ElaborateText(text);
    ASSERT_TRUE(want->ok) << text << "\n" << want->errors;
    EXPECT_EQ(Starts(*got), Starts(*want)) << c.sets[0].name;
    EXPECT_NE(Starts(*got), Starts(*ElaborateText(kJoints))) << c.sets[0].name;
  }
  // Not a start: other attributes, parameters, unknown members keep their diagnostics.
  const std::pair<const char*, const char*> bad[] = {
      {"j.q.fixed", "E201"}, {"j.qq.start", "E201"}, {"a.start", "E211"}, {"j.q.start.x", "E201"},
      {"j.q.start", "E201"}};
  for (const auto& [name, code] : bad) {
    auto e = ElaborateText(kJoints, {{name, std::string(name) == "j.q.start" ? "nosuch" : "1"}});
    EXPECT_FALSE(e->ok) << name;
    EXPECT_TRUE(e->HasCode(code)) << name << "\n" << e->errors;
  }
}

// Every instance of a declaration made of literals (Revolute's `mu(min = 0) = 0`, q's
// `start = 0`) reads one modifier built once (Instantiator::DeclarationMod). If this fails,
// a --set of one instance's parameter or start value reached the others through it, or
// an instance lost the declaration's value or bounds.
TEST(Set, OneInstanceOfASharedDeclarationChangesAlone) {
  const std::string model = ModelWith("  Revolute j1, j2, j3;");
  auto e = ElaborateText(model, {{"j1.mu", "0.3"}, {"j2.q.start", "0.7"}});
  ASSERT_TRUE(e->ok) << e->errors;
  EXPECT_DOUBLE_EQ(e->P("j1.mu"), 0.3);
  EXPECT_DOUBLE_EQ(e->P("j1.mu_s"), 0.3);  // bound to mu in the declaration
  EXPECT_DOUBLE_EQ(e->P("j2.mu"), 0);
  EXPECT_DOUBLE_EQ(e->P("j3.mu_s"), 0);
  EXPECT_DOUBLE_EQ(e->P("j3.friction_v"), 1e-3);
  ASSERT_EQ(e->mech.joints.size(), 3u);
  const double starts[3] = {0, 0.7, 0};
  for (size_t i = 0; i < 3; ++i) {
    const flat::ExprId q0 = e->mech.joints[i].q_start[0];
    const double got = q0 == flat::kNoExpr ? 0 : flat::EvalParamExpr(e->mech, e->values, q0);
    EXPECT_DOUBLE_EQ(got, starts[i]) << e->mech.joints[i].name;
  }
  // The declaration's bound (restitution max = 1) holds for the instance set, not for the others.
  auto bad = ElaborateText(model, {{"j3.restitution", "2"}});
  EXPECT_FALSE(bad->ok);
  EXPECT_NE(bad->errors.find("'j3.restitution' = 2.000000 is outside its range"), std::string::npos) << bad->errors;
  EXPECT_EQ(bad->errors.find("'j1.restitution'"), std::string::npos) << bad->errors;
}

// A value given from outside over a declaration of literals (Revolute's
// `friction_torque(unit = "N.m", min = 0) = 0` given `friction_torque = 0.5`, a Rod's
// `body(m = m)`) is the instance's own, read under the declaration's attributes
// (Node::mod_over_decl). If this fails, an instance read another's value, a --set of one
// instance (or one array element) reached the others, or the declaration's bound was lost.
TEST(Set, AValueGivenFromOutsideKeepsTheDeclarationsAttributes) {
  const std::string model =
      ModelWith("  Revolute j1(friction_torque = 0.5), j2(friction_torque = 0.125), j3;\n  Rod links[3](each L = 2);");
  auto e = ElaborateText(model, {{"j2.friction_torque", "0.25"}, {"links[2].m", "5"}, {"links[3].body.m", "4"}});
  ASSERT_TRUE(e->ok) << e->errors;
  EXPECT_DOUBLE_EQ(e->P("j1.friction_torque"), 0.5);
  EXPECT_DOUBLE_EQ(e->P("j1.friction_torque_s"), 0.5);  // bound to friction_torque in the declaration
  EXPECT_DOUBLE_EQ(e->P("j2.friction_torque"), 0.25);
  EXPECT_DOUBLE_EQ(e->P("j2.friction_torque_s"), 0.25);
  EXPECT_DOUBLE_EQ(e->P("j3.friction_torque"), 0);
  const double body_m[3] = {1, 5, 4};
  for (int k = 0; k < 3; ++k) {
    const std::string el = "links[" + std::to_string(k + 1) + "]";
    EXPECT_DOUBLE_EQ(e->P(el + ".body.m"), body_m[k]) << el;
    EXPECT_DOUBLE_EQ(e->P(el + ".tip.r[1]"), 2) << el;
  }
  // The declaration's bound (min = 0) holds under a value from the file and from --set,
  // for the instance given it alone.
  auto bad = ElaborateText(ModelWith("  Revolute j1(friction_torque = -1), j2(friction_torque = 1);"));
  EXPECT_FALSE(bad->ok);
  EXPECT_NE(bad->errors.find("'j1.friction_torque' = -1.000000 is outside its range [0.000000, inf]"),
            std::string::npos)
      << bad->errors;
  EXPECT_EQ(bad->errors.find("'j2.friction_torque'"), std::string::npos) << bad->errors;
  auto bad_set = ElaborateText(ModelWith("  Rod links[3];"), {{"links[3].body.m", "-2"}});
  EXPECT_FALSE(bad_set->ok);
  EXPECT_NE(bad_set->errors.find("'links[3].body.m' = -2.000000 is outside its range"), std::string::npos)
      << bad_set->errors;
  EXPECT_EQ(bad_set->errors.find("'links[2].body.m'"), std::string::npos) << bad_set->errors;
}

}  // namespace
}  // namespace kanesim::lang::test
