// The unit check's inside (lang/elab_units.h is its interface), shared by its two files:
// lang/elab_units.cpp (the values shown by the emitter's walk, declared and inferred units)
// and lang/elab_units_expr.cpp (an expression's unit, bottom-up). Included by those alone.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <map>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

#include "lang/elab_units.h"
#include "lang/lexer.h"
#include "lang/units.h"

namespace kanesim::lang::elab {

// What is known of an expression's unit. Literal: built from numbers alone (dimensionless
// in products, adapting in sums); Unknown: reads a variable of no known unit (unchecked).
struct UVal {
  Unit unit;
  const Node* origin = nullptr;         // the variable whose unit this is, for notes
  const std::string* text = nullptr;    // that unit as declared ("N.m"), when unchanged
  enum Kind : std::uint8_t { Unknown, Literal, Known } kind = Unknown;
  // From `time` and numbers alone (sin(time), sqrt(0.5 - time): test signals that read time
  // as a number): used where it meets a unit, never reported.
  bool soft = false;

  static UVal Of(const Unit& u) {
    UVal v;
    v.kind = Known;
    v.unit = u;
    return v;
  }
  static UVal Lit() {
    UVal v;
    v.kind = Literal;
    return v;
  }
};

// A unit in quotes as the user wrote it, or in SI form when computed.
inline std::string Shown(const UVal& v) { return "\"" + (v.text ? *v.text : v.unit.ToString()) + "\""; }

// s == lit, the literal's length known at compile time (no strlen, an inlined compare).
template <size_t N>
inline bool Is(const std::string& s, const char (&lit)[N]) {
  return s.size() == N - 1 && std::memcmp(s.data(), lit, N - 1) == 0;
}

// The functions the check knows, by what they do to units.
enum class Fn : std::uint8_t {
  Other,          // unknown unit
  Dimensionless,  // sin, exp...: a dimensionless argument, result 1
  Inverse,        // asin, acos, atan: a dimensionless argument, result rad
  Atan2, Sqrt, Der,
  Pair,           // min, max, mod: two arguments in one unit
  Keep,           // abs, norm, sum...: the argument's unit
  Fill,
  Product,        // cross, dot, outerProduct
  Plain,          // sign, identity, zeros...: numbers
  MeshVolume, MeshCentre, MeshInertia, Cat,
};

inline Fn FnOf(const std::string& name) {
  struct Entry {
    std::string_view name;
    Fn fn;
  };
  static constexpr Entry kFns[] = {
      {"sin", Fn::Dimensionless}, {"cos", Fn::Dimensionless}, {"tan", Fn::Dimensionless},
      {"exp", Fn::Dimensionless}, {"log", Fn::Dimensionless}, {"sinh", Fn::Dimensionless},
      {"cosh", Fn::Dimensionless}, {"tanh", Fn::Dimensionless}, {"asin", Fn::Inverse},
      {"acos", Fn::Inverse},      {"atan", Fn::Inverse},      {"atan2", Fn::Atan2},
      {"sqrt", Fn::Sqrt},         {"der", Fn::Der},           {"min", Fn::Pair},
      {"max", Fn::Pair},          {"mod", Fn::Pair},          {"abs", Fn::Keep},
      {"floor", Fn::Keep},        {"ceil", Fn::Keep},         {"norm", Fn::Keep},
      {"transpose", Fn::Keep},    {"sum", Fn::Keep},          {"skew", Fn::Keep},
      {"vector", Fn::Keep},       {"diagonal", Fn::Keep},     {"fill", Fn::Fill},
      {"cross", Fn::Product},     {"dot", Fn::Product},       {"outerProduct", Fn::Product},
      {"sign", Fn::Plain},        {"identity", Fn::Plain},    {"zeros", Fn::Plain},
      {"ones", Fn::Plain},        {"size", Fn::Plain},        {"integer", Fn::Plain},
      {"meshVolume", Fn::MeshVolume}, {"meshCentre", Fn::MeshCentre}, {"meshInertia", Fn::MeshInertia},
      {"cat", Fn::Cat},
  };
  const std::string_view n = name;
  for (const Entry& f : kFns)
    if (f.name.size() == n.size() && f.name == n) return f.fn;
  return Fn::Other;
}

// A number, or minus one (`= 0`, `min = -1`): its unit is what it is bound to.
inline bool IsNumber(const ast::Expr& e) {
  if (e.kind == ast::ExprKind::Number) return true;
  return e.kind == ast::ExprKind::Unary && static_cast<Tok>(e.op) == Tok::Minus && e.args.size() == 1 &&
         e.args[0]->kind == ast::ExprKind::Number;
}

// Numbers alone, in arrays and matrices too ({0, 1, 0}, [1, 0; 0, 1]): never a unit, so
// nothing to check and nothing inferred (Expr gives them Literal at most). Nested deeper
// than `depth` allows: false (left to Expr).
inline bool IsLiteral(const ast::Expr& e, int depth = 0) {
  if (IsNumber(e)) return true;
  if (depth > 8 || !e.named_args.empty()) return false;
  if (e.kind == ast::ExprKind::Array) {
    for (const auto& a : e.args)
      if (!a || !IsLiteral(*a, depth + 1)) return false;
    return true;
  }
  if (e.kind != ast::ExprKind::Matrix) return false;
  for (const auto& row : e.rows)
    for (const auto& x : row)
      if (!x || !IsLiteral(*x, depth + 1)) return false;
  return true;
}

// Expressions nested deeper than this are left unchecked instead of recursed into (the
// parser allows 100,000 levels; the native stack does not).
inline constexpr int kMaxCheckDepth = 200;
// Undeclared variables whose unit is inferred from a binding that names another such
// variable, nested deeper than this, are left unchecked: each step costs several native
// frames (VarUnit, Bound, Expr, Operator, Ref), and a 1 MiB thread stack must hold the
// chain under AddressSanitizer too (Bounds.NestedEvaluationOnASmallThreadStack).
inline constexpr int kMaxInferChain = 24;

// Values checked per batch (UnitChecker::Flush): enough that the check's code is loaded once
// for many variables, few enough that their nodes are still in the data cache.
inline constexpr size_t kBatch = 64;

// Node::unit_slot of a variable without a declared unit: its inference's progress.
inline constexpr int kNoUnit = -2;            // nothing tried yet
inline constexpr int kInferred = -3;          // it has an entry in UnitChecker::inferred_
inline constexpr int kInferredNothing = -4;   // its binding gave no unit, and no use gave one yet
inline constexpr int kInferring = -5;         // its binding is being read (a cycle reads no unit)

// A variable's `unit` attribute, or null. "unit" sorts after every other attribute's name:
// when there, it is nearly always last.
inline const Mod* UnitMod(const ModMap& attrs) {
  if (attrs.empty()) return nullptr;
  if (const auto& last = *attrs.rbegin(); Is(last.first, "unit")) return &last.second;
  if (std::string_view(attrs.rbegin()->first) < std::string_view("unit")) return nullptr;
  auto it = attrs.find(std::string_view("unit"));
  return it != attrs.end() ? &it->second : nullptr;
}

// var, an element of `scope`, has no unit, or its unit is written in the text of scope's class
// (its declaration there, or a modifier in it, of the instance itself): the same in every
// instance of that class of which this holds. Not so: a unit from a modifier outside the
// instance, or from a short class definition (`model C2 = C(x(unit = "mm"))`), or a base.
inline bool UnitFromClass(const Node* var, const Node* scope) {
  if (var->kind != Node::kVar) return false;
  if (var->mod_from_decl) return true;  // its declaration's literals, not modified (DeclarationMod)
  const Mod* unit = UnitMod(var->Modifiers().sub);
  if (!unit || !unit->value) return true;
  const ModValue& v = *unit->value;
  const Span at = v.expr ? v.expr->span : v.span;
  const Span& c = scope->cls->span;
  return v.scope == scope && at.file == c.file && at.begin >= c.begin && at.end <= c.end;
}

inline Unit Seconds() {
  Unit s;
  s.twice[2] = 2;
  return s;
}
inline Unit Metres(int power) {
  Unit u;
  u.twice[0] = static_cast<std::int16_t>(2 * power);
  return u;
}
inline Unit Radians() {
  Unit u;
  u.twice[Unit::kRad] = 2;
  return u;
}


class UnitChecker {
 public:
  explicit UnitChecker(Diagnostics& diags) : diags_(diags) {}
  // Every value given to `var`: its binding (declaration, modifier, --set or equation), its
  // elements' equations, and its start, min and max attributes. Its declared unit is read
  // at once; the values are checked in batches (Flush), in the order shown: between two
  // batches the emitter's walk runs without the check's code in the instruction cache.
  void Show(Node* var);
  void Flush();
  // The units a spring on flanges takes from the joint its flanges act on.
  void SpringUnits(const InstanceTree& tree, const Links& links);
  // A variable's unit: declared, or inferred (from its binding or from its uses).
  UVal VarUnit(const Node* var);
  // The units inferred for variables that declare none, by path ("" none).
  struct PathHash {  // looked up by std::string_view (Mechanism::ParamName) without a copy
    using is_transparent = void;
    size_t operator()(std::string_view s) const { return std::hash<std::string_view>()(s); }
  };
  using ByPath = std::unordered_map<std::string, std::string, PathHash, std::equal_to<>>;
  ByPath InferredByPath() const;

 private:
  struct Declared {
    bool ok = false;
    int index = -1;  // in table_ (Node::unit_slot)
    Unit unit;
    std::string text;
  };
  struct Inferred {
    UVal val;
    bool busy = false;        // being inferred from its binding (a cycle reads it as unknown)
    bool from_use = false;    // inferred from a use, not its binding
    Span where;               // that use
  };

  void CheckBinding(Node* var, const ModValue& mv, const char* what, bool is_equation);
  void Pend(Node* var, const ModValue* mv, const char* what, bool is_equation);  // a value for the batch
  // A joint's q or u without one unit: element k of a start array, or an element equation,
  // against the coordinate's unit.
  void CheckCoordinates(Node* var);
  void CheckElement(Node* var, const ast::Expr& e, const ModValue& mv, int k, const char* what);
  const Declared* DeclaredUnit(const Node* var);
  const Declared* FindDeclaredUnit(const Node* var);
  UVal Expr(const ast::Expr& e, const Node* scope, const Iters* iters);
  // The unit of e, the value of binding mv: a declaration's, a modifier's or an attribute's
  // (`binding`), or an equation's right side.
  UVal Bound(const ast::Expr& e, const ModValue& mv, bool binding);
  // Bound of a binding read alike by several variables (`where`: see CheckBinding); *hit
  // when an earlier answer was reused.
  // `within`: the binding's scope when the key is its class (see CheckBinding); the answer
  // is then kept only if it read the units of `within`'s own variables alone, each from the
  // class's text, and is reused in another instance whose same variables have them too.
  UVal BoundOnce(const ModValue& mv, bool binding, std::intptr_t where, const Node* within, bool* hit);
  // In BoundOnce's class-keyed reading: var's unit is the same in every instance of the class
  // of within_ that passes this test too (recorded for that test).
  bool ReadInClass(const Node* var);
  UVal Ref(const ast::Expr& e, const Node* scope, const Iters* iters);
  UVal Call(const ast::Expr& e, const Node* scope, const Iters* iters);
  UVal Operator(const ast::Expr& e, const Node* scope, const Iters* iters);
  // Elements of an array: all in one unit, else unknown (arrays of mixed units are allowed).
  void Element(const ast::Expr& x, const Node* scope, const Iters* iters, UVal* acc, bool* mixed);
  // a and b must agree (sums, comparisons, branches); the result's unit. `what` names the
  // place for the message.
  UVal Same(const UVal& a, const ast::Expr* ea, const UVal& b, const ast::Expr* eb, Span at, const char* what,
            const Node* scope);
  UVal NeedDimensionless(const UVal& a, const ast::Expr& arg, const std::string& fn, UVal result);
  // An undeclared scalar variable read bare in `e` takes unit u from this use.
  // A variable with a unit from an earlier use is E238 when `report` (else left as it is).
  void InferFromUse(const ast::Expr* e, const UVal& u, const Node* scope, Span at, bool report = true);
  // An expression of no known unit used as u: each undeclared variable it is a sum, a
  // difference, a negation or an if-branch of takes u (`L = 1 + k` makes k a length).
  // Products are not entered: a number there is a factor, or open in an equation. Inside,
  // a variable that has a unit already is not reported again: the sum would have had
  // that unit, so it had none because of a mismatch already reported.
  void InferDown(const ast::Expr* e, const UVal& u, const Node* scope, Span at, int depth = 0);
  void NoteOrigin(Diagnostic& d, const UVal& v);
  // `inferred` is the unit an undeclared variable took from an earlier use, and `other`
  // disagrees: E238 (true) instead of a plain mismatch.
  bool ReportConflict(const UVal& inferred, const UVal& other, Span at);

  Diagnostics& diags_;
  std::unordered_map<const ast::Expr*, Declared> declared_;  // unit string literal -> parsed
  std::vector<const Declared*> table_;                        // declared_'s parsed units, by index
  std::array<std::pair<const ast::Expr*, const Declared*>, 64> recent_{};  // FindDeclaredUnit's
  std::array<const Mod*, 64> seen_decl_{};  // Show's: declarations' shared modifiers whose unit was parsed
  std::unordered_map<const Node*, Inferred> inferred_;       // undeclared variables
  std::unordered_map<const Node*, Declared> implied_;        // a spring's c, d, phi_rel0 from its joint
  using Reads = std::vector<std::pair<int, const ast::Component*>>;  // index in within_->children, declaration
  struct Reuse {
    UVal val;
    const Iters* iters = nullptr;
    bool binding = false;
    bool valid = false;
    Reads reads;  // class keys: the scope's variables read (ReadInClass)
  };
  struct ReuseHash {
    size_t operator()(const std::pair<const ast::Expr*, std::intptr_t>& k) const {
      return std::hash<const void*>()(k.first) * 31 + std::hash<std::intptr_t>()(k.second);
    }
  };
  std::unordered_map<std::pair<const ast::Expr*, std::intptr_t>, Reuse, ReuseHash> reused_;  // BoundOnce's
  long impure_ = 0;  // reads of inferred or implied units (BoundOnce keeps no answer that made one)
  const Node* within_ = nullptr;  // BoundOnce's class-keyed scope (ReadInClass)
  Reads reads_;                   // ReadInClass's variables
  struct Pending {
    Node* var;
    const ModValue* mv;  // null: the joint coordinates of var (CheckCoordinates)
    const char* what;
    bool is_equation;
  };
  std::vector<Pending> pending_;  // values shown and not yet checked
  bool flushing_ = false;
  int depth_ = 0;
  int chain_ = 0;                   // VarUnit's inference nesting (kMaxInferChain)
  bool factors_ = false;            // in a binding: a number in a product is a plain factor
};

}  // namespace kanesim::lang::elab
