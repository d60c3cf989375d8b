#include "lang/parser.h"

#include <algorithm>
#include <cctype>
#include <utility>

#include "lang/lexer.h"

namespace kanesim::lang {
namespace {

using namespace ast;

bool IsClassKeyword(Tok t);
bool IsClassStart(Tok t);

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
  const Token& Peek(int k = 0) const {
    size_t i = pos_ + static_cast<size_t>(k);
    return i < toks_.size() ? toks_[i] : toks_.back();
  }
  bool At(Tok t) const { return Peek().kind == t; }
  Token Advance() {
    Token t = Peek();
    if (pos_ + 1 < toks_.size()) ++pos_;
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
    std::string found = t.kind == Tok::Ident ? "identifier '" + t.text + "'"
                        : t.kind == Tok::Number ? "number " + t.text
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
  // Binary node `lhs op rhs`, finished.
  ExprPtr MakeBinary(Tok op, ExprPtr lhs, ExprPtr rhs, const Span& begin, const Span& op_span) {
    auto e = std::make_unique<Expr>();
    e->kind = ExprKind::Binary;
    e->op = static_cast<int>(op);
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
  std::unique_ptr<Modification> AnnotationOpt();
  ExprPtr Expression();
  ExprPtr SimpleExpression();
  ExprPtr Logical(int level);
  ExprPtr Arithmetic(int level);
  ExprPtr Unary();
  ExprPtr Power();
  ExprPtr Primary();
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
};

// stored_definition := [within name ';'] { import_clause ';' | class_definition ';' }
std::unique_ptr<StoredDefinition> Parser::Run() {
  auto def = std::make_unique<StoredDefinition>();
  def->file = file_;
  if (Accept(Tok::KwWithin)) {
    if (!At(Tok::Semicolon)) def->within = Name(nullptr);
    Expect(Tok::Semicolon, "after 'within'");
  }
  while (!At(Tok::Eof) && !diags_.Full()) {
    size_t before = pos_;
    if (At(Tok::KwImport)) {
      Token kw = Advance();
      Import imp;
      imp.span = kw.span;
      if (At(Tok::Ident) && Peek(1).kind == Tok::Assign) {
        imp.alias = Advance().text;
        Advance();
      }
      imp.name = Name(nullptr);
      if (Accept(Tok::Dot)) {
        Expect(Tok::Star, "after '.' in import");
        imp.wildcard = true;
      }
      imp.span = SpanFrom(kw.span);
      def->imports.push_back(std::move(imp));
      if (!Expect(Tok::Semicolon, "after import")) Recover();
      continue;
    }
    auto c = ClassDefinition(nullptr);
    if (c) {
      def->classes.push_back(std::move(c));
      if (!Expect(Tok::Semicolon, "after class definition") && !IsClassStart(Peek().kind)) Recover();
    } else {
      Recover();
    }
    if (pos_ == before) Advance();  // guarantee progress
  }
  return def;
}

// name := IDENT { '.' IDENT }
std::vector<std::string> Parser::Name(Span* span) {
  std::vector<std::string> parts;
  Span b = Peek().span;
  if (!At(Tok::Ident)) {
    ErrorExpected("a name", "");
    return parts;
  }
  parts.push_back(Advance().text);
  while (At(Tok::Dot) && Peek(1).kind == Tok::Ident) {
    Advance();
    parts.push_back(Advance().text);
  }
  if (span) *span = SpanFrom(b);
  return parts;
}

// string_comment := [ STRING { '+' STRING } ]
std::string Parser::StringComment() {
  std::string s;
  if (!At(Tok::String)) return s;
  s = Advance().text;
  while (At(Tok::Plus) && Peek(1).kind == Tok::String) {
    Advance();
    s += Advance().text;
  }
  return s;
}

bool IsClassStart(Tok t) {
  return IsClassKeyword(t) || t == Tok::KwPartial || t == Tok::KwEncapsulated || t == Tok::KwImport;
}

bool IsClassKeyword(Tok t) {
  return t == Tok::KwModel || t == Tok::KwPackage || t == Tok::KwConnector || t == Tok::KwRecord ||
         t == Tok::KwBlock || t == Tok::KwClass || t == Tok::KwType || t == Tok::KwFunction;
}

// class_definition := [encapsulated] [partial] class_prefix IDENT
//     ( string_comment composition end IDENT | '=' name [class_modification] comment )
std::unique_ptr<ClassDef> Parser::ClassDefinition(ClassDef* parent) {
  DepthGuard guard(this);
  if (!guard.ok) return SkipRest(), nullptr;
  auto c = std::make_unique<ClassDef>();
  c->parent = parent;
  Span b = Peek().span;
  Accept(Tok::KwEncapsulated);
  if (Accept(Tok::KwPartial)) c->partial = true;
  if (!IsClassKeyword(Peek().kind)) {
    ErrorExpected("a class definition ('model', 'package', 'connector', ...)", "");
    return nullptr;
  }
  switch (Advance().kind) {
    case Tok::KwPackage: c->kind = ClassKind::Package; break;
    case Tok::KwConnector: c->kind = ClassKind::Connector; break;
    case Tok::KwRecord: c->kind = ClassKind::Record; break;
    case Tok::KwBlock: c->kind = ClassKind::Block; break;
    case Tok::KwClass: c->kind = ClassKind::Class; break;
    case Tok::KwType: c->kind = ClassKind::Type; break;
    case Tok::KwFunction: c->kind = ClassKind::Function; break;
    default: c->kind = ClassKind::Model; break;
  }
  if (!At(Tok::Ident)) {
    ErrorExpected("the class name", "");
    return nullptr;
  }
  c->name_span = Peek().span;
  c->name = Advance().text;
  if (Accept(Tok::Assign)) {
    c->is_short = true;
    c->short_base = Name(nullptr);
    if (At(Tok::LParen)) c->short_mod = ClassModification();
    c->description = StringComment();
    c->annotation = AnnotationOpt();
    c->span = SpanFrom(b);
    return c;
  }
  c->description = StringComment();
  Composition(*c);
  if (!At(Tok::KwEnd)) {
    ErrorExpected("'end " + c->name + "'", "to close the class");
    auto& d = diags_.All();
    (void)d;
    c->span = SpanFrom(b);
    return c;
  }
  Advance();
  if (At(Tok::Ident)) {
    Token endname = Advance();
    if (endname.text != c->name) {
      auto& d = diags_.Error(DiagCode::EndNameMismatch, endname.span,
                             "'end " + endname.text + "' closes class '" + c->name + "'");
      d.notes.push_back({c->name_span, "class '" + c->name + "' begins here"});
      d.hint = "write 'end " + c->name + ";'";
    }
  } else {
    ErrorExpected("the class name '" + c->name + "'", "after 'end'");
  }
  c->span = SpanFrom(b);
  return c;
}

// composition := element_list { public element_list | protected element_list
//                              | equation { equation ';' } } [ annotation ';' ]
void Parser::Composition(ClassDef& c) {
  bool is_protected = false;
  bool in_equations = false;
  while (!At(Tok::KwEnd) && !At(Tok::Eof) && !diags_.Full()) {
    size_t before = pos_;
    if (Accept(Tok::KwPublic)) {
      is_protected = false;
      in_equations = false;
      continue;
    }
    if (Accept(Tok::KwProtected)) {
      is_protected = true;
      in_equations = false;
      continue;
    }
    if (At(Tok::KwInitial) && Peek(1).kind == Tok::KwEquation) {
      diags_.Error(DiagCode::BadEquation, Peek().span, "'initial equation' is not supported").hint =
          "give start values with q(start = ...) and u(start = ...)";
      Advance();
      Advance();
      in_equations = true;
      continue;
    }
    if (Accept(Tok::KwEquation)) {
      in_equations = true;
      continue;
    }
    if (At(Tok::KwAlgorithm)) {
      diags_.Error(DiagCode::BadEquation, Peek().span, "'algorithm' sections are not supported").hint =
          "write equations in an 'equation' section";
      Advance();
      in_equations = true;
      continue;
    }
    if (At(Tok::KwAnnotation)) {
      c.annotation = AnnotationOpt();
      if (!Expect(Tok::Semicolon, "after annotation")) Recover();
      continue;
    }
    bool ok = in_equations ? EquationItem(c.equations) : ElementDecl(c, is_protected);
    if (!ok) Recover();
    if (pos_ == before) {
      Advance();
    }
  }
}

// element := import_clause | extends_clause
//          | [redeclare] [final] [inner|outer] [replaceable] (class_definition | component_clause)
bool Parser::ElementDecl(ClassDef& c, bool is_protected) {
  if (At(Tok::KwImport)) {
    Token kw = Advance();
    Element el;
    el.kind = Element::kImport;
    el.import = std::make_unique<Import>();
    if (At(Tok::Ident) && Peek(1).kind == Tok::Assign) {
      el.import->alias = Advance().text;
      Advance();
    }
    el.import->name = Name(nullptr);
    if (Accept(Tok::Dot)) {
      if (!Expect(Tok::Star, "after '.' in import")) return false;
      el.import->wildcard = true;
    }
    el.import->span = SpanFrom(kw.span);
    c.elements.push_back(std::move(el));
    return Expect(Tok::Semicolon, "after import");
  }
  if (At(Tok::KwExtends)) {
    Token kw = Advance();
    Element el;
    el.kind = Element::kExtends;
    el.extends = std::make_unique<Extends>();
    el.extends->base = Name(nullptr);
    if (At(Tok::LParen)) el.extends->mod = ClassModification();
    AnnotationOpt();
    el.extends->span = SpanFrom(kw.span);
    c.elements.push_back(std::move(el));
    return Expect(Tok::Semicolon, "after extends clause");
  }
  Element prefix;
  while (true) {
    if (Accept(Tok::KwRedeclare)) prefix.redeclare = true;
    else if (Accept(Tok::KwFinal)) prefix.is_final = true;
    else if (Accept(Tok::KwReplaceable)) prefix.replaceable = true;
    else if (At(Tok::KwInner) || At(Tok::KwOuter)) {
      diags_.Error(DiagCode::ExpectedToken, Peek().span, "'inner'/'outer' are not supported").hint =
          "pass the World's frame with connect() instead";
      Advance();
    } else break;
  }
  if (IsClassKeyword(Peek().kind) || At(Tok::KwPartial) || At(Tok::KwEncapsulated)) {
    auto nested = ClassDefinition(&c);
    if (!nested) return false;
    Element el;
    el.kind = Element::kClass;
    el.is_final = prefix.is_final;
    el.replaceable = prefix.replaceable;
    el.redeclare = prefix.redeclare;
    el.class_def = std::move(nested);
    c.elements.push_back(std::move(el));
    return Expect(Tok::Semicolon, "after class definition");
  }
  Variability var = Variability::None;
  Causality caus = Causality::None;
  if (Accept(Tok::KwParameter)) var = Variability::Parameter;
  else if (Accept(Tok::KwConstant)) var = Variability::Constant;
  else if (At(Tok::KwDiscrete)) {
    diags_.Error(DiagCode::ExpectedToken, Peek().span, "'discrete' variables are not supported");
    Advance();
  }
  if (Accept(Tok::KwInput)) caus = Causality::Input;
  else if (Accept(Tok::KwOutput)) caus = Causality::Output;
  if (!At(Tok::Ident)) {
    ErrorExpected("a declaration", "in the class body");
    return false;
  }
  size_t before = c.elements.size();
  ComponentClause(c, std::move(prefix), is_protected, var, caus);
  if (c.elements.size() == before) return false;
  return Expect(Tok::Semicolon, "after declaration");
}

// component_clause := type_specifier [array_subscripts] component_decl { ',' component_decl }
// component_decl := IDENT [array_subscripts] [modification] [if expression] comment
void Parser::ComponentClause(ClassDef& c, Element prefix, bool is_protected, Variability var,
                             Causality caus) {
  Span tspan;
  std::vector<std::string> type_name = Name(&tspan);
  // Type dimensions (Real[3] a, b) belong to every component of the clause: parse them
  // once and give each component its own copy.
  std::vector<ExprPtr> type_dims;
  if (At(Tok::LBracket)) Subscripts(type_dims);
  do {
    if (!At(Tok::Ident)) {
      ErrorExpected("a component name", "after the type");
      return;
    }
    auto comp = std::make_unique<Component>();
    comp->variability = var;
    comp->causality = caus;
    comp->is_final = prefix.is_final;
    comp->replaceable = prefix.replaceable;
    comp->redeclare = prefix.redeclare;
    comp->is_protected = is_protected;
    comp->type_name = type_name;
    comp->type_span = tspan;
    for (const auto& d : type_dims) comp->type_dims.push_back(ast::Clone(*d));
    Span b = Peek().span;
    comp->name_span = b;
    comp->name = Advance().text;
    if (At(Tok::LBracket)) Subscripts(comp->dims);
    comp->mod = ModificationOpt();
    if (Accept(Tok::KwIf)) comp->condition = Expression();
    comp->description = StringComment();
    comp->annotation = AnnotationOpt();
    comp->span = SpanFrom(tspan);
    Element el;
    el.kind = Element::kComponent;
    el.is_final = prefix.is_final;
    el.replaceable = prefix.replaceable;
    el.redeclare = prefix.redeclare;
    el.component = std::move(comp);
    c.elements.push_back(std::move(el));
  } while (Accept(Tok::Comma));
}

// modification := class_modification ['=' expression] | '=' expression | ':=' expression
std::unique_ptr<Modification> Parser::ModificationOpt() {
  std::unique_ptr<Modification> m;
  if (At(Tok::LParen)) m = ClassModification();
  if (At(Tok::Assign) || At(Tok::ColonAssign)) {
    if (!m) {
      m = std::make_unique<Modification>();
      m->span = Peek().span;
    }
    Advance();
    m->value = Expression();
    m->span = SpanFrom(m->span);
  }
  return m;
}

// class_modification := '(' [ argument { ',' argument } ] ')'
std::unique_ptr<Modification> Parser::ClassModification() {
  DepthGuard guard(this);
  auto m = std::make_unique<Modification>();
  m->has_args = true;
  Token open = Advance();  // '('
  m->span = open.span;
  if (!guard.ok) {
    Recover();
    return m;
  }
  if (!At(Tok::RParen)) {
    do {
      Argument a;
      if (!ArgumentItem(a)) {
        // skip to ',' or ')' at this depth
        int depth = 0;
        while (!At(Tok::Eof)) {
          Tok k = Peek().kind;
          if (depth == 0 && (k == Tok::Comma || k == Tok::RParen || k == Tok::Semicolon)) break;
          if (k == Tok::LParen || k == Tok::LBracket || k == Tok::LBrace) ++depth;
          if (k == Tok::RParen || k == Tok::RBracket || k == Tok::RBrace) --depth;
          Advance();
        }
      } else {
        m->args.push_back(std::move(a));
      }
    } while (Accept(Tok::Comma));
  }
  ExpectClose(Tok::RParen, open);
  m->span = SpanFrom(open.span);
  return m;
}

// argument := [each] [final] name [modification] string_comment
//           | redeclare [each] [final] type_specifier IDENT [class_modification]
bool Parser::ArgumentItem(Argument& a) {
  Span b = Peek().span;
  if (Accept(Tok::KwRedeclare)) a.redeclare = true;
  if (Accept(Tok::KwEach)) a.each = true;
  if (Accept(Tok::KwFinal)) a.is_final = true;
  if (Accept(Tok::KwReplaceable)) {
  }
  if (a.redeclare) {
    std::vector<std::string> type = Name(nullptr);
    if (type.empty()) return false;
    a.redeclare_type = ast::JoinName(type);
    if (!At(Tok::Ident)) {
      ErrorExpected("the name of the redeclared component", "");
      return false;
    }
    a.name_span = Peek().span;
    a.path = {Advance().text};
    if (At(Tok::LParen)) a.mod = ClassModification();
    a.span = SpanFrom(b);
    return true;
  }
  if (!At(Tok::Ident)) {
    ErrorExpected("a modifier name", "in the modification");
    return false;
  }
  a.path = Name(&a.name_span);
  a.mod = ModificationOpt();
  a.description = StringComment();
  a.span = SpanFrom(b);
  return true;
}

// annotation := annotation class_modification
std::unique_ptr<Modification> Parser::AnnotationOpt() {
  if (!At(Tok::KwAnnotation)) return nullptr;
  Advance();
  if (!At(Tok::LParen)) {
    ErrorExpected("'('", "after 'annotation'");
    return nullptr;
  }
  return ClassModification();
}

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
    Token open = Advance();
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

// simple_expression := logical_expression [ ':' logical_expression [ ':' logical_expression ] ]
ExprPtr Parser::SimpleExpression() {
  Span b = Peek().span;
  ExprPtr first = Logical(0);
  if (!At(Tok::Colon)) return first;
  auto r = std::make_unique<Expr>();
  r->kind = ExprKind::Range;
  r->args.push_back(std::move(first));
  Advance();
  r->args.push_back(Logical(0));
  if (Accept(Tok::Colon)) r->args.push_back(Logical(0));
  r->span = SpanFrom(b);
  return Finish(std::move(r), b);
}

// Operator precedence, lowest first (Modelica 3.5 §3.2):
//   or; and; not; relational; additive (+ -); multiplicative (* /); unary +-; ^
// logical_expression := logical_term { or logical_term }
// logical_term := logical_factor { and logical_factor }
// logical_factor := [not] relation
// relation := arithmetic_expression [ rel_op arithmetic_expression ]
ExprPtr Parser::Logical(int level) {
  Span b = Peek().span;
  if (level == 0 || level == 1) {
    Tok op = level == 0 ? Tok::KwOr : Tok::KwAnd;
    ExprPtr lhs = Logical(level + 1);
    while (At(op)) {
      Span op_span = Advance().span;
      ExprPtr rhs = Logical(level + 1);
      lhs = MakeBinary(op, std::move(lhs), std::move(rhs), b, op_span);
    }
    return lhs;
  }
  if (level == 2) {
    if (At(Tok::KwNot)) {
      DepthGuard guard(this);
      if (!guard.ok) return ErrorExpr(b);
      Advance();
      auto e = std::make_unique<Expr>();
      e->kind = ExprKind::Unary;
      e->op = static_cast<int>(Tok::KwNot);
      e->args.push_back(Logical(2));
      e->span = SpanFrom(b);
      return Finish(std::move(e), b);
    }
    return Logical(3);
  }
  // relation
  ExprPtr lhs = Arithmetic(0);
  Tok k = Peek().kind;
  if (k == Tok::Lt || k == Tok::Le || k == Tok::Gt || k == Tok::Ge || k == Tok::EqEq || k == Tok::Ne) {
    Span op_span = Advance().span;
    ExprPtr rhs = Arithmetic(0);
    return MakeBinary(k, std::move(lhs), std::move(rhs), b, op_span);
  }
  return lhs;
}

// arithmetic_expression := [add_op] term { add_op term }
// term := factor { mul_op factor }
ExprPtr Parser::Arithmetic(int level) {
  Span b = Peek().span;
  if (level == 0) {
    ExprPtr lhs = Unary();
    while (At(Tok::Plus) || At(Tok::Minus)) {
      Token op = Advance();
      ExprPtr rhs = Arithmetic(1);
      lhs = MakeBinary(op.kind, std::move(lhs), std::move(rhs), b, op.span);
    }
    return lhs;
  }
  ExprPtr lhs = Power();
  while (At(Tok::Star) || At(Tok::Slash)) {
    Token op = Advance();
    ExprPtr rhs = Power();
    lhs = MakeBinary(op.kind, std::move(lhs), std::move(rhs), b, op.span);
  }
  return lhs;
}

// Leading unary +/- applies to the whole first term: -a*b = -(a*b), -a^2 = -(a^2).
ExprPtr Parser::Unary() {
  Span b = Peek().span;
  if (At(Tok::Minus) || At(Tok::Plus)) {
    Tok op = Advance().kind;
    DepthGuard guard(this);
    if (!guard.ok) return ErrorExpr(b);
    auto e = std::make_unique<Expr>();
    e->kind = ExprKind::Unary;
    e->op = static_cast<int>(op);
    e->args.push_back(Arithmetic(1));
    e->span = SpanFrom(b);
    return Finish(std::move(e), b);
  }
  return Arithmetic(1);
}

// factor := primary [ '^' primary ]   (Modelica: no chaining without parentheses; we
// accept a^b^c as a^(b^c)? No: reported as an error, like Modelica.)
ExprPtr Parser::Power() {
  Span b = Peek().span;
  ExprPtr base = Primary();
  if (!At(Tok::Caret)) return base;
  Advance();
  auto e = std::make_unique<Expr>();
  e->kind = ExprKind::Binary;
  e->op = static_cast<int>(Tok::Caret);
  e->args.push_back(std::move(base));
  if (At(Tok::Minus) || At(Tok::Plus)) {
    // a ^ -2 : Modelica requires parentheses; accept and note via hint-free parse.
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
  Token open = Advance();  // '['
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
// function_call_args := '(' [ expression { ',' expression } { ',' IDENT '=' expression }
//                       | expression for IDENT in expression ] ')'
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
    case Tok::Number: {
      auto e = std::make_unique<Expr>();
      e->kind = ExprKind::Number;
      e->number = t.number;
      e->is_integer = t.is_integer;
      e->span = t.span;
      Advance();
      return e;
    }
    case Tok::String: {
      auto e = std::make_unique<Expr>();
      e->kind = ExprKind::String;
      e->text = t.text;
      e->span = t.span;
      Advance();
      return e;
    }
    case Tok::KwTrue:
    case Tok::KwFalse: {
      auto e = std::make_unique<Expr>();
      e->kind = ExprKind::Bool;
      e->number = t.kind == Tok::KwTrue ? 1 : 0;
      e->span = t.span;
      Advance();
      return e;
    }
    case Tok::LParen: {
      Token open = Advance();
      ExprPtr inner = Expression();
      ExpectClose(Tok::RParen, open);
      return inner;
    }
    case Tok::LBrace: {
      Token open = Advance();
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
          e->args.push_back(std::move(first));
          while (Accept(Tok::Comma)) e->args.push_back(Expression());
        }
      }
      ExpectClose(Tok::RBrace, open);
      e->span = SpanFrom(b);
      return Finish(std::move(e), b);
    }
    case Tok::LBracket: {
      Token open = Advance();
      auto e = std::make_unique<Expr>();
      e->kind = ExprKind::Matrix;
      e->rows.emplace_back();
      if (!At(Tok::RBracket)) {
        do {
          do {
            e->rows.back().push_back(Expression());
          } while (Accept(Tok::Comma));
          if (At(Tok::Semicolon)) e->rows.emplace_back();
        } while (Accept(Tok::Semicolon));
      }
      ExpectClose(Tok::RBracket, open);
      e->span = SpanFrom(b);
      return Finish(std::move(e), b);
    }
    case Tok::Ident: {
      ExprPtr ref = ComponentRef();
      if (!At(Tok::LParen)) return ref;
      Token open = Advance();
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
          } else {
            ExprPtr a = Expression();
            if (At(Tok::KwFor)) {
              // f(expr for i in range): a reduction like sum(...) — represented as a
              // call whose single argument is a comprehension.
              Advance();
              auto comp = std::make_unique<Expr>();
              comp->kind = ExprKind::Comprehension;
              comp->span = a->span;
              comp->args.push_back(std::move(a));
              if (At(Tok::Ident)) comp->text = Advance().text;
              else ErrorExpected("an iterator name", "after 'for'");
              Expect(Tok::KwIn, "after the iterator");
              comp->args.push_back(Expression());
              const Span comp_span = comp->span;
              call->args.push_back(Finish(std::move(comp), comp_span));
              break;
            }
            call->args.push_back(std::move(a));
          }
        } while (Accept(Tok::Comma));
      }
      ExpectClose(Tok::RParen, open);
      call->span = SpanFrom(b);
      return Finish(std::move(call), b);
    }
    default:
      return MissingOperand(b);
  }
}

}  // namespace

std::unique_ptr<ast::StoredDefinition> Parse(int file, const SourceManager& sm, Diagnostics& diags) {
  Parser p(file, sm, diags);
  return p.Run();
}

std::unique_ptr<ast::Expr> ParseExpression(int file, const SourceManager& sm, Diagnostics& diags) {
  Parser p(file, sm, diags);
  return p.RunExpression();
}

}  // namespace kanesim::lang
