// Parser, grammar rule by rule (the rules are the comments above each parse function in
// lang/parser.cpp), checked through ast::Dump / ast::DumpExpr, then error recovery. A
// failure means a valid model is rejected or misread, or a bad one is reported wrongly.
#include <gtest/gtest.h>

#include <string>

#include "lang_test_util.h"

namespace kanesim::lang {
namespace {

using testing::ParseText;

// Parses `text`, expects no diagnostics, returns the AST dump.
std::string DumpOf(const std::string& text) {
  auto r = ParseText(text);
  EXPECT_TRUE(r->diags.All().empty()) << text << "\n" << r->diags.RenderAll();
  return ast::Dump(*r->def);
}

// Parses `expr` as a parameter binding, expects no diagnostics, returns DumpExpr.
std::string ExprOf(const std::string& expr) {
  auto r = ParseText("model M\n  parameter Real x = " + expr + ";\nend M;\n");
  EXPECT_TRUE(r->diags.All().empty()) << expr << "\n" << r->diags.RenderAll();
  if (r->def->classes.size() != 1 || r->def->classes[0]->elements.empty()) return "<no class>";
  const auto& el = r->def->classes[0]->elements[0];
  if (el.kind != ast::Element::kComponent || !el.component->mod || !el.component->mod->value)
    return "<no binding>";
  return ast::DumpExpr(*el.component->mod->value);
}

const ast::ClassDef& OnlyClass(const testing::Parsed& r) {
  EXPECT_EQ(r.def->classes.size(), 1u);
  return *r.def->classes.at(0);
}

// --- stored_definition, within, import ------------------------------------------------

TEST(ParserStoredDefinition, WithinImportsAndSeveralClasses) {
  EXPECT_EQ(DumpOf("within A.B;\nimport X.Y;\nimport Z = X.W;\nimport Q.R.*;\nmodel M end M;\npackage P end P;\n"),
            "within A.B;\nimport X.Y;\nimport Z = X.W;\nimport Q.R.*;\nmodel M\nend M;\npackage P\nend P;\n");
}

TEST(ParserStoredDefinition, EmptyWithinAndEmptyFile) {
  auto r = ParseText("within;\n");
  EXPECT_TRUE(r->diags.All().empty()) << r->diags.RenderAll();
  EXPECT_TRUE(r->def->within.empty());
  EXPECT_TRUE(r->def->classes.empty());
  EXPECT_EQ(DumpOf(""), "");
  EXPECT_EQ(DumpOf("// only a comment\n"), "");
}

TEST(ParserStoredDefinition, ImportSpansCoverTheClause) {
  auto r = ParseText("import A.B.*;");
  ASSERT_EQ(r->def->imports.size(), 1u);
  const auto& imp = r->def->imports[0];
  EXPECT_TRUE(imp.wildcard);
  EXPECT_EQ(imp.name, (std::vector<std::string>{"A", "B"}));
  EXPECT_EQ(imp.span.begin, 0);
  EXPECT_EQ(imp.span.end, 12);
}

TEST(ParserStoredDefinition, MissingSemicolonAfterClassIsReported) {
  auto r = ParseText("model M end M\nmodel N end N;");
  EXPECT_EQ(r->NumErrors(DiagCode::ExpectedToken), 1) << r->diags.RenderAll();
  EXPECT_EQ(r->def->classes.size(), 2u);
}

// --- class_definition ---------------------------------------------------------------

TEST(ParserClass, KindsPartialAndStringComment) {
  EXPECT_EQ(DumpOf("partial model A \"doc \" + \"more\" end A;\nconnector C end C;\nrecord R end R;\n"
                   "block B end B;\nclass K end K;\ntype T end T;\nfunction F end F;\n"
                   "encapsulated package P end P;"),
            "partial model A \"doc more\"\nend A;\nconnector C\nend C;\nrecord R\nend R;\nblock B\nend B;\n"
            "class K\nend K;\ntype T\nend T;\nfunction F\nend F;\npackage P\nend P;\n");
}

TEST(ParserClass, ShortClassDefinition) {
  auto r = ParseText("model A = Lib.B(x = 1, y(start = 2)) \"an A\";");
  ASSERT_TRUE(r->diags.All().empty()) << r->diags.RenderAll();
  const auto& c = OnlyClass(*r);
  EXPECT_TRUE(c.is_short);
  EXPECT_EQ(c.short_base, (std::vector<std::string>{"Lib", "B"}));
  EXPECT_EQ(c.description, "an A");
  EXPECT_EQ(ast::Dump(*r->def), "model A = Lib.B(x = 1, y(start = 2));\n");
}

TEST(ParserClass, NestedClassesKnowTheirParent) {
  auto r = ParseText("package P\n  model M\n    Real x;\n  end M;\nend P;");
  ASSERT_TRUE(r->diags.All().empty()) << r->diags.RenderAll();
  const auto& p = OnlyClass(*r);
  ASSERT_EQ(p.elements.size(), 1u);
  ASSERT_EQ(p.elements[0].kind, ast::Element::kClass);
  EXPECT_EQ(p.elements[0].class_def->parent, &p);
  EXPECT_EQ(p.parent, nullptr);
  EXPECT_EQ(ast::Dump(*r->def), "package P\n  model M\n    Real x;\n  end M;\nend P;\n");
}

TEST(ParserClass, SpansOfClassAndName) {
  auto r = ParseText("model Pendulum\nend Pendulum;");
  const auto& c = OnlyClass(*r);
  EXPECT_EQ(c.name_span.begin, 6);
  EXPECT_EQ(c.name_span.end, 14);
  EXPECT_EQ(c.span.begin, 0);
  EXPECT_EQ(c.span.end, 27);  // through the end name, before ';'
}

// --- composition ----------------------------------------------------------------------

TEST(ParserComposition, PublicProtectedEquationAndAnnotation) {
  auto r = ParseText(
      "model M\n  Real a;\nprotected\n  Real b;\npublic\n  Real c;\nequation\n  a = b;\nprotected\n  Real d;\n"
      "equation\n  c = d;\n  annotation(experiment(StopTime = 10));\nend M;");
  ASSERT_TRUE(r->diags.All().empty()) << r->diags.RenderAll();
  const auto& c = OnlyClass(*r);
  ASSERT_EQ(c.elements.size(), 4u);
  EXPECT_FALSE(c.elements[0].component->is_protected);
  EXPECT_TRUE(c.elements[1].component->is_protected);
  EXPECT_FALSE(c.elements[2].component->is_protected);
  EXPECT_TRUE(c.elements[3].component->is_protected);
  EXPECT_EQ(c.equations.size(), 2u);
  ASSERT_NE(c.annotation, nullptr);
  EXPECT_EQ(ast::Dump(*r->def),
            "model M\n  Real a;\n  protected Real b;\n  Real c;\n  protected Real d;\nequation\n  a = b;\n  c = d;\n"
            "  annotation(experiment(StopTime = 10));\nend M;\n");
}

TEST(ParserComposition, InitialEquationAndAlgorithmAreE216) {
  auto r = ParseText("model M\n  Real x;\ninitial equation\n  x = 1;\nalgorithm\n  x := 2;\nend M;");
  EXPECT_EQ(r->NumErrors(DiagCode::BadEquation), 2) << r->diags.RenderAll();
}

// --- element, prefixes ---------------------------------------------------------------

TEST(ParserElement, PrefixesExtendsAndImport) {
  EXPECT_EQ(DumpOf("model M\n  import Kanesim.*;\n  import J = Kanesim.Joints;\n  extends Base(m = 2);\n"
                   "  parameter Real p = 1;\n  constant Integer n = 3;\n  output Real y;\n  input Real u;\n"
                   "  final parameter Real f = 2;\n  replaceable Body b;\n  redeclare Rod r;\n"
                   "  final replaceable parameter Real g;\n  replaceable model Inner = Body;\nend M;"),
            "model M\n  import Kanesim.*;\n  import J = Kanesim.Joints;\n  extends Base(m = 2);\n"
            "  parameter Real p = 1;\n  constant Integer n = 3;\n  output Real y;\n  input Real u;\n"
            "  final parameter Real f = 2;\n  replaceable Body b;\n  redeclare Rod r;\n"
            "  final replaceable parameter Real g;\n  model Inner = Body;\nend M;\n");
}

TEST(ParserElement, ReplaceableNestedClassKeepsItsPrefix) {
  auto r = ParseText("model M\n  replaceable model Inner = Body;\nend M;");
  ASSERT_TRUE(r->diags.All().empty()) << r->diags.RenderAll();
  const auto& el = OnlyClass(*r).elements.at(0);
  EXPECT_EQ(el.kind, ast::Element::kClass);
  EXPECT_TRUE(el.replaceable);
}

TEST(ParserElement, InnerOuterAndDiscreteAreRejected) {
  auto r = ParseText("model M\n  inner World world;\n  discrete Real d;\nend M;");
  EXPECT_EQ(r->NumErrors(DiagCode::ExpectedToken), 2) << r->diags.RenderAll();
}

// --- component_clause ----------------------------------------------------------------

TEST(ParserComponent, TypeDimensionsAreSharedByEveryComponentOfTheClause) {
  auto r = ParseText("model M\n  parameter Real[3] a, b = {1, 2, 3}, c[2];\nend M;");
  ASSERT_TRUE(r->diags.All().empty()) << r->diags.RenderAll();
  const auto& c = OnlyClass(*r);
  ASSERT_EQ(c.elements.size(), 3u);
  for (const auto& el : c.elements) {
    ASSERT_EQ(el.component->type_dims.size(), 1u) << el.component->name;
    EXPECT_EQ(ast::DumpExpr(*el.component->type_dims[0]), "3");
    EXPECT_EQ(el.component->variability, ast::Variability::Parameter);
  }
  // Each component owns its own copy (distinct nodes), so the elaborator may consume them.
  EXPECT_NE(c.elements[0].component->type_dims[0].get(), c.elements[1].component->type_dims[0].get());
  EXPECT_EQ(ast::Dump(*r->def),
            "model M\n  parameter Real[3] a;\n  parameter Real[3] b = {1, 2, 3};\n  parameter Real[3] c[2];\nend M;\n");
}

TEST(ParserComponent, ArraysOfComponentsAndMatrixTypes) {
  EXPECT_EQ(DumpOf("model M\n  Rod links[N](each L = 0.5);\n  Real[3, 3] I;\n  Real A[2, :];\nend M;"),
            "model M\n  Rod links[N](each L = 0.5);\n  Real[3, 3] I;\n  Real A[2, :];\nend M;\n");
}

TEST(ParserComponent, ConditionalComponentDescriptionAndAnnotation) {
  auto r = ParseText("model M\n  Damper d(d = 0.5) if withDamper \"optional\" annotation(x = 1);\nend M;");
  ASSERT_TRUE(r->diags.All().empty()) << r->diags.RenderAll();
  const auto& k = *OnlyClass(*r).elements.at(0).component;
  ASSERT_NE(k.condition, nullptr);
  EXPECT_EQ(ast::DumpExpr(*k.condition), "withDamper");
  EXPECT_EQ(k.description, "optional");
  EXPECT_NE(k.annotation, nullptr);
  EXPECT_EQ(ast::Dump(*r->def), "model M\n  Damper d(d = 0.5) if withDamper;\nend M;\n");
}

TEST(ParserComponent, QualifiedTypeNameAndSpans) {
  auto r = ParseText("model M\n  Kanesim.Joints.Revolute j;\nend M;");
  ASSERT_TRUE(r->diags.All().empty()) << r->diags.RenderAll();
  const auto& k = *OnlyClass(*r).elements.at(0).component;
  EXPECT_EQ(k.type_name, (std::vector<std::string>{"Kanesim", "Joints", "Revolute"}));
  EXPECT_EQ(r->sm.Locate(r->file, k.name_span.begin).col, 27);
  EXPECT_EQ(r->sm.Locate(r->file, k.type_span.begin).col, 3);
}

// --- modification / argument ---------------------------------------------------------

TEST(ParserModification, NestedModifiersAndValues) {
  EXPECT_EQ(DumpOf("model M\n  Revolute j(q(start = 0.5, fixed = true), axis = {0, 0, 1});\n"
                   "  Real x(unit = \"kg\", min = 0) = 2;\n  Body b(r_CM.start = 1);\nend M;"),
            "model M\n  Revolute j(q(start = 0.5, fixed = true), axis = {0, 0, 1});\n"
            "  Real x(unit = \"kg\", min = 0) = 2;\n  Body b(r_CM.start = 1);\nend M;\n");
}

TEST(ParserModification, EachFinalAndRedeclareArguments) {
  auto r = ParseText("model M\n  Arm a(each final m = 1, redeclare Rod link(L = 2), final n);\nend M;");
  ASSERT_TRUE(r->diags.All().empty()) << r->diags.RenderAll();
  const auto& mod = *OnlyClass(*r).elements.at(0).component->mod;
  ASSERT_EQ(mod.args.size(), 3u);
  EXPECT_TRUE(mod.args[0].each);
  EXPECT_TRUE(mod.args[0].is_final);
  EXPECT_FALSE(mod.args[0].redeclare);
  EXPECT_TRUE(mod.args[1].redeclare);
  EXPECT_EQ(mod.args[1].redeclare_type, "Rod");
  EXPECT_EQ(mod.args[1].path, (std::vector<std::string>{"link"}));
  EXPECT_TRUE(mod.args[2].is_final);
  EXPECT_EQ(mod.args[2].mod, nullptr);
  EXPECT_EQ(ast::Dump(*r->def), "model M\n  Arm a(each final m = 1, redeclare Rod link(L = 2), final n);\nend M;\n");
}

TEST(ParserModification, ArgumentSpansPointAtThePath) {
  auto r = ParseText("model M\n  Revolute j(axs = {0, 0, 1});\nend M;");
  const auto& a = OnlyClass(*r).elements.at(0).component->mod->args.at(0);
  EXPECT_EQ(r->sm.Locate(r->file, a.name_span.begin).col, 14);
  EXPECT_EQ(a.name_span.end - a.name_span.begin, 3);
}

TEST(ParserModification, EmptyClassModification) {
  EXPECT_EQ(DumpOf("model M\n  Body b();\nend M;"), "model M\n  Body b();\nend M;\n");
}

// --- equations --------------------------------------------------------------------------

TEST(ParserEquation, EqualityConnectForIf) {
  EXPECT_EQ(DumpOf("model M\nequation\n  connect(world.frame_b, j[1].frame_a);\n"
                   "  shoulder.tau = -0.5 * shoulder.u + 2 * sin(time);\n"
                   "  for i in 1:N - 1 loop\n    connect(j[i].frame_b, j[i + 1].frame_a);\n  end for;\n"
                   "  if n > 2 then\n    a = 1;\n  elseif n > 1 then\n    a = 2;\n  else\n    a = 3;\n  end if;\n"
                   "  if flag then\n    b = 1;\n  end if;\nend M;"),
            "model M\nequation\n  connect(world.frame_b, j[1].frame_a);\n"
            "  shoulder.tau = ((-(0.5 * shoulder.u)) + (2 * sin(time)));\n"
            "  for i in (1:(N - 1)) loop\n    connect(j[i].frame_b, j[(i + 1)].frame_a);\n  end for;\n"
            "  if (n > 2) then\n    a = 1;\n  elseif (n > 1) then\n    a = 2;\n  else\n    a = 3;\n  end if;\n"
            "  if flag then\n    b = 1;\n  end if;\nend M;\n");
}

TEST(ParserEquation, NestedForAndIfWithStringCommentsAndAnnotations) {
  auto r = ParseText(
      "model M\nequation\n  for i in 1:2 loop\n    for k in {1, 3} loop\n      if i == k then\n"
      "        x[i] = k \"doc\" annotation(a = 1);\n      end if;\n    end for;\n  end for;\nend M;");
  ASSERT_TRUE(r->diags.All().empty()) << r->diags.RenderAll();
  const auto& eqs = OnlyClass(*r).equations;
  ASSERT_EQ(eqs.size(), 1u);
  ASSERT_EQ(eqs[0].body.size(), 1u);
  ASSERT_EQ(eqs[0].body[0].body.size(), 1u);
  EXPECT_EQ(eqs[0].body[0].body[0].kind, ast::EqKind::If);
  EXPECT_EQ(eqs[0].body[0].body[0].branches.at(0).size(), 1u);
}

TEST(ParserEquation, AssignmentOperatorInEquationIsReportedWithHint) {
  auto r = ParseText("model M\nequation\n  x := 1;\nend M;");
  ASSERT_EQ(r->diags.All().size(), 1u) << r->diags.RenderAll();
  EXPECT_EQ(r->diags.All()[0].code, DiagCode::ExpectedToken);
  EXPECT_FALSE(r->diags.All()[0].hint.empty());
}

// --- expressions -----------------------------------------------------------------------

TEST(ParserExpression, Literals) {
  EXPECT_EQ(ExprOf("42"), "42");
  EXPECT_EQ(ExprOf("0.25"), "0.25");
  EXPECT_EQ(ExprOf("\"kg\""), "\"kg\"");
  EXPECT_EQ(ExprOf("true"), "true");
  EXPECT_EQ(ExprOf("false"), "false");
  EXPECT_EQ(ExprOf("pi"), "pi");
  EXPECT_EQ(ExprOf("time"), "time");
}

TEST(ParserExpression, ArithmeticPrecedenceAndAssociativity) {
  EXPECT_EQ(ExprOf("a + b * c"), "(a + (b * c))");
  EXPECT_EQ(ExprOf("a * b + c"), "((a * b) + c)");
  EXPECT_EQ(ExprOf("a - b - c"), "((a - b) - c)");
  EXPECT_EQ(ExprOf("a / b / c"), "((a / b) / c)");
  EXPECT_EQ(ExprOf("(a + b) * c"), "((a + b) * c)");
  EXPECT_EQ(ExprOf("a * b ^ 2"), "(a * (b ^ 2))");
  EXPECT_EQ(ExprOf("2 ^ (3 ^ 4)"), "(2 ^ (3 ^ 4))");
}

// Modelica: a leading unary minus applies to the whole first term.
TEST(ParserExpression, UnaryMinusBindsLooserThanPowerAndProduct) {
  EXPECT_EQ(ExprOf("-a^2"), "(-(a ^ 2))");
  EXPECT_EQ(ExprOf("-a*b"), "(-(a * b))");
  EXPECT_EQ(ExprOf("-a + b"), "((-a) + b)");
  EXPECT_EQ(ExprOf("+a"), "(+a)");
  EXPECT_EQ(ExprOf("a ^ -2"), "(a ^ (-2))");
  EXPECT_EQ(ExprOf("-(a + b)"), "(-(a + b))");
}

TEST(ParserExpression, LogicalAndRelational) {
  EXPECT_EQ(ExprOf("not a and b"), "((not a) and b)");
  EXPECT_EQ(ExprOf("a or b and c"), "(a or (b and c))");
  EXPECT_EQ(ExprOf("a and b or c"), "((a and b) or c)");
  EXPECT_EQ(ExprOf("not not a"), "(not (not a))");
  EXPECT_EQ(ExprOf("a + 1 < b * 2"), "((a + 1) < (b * 2))");
  EXPECT_EQ(ExprOf("a <= b"), "(a <= b)");
  EXPECT_EQ(ExprOf("a > b"), "(a > b)");
  EXPECT_EQ(ExprOf("a >= b"), "(a >= b)");
  EXPECT_EQ(ExprOf("a == b"), "(a == b)");
  EXPECT_EQ(ExprOf("a <> b"), "(a <> b)");
  EXPECT_EQ(ExprOf("not a < b"), "(not (a < b))");
  EXPECT_EQ(ExprOf("a < b and c > d"), "((a < b) and (c > d))");
}

// The precedence table's non-associative rows and its prefix operators accept exactly the
// grammar's sentences: a relation or a power does not chain, not even across a lower
// operator (a naive precedence loop would read `a and b < c < d` as ((a and (b < c)) < d)),
// and a sign begins only an arithmetic expression.
TEST(ParserExpression, OperatorTableAcceptsOnlyTheGrammar) {
  auto first_error = [](const std::string& expr) {
    auto r = ParseText("model M\n  parameter Real x = " + expr + ";\nend M;\n");
    return r->diags.All().empty() ? std::string("<none>") : r->diags.All()[0].message;
  };
  EXPECT_EQ(first_error("a < b < c"), "expected ';' after declaration, found '<'");
  EXPECT_EQ(first_error("a and b < c < d"), "expected ';' after declaration, found '<'");
  EXPECT_EQ(first_error("not a < b < c"), "expected ';' after declaration, found '<'");
  EXPECT_EQ(first_error("-a < b == c"), "expected ';' after declaration, found '=='");
  EXPECT_EQ(first_error("a ^ b ^ c"), "'^' does not chain");
  EXPECT_EQ(first_error("a + -b"), "expected an expression, found '-'");
  EXPECT_EQ(first_error("a < not b"), "expected an expression, found 'not'");
  EXPECT_EQ(ExprOf("a < -b"), "(a < (-b))");
  EXPECT_EQ(ExprOf("a and not b or c"), "((a and (not b)) or c)");
  EXPECT_EQ(ExprOf("-a * b ^ c + d < e / f and g"), "((((-(a * (b ^ c))) + d) < (e / f)) and g)");
  EXPECT_EQ(ExprOf("a - b * c - d"), "((a - (b * c)) - d)");
}

TEST(ParserExpression, IfExpressions) {
  EXPECT_EQ(ExprOf("if a then 1 else 2"), "(if a then 1 else 2)");
  EXPECT_EQ(ExprOf("if a then 1 elseif b then 2 else 3"), "(if a then 1 elseif b then 2 else 3)");
  EXPECT_EQ(ExprOf("if a > 0 then if b then 1 else 2 else 3"), "(if (a > 0) then (if b then 1 else 2) else 3)");
  EXPECT_EQ(ExprOf("1 + (if a then 1 else 2)"), "(1 + (if a then 1 else 2))");
}

TEST(ParserExpression, IfExpressionWithoutElseIsAnError) {
  auto r = ParseText("model M\n  parameter Real x = if a then 1;\nend M;");
  EXPECT_EQ(r->NumErrors(DiagCode::ExpectedToken), 1) << r->diags.RenderAll();
}

TEST(ParserExpression, Ranges) {
  EXPECT_EQ(ExprOf("1:N"), "(1:N)");
  EXPECT_EQ(ExprOf("1:2:10"), "(1:2:10)");
  EXPECT_EQ(ExprOf("1:N-1"), "(1:(N - 1))");
}

TEST(ParserExpression, ArraysMatricesAndComprehensions) {
  EXPECT_EQ(ExprOf("{1, 0, 0}"), "{1, 0, 0}");
  EXPECT_EQ(ExprOf("{}"), "{}");
  EXPECT_EQ(ExprOf("{{1, 2}, {3, 4}}"), "{{1, 2}, {3, 4}}");
  EXPECT_EQ(ExprOf("[1, 2; 3, 4]"), "[1, 2; 3, 4]");
  EXPECT_EQ(ExprOf("[1; 2; 3]"), "[1; 2; 3]");
  EXPECT_EQ(ExprOf("[1, 2]"), "[1, 2]");
  EXPECT_EQ(ExprOf("{f(i) for i in 1:N}"), "{f(i) for i in (1:N)}");
  EXPECT_EQ(ExprOf("{i ^ 2 for i in {1, 2}}"), "{(i ^ 2) for i in {1, 2}}");
}

TEST(ParserExpression, MatrixRowsAreKept) {
  auto r = ParseText("model M\n  parameter Real x = [1, 2, 3; 4, 5, 6];\nend M;");
  const auto& e = *OnlyClass(*r).elements.at(0).component->mod->value;
  ASSERT_EQ(e.kind, ast::ExprKind::Matrix);
  ASSERT_EQ(e.rows.size(), 2u);
  EXPECT_EQ(e.rows[0].size(), 3u);
  EXPECT_EQ(e.rows[1].size(), 3u);
}

TEST(ParserExpression, FunctionCalls) {
  EXPECT_EQ(ExprOf("sin(time)"), "sin(time)");
  EXPECT_EQ(ExprOf("atan2(y, x)"), "atan2(y, x)");
  EXPECT_EQ(ExprOf("identity(3)"), "identity(3)");
  EXPECT_EQ(ExprOf("f()"), "f()");
  EXPECT_EQ(ExprOf("f(1, b = 2, c = x + 1)"), "f(1, b = 2, c = (x + 1))");
  EXPECT_EQ(ExprOf("Lib.f(x)"), "Lib.f(x)");
  EXPECT_EQ(ExprOf("sum(x[i] for i in 1:3)"), "sum({x[i] for i in (1:3)})");
  EXPECT_EQ(ExprOf("cross(a.frame_b.r, {0, 0, 1})"), "cross(a.frame_b.r, {0, 0, 1})");
}

TEST(ParserExpression, ComponentReferencesAndSubscripts) {
  EXPECT_EQ(ExprOf("a.b[1].c"), "a.b[1].c");
  EXPECT_EQ(ExprOf("m[1, 2]"), "m[1, 2]");
  EXPECT_EQ(ExprOf("m[:, 1]"), "m[:, 1]");
  EXPECT_EQ(ExprOf("m[end, :]"), "m[end, :]");
  EXPECT_EQ(ExprOf("x[2:3]"), "x[(2:3)]");
  EXPECT_EQ(ExprOf("j[i + 1].q"), "j[(i + 1)].q");
}

// Modelica allows 'end' anywhere inside a subscript expression: x[end - 1], x[2:end].
TEST(ParserExpression, EndInsideSubscriptExpressions) {
  EXPECT_EQ(ExprOf("x[end - 1]"), "x[(end - 1)]");
  EXPECT_EQ(ExprOf("x[2:end]"), "x[(2:end)]");
}

// --- annotations -------------------------------------------------------------------------

TEST(ParserAnnotation, ExperimentAnnotationOnClass) {
  auto r = ParseText(
      "model M\n  annotation(experiment(StartTime = 0, StopTime = 10, Tolerance = 1e-8, Interval = 0.25));\nend M;");
  ASSERT_TRUE(r->diags.All().empty()) << r->diags.RenderAll();
  ASSERT_NE(OnlyClass(*r).annotation, nullptr);
  EXPECT_EQ(ast::Dump(*r->def),
            "model M\n  annotation(experiment(StartTime = 0, StopTime = 10, Tolerance = 1e-08, Interval = 0.25));\n"
            "end M;\n");
}

TEST(ParserAnnotation, AnnotationOnShortClassAndExtends) {
  EXPECT_EQ(DumpOf("model A = B annotation(x = 1);\nmodel C\n  extends B(m = 1) annotation(y = 2);\nend C;"),
            "model A = B;\nmodel C\n  extends B(m = 1);\nend C;\n");
}

// --- error recovery ----------------------------------------------------------------------

// Every error of a file is reported, once, at its own line (no cascades, nothing lost).
TEST(ParserRecovery, SeveralErrorsAreAllReportedOnceEach) {
  auto r = ParseText(
      "model A\n"
      "  Real x = ;\n"             // 2
      "  Real y = 1 + ;\n"         // 3
      "  Real ok = 1;\n"
      "equation\n"
      "  x = * 2;\n"               // 6
      "  connect(a.b c.d);\n"      // 7
      "end A;\n"
      "model B\n"
      "  Real 3;\n"                // 10
      "  Body b(m = );\n"          // 11
      "end B;\n");
  std::vector<int> lines;
  for (const auto& d : r->diags.All()) lines.push_back(r->Where(d).line);
  EXPECT_EQ(lines, (std::vector<int>{2, 3, 6, 7, 10, 11})) << r->diags.RenderAll();
  EXPECT_EQ(r->def->classes.size(), 2u);
}

TEST(ParserRecovery, MissingSemicolonPointsAfterThePreviousToken) {
  auto r = ParseText("model M\n  Real x = 1\n  Real y;\nend M;");
  ASSERT_GE(r->diags.All().size(), 1u);
  const auto& d = r->diags.All()[0];
  EXPECT_EQ(d.code, DiagCode::ExpectedToken);
  LineCol lc = r->Where(d);
  EXPECT_EQ(lc.line, 2);
  EXPECT_EQ(lc.col, 13);
  EXPECT_NE(d.hint.find("';'"), std::string::npos);
  EXPECT_EQ(r->diags.All().size(), 1u) << r->diags.RenderAll();
}

// An error inside shared type dimensions (Real[..] a, b) is reported once, not once per
// component of the clause.
TEST(ParserRecovery, ErrorInSharedTypeDimensionsIsReportedOnce) {
  auto r = ParseText("model M\n  Real[2 ^ 2 ^ 2] a, b;\nend M;");
  EXPECT_EQ(r->diags.All().size(), 1u) << r->diags.RenderAll();
}

TEST(ParserRecovery, P102UnclosedBracketNamesBothEnds) {
  struct Case {
    const char* line;
    const char* open;
    int open_col;
  };
  const Case cases[] = {{"  parameter Real x = (1 + 2;", "'('", 22},
                        {"  parameter Real[3] r = {1, 2, 3;", "'{'", 25},
                        {"  parameter Real x = f({1, 2);", "'{'", 24},
                        {"  Revolute j(axis = {0, 0, 1};", "'('", 13},
                        {"  parameter Real x = a[1, 2;", "'['", 23},
                        {"  parameter Real x = sin(2;", "'('", 25}};
  for (const Case& c : cases) {
    auto r = ParseText(std::string("model M\n") + c.line + "\nend M;");
    ASSERT_EQ(r->diags.All().size(), 1u) << c.line << "\n" << r->diags.RenderAll();
    const auto& d = r->diags.All()[0];
    EXPECT_EQ(d.code, DiagCode::UnclosedBracket) << c.line;
    EXPECT_EQ(r->Where(d).line, 2) << c.line;
    ASSERT_EQ(d.notes.size(), 1u) << c.line;
    LineCol open = r->sm.Locate(d.notes[0].span.file, d.notes[0].span.begin);
    EXPECT_EQ(open.line, 2) << c.line;
    EXPECT_EQ(open.col, c.open_col) << c.line;
    EXPECT_NE(d.notes[0].message.find(c.open), std::string::npos) << d.notes[0].message;
    std::string s = r->diags.Render(d);
    EXPECT_NE(s.find("opened here"), std::string::npos) << s;
  }
}

TEST(ParserRecovery, P102UnclosedAtEndOfFileIsOneError) {
  auto r = ParseText("model M\n  parameter Real x = (1 + 2");
  EXPECT_EQ(r->NumErrors(DiagCode::UnclosedBracket), 1) << r->diags.RenderAll();
  EXPECT_EQ(r->diags.All().size(), 1u) << r->diags.RenderAll();
}

TEST(ParserRecovery, P103EndNameMismatchNotesTheClassName) {
  auto r = ParseText("model Pendulum\n  Real x;\nend Pendulm;");
  ASSERT_EQ(r->diags.All().size(), 1u) << r->diags.RenderAll();
  const auto& d = r->diags.All()[0];
  EXPECT_EQ(d.code, DiagCode::EndNameMismatch);
  EXPECT_EQ(r->Where(d).line, 3);
  EXPECT_EQ(r->Where(d).col, 5);
  ASSERT_EQ(d.notes.size(), 1u);
  EXPECT_EQ(r->sm.Locate(d.notes[0].span.file, d.notes[0].span.begin).line, 1);
  EXPECT_NE(d.hint.find("end Pendulum;"), std::string::npos);
  EXPECT_EQ(r->def->classes.size(), 1u);
}

TEST(ParserRecovery, MissingEndIsReported) {
  auto r = ParseText("model M\n  Real x;\n");
  EXPECT_EQ(r->diags.All().size(), 1u) << r->diags.RenderAll();
  EXPECT_EQ(r->def->classes.size(), 1u);
}

// 10000 nested '(' hit the nesting limit cleanly: one P104, no stack overflow.
TEST(ParserRecovery, P104DeepParenthesesAreAnErrorNotACrash) {
  std::string text = "model M\n  parameter Real x = " + std::string(10000, '(') + "1" + std::string(10000, ')') +
                     ";\nend M;";
  auto r = ParseText(text);
  EXPECT_EQ(r->NumErrors(DiagCode::NestingTooDeep), 1) << r->diags.RenderAll();
  EXPECT_LE(r->diags.NumErrors(), 3) << r->diags.RenderAll();
}

TEST(ParserRecovery, P104DeepNestingOfEveryKind) {
  const int n = 5000;
  std::string classes, ends;
  for (int i = 0; i < n; ++i) {
    classes += "package P" + std::to_string(i) + " ";
    ends = "end P" + std::to_string(i) + "; " + ends;
  }
  std::string equations = "model M\nequation\n";
  for (int i = 0; i < n; ++i) equations += "if a then ";
  equations += "x = 1;";
  for (int i = 0; i < n; ++i) equations += " end if;";
  equations += "\nend M;";
  std::string mods = "model M\n  Body b";
  for (int i = 0; i < n; ++i) mods += "(x";
  mods += ";\nend M;";
  std::string chain = "model M\n  parameter Real x = ";
  for (int i = 0; i < n; ++i) chain += "not -{[a[";
  chain += "1;\nend M;";
  std::string ifs = "model M\n  parameter Real x = ";
  for (int i = 0; i < n; ++i) ifs += "if a then 1 else ";
  ifs += "1;\nend M;";
  for (const std::string& text : {classes + ends, equations, mods, chain, ifs}) {
    auto r = ParseText(text);
    EXPECT_EQ(r->NumErrors(DiagCode::NestingTooDeep), 1) << text.substr(0, 60) << "\n" << r->diags.RenderAll();
  }
}

// kMaxNesting is documented as a limit on syntactic nesting (brackets, classes, if/for):
// well under it, nested brackets must parse.
TEST(ParserRecovery, NestingWellBelowTheLimitParses) {
  const int n = kMaxNesting / 2;
  std::string e = std::string(static_cast<size_t>(n), '(') + "1" + std::string(static_cast<size_t>(n), ')');
  EXPECT_EQ(ExprOf(e), "1");
}

TEST(ParserRecovery, P105ErrorCapStopsTheParser) {
  std::string text = "model M\n";
  for (int i = 0; i < 200; ++i) text += "  Real 1;\n";
  text += "end M;\n";
  auto r = ParseText(text);
  EXPECT_EQ(r->diags.NumErrors(), Diagnostics::kMaxErrors);
  EXPECT_EQ(r->NumErrors(DiagCode::TooManyErrors), 1);
  EXPECT_EQ(r->diags.All().back().code, DiagCode::TooManyErrors);
  EXPECT_EQ(r->NumErrors(DiagCode::ExpectedToken), Diagnostics::kMaxErrors - 1);
}

TEST(ParserRecovery, ChainedPowerIsAnError) {
  auto r = ParseText("model M\n  parameter Real x = 2 ^ 3 ^ 4;\nend M;");
  ASSERT_EQ(r->diags.All().size(), 1u) << r->diags.RenderAll();
  EXPECT_FALSE(r->diags.All()[0].hint.empty());
}

// Garbage at the top level or in a class body never loops forever and always ends.
TEST(ParserRecovery, GarbageTerminates) {
  const char* inputs[] = {")))", "model", "model M", "model M (", "end end end ;;;", "model M equation end",
                          "model M Real x(((( end M;", "import", "within", "model M = ;", "{[(", "model M if"};
  for (const char* in : inputs) {
    auto r = ParseText(in);
    EXPECT_TRUE(r->diags.HasErrors()) << in;
    EXPECT_LT(r->diags.NumErrors(), 10) << in << "\n" << r->diags.RenderAll();
  }
}

}  // namespace
}  // namespace kanesim::lang
