// Abstract syntax tree of a .mech file. One node type per grammar construct; every node
// keeps its span. The parser builds it, the elaborator reads it, nothing else does.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "lang/node_pool.h"
#include "lang/source.h"

namespace kanesim::lang::ast {

struct Expr;
using ExprPtr = std::unique_ptr<Expr>;

// One part of a dotted reference: name[subscripts].
struct RefPart {
  std::string name;
  std::vector<ExprPtr> subscripts;  // empty = none; a ':' subscript is a Colon expr
  Span span;
};

enum class ExprKind {
  Number,         // number, is_integer
  String,         // text
  Bool,           // number 0/1
  Ref,            // parts (a.b[1].c); also `time`, `pi`
  Call,           // parts = function name, args, named_args
  Array,          // {a, b, c}; args
  Comprehension,  // {expr for iter in range}; args[0] = expr, iter, args[1] = range
  Matrix,         // [a, b; c, d]; rows
  Range,          // a:b or a:s:b; args = {start, stop} or {start, step, stop}
  Colon,          // ':' as a subscript (whole dimension)
  End,            // 'end' inside subscripts
  Unary,          // op (Tok::Minus, Tok::Plus, Tok::KwNot), args[0]
  Binary,         // op, args[0], args[1]
  If,             // args = {c1, e1, c2, e2, ..., else}
};

struct NamedArg {
  std::string name;
  ExprPtr value;
  Span span;
};

// Expression trees can be as deep as the input is long (a + b + c + ... is a left-deep
// chain, one level per operator): nothing here recurses over them. The destructor, Clone
// and Dump use explicit stacks; the parser records each node's depth and bounds it by
// kMaxExprDepth (lang/parser.h).
struct Expr {
  // User-provided: make_unique<Expr>() then runs the member initializers only instead of
  // zeroing the node first (value-initialization of a defaulted constructor).
  Expr() {}  // NOLINT(modernize-use-equals-default)
  Expr(Expr&&) = default;
  Expr(const Expr&) = delete;
  Expr& operator=(const Expr&) = delete;
  ~Expr();  // iterative: frees any depth of children without recursion
  KANESIM_POOLED_NODE(Expr)  // thousands per model file (lang/node_pool.h)

  ExprKind kind = ExprKind::Number;
  Span span;
  double number = 0;
  bool is_integer = false;
  std::string text;                 // String literal, or Comprehension iterator name
  int op = 0;                       // a Tok value for Unary/Binary
  std::vector<RefPart> parts;       // Ref / Call name
  std::vector<ExprPtr> args;
  std::vector<NamedArg> named_args; // Call
  std::vector<std::vector<ExprPtr>> rows;  // Matrix
  // Nodes on the longest path from this node down to a leaf (1 for a leaf). Set by the
  // parser, which keeps it <= kMaxExprDepth; informational for every other reader.
  std::int32_t depth = 1;
};

// Calls f(child) for every direct child slot of `e` (an ExprPtr, possibly null), in source
// order: subscripts of the reference parts, args, named_args' values, matrix rows.
template <class E, class F>
void ForEachChild(E& e, F&& f) {
  for (auto& p : e.parts)
    for (auto& s : p.subscripts) f(s);
  for (auto& a : e.args) f(a);
  for (auto& n : e.named_args) f(n.value);
  for (auto& r : e.rows)
    for (auto& x : r) f(x);
}

struct Modification;

// One argument of a class modification: [each] [final] name.path [mod] or a redeclare.
struct Argument {
  bool each = false;
  bool is_final = false;
  bool redeclare = false;
  std::vector<std::string> path;  // q.start -> {"q", "start"}; for redeclare: component name
  std::string redeclare_type;     // redeclare Type name(...)
  std::unique_ptr<Modification> mod;
  std::string description;
  Span span;      // whole argument
  Span name_span; // the path
};

struct Modification {
  KANESIM_POOLED_NODE(Modification)
  std::vector<Argument> args;  // class modification "( ... )"
  bool has_args = false;
  ExprPtr value;               // "= expr"
  Span span;
};

struct ClassDef;

enum class Variability { None, Parameter, Constant };
enum class Causality { None, Input, Output };

struct Component {
  Variability variability = Variability::None;
  Causality causality = Causality::None;
  bool is_final = false, replaceable = false, redeclare = false, is_protected = false;
  std::vector<std::string> type_name;  // dotted
  std::vector<ExprPtr> type_dims;      // Real[3] x
  std::string name;
  std::vector<ExprPtr> dims;           // x[3]
  std::unique_ptr<Modification> mod;
  ExprPtr condition;                   // `if cond`
  std::string description;
  std::unique_ptr<Modification> annotation;
  Span span, name_span, type_span;
};

struct Extends {
  std::vector<std::string> base;
  std::unique_ptr<Modification> mod;
  Span span;
};

struct Import {
  std::vector<std::string> name;  // A.B.C
  std::string alias;              // import X = A.B;
  bool wildcard = false;          // import A.B.*;
  Span span;
};

// When: conditions[0] the condition, body its statements (Call: reinit(...), terminate(...)).
enum class EqKind { Equality, Connect, For, If, When, Call };

struct Equation {
  EqKind kind = EqKind::Equality;
  ExprPtr lhs, rhs;                  // Equality; Connect: lhs/rhs are Refs; Call: lhs the call
  std::string iter;                  // For
  ExprPtr range;                     // For
  std::vector<Equation> body;        // For, When body
  std::vector<ExprPtr> conditions;   // If: one per branch
  std::vector<std::vector<Equation>> branches;  // If: conditions.size() or +1 for else
  Span span;
};

enum class ClassKind { Model, Package, Connector, Record, Block, Class, Type, Function };

struct Element {
  enum Kind { kComponent, kExtends, kImport, kClass } kind = kComponent;
  std::unique_ptr<Component> component;
  std::unique_ptr<Extends> extends;
  std::unique_ptr<Import> import;
  std::unique_ptr<ClassDef> class_def;
  bool is_final = false, replaceable = false, redeclare = false;
};

struct ClassDef {
  ClassKind kind = ClassKind::Model;
  std::string name;
  std::string description;
  bool partial = false;
  std::vector<Element> elements;
  std::vector<Equation> equations;
  std::unique_ptr<Modification> annotation;
  // Short class definition: model A = B(mods);
  bool is_short = false;
  std::vector<std::string> short_base;
  std::unique_ptr<Modification> short_mod;
  Span span, name_span;
  ClassDef* parent = nullptr;  // enclosing class (set by the parser)
};

struct StoredDefinition {
  int file = -1;
  std::vector<std::string> within;
  std::vector<Import> imports;               // file-level imports
  std::vector<std::unique_ptr<ClassDef>> classes;
};

std::string JoinName(const std::vector<std::string>& parts);

// Deep copy of an expression tree (iterative: any depth).
ExprPtr Clone(const Expr& e);

// Readable dump for `kanesim check --emit ast` and parser tests (iterative: any depth).
std::string Dump(const StoredDefinition& def);
std::string DumpExpr(const Expr& e);

}  // namespace kanesim::lang::ast
