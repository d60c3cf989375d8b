// Equations: `a = b`, connect(), for- and if-equations (the grammar rule is above the
// function). The Parser class is in lang/parser_internal.h.
#include <utility>

#include "lang/parser_internal.h"

namespace kanesim::lang::parsing {

// equation := ( simple_expression '=' expression | connect_clause | for_equation
//             | if_equation | when_equation ) comment
bool Parser::EquationItem(std::vector<Equation>& out) {
  DepthGuard guard(this);
  if (!guard.ok) return SkipRest(), false;
  Equation eq;
  Span b = Peek().span;
  bool ok = At(Tok::KwConnect) ? ConnectClause(eq)
            : At(Tok::KwFor)   ? ForEquation(eq)
            : At(Tok::KwIf)    ? IfEquation(eq)
            : At(Tok::KwWhen)  ? WhenEquation(eq)
                               : Equality(eq);
  if (!ok) return false;
  StringComment();
  AnnotationOpt();
  eq.span = SpanFrom(b);
  out.push_back(std::move(eq));
  return Expect(Tok::Semicolon, "after equation");
}

// connect_clause := connect '(' component_reference ',' component_reference ')'
bool Parser::ConnectClause(Equation& eq) {
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
  return true;
}

// for_equation := for IDENT in expression loop { equation ';' } end for
bool Parser::ForEquation(Equation& eq) {
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
  return true;
}

// if_equation := if expression then { equation ';' } { elseif expression then ... }
//                [ else { equation ';' } ] end if
bool Parser::IfEquation(Equation& eq) {
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
  return true;
}

// when_equation := when expression then { when_statement ';' } end when
// (Modelica's elsewhen is not read: a second when clause says the same for conditions that
// do not become true at one instant.)
bool Parser::WhenEquation(Equation& eq) {
  Advance();
  eq.kind = EqKind::When;
  eq.conditions.push_back(Expression());
  if (!Expect(Tok::KwThen, "after the when condition")) return false;
  while (!At(Tok::KwEnd) && !At(Tok::Eof) && !diags_.Full()) {
    if (At(Tok::Ident) && Peek().text == "elsewhen") {
      diags_.Error(DiagCode::ExpectedToken, Peek().span, "'elsewhen' is not supported").hint =
          "write a second 'when' clause";
      while (!At(Tok::KwEnd) && !At(Tok::Eof)) Advance();  // the branch, to the clause's `end when`
      break;
    }
    size_t before = pos_;
    Equation st;
    Span b = Peek().span;
    if (!WhenStatement(st)) {
      Recover();
    } else {
      st.span = SpanFrom(b);
      eq.body.push_back(std::move(st));
      Expect(Tok::Semicolon, "after the statement");
    }
    if (pos_ == before) Advance();
  }
  Expect(Tok::KwEnd, "to close 'when'");
  Expect(Tok::KwWhen, "after 'end'");
  return true;
}

// when_statement := reinit '(' component_reference ',' expression ')'
//                 | terminate '(' string ')' | simple_expression '=' expression
// (the last is parsed so that the elaborator can say why it is refused)
bool Parser::WhenStatement(Equation& eq) {
  ExprPtr e = SimpleExpression();
  if (!e) return false;
  if (At(Tok::Assign) || At(Tok::ColonAssign)) {
    eq.kind = EqKind::Equality;
    eq.lhs = std::move(e);
    Advance();
    eq.rhs = Expression();
    return true;
  }
  eq.kind = EqKind::Call;
  eq.lhs = std::move(e);
  return true;
}

// simple_expression '=' expression (':=' is reported and read as '=')
bool Parser::Equality(Equation& eq) {
  eq.kind = EqKind::Equality;
  eq.lhs = SimpleExpression();
  if (At(Tok::ColonAssign)) {
    diags_.Error(DiagCode::ExpectedToken, Peek().span, "':=' is an assignment; equations use '='").hint =
        "write 'a = b'";
  } else if (!At(Tok::Assign)) {
    ErrorExpected("'='", "in the equation");
    return false;
  }
  Advance();
  eq.rhs = Expression();
  return true;
}

}  // namespace kanesim::lang::parsing
