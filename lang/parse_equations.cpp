// Equations: `a = b`, connect(), for- and if-equations (the grammar rule is above the
// function). The Parser class is in lang/parser_internal.h.
#include <utility>

#include "lang/parser_internal.h"

namespace kanesim::lang::parsing {

// equation := ( simple_expression '=' expression | connect_clause | for_equation
//             | if_equation ) comment
// connect_clause := connect '(' component_reference ',' component_reference ')'
// for_equation := for IDENT in expression loop { equation ';' } end for
// if_equation := if expression then { equation ';' } { elseif expression then ... }
//                [ else { equation ';' } ] end if
bool Parser::EquationItem(std::vector<Equation>& out) {
  DepthGuard guard(this);
  if (!guard.ok) return SkipRest(), false;
  Equation eq;
  Span b = Peek().span;
  if (At(Tok::KwConnect)) {
    Advance();
    eq.kind = EqKind::Connect;
    if (!At(Tok::LParen)) {
      ErrorExpected("'('", "after 'connect'");
      return false;
    }
    const Token& open = Advance();
    eq.lhs = ComponentRef();
    if (!Expect(Tok::Comma, "between the two connectors")) return false;
    eq.rhs = ComponentRef();
    ExpectClose(Tok::RParen, open);
  } else if (At(Tok::KwFor)) {
    Advance();
    eq.kind = EqKind::For;
    if (!At(Tok::Ident)) {
      ErrorExpected("a loop variable", "after 'for'");
      return false;
    }
    eq.iter = Advance().text;
    if (!Expect(Tok::KwIn, "after the loop variable")) return false;
    eq.range = Expression();
    if (!Expect(Tok::KwLoop, "after the range")) return false;
    while (!At(Tok::KwEnd) && !At(Tok::Eof) && !diags_.Full()) {
      size_t before = pos_;
      if (!EquationItem(eq.body)) Recover();
      if (pos_ == before) Advance();
    }
    Expect(Tok::KwEnd, "to close 'for'");
    Expect(Tok::KwFor, "after 'end'");
  } else if (At(Tok::KwIf)) {
    Advance();
    eq.kind = EqKind::If;
    eq.conditions.push_back(Expression());
    if (!Expect(Tok::KwThen, "after the condition")) return false;
    eq.branches.emplace_back();
    while (!At(Tok::Eof) && !diags_.Full()) {
      if (At(Tok::KwElseif)) {
        Advance();
        eq.conditions.push_back(Expression());
        if (!Expect(Tok::KwThen, "after the condition")) return false;
        eq.branches.emplace_back();
        continue;
      }
      if (At(Tok::KwElse)) {
        Advance();
        eq.branches.emplace_back();
        continue;
      }
      if (At(Tok::KwEnd)) break;
      size_t before = pos_;
      if (!EquationItem(eq.branches.back())) Recover();
      if (pos_ == before) Advance();
    }
    Expect(Tok::KwEnd, "to close 'if'");
    Expect(Tok::KwIf, "after 'end'");
  } else {
    eq.kind = EqKind::Equality;
    eq.lhs = SimpleExpression();
    if (!At(Tok::Assign)) {
      if (At(Tok::ColonAssign)) {
        diags_.Error(DiagCode::ExpectedToken, Peek().span, "':=' is an assignment; equations use '='").hint =
            "write 'a = b'";
        Advance();
      } else {
        ErrorExpected("'='", "in the equation");
        return false;
      }
    } else {
      Advance();
    }
    eq.rhs = Expression();
  }
  StringComment();
  AnnotationOpt();
  eq.span = SpanFrom(b);
  out.push_back(std::move(eq));
  return Expect(Tok::Semicolon, "after equation");
}

}  // namespace kanesim::lang::parsing
