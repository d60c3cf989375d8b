// Expressions: `if`, ranges, operators by one precedence table (Parser::Rule), primaries
// (each function carries its grammar rule). The Parser class is in lang/parser_internal.h.
#include <array>
#include <utility>

#include "lang/parser_internal.h"

namespace kanesim::lang::parsing {

// expression := simple_expression
//             | if expression then expression { elseif expression then expression }
//               else expression
ExprPtr Parser::Expression() {
  if (At(Tok::KwIf)) {
    DepthGuard guard(this);
    if (!guard.ok) return ErrorExpr(Peek().span);
    Span b = Advance().span;
    auto e = std::make_unique<Expr>();
    e->kind = ExprKind::If;
    e->args.push_back(Expression());
    Expect(Tok::KwThen, "in the if-expression");
    e->args.push_back(Expression());
    while (Accept(Tok::KwElseif)) {
      e->args.push_back(Expression());
      Expect(Tok::KwThen, "in the if-expression");
      e->args.push_back(Expression());
    }
    Expect(Tok::KwElse, "in the if-expression (it needs an else branch)");
    e->args.push_back(Expression());
    e->span = SpanFrom(b);
    return Finish(std::move(e), b);
  }
  return SimpleExpression();
}

// simple_expression := operators [ ':' operators [ ':' operators ] ]
ExprPtr Parser::SimpleExpression() {
  Span b = Peek().span;
  ExprPtr first = Operators(Prec::Or);
  if (!At(Tok::Colon)) return first;
  auto r = std::make_unique<Expr>();
  r->kind = ExprKind::Range;
  r->args.push_back(std::move(first));
  Advance();
  r->args.push_back(Operators(Prec::Or));
  if (Accept(Tok::Colon)) r->args.push_back(Operators(Prec::Or));
  r->span = SpanFrom(b);
  return Finish(std::move(r), b);
}

// The operator table (Modelica 3.5 §3.2), one row per token kind, as clox's rules[].
// Precedence, lowest first: or; and; not; relational (non-associative: a < b < c is not
// an expression); + - and a leading sign; * /; ^ (non-associative). A leading sign applies
// to the whole first term (-a*b = -(a*b), -a^2 = -(a^2)) and may begin only an
// arithmetic expression (a + -b is an error; a ^ -2 is accepted).
const Parser::OpRule& Parser::Rule(Tok t) {
  static constexpr size_t kNumTokens = 0
#define KANESIM_X(e, s) +1
      KANESIM_TOKENS(KANESIM_X)
#undef KANESIM_X
      ;
  static const std::array<OpRule, kNumTokens> kRules = [] {
    std::array<OpRule, kNumTokens> r{};
    auto row = [&r](Tok k) -> OpRule& { return r[static_cast<size_t>(k)]; };
    // Columns: prefix handler, it may begin an operand of (at most) this precedence, its
    // operand's precedence; infix handler, precedence, associativity.
    row(Tok::KwOr) = {nullptr, Prec::None, Prec::None, &Parser::InfixBinary, Prec::Or, Assoc::Left};
    row(Tok::KwAnd) = {nullptr, Prec::None, Prec::None, &Parser::InfixBinary, Prec::And, Assoc::Left};
    row(Tok::KwNot) = {&Parser::PrefixNot, Prec::Not, Prec::Not, nullptr, Prec::None, Assoc::Left};
    for (Tok k : {Tok::Lt, Tok::Le, Tok::Gt, Tok::Ge, Tok::EqEq, Tok::Ne})
      row(k) = {nullptr, Prec::None, Prec::None, &Parser::InfixBinary, Prec::Relation, Assoc::None};
    for (Tok k : {Tok::Plus, Tok::Minus})
      row(k) = {&Parser::PrefixSign, Prec::Additive, Prec::Multiplicative, &Parser::InfixBinary, Prec::Additive,
                Assoc::Left};
    for (Tok k : {Tok::Star, Tok::Slash})
      row(k) = {nullptr, Prec::None, Prec::None, &Parser::InfixBinary, Prec::Multiplicative, Assoc::Left};
    row(Tok::Caret) = {nullptr, Prec::None, Prec::None, &Parser::InfixPower, Prec::Power, Assoc::None};
    return r;
  }();
  return kRules[static_cast<size_t>(t)];
}

// operators := [prefix_op] operand { infix_op operand }, driven by the table: an infix
// operator joins while its precedence is at least `min` (its right operand is parsed at
// the next higher one, so chains associate to the left) and at most `max`, which the last
// operator lowers (a non-associative one to below itself; a prefix one to below its
// operand), so that exactly the sentences of the grammar's levels are accepted:
//   logical_expression := logical_term { or logical_term }
//   logical_term := logical_factor { and logical_factor }
//   logical_factor := [not] relation
//   relation := arithmetic_expression [ rel_op arithmetic_expression ]
//   arithmetic_expression := [add_op] term { add_op term }
//   term := factor { mul_op factor };  factor := primary [ '^' primary ]
// Chains are a loop, not one native frame per operator; the recursion is bounded by the
// number of levels (prefix `not`, which may repeat, takes a DepthGuard).
ExprPtr Parser::Operators(Prec min) {
  const Span b = Peek().span;
  const OpRule* rule = &Rule(Peek().kind);
  ExprPtr lhs;
  Prec max = Prec::Power;
  if (rule->prefix && min <= rule->prefix_prec) {
    lhs = (this->*rule->prefix)(b, rule->operand);
    max = Below(rule->operand);
  } else {
    lhs = Primary();
  }
  while (true) {
    rule = &Rule(Peek().kind);
    if (!rule->infix || rule->prec < min || rule->prec > max) return lhs;
    const Token& op = Advance();
    lhs = (this->*rule->infix)(std::move(lhs), b, op, Above(rule->prec));
    max = rule->assoc == Assoc::Left ? rule->prec : Below(rule->prec);
  }
}

// not logical_factor
ExprPtr Parser::PrefixNot(const Span& b, Prec operand) {
  DepthGuard guard(this);
  if (!guard.ok) return ErrorExpr(b);
  Advance();
  auto e = std::make_unique<Expr>();
  e->kind = ExprKind::Unary;
  e->op = static_cast<int>(Tok::KwNot);
  e->args.push_back(Operators(operand));
  e->span = SpanFrom(b);
  return Finish(std::move(e), b);
}

// add_op term: a leading sign.
ExprPtr Parser::PrefixSign(const Span& b, Prec operand) {
  Tok op = Advance().kind;
  DepthGuard guard(this);
  if (!guard.ok) return ErrorExpr(b);
  auto e = std::make_unique<Expr>();
  e->kind = ExprKind::Unary;
  e->op = static_cast<int>(op);
  e->args.push_back(Operators(operand));
  e->span = SpanFrom(b);
  return Finish(std::move(e), b);
}

// lhs op rhs, for every binary operator but '^'; the operator is consumed.
ExprPtr Parser::InfixBinary(ExprPtr lhs, const Span& b, const Token& op, Prec rhs_min) {
  ExprPtr rhs = Operators(rhs_min);
  return MakeBinary(op.kind, std::move(lhs), std::move(rhs), b, op.span);
}

// factor := primary '^' primary (Modelica: no chaining without parentheses, reported; a
// signed exponent a ^ -2 is accepted without them). `base` is the primary.
ExprPtr Parser::InfixPower(ExprPtr base, const Span& b, const Token&, Prec) {
  auto e = std::make_unique<Expr>();
  e->kind = ExprKind::Binary;
  e->op = static_cast<int>(Tok::Caret);
  e->args.reserve(2);
  e->args.push_back(std::move(base));
  if (At(Tok::Minus) || At(Tok::Plus)) {
    Span ub = Peek().span;
    Tok op = Advance().kind;
    auto u = std::make_unique<Expr>();
    u->kind = ExprKind::Unary;
    u->op = static_cast<int>(op);
    u->args.push_back(Primary());
    u->span = SpanFrom(ub);
    e->args.push_back(Finish(std::move(u), ub));
  } else {
    e->args.push_back(Primary());
  }
  e->span = SpanFrom(b);
  e = Finish(std::move(e), b);
  if (At(Tok::Caret)) {
    diags_.Error(DiagCode::ExpectedToken, Peek().span, "'^' does not chain").hint =
        "add parentheses: a^(b^c) or (a^b)^c";
    Advance();
    Primary();
  }
  return e;
}

// No expression where one must begin. After an operator ('1 - - 2', 'a * / b', a run of
// 200 000 signs) the whole run of operators gets one error, and parsing goes on with the
// operand that follows it, so the run neither cascades into one error per sign nor grows
// the tree.
ExprPtr Parser::MissingOperand(const Span& b) {
  const Tok k = Peek().kind;
  const bool sign = k == Tok::Plus || k == Tok::Minus;
  const bool op = sign || k == Tok::Star || k == Tok::Slash || k == Tok::Caret;
  Diagnostic* d = ErrorExpected("an expression", "");
  if (!op) return ErrorExpr(b);
  if (d) {
    d->hint = sign ? std::string("a sign cannot follow another operator: write a - (-b), a * (-b)")
                   : std::string("an operand is missing before '") + TokSpelling(k) + "'";
  }
  while (At(Tok::Plus) || At(Tok::Minus) || At(Tok::Star) || At(Tok::Slash) || At(Tok::Caret)) Advance();
  last_error_pos_ = pos_;  // nothing to parse here either: no second error
  return Primary();
}

// subscripts := '[' subscript { ',' subscript } ']';  subscript := ':' | expression
void Parser::Subscripts(std::vector<ExprPtr>& out) {
  const Token& open = Advance();  // '['
  DepthGuard guard(this);
  if (!guard.ok) return;
  do {
    if (At(Tok::Colon) && (Peek(1).kind == Tok::Comma || Peek(1).kind == Tok::RBracket)) {
      auto e = std::make_unique<Expr>();
      e->kind = ExprKind::Colon;
      e->span = Advance().span;
      out.push_back(std::move(e));
    } else {
      ++subscript_depth_;
      out.push_back(Expression());
      --subscript_depth_;
    }
  } while (Accept(Tok::Comma));
  ExpectClose(Tok::RBracket, open);
}

// component_reference := IDENT [subscripts] { '.' IDENT [subscripts] }
ExprPtr Parser::ComponentRef() {
  Span b = Peek().span;
  auto e = std::make_unique<Expr>();
  e->kind = ExprKind::Ref;
  if (!At(Tok::Ident)) {
    ErrorExpected("a component reference", "");
    e->span = b;
    return e;
  }
  do {
    if (!At(Tok::Ident)) {
      ErrorExpected("a name", "after '.'");
      break;
    }
    RefPart p;
    p.span = Peek().span;
    p.name = Advance().text;
    if (At(Tok::LBracket)) Subscripts(p.subscripts);
    p.span = SpanFrom(p.span);
    e->parts.push_back(std::move(p));
  } while (Accept(Tok::Dot));
  e->span = SpanFrom(b);
  return Finish(std::move(e), b);
}

// primary := NUMBER | STRING | false | true | component_reference
//          | component_reference function_call_args
//          | '(' expression ')' | '{' array_arguments '}' | '[' matrix ']'
ExprPtr Parser::Primary() {
  Span b = Peek().span;
  const Token& t = Peek();
  // Brackets nest; each level counts once against kMaxNesting.
  bool opens = t.kind == Tok::LParen || t.kind == Tok::LBrace || t.kind == Tok::LBracket || t.kind == Tok::Ident;
  DepthGuard guard(this, opens);
  if (!guard.ok) return ErrorExpr(b);
  if (t.kind == Tok::KwEnd && subscript_depth_ > 0) {
    auto e = std::make_unique<Expr>();
    e->kind = ExprKind::End;
    e->span = Advance().span;
    return e;
  }
  switch (t.kind) {
    case Tok::Number:
    case Tok::String:
    case Tok::KwTrue:
    case Tok::KwFalse: return Literal();
    case Tok::LParen: {
      const Token& open = Advance();
      ExprPtr inner = Expression();
      ExpectClose(Tok::RParen, open);
      return inner;
    }
    case Tok::LBrace: return ArrayConstructor();
    case Tok::LBracket: return MatrixConstructor();
    case Tok::Ident: return ReferenceOrCall();
    default: return MissingOperand(b);
  }
}

// NUMBER | STRING | false | true
ExprPtr Parser::Literal() {
  const Token& t = Advance();
  auto e = std::make_unique<Expr>();
  e->span = t.span;
  if (t.kind == Tok::Number) {
    e->kind = ExprKind::Number;
    e->number = t.number;
    e->is_integer = t.is_integer;
  } else if (t.kind == Tok::String) {
    e->kind = ExprKind::String;
    e->text = t.text;
  } else {
    e->kind = ExprKind::Bool;
    e->number = t.kind == Tok::KwTrue ? 1 : 0;
  }
  return e;
}

// '{' array_arguments '}'
// array_arguments := [ expression { ',' expression } | expression for IDENT in expression ]
ExprPtr Parser::ArrayConstructor() {
  Span b = Peek().span;
  const Token& open = Advance();
  auto e = std::make_unique<Expr>();
  e->kind = ExprKind::Array;
  if (!At(Tok::RBrace)) {
    ExprPtr first = Expression();
    if (At(Tok::KwFor)) {
      Advance();
      e->kind = ExprKind::Comprehension;
      e->args.push_back(std::move(first));
      if (At(Tok::Ident)) {
        e->text = Advance().text;
      } else {
        ErrorExpected("an iterator name", "after 'for'");
      }
      Expect(Tok::KwIn, "after the iterator");
      e->args.push_back(Expression());
    } else {
      const size_t from = elements_.size();
      elements_.push_back(std::move(first));
      while (Accept(Tok::Comma)) elements_.push_back(Expression());
      e->args = TakeElements(from);
    }
  }
  ExpectClose(Tok::RBrace, open);
  e->span = SpanFrom(b);
  return Finish(std::move(e), b);
}

// '[' matrix ']'
// matrix := expression { ',' expression } { ';' expression { ',' expression } }
ExprPtr Parser::MatrixConstructor() {
  Span b = Peek().span;
  const Token& open = Advance();
  auto e = std::make_unique<Expr>();
  e->kind = ExprKind::Matrix;
  e->rows.emplace_back();
  if (!At(Tok::RBracket)) {
    do {
      const size_t from = elements_.size();
      do {
        elements_.push_back(Expression());
      } while (Accept(Tok::Comma));
      e->rows.back() = TakeElements(from);
      if (At(Tok::Semicolon)) e->rows.emplace_back();
    } while (Accept(Tok::Semicolon));
  }
  ExpectClose(Tok::RBracket, open);
  e->span = SpanFrom(b);
  return Finish(std::move(e), b);
}

// component_reference [ function_call_args ]
// function_call_args := '(' [ expression { ',' expression } { ',' IDENT '=' expression }
//                       | expression for IDENT in expression ] ')'
ExprPtr Parser::ReferenceOrCall() {
  Span b = Peek().span;
  ExprPtr ref = ComponentRef();
  if (!At(Tok::LParen)) return ref;
  const Token& open = Advance();
  auto call = std::make_unique<Expr>();
  call->kind = ExprKind::Call;
  call->parts = std::move(ref->parts);
  if (!At(Tok::RParen)) {
    do {
      if (At(Tok::Ident) && Peek(1).kind == Tok::Assign) {
        NamedArg na;
        na.span = Peek().span;
        na.name = Advance().text;
        Advance();
        na.value = Expression();
        call->named_args.push_back(std::move(na));
        continue;
      }
      ExprPtr a = Expression();
      if (At(Tok::KwFor)) {
        call->args.push_back(Reduction(std::move(a)));
        break;
      }
      call->args.push_back(std::move(a));
    } while (Accept(Tok::Comma));
  }
  ExpectClose(Tok::RParen, open);
  call->span = SpanFrom(b);
  return Finish(std::move(call), b);
}

// f(expr for i in range): a reduction like sum(...) — represented as a call whose single
// argument is a comprehension. `body` is expr; the next token is `for`.
ExprPtr Parser::Reduction(ExprPtr body) {
  Advance();
  auto comp = std::make_unique<Expr>();
  comp->kind = ExprKind::Comprehension;
  comp->span = body->span;
  comp->args.push_back(std::move(body));
  if (At(Tok::Ident)) comp->text = Advance().text;
  else ErrorExpected("an iterator name", "after 'for'");
  Expect(Tok::KwIn, "after the iterator");
  comp->args.push_back(Expression());
  const Span comp_span = comp->span;
  return Finish(std::move(comp), comp_span);
}

}  // namespace kanesim::lang::parsing
