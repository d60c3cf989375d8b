// The front end's limits on hostile input (docs/language.md §10), tried over generated
// members of each class rather than one file: operator chains of every chaining operator,
// in several contexts and at sizes around kMaxExprDepth; runs of operators; deep nesting
// of every kind; expression trees of any shape and depth walked by the destructor, Clone
// and Dump. A failure means a crash (stack overflow in a recursive walk), a flood of
// diagnostics, a legitimate long expression rejected, or a too-deep one accepted.
#include <gtest/gtest.h>

#include <functional>
#include <string>

#include "lang_test_util.h"

namespace kanesim::lang {
namespace {

using testing::ParseText;

// A chaining binary operator and an operand of a type it accepts.
struct ChainOp {
  const char* op;       // as written between operands
  const char* operand;
  const char* dumped;   // as ast::DumpExpr writes it between operands
};
const ChainOp kChainOps[] = {
    {"+", "1", " + "}, {"-", "1", " - "}, {"*", "x", " * "}, {"/", "x", " / "}, {" and ", "b", " and "},
    {" or ", "b", " or "},
};

std::string Chain(const ChainOp& c, int terms) {
  std::string s = c.operand;
  s.reserve(static_cast<size_t>(terms) * (std::char_traits<char>::length(c.op) + 1));
  for (int i = 1; i < terms; ++i) (s += c.op) += c.operand;
  return s;
}

size_t Count(const std::string& s, const std::string& what) {
  size_t n = 0;
  for (size_t at = s.find(what); at != std::string::npos; at = s.find(what, at + what.size())) ++n;
  return n;
}

std::string Declaration(const std::string& expr) { return "model M\n  parameter Real x = " + expr + ";\nend M;\n"; }

const ast::Expr& Binding(const testing::Parsed& r) {
  return *r.def->classes.at(0)->elements.at(0).component->mod->value;
}

// A chain of `terms` operands is a left-deep tree of depth `terms`: accepted up to
// kMaxExprDepth (a 10 000-term sum is a legitimate expression), one P106 beyond it. The
// accepted tree prints every operator, and its clone prints the same.
TEST(LimitsOperatorChain, EveryOperatorUpToTheDepthLimitAndOneErrorBeyond) {
  for (const ChainOp& c : kChainOps) {
    for (int terms : {10000, kMaxExprDepth}) {
      auto r = ParseText(Declaration(Chain(c, terms)));
      ASSERT_FALSE(r->diags.HasErrors()) << c.op << " x" << terms << "\n" << r->diags.RenderAll().substr(0, 2000);
      const ast::Expr& e = Binding(*r);
      EXPECT_EQ(e.depth, terms) << c.op;
      const std::string dump = ast::DumpExpr(e);
      EXPECT_EQ(Count(dump, c.dumped), static_cast<size_t>(terms - 1)) << c.op;
      EXPECT_EQ(ast::DumpExpr(*ast::Clone(e)), dump) << c.op;
    }
    for (int terms : {kMaxExprDepth + 1}) {
      auto r = ParseText(Declaration(Chain(c, terms)));
      EXPECT_EQ(r->NumErrors(DiagCode::ExpressionTooDeep), 1) << c.op << " x" << terms;
      EXPECT_EQ(r->diags.NumErrors(), 1) << c.op << " x" << terms << "\n" << r->diags.RenderAll().substr(0, 2000);
    }
  }
}

// The same chain inside other constructs: a call argument, an array element, a subscript,
// brackets, an equation, a condition, a --set value. Each construct adds a level or two,
// so the sizes stay clear of the boundary on either side.
TEST(LimitsOperatorChain, InsideEveryConstruct) {
  const std::function<std::string(const std::string&)> contexts[] = {
      [](const std::string& e) { return Declaration("sin(" + e + ")"); },
      [](const std::string& e) { return Declaration("{" + e + "}"); },
      [](const std::string& e) { return Declaration("[1, " + e + "; 2, 3]"); },
      [](const std::string& e) { return Declaration("y[" + e + "]"); },
      [](const std::string& e) { return Declaration("(" + e + ") * 2"); },
      [](const std::string& e) { return Declaration("if " + e + " > 0 then 1 else 2"); },
      [](const std::string& e) { return Declaration("{i for i in 1:" + e + "}"); },
      [](const std::string& e) { return "model M\n  Real x;\nequation\n  x = " + e + ";\nend M;\n"; },
  };
  const ChainOp& plus = kChainOps[0];
  for (const auto& context : contexts) {
    const std::string accepted = context(Chain(plus, kMaxExprDepth - 10));
    auto r = ParseText(accepted);
    EXPECT_FALSE(r->diags.HasErrors()) << accepted.substr(0, 60) << "\n" << r->diags.RenderAll().substr(0, 2000);
    const std::string rejected = context(Chain(plus, kMaxExprDepth + 10));
    auto q = ParseText(rejected);
    EXPECT_EQ(q->NumErrors(DiagCode::ExpressionTooDeep), 1) << rejected.substr(0, 60);
    EXPECT_EQ(q->diags.NumErrors(), 1) << rejected.substr(0, 60) << "\n" << q->diags.RenderAll().substr(0, 2000);
  }
  // A --set value goes through ParseExpression.
  for (int terms : {kMaxExprDepth, kMaxExprDepth + 1}) {
    SourceManager sm;
    Diagnostics diags(&sm);
    int file = sm.Add("<--set x>", Chain(plus, terms));
    auto e = ParseExpression(file, sm, diags);
    ASSERT_TRUE(e);
    EXPECT_EQ(diags.NumErrors(), terms > kMaxExprDepth ? 1 : 0) << terms;
  }
}

// Mixed precedence (1 + 2*3 - 4/5 ...): the depth counts every operator on the path, and
// the parser's own stack stays flat however long the expression.
TEST(LimitsOperatorChain, MixedPrecedenceChainsOfAnyLength) {
  for (int groups : {1000, 40000, 200000}) {
    std::string e = "1";
    for (int i = 0; i < groups; ++i) e += i % 2 ? "-4/5" : "+2*3";
    auto r = ParseText(Declaration(e));
    // Depth: one level per + or - on the left spine, plus the product under the last one.
    const int depth = groups + 2;
    EXPECT_EQ(r->NumErrors(DiagCode::ExpressionTooDeep), depth > kMaxExprDepth ? 1 : 0) << groups;
    EXPECT_LE(r->diags.NumErrors(), 1) << groups;
  }
}

// Runs of operators where one operand was expected ('1 - - 2', 200 000 signs, '* * 3'):
// one P101 for the run, whatever its length and operator, and the tree stays small.
TEST(LimitsOperatorRun, OneErrorPerRunOfAnyOperatorAndLength) {
  for (const char* before : {"", "1 "}) {
    for (const char* op : {"-", "+", "*", "/", "^", "- +"}) {
      for (int n : {2, 1000, 200000}) {
        std::string run;
        for (int i = 0; i < n; ++i) (run += op) += ' ';
        const std::string text = Declaration(before + run + "2");
        auto r = ParseText(text);
        const std::string what = std::string("'") + before + op + "' x" + std::to_string(n);
        EXPECT_EQ(r->diags.NumErrors(), 1) << what << "\n" << r->diags.RenderAll().substr(0, 2000);
        EXPECT_EQ(r->NumErrors(DiagCode::ExpectedToken), 1) << what;
        ASSERT_EQ(r->def->classes.size(), 1u) << what;
        EXPECT_LE(Binding(*r).depth, 3) << what;
      }
    }
  }
}

// Nesting of every kind, far past kMaxNesting: one P104 (for modifiers one follow-up error),
// never a stack overflow or a cascade from the enclosing levels, for sizes up to what a
// 4 MiB file holds.
TEST(LimitsNesting, EveryKindAtAnyDepthIsOneP104) {
  struct Kind {
    const char* name;
    std::function<std::string(int)> text;
    int max_errors = 1;  // P104 alone: no cascade of "expected ..." from the enclosing levels
  };
  auto repeat = [](const std::string& s, int n) {
    std::string out;
    for (int i = 0; i < n; ++i) out += s;
    return out;
  };
  const Kind kinds[] = {
      {"parentheses", [&](int n) { return Declaration(repeat("(", n) + "1" + repeat(")", n)); }},
      {"braces", [&](int n) { return Declaration(repeat("{", n) + "1" + repeat("}", n)); }},
      {"matrices", [&](int n) { return Declaration(repeat("[", n) + "1" + repeat("]", n)); }},
      {"calls", [&](int n) { return Declaration(repeat("f(", n) + "1" + repeat(")", n)); }},
      {"signs and brackets", [&](int n) { return Declaration(repeat("-(", n) + "1" + repeat(")", n)); }},
      {"not", [&](int n) { return Declaration(repeat("not ", n) + "true"); }},
      {"subscripts", [&](int n) { return Declaration(repeat("a[", n) + "1" + repeat("]", n)); }},
      {"if-expressions", [&](int n) { return Declaration(repeat("if c then 1 else ", n) + "2"); }},
      {"modifiers", [&](int n) { return "model M\n  Body b" + repeat("(x", n) + repeat(")", n) + ";\nend M;\n"; }, 2},
      {"classes", [&](int n) { return repeat("package P ", n) + repeat("end P; ", n); }},
      {"for-equations", [&](int n) {
         return "model M\nequation\n" + repeat("for i in 1:2 loop ", n) + "x = 1;" + repeat(" end for;", n) + "\nend M;";
       }},
  };
  for (const Kind& k : kinds) {
    for (int n : {kMaxNesting + 1, 10000, 200000}) {
      const std::string text = k.text(n);
      auto r = ParseText(text);
      // Past 4 MiB the size limit speaks first, alone.
      const DiagCode code = text.size() > SourceManager::kMaxFileBytes ? DiagCode::FileTooLarge : DiagCode::NestingTooDeep;
      EXPECT_EQ(r->NumErrors(code), 1) << k.name << " x" << n;
      EXPECT_LE(r->diags.NumErrors(), k.max_errors) << k.name << " x" << n << "\n" << r->diags.RenderAll().substr(0, 3000);
    }
  }
}

// Trees built directly, deeper than any parse can make them, through every kind of child
// slot (args, subscripts, named arguments, matrix rows): destroyed, cloned and printed
// with explicit stacks. A recursive walk overflows the stack here.
TEST(LimitsTreeWalks, AnyDepthThroughEverySlotIsDestroyedClonedAndPrinted) {
  const int depth = 200000;
  using Grow = std::function<ast::ExprPtr(ast::ExprPtr)>;
  const std::pair<const char*, Grow> slots[] = {
      {"binary", [](ast::ExprPtr c) {
         auto e = std::make_unique<ast::Expr>();
         e->kind = ast::ExprKind::Binary;
         e->op = static_cast<int>(Tok::Plus);
         e->args.push_back(std::move(c));
         auto one = std::make_unique<ast::Expr>();
         one->number = 1;
         e->args.push_back(std::move(one));
         return e;
       }},
      {"unary", [](ast::ExprPtr c) {
         auto e = std::make_unique<ast::Expr>();
         e->kind = ast::ExprKind::Unary;
         e->op = static_cast<int>(Tok::Minus);
         e->args.push_back(std::move(c));
         return e;
       }},
      {"subscript", [](ast::ExprPtr c) {
         auto e = std::make_unique<ast::Expr>();
         e->kind = ast::ExprKind::Ref;
         e->parts.push_back({"a", {}, {}});
         e->parts.back().subscripts.push_back(std::move(c));
         return e;
       }},
      {"named argument", [](ast::ExprPtr c) {
         auto e = std::make_unique<ast::Expr>();
         e->kind = ast::ExprKind::Call;
         e->parts.push_back({"f", {}, {}});
         e->named_args.push_back({"x", std::move(c), {}});
         return e;
       }},
      {"matrix", [](ast::ExprPtr c) {
         auto e = std::make_unique<ast::Expr>();
         e->kind = ast::ExprKind::Matrix;
         e->rows.emplace_back();
         e->rows.back().push_back(std::move(c));
         return e;
       }},
  };
  for (const auto& [name, grow] : slots) {
    auto e = std::make_unique<ast::Expr>();
    for (int i = 0; i < depth; ++i) e = grow(std::move(e));
    const std::string dump = ast::DumpExpr(*e);
    EXPECT_GT(dump.size(), static_cast<size_t>(depth)) << name;
    ast::ExprPtr copy = ast::Clone(*e);
    EXPECT_EQ(ast::DumpExpr(*copy), dump) << name;
    e.reset();
    copy.reset();
  }
}

}  // namespace
}  // namespace kanesim::lang
