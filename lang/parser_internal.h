// The recursive-descent parser's class, shared by its three files: lang/parser.cpp
// (stored definitions, classes, components, modifications), lang/parse_equations.cpp
// (equations) and lang/parse_expressions.cpp (expressions, by precedence). Only those
// files include this.
#pragma once

#include <algorithm>
#include <cctype>
#include <cstddef>
#include <cstdint>
#include <iterator>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "lang/lexer.h"
#include "lang/parser.h"

namespace kanesim::lang::parsing {

using namespace ast;

class Parser {
 public:
  Parser(int file, const SourceManager& sm, Diagnostics& diags)
      : file_(file), diags_(diags), toks_(Lex(file, sm, diags)) {}

  std::unique_ptr<StoredDefinition> Run();
  // expression_only := expression EOF   (for --set values)
  ExprPtr RunExpression() {
    ExprPtr e = Expression();
    if (!At(Tok::Eof)) ErrorExpected("end of the value", "");
    return e;
  }

 private:
  // --- token helpers -------------------------------------------------------------
  // toks_ ends with the one Eof token, and pos_ never passes it.
  const Token& Peek() const { return toks_[pos_]; }
  const Token& Peek(int k) const {
    size_t i = pos_ + static_cast<size_t>(k);
    return i < toks_.size() ? toks_[i] : toks_.back();
  }
  bool At(Tok t) const { return toks_[pos_].kind == t; }
  // The current token, then moves past it (a reference into toks_, which never changes).
  const Token& Advance() {
    const Token& t = toks_[pos_];
    if (t.kind != Tok::Eof) ++pos_;
    return t;
  }
  bool Accept(Tok t) {
    if (!At(t)) return false;
    Advance();
    return true;
  }
  bool Expect(Tok t, const char* context) {
    if (Accept(t)) return true;
    ErrorExpected(std::string("'") + TokSpelling(t) + "'", context);
    return false;
  }
  // Reports "expected X[ context], found Y" once per position (no cascades); the
  // diagnostic, or null when suppressed.
  Diagnostic* ErrorExpected(const std::string& what, const char* context) {
    if (last_error_pos_ == pos_ && pos_ != 0) return nullptr;
    last_error_pos_ = pos_;
    const Token& t = Peek();
    std::string found = t.kind == Tok::Ident ? "identifier '" + std::string(t.text) + "'"
                        : t.kind == Tok::Number ? "number " + std::string(t.text)
                        : t.kind == Tok::Eof    ? std::string("end of file")
                                                : std::string("'") + TokSpelling(t.kind) + "'";
    std::string message = "expected " + what;
    if (*context != '\0') message += std::string(" ") + context;
    auto& d = diags_.Error(DiagCode::ExpectedToken, t.span, message + ", found " + found);
    if (what == "';'" && pos_ > 0) {
      d.span = Span{file_, toks_[pos_ - 1].span.end, toks_[pos_ - 1].span.end + 1};
      d.hint = "add ';' at the end of the previous declaration or equation";
    } else if (t.kind != Tok::Ident && (what.find("name") != std::string::npos ||
                                         what.find("reference") != std::string::npos)) {
      // A reserved word where a name belongs ("Body block(...)"): say so.
      const std::string word = TokSpelling(t.kind);
      const bool is_word = !word.empty() && std::all_of(word.begin(), word.end(), [](char c) {
        return std::isalpha(static_cast<unsigned char>(c)) != 0 || c == '_';
      });
      if (is_word)
        d.hint = "'" + word + "' is a reserved word of the language and cannot name a component or class; choose another "
                 "name, such as '" + word + "_'";
    }
    return &d;
  }
  // Closing bracket: names both ends when missing.
  void ExpectClose(Tok close, const Token& open) {
    if (Accept(close)) return;
    if (last_error_pos_ == pos_) return;
    last_error_pos_ = pos_;
    auto& d = diags_.Error(DiagCode::UnclosedBracket, Peek().span,
                           std::string("expected '") + TokSpelling(close) + "' to close '" +
                               TokSpelling(open.kind) + "'");
    d.notes.push_back({open.span, std::string("'") + TokSpelling(open.kind) + "' opened here"});
  }
  // Skips to just after the next ';' at bracket depth 0, or to a token that can start
  // the next construct.
  void Recover() {
    int depth = 0;
    while (!At(Tok::Eof)) {
      Tok k = Peek().kind;
      if (k == Tok::LParen || k == Tok::LBracket || k == Tok::LBrace) ++depth;
      if ((k == Tok::RParen || k == Tok::RBracket || k == Tok::RBrace) && depth > 0) --depth;
      if (depth == 0 && k == Tok::Semicolon) {
        Advance();
        return;
      }
      if (depth == 0 && (k == Tok::KwEnd || k == Tok::KwEquation || k == Tok::KwPublic ||
                         k == Tok::KwProtected))
        return;
      Advance();
    }
  }
  // After P104 in nested classes or equations: every enclosing level would report its
  // missing 'end' (one error per level, up to the cap), so the rest of the file is skipped.
  void SkipRest() {
    pos_ = toks_.size() - 1;  // the Eof token
    last_error_pos_ = pos_;
  }
  struct DepthGuard {
    Parser* p;
    bool ok;
    bool counted;
    explicit DepthGuard(Parser* parser, bool count = true)
        : p(parser), ok(!count || ++parser->depth_ <= kMaxNesting), counted(count) {
      if (!ok) p->last_error_pos_ = p->pos_;  // no "expected ..." cascade at the same token
      if (!ok && !p->depth_reported_) {
        p->depth_reported_ = true;
        p->diags_.Error(DiagCode::NestingTooDeep, p->Peek().span,
                        "nesting deeper than " + std::to_string(kMaxNesting) + " levels")
            .hint = "simplify the expression or split the class";
      }
    }
    ~DepthGuard() {
      if (counted) --p->depth_;
    }
  };
  Span SpanFrom(const Span& b) const {
    int32_t end = pos_ > 0 ? toks_[pos_ - 1].span.end : b.end;
    return Span{file_, b.begin, end < b.begin ? b.begin : end};
  }
  ExprPtr ErrorExpr(Span s) {
    auto e = std::make_unique<Expr>();
    e->kind = ExprKind::Number;
    e->span = s;
    return e;
  }
  // Every node with children passes through here once its children are parsed: it records
  // the node's depth (ast::Expr::depth) and enforces kMaxExprDepth. A deeper node is
  // reported once (P106) at `where` and replaced by an error leaf, so the tree stays
  // bounded however long the input is.
  ExprPtr Finish(ExprPtr e, Span where) {
    std::int32_t below = 0;
    ForEachChild(*e, [&below](const ExprPtr& c) {
      if (c && c->depth > below) below = c->depth;
    });
    e->depth = below + 1;
    if (e->depth <= kMaxExprDepth) return e;
    if (!expr_depth_reported_) {
      expr_depth_reported_ = true;
      diags_.Error(DiagCode::ExpressionTooDeep, where,
                   "expression deeper than " + std::to_string(kMaxExprDepth) +
                       " levels (each operator of a chain such as a + b + c counts one level)")
          .hint = "write a long sum as sum({a, b, c, ...}), or split it into partial results in separate "
                  "parameters (s1 = a1 + ... + a1000; s = s1 + s2)";
    }
    return ErrorExpr(e->span);
  }
  // The elements of the lists being parsed (arrays, matrix rows), the innermost list's on
  // top. A list moves its own out when it closes, into a vector of their final size: one
  // allocation, where a vector grown element by element allocates at 1, 2 and 4 (the
  // arrays and rows of a model are mostly of three).
  std::vector<ExprPtr> TakeElements(size_t from) {
    std::vector<ExprPtr> out(std::make_move_iterator(elements_.begin() + static_cast<std::ptrdiff_t>(from)),
                             std::make_move_iterator(elements_.end()));
    elements_.erase(elements_.begin() + static_cast<std::ptrdiff_t>(from), elements_.end());
    return out;
  }
  // Binary node `lhs op rhs`, finished.
  ExprPtr MakeBinary(Tok op, ExprPtr lhs, ExprPtr rhs, const Span& begin, const Span& op_span) {
    auto e = std::make_unique<Expr>();
    e->kind = ExprKind::Binary;
    e->op = static_cast<int>(op);
    e->args.reserve(2);  // one allocation, not two
    e->args.push_back(std::move(lhs));
    e->args.push_back(std::move(rhs));
    e->span = SpanFrom(begin);
    return Finish(std::move(e), op_span);
  }

  // --- grammar ---------------------------------------------------------------------
  std::vector<std::string> Name(Span* span);
  std::string StringComment();
  std::unique_ptr<ClassDef> ClassDefinition(ClassDef* parent);
  void Composition(ClassDef& c);
  bool ElementDecl(ClassDef& c, bool is_protected);
  std::unique_ptr<Modification> ModificationOpt();
  std::unique_ptr<Modification> ClassModification();
  bool ArgumentItem(Argument& a);
  void ComponentClause(ClassDef& c, Element prefix, bool is_protected, Variability var, Causality caus);
  bool EquationItem(std::vector<Equation>& out);
  bool ConnectClause(Equation& eq);  // each: false when the equation is given up
  bool ForEquation(Equation& eq);
  bool IfEquation(Equation& eq);
  bool WhenEquation(Equation& eq);
  bool WhenStatement(Equation& eq);
  bool Equality(Equation& eq);
  std::unique_ptr<Modification> AnnotationOpt();
  ExprPtr Expression();
  ExprPtr SimpleExpression();
  // Operator expressions (lang/parse_expressions.cpp): one loop over the table Rule.
  enum class Prec : std::uint8_t { None, Or, And, Not, Relation, Additive, Multiplicative, Power };
  enum class Assoc : std::uint8_t { Left, None };
  static Prec Above(Prec p) { return static_cast<Prec>(static_cast<int>(p) + 1); }
  static Prec Below(Prec p) { return static_cast<Prec>(static_cast<int>(p) - 1); }
  struct OpRule {
    ExprPtr (Parser::*prefix)(const Span& begin, Prec operand);  // null: not a prefix operator
    Prec prefix_prec;  // a prefix operator may begin an operand parsed at this precedence or lower
    Prec operand;      // the precedence its operand is parsed at
    ExprPtr (Parser::*infix)(ExprPtr lhs, const Span& begin, const Token& op, Prec rhs_min);  // null: not infix
    Prec prec;         // the infix operator's precedence
    Assoc assoc;
  };
  static const OpRule& Rule(Tok t);
  ExprPtr Operators(Prec min);
  ExprPtr PrefixNot(const Span& b, Prec operand);
  ExprPtr PrefixSign(const Span& b, Prec operand);
  ExprPtr InfixBinary(ExprPtr lhs, const Span& b, const Token& op, Prec rhs_min);
  ExprPtr InfixPower(ExprPtr base, const Span& b, const Token& op, Prec rhs_min);
  ExprPtr Primary();
  ExprPtr Literal();            // NUMBER | STRING | false | true
  ExprPtr ArrayConstructor();   // '{' ... '}'
  ExprPtr MatrixConstructor();  // '[' ... ']'
  ExprPtr ReferenceOrCall();    // a component reference, or a call f(...)
  ExprPtr Reduction(ExprPtr body);  // f(body for i in range)
  ExprPtr MissingOperand(const Span& b);
  void Subscripts(std::vector<ExprPtr>& out);
  ExprPtr ComponentRef();

  int file_;
  Diagnostics& diags_;
  std::vector<Token> toks_;
  size_t pos_ = 0;
  size_t last_error_pos_ = static_cast<size_t>(-1);
  int depth_ = 0;
  int subscript_depth_ = 0;  // > 0 inside [...] subscripts, where `end` is an expression
  bool depth_reported_ = false;
  bool expr_depth_reported_ = false;
  std::vector<ExprPtr> elements_;  // of the open lists (TakeElements)
};

}  // namespace kanesim::lang::parsing
