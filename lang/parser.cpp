// Declarations: stored definitions, classes, components, modifications and annotations.
// Equations are parsed in lang/parse_equations.cpp, expressions in
// lang/parse_expressions.cpp; the Parser class is in lang/parser_internal.h.
#include "lang/parser.h"

#include <algorithm>
#include <cctype>
#include <utility>

#include "lang/parser_internal.h"

namespace kanesim::lang {
namespace parsing {
namespace {

bool IsClassKeyword(Tok t) {
  return t == Tok::KwModel || t == Tok::KwPackage || t == Tok::KwConnector || t == Tok::KwRecord ||
         t == Tok::KwBlock || t == Tok::KwClass || t == Tok::KwType || t == Tok::KwFunction;
}

bool IsClassStart(Tok t) {
  return IsClassKeyword(t) || t == Tok::KwPartial || t == Tok::KwEncapsulated || t == Tok::KwImport;
}

}  // namespace

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
      const Token& kw = Advance();
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
  parts.emplace_back(Advance().text);
  while (At(Tok::Dot) && Peek(1).kind == Tok::Ident) {
    Advance();
    parts.emplace_back(Advance().text);
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
    const Token& endname = Advance();
    if (endname.text != c->name) {
      auto& d = diags_.Error(DiagCode::EndNameMismatch, endname.span,
                             "'end " + std::string(endname.text) + "' closes class '" + c->name + "'");
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
    const Token& kw = Advance();
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
    const Token& kw = Advance();
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
    // The last component of the clause takes the type's name; the others copy it.
    if (At(Tok::Comma)) comp->type_name = type_name;
    else comp->type_name = std::move(type_name);
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
  const Token& open = Advance();  // '('
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
    a.path = {std::string(Advance().text)};
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

}  // namespace parsing

std::unique_ptr<ast::StoredDefinition> Parse(int file, const SourceManager& sm, Diagnostics& diags) {
  parsing::Parser p(file, sm, diags);
  return p.Run();
}

std::unique_ptr<ast::Expr> ParseExpression(int file, const SourceManager& sm, Diagnostics& diags) {
  parsing::Parser p(file, sm, diags);
  return p.RunExpression();
}

}  // namespace kanesim::lang
