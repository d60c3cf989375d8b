// The unit check (lang/elab_units.h): shown each variable by the emitter's walk, it gives
// each binding's expression a unit, bottom-up, and compares it with the variable's.
#include "lang/elab_units.h"

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "lang/lexer.h"
#include "lang/units.h"

namespace kanesim::lang::elab {

namespace {

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
std::string Shown(const UVal& v) { return "\"" + (v.text ? *v.text : v.unit.ToString()) + "\""; }

// s == lit, the literal's length known at compile time (no strlen, an inlined compare).
template <size_t N>
bool Is(const std::string& s, const char (&lit)[N]) {
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

Fn FnOf(const std::string& name) {
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
bool IsNumber(const ast::Expr& e) {
  if (e.kind == ast::ExprKind::Number) return true;
  return e.kind == ast::ExprKind::Unary && static_cast<Tok>(e.op) == Tok::Minus && e.args.size() == 1 &&
         e.args[0]->kind == ast::ExprKind::Number;
}

// Numbers alone, in arrays and matrices too ({0, 1, 0}, [1, 0; 0, 1]): never a unit, so
// nothing to check and nothing inferred (Expr gives them Literal at most). Nested deeper
// than `depth` allows: false (left to Expr).
bool IsLiteral(const ast::Expr& e, int depth = 0) {
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
constexpr int kMaxCheckDepth = 200;
// Undeclared variables whose unit is inferred from a binding that names another such
// variable, nested deeper than this, are left unchecked: each step costs several native
// frames (VarUnit, Bound, Expr, Operator, Ref), and a 1 MiB thread stack must hold the
// chain under AddressSanitizer too (Bounds.NestedEvaluationOnASmallThreadStack).
constexpr int kMaxInferChain = 24;

// Values checked per batch (UnitChecker::Flush): enough that the check's code is loaded once
// for many variables, few enough that their nodes are still in the data cache.
constexpr size_t kBatch = 64;

// Node::unit_slot of a variable without a declared unit: its inference's progress.
constexpr int kNoUnit = -2;            // nothing tried yet
constexpr int kInferred = -3;          // it has an entry in UnitChecker::inferred_
constexpr int kInferredNothing = -4;   // its binding gave no unit, and no use gave one yet
constexpr int kInferring = -5;         // its binding is being read (a cycle reads no unit)

// A variable's `unit` attribute, or null. "unit" sorts after every other attribute's name:
// when there, it is nearly always last.
const Mod* UnitMod(const std::map<std::string, Mod, std::less<>>& attrs) {
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
bool UnitFromClass(const Node* var, const Node* scope) {
  if (var->kind != Node::kVar) return false;
  if (var->mod_from_decl) return true;  // its declaration's literals, not modified (DeclarationMod)
  const Mod* unit = UnitMod(var->Modifiers().sub);
  if (!unit || !unit->value) return true;
  const ModValue& v = *unit->value;
  const Span at = v.expr ? v.expr->span : v.span;
  const Span& c = scope->cls->span;
  return v.scope == scope && at.file == c.file && at.begin >= c.begin && at.end <= c.end;
}

Unit Seconds() {
  Unit s;
  s.twice[2] = 2;
  return s;
}
Unit Metres(int power) {
  Unit u;
  u.twice[0] = static_cast<std::int16_t>(2 * power);
  return u;
}
Unit Radians() {
  Unit u;
  u.twice[Unit::kRad] = 2;
  return u;
}

}  // namespace

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

void UnitChecker::Show(Node* var) {
  if ((var->vtype != VType::Real && var->vtype != VType::Integer) || diags_.Full()) return;
  if (var->mod_from_decl) {
    // The declaration's literals (Instantiator::DeclarationMod): a number, string or array of
    // numbers has no unit to check and infers none; only the declared unit is parsed (E236),
    // once per declaration (the other instances share the modifier; read when named). A value
    // given from outside (Node::mod_over_decl) is checked.
    auto& seen = seen_decl_[(reinterpret_cast<std::uintptr_t>(var->shared_mod) >> 4) % seen_decl_.size()];
    if (seen != var->shared_mod) {
      DeclaredUnit(var);
      seen = var->shared_mod;
    }
    if (const ModValue* v = var->mod_over_decl ? var->Modifiers().value : nullptr) Pend(var, v, "the value of", false);
  } else if (!var->shared_mod) {  // (an array element's shared with element 1: checked there, lang/elab_share.cpp)
    DeclaredUnit(var);  // parses a declared unit (E236) even when nothing is bound
    const ModView mods = var->Modifiers();
    const ModValue* attrs[3] = {};  // start, min, max: one pass over the few attributes
    for (const auto& [key, sub] : mods.sub) {
      if (!sub.value) continue;
      if (Is(key, "start")) attrs[0] = &*sub.value;
      else if (Is(key, "min")) attrs[1] = &*sub.value;
      else if (Is(key, "max")) attrs[2] = &*sub.value;
    }
    if (mods.value) Pend(var, &*mods.value, "the value of", false);
    if (attrs[0]) Pend(var, attrs[0], "start", false);
    if (attrs[1]) Pend(var, attrs[1], "min", false);
    if (attrs[2]) Pend(var, attrs[2], "max", false);
  }
  if (var->eq_binding) Pend(var, &*var->eq_binding, "", true);
  if (!var->eq_elem_binding.empty())
    for (const auto& [k, mv] : var->eq_elem_binding) Pend(var, &mv, "", !mv.from_set);
  if (!var->shape.empty() && (Is(var->name, "q") || Is(var->name, "u")) && var->parent &&
      var->parent->prim == Prim::Joint)
    pending_.push_back({var, nullptr, nullptr, false});  // its coordinates, unless it declares one unit
  if (pending_.size() >= kBatch) Flush();
}

void UnitChecker::Pend(Node* var, const ModValue* mv, const char* what, bool is_equation) {
  // A number takes the unit it is given (min = 0), numbers in an array none: nothing to
  // check, nothing to infer (a variable's own binding is read by its first value checked).
  if (!mv->expr || IsNumber(*mv->expr)) return;
  if ((mv->expr->kind != ast::ExprKind::Array && mv->expr->kind != ast::ExprKind::Matrix) || !IsLiteral(*mv->expr))
    pending_.push_back({var, mv, what, is_equation});
}

void UnitChecker::Flush() {
  if (flushing_) return;
  flushing_ = true;
  for (const Pending& p : pending_) {
    if (p.mv) CheckBinding(p.var, *p.mv, p.what, p.is_equation);
    else if (!diags_.Full() && !DeclaredUnit(p.var)) CheckCoordinates(p.var);
  }
  pending_.clear();
  flushing_ = false;
}

void UnitChecker::CheckCoordinates(Node* var) {
  if (auto it = var->Modifiers().sub.find("start"); it != var->Modifiers().sub.end() && it->second.value) {
    const ModValue& mv = *it->second.value;
    if (mv.expr && mv.expr->kind == ast::ExprKind::Array)
      for (size_t k = 0; k < mv.expr->args.size(); ++k) CheckElement(var, *mv.expr->args[k], mv, static_cast<int>(k), "start");
  }
  for (const auto& [k, mv] : var->eq_elem_binding)
    if (mv.expr) CheckElement(var, *mv.expr, mv, k, "");
}

void UnitChecker::CheckElement(Node* var, const ast::Expr& e, const ModValue& mv, int k, const char* what) {
  const Node* joint = var->parent;
  const bool quaternion = joint->prim_kind == "free" ? var->shape[0] == 7 : var->shape[0] == 4;
  const std::string text = JointCoordinateUnit(joint->prim_kind, quaternion, k, var->name == "u");
  Unit want;
  std::string error;
  if (text.empty() || !ParseUnit(text, &want, &error)) return;
  const UVal got = Bound(e, mv, *what != 0);
  if (got.kind != UVal::Known || got.soft || got.unit.Agrees(want)) return;
  const std::string name = "'" + var->Path() + "[" + std::to_string(k + 1) + "]'";
  auto& d = diags_.Error(DiagCode::UnitMismatch, e.span,
                         (*what ? std::string("the start value of ") + name : "the equation of " + name) + " has unit " +
                             Shown(got) + ", not \"" + text + "\"");
  NoteOrigin(d, got);
  d.hint = "coordinate " + std::to_string(k + 1) + " of a " + joint->prim_kind + " joint's " + var->name + " is in \"" +
           text + "\"";
}

// A spring or damper on flanges (Prim::RotSpring) connected to a joint's drive or support:
// its stiffness, damping and unstretched coordinate in the joint's units.
void UnitChecker::SpringUnits(const InstanceTree& tree, const Links& links) {
  auto joint_of = [&](int flange) -> const Node* {
    if (flange < 0 || static_cast<size_t>(flange) >= tree.flanges.size()) return nullptr;
    const Node* p = tree.flanges[static_cast<size_t>(flange)]->parent;
    return p && p->prim == Prim::Joint ? p : nullptr;
  };
  auto spring_of = [&](int flange) -> const Node* {
    if (flange < 0 || static_cast<size_t>(flange) >= tree.flanges.size()) return nullptr;
    const Node* p = tree.flanges[static_cast<size_t>(flange)]->parent;
    return p && p->prim == Prim::RotSpring ? p : nullptr;
  };
  for (const auto& [a, b] : links.flanges) {
    const Node* spring = spring_of(a) ? spring_of(a) : spring_of(b);
    const Node* joint = joint_of(a) ? joint_of(a) : joint_of(b);
    if (!spring || !joint) continue;
    const std::string q = JointCoordinateUnit(joint->prim_kind, false, 0, false);
    if (q.empty() || joint->prim_kind == "cylindrical" || joint->prim_kind == "planar" || joint->prim_kind == "free")
      continue;  // several coordinates: no one unit
    const char* force = q == "m" ? "N" : "N.m";
    for (const auto& [field, text] : {std::pair<const char*, std::string>{"c", std::string(force) + "/" + q},
                                      {"d", std::string(force) + ".s/" + q}, {"phi_rel0", q}}) {
      const Node* v = spring->Child(field);
      if (!v || v->kind != Node::kVar || DeclaredUnit(v)) continue;
      Declared& slot = implied_[v];
      slot.text = text;
      std::string error;
      slot.ok = ParseUnit(text, &slot.unit, &error);
    }
  }
}

void UnitChecker::CheckBinding(Node* var, const ModValue& mv, const char* what, bool is_equation) {
  // A number takes the unit it is given (min = 0): nothing to check, nothing to infer.
  if (!mv.expr || diags_.Full() || IsNumber(*mv.expr)) return;
  const UVal want = VarUnit(var);  // an undeclared scalar: its binding checked inside, once
  const bool own = &mv == (var->Modifiers().value ? &*var->Modifiers().value : var->eq_binding ? &*var->eq_binding : nullptr);
  if (want.kind != UVal::Known && own && var->shape.empty()) return;
  // Where the answer may be reused: the scope of a slice, or the copy id (negative).
  // Else, inside an instance of a class (not the model's root), that class: a binding written
  // in a library model reads the same declared units in each of its instances.
  const Node* cls = nullptr;
  std::intptr_t where = 0;
  if (mv.pre) {
    where = reinterpret_cast<std::intptr_t>(mv.scope);
  } else if (mv.scope && mv.scope->kind == Node::kClass && mv.scope->unit_slot >= 0) {
    where = -1 - static_cast<std::intptr_t>(mv.scope->unit_slot);
  } else if (mv.scope && mv.scope->kind == Node::kClass && mv.scope->parent && mv.scope->cls) {
    cls = mv.scope;
    where = reinterpret_cast<std::intptr_t>(cls->cls);
  }
  bool reused = false;
  UVal got = where ? BoundOnce(mv, !is_equation, where, cls, &reused) : Bound(*mv.expr, mv, !is_equation);
  if (want.kind != UVal::Known) return;
  if (got.kind != UVal::Known) {
    InferDown(mv.expr, want, mv.scope, mv.expr->span);
    return;
  }
  if (got.soft) return;
  if (want.unit.Agrees(got.unit)) return;
  if (reused && (where < 0 || cls)) {  // read again: the notes name this instance's declarations
    got = Bound(*mv.expr, mv, !is_equation);
    if (got.kind != UVal::Known) {
      InferDown(mv.expr, want, mv.scope, mv.expr->span);
      return;
    }
    if (got.soft || want.unit.Agrees(got.unit)) return;
  }
  const std::string name = "'" + var->Path() + "'";
  std::string msg = is_equation ? "the two sides of the equation have different units: " + name + " is " + Shown(want) +
                                      ", the right side " + Shown(got)
                    : std::string(what) == "the value of"
                        ? name + " has unit " + Shown(want) + " but its value has unit " + Shown(got)
                        : "the " + std::string(what) + " value of " + name + " has unit " + Shown(got) +
                              ", not " + Shown(want);
  auto& d = diags_.Error(DiagCode::UnitMismatch, is_equation ? mv.span : mv.expr->span, msg);
  if (var->decl) d.notes.push_back({var->decl->name_span, name + " is declared with unit " + Shown(want) + " here"});
  NoteOrigin(d, got);
  d.hint = want.unit.SameDimension(got.unit)
               ? "same dimension, different scale: convert the value to " + Shown(want)
               : "the value must be in " + Shown(want) + (got.origin ? "; check the unit of '" + got.origin->Path() + "'" : "");
}

void UnitChecker::NoteOrigin(Diagnostic& d, const UVal& v) {
  if (!v.origin || !v.origin->decl) return;
  auto it = inferred_.find(v.origin);
  const std::string how = it != inferred_.end() ? " (inferred)" : "";
  d.notes.push_back({v.origin->decl->name_span, "'" + v.origin->Path() + "' has unit " + Shown(VarUnit(v.origin)) + how});
}

const UnitChecker::Declared* UnitChecker::DeclaredUnit(const Node* var) {
  // Kept on the node: a variable is read by every binding that names it.
  if (var->unit_slot >= 0) return table_[static_cast<size_t>(var->unit_slot)];
  if (var->unit_slot <= kNoUnit) return nullptr;
  const Declared* d = FindDeclaredUnit(var);
  var->unit_slot = d ? d->index : kNoUnit;
  return d;
}

const UnitChecker::Declared* UnitChecker::FindDeclaredUnit(const Node* var) {
  const Mod* unit = UnitMod(var->Modifiers().sub);
  if (!unit || !unit->value || !unit->value->expr) return nullptr;
  const ast::Expr* e = unit->value->expr;
  // A direct-mapped cache in front of declared_: a model has a few dozen unit strings.
  auto& recent = recent_[(reinterpret_cast<std::uintptr_t>(e) >> 4) % recent_.size()];
  if (recent.first == e) return recent.second;
  if (e->kind != ast::ExprKind::String || e->text.empty()) return nullptr;
  // A unit string not seen yet may be reported (E236): the values shown before are checked
  // first, so that the messages come in the order of the walk.
  if (!flushing_ && !pending_.empty() && !declared_.count(e)) Flush();
  auto [slot, fresh] = declared_.try_emplace(e);
  if (fresh) {
    slot->second.index = static_cast<int>(table_.size());
    table_.push_back(&slot->second);
    std::string error;
    slot->second.ok = ParseUnit(e->text, &slot->second.unit, &error);
    slot->second.text = e->text;
    if (!slot->second.ok)
      diags_.Error(DiagCode::BadUnit, e->span, "\"" + e->text + "\" is not a unit: " + error)
          .hint = "Modelica unit syntax: \"N.m/rad\", \"kg.m2\", \"m/s2\", \"1\"; prefixes m, k, M, u, n, G...";
  }
  recent = {e, slot->second.ok ? &slot->second : nullptr};
  return recent.second;
}

UVal UnitChecker::VarUnit(const Node* var) {
  const Declared* d = DeclaredUnit(var);
  if (!d && !implied_.empty())
    if (auto it = implied_.find(var); it != implied_.end() && it->second.ok) {
      d = &it->second;
      ++impure_;  // from the joint the spring acts on: may differ between array elements
    }
  if (d) {
    if (within_ && !ReadInClass(var)) ++impure_;
    UVal v = UVal::Of(d->unit);
    v.origin = var;
    v.text = &d->text;
    return v;
  }
  // An array of no unit has none (nothing is inferred for arrays).
  if (!within_ || var->shape.empty() || !ReadInClass(var)) ++impure_;
  const int state = var->unit_slot;
  if (state == kInferredNothing || state == kInferring) return UVal{};
  if (state == kInferred) {
    const Inferred& slot = inferred_.find(var)->second;
    return slot.busy ? UVal{} : slot.val;
  }
  // Inferred from the binding, once: an output's unit from its expression.
  const ModValue* b = var->Modifiers().value ? &*var->Modifiers().value : var->eq_binding ? &*var->eq_binding : nullptr;
  if (chain_ >= kMaxInferChain) return UVal{};  // tried again where the chain is shorter
  if (!b || !b->expr || !var->shape.empty() || IsNumber(*b->expr)) {
    var->unit_slot = kInferredNothing;
    return UVal{};
  }
  var->unit_slot = kInferring;
  ++chain_;
  UVal v = Bound(*b->expr, *b, var->Modifiers().value && b == &*var->Modifiers().value);
  --chain_;
  if (v.kind == UVal::Known) v.origin = var;
  if (var->unit_slot == kInferred) {  // a use inside its own binding gave it a unit meanwhile
    Inferred& slot = inferred_[var];
    slot.busy = false;
    if (v.kind == UVal::Known) slot.val = v;
    return slot.val;
  }
  if (v.kind != UVal::Known) {
    var->unit_slot = kInferredNothing;  // no entry in inferred_: most undeclared variables
    return UVal{};
  }
  inferred_[var].val = v;
  var->unit_slot = kInferred;
  return v;
}

UnitChecker::ByPath UnitChecker::InferredByPath() const {
  ByPath out;
  for (const auto& [n, slot] : inferred_)
    if (slot.val.kind == UVal::Known && !slot.val.soft && n->shape.empty())
      out.emplace(n->Path(), slot.val.text ? *slot.val.text : slot.val.unit.ToString());
  return out;
}

void UnitChecker::InferDown(const ast::Expr* e, const UVal& u, const Node* scope, Span at, int depth) {
  if (!e || depth + depth_ >= kMaxCheckDepth) return;  // as deep as Expr went, no deeper
  const Tok op = static_cast<Tok>(e->op);
  switch (e->kind) {
    case ast::ExprKind::Ref: InferFromUse(e, u, scope, at, depth == 0); return;
    case ast::ExprKind::Unary:
      if (op == Tok::Minus || op == Tok::Plus)
        for (const auto& x : e->args) InferDown(x.get(), u, scope, at, depth + 1);
      return;
    case ast::ExprKind::Binary:
      if (op == Tok::Plus || op == Tok::Minus)
        for (const auto& x : e->args) InferDown(x.get(), u, scope, at, depth + 1);
      return;
    case ast::ExprKind::If:  // the branches (odd positions and the last), not the conditions
      for (size_t i = 0; i < e->args.size(); ++i)
        if (i % 2 == 1 || i + 1 == e->args.size()) InferDown(e->args[i].get(), u, scope, at, depth + 1);
      return;
    default: return;
  }
}

void UnitChecker::InferFromUse(const ast::Expr* e, const UVal& u, const Node* scope, Span at, bool report) {
  if (!e || e->kind != ast::ExprKind::Ref || u.kind != UVal::Known || !scope) return;
  const Node* n = scope;
  for (const auto& p : e->parts) {
    if (n->kind != Node::kClass) return;
    n = n->Child(p.name);
    if (!n) return;
    if (n->kind == Node::kArray) {
      if (n->elems.empty()) return;
      n = n->elems[0].get();
    }
  }
  if (n->kind != Node::kVar || !n->shape.empty() || DeclaredUnit(n)) return;
  ++impure_;
  Inferred& slot = inferred_[n];
  if (n->unit_slot == kInferring) slot.busy = true;
  n->unit_slot = kInferred;
  if (slot.val.kind == UVal::Known) {
    if (!slot.from_use || slot.val.unit.Agrees(u.unit) || !report) return;
    auto& d = diags_.Error(DiagCode::UnitConflict, at,
                           "'" + n->Path() + "' has no unit and is used here as " + Shown(u) + ", but earlier as " +
                               Shown(slot.val));
    d.notes.push_back({slot.where, "used as " + Shown(slot.val) + " here"});
    d.hint = "declare its unit: " + n->name + "(unit = \"...\")";
    return;
  }
  slot.val = u;
  slot.val.origin = n;
  // u.text stays: the unit as declared where it came from ("N", not "m.kg/s2")
  slot.from_use = true;
  slot.where = at;
}

// A binding's unit found once for several variables: a slice of an array's modifier
// (`Revolute j[N](axis = {...})`) is the whole array's expression, read in the same scope by
// every element; a binding read inside an array element copied from element 1 reads names
// of the same declared units in every copy (Node::unit_slot). Reused while it read only
// declared units and reported nothing (inferred units may change, implied ones differ).
UVal UnitChecker::BoundOnce(const ModValue& mv, bool binding, std::intptr_t where, const Node* within, bool* hit) {
  Reuse& r = reused_[{mv.expr, where}];
  *hit = r.valid && r.iters == mv.iters.get() && r.binding == binding;
  if (*hit && within) {  // this instance's variables read there: their units from the class too
    const auto& kids = within->children;
    for (const auto& [k, decl] : r.reads) {
      const Node* var = static_cast<size_t>(k) < kids.size() ? kids[static_cast<size_t>(k)].get() : nullptr;
      if (!var || var->decl != decl || !UnitFromClass(var, within)) *hit = false;
    }
  }
  if (*hit) return r.val;
  const long impure = impure_;
  const size_t reported = diags_.All().size();
  within_ = within;
  reads_.clear();
  const UVal v = Bound(*mv.expr, mv, binding);
  within_ = nullptr;
  r.val = v;
  r.iters = mv.iters.get();
  r.binding = binding;
  r.valid = impure_ == impure && diags_.All().size() == reported;
  if (within) r.reads = reads_;
  return v;
}

bool UnitChecker::ReadInClass(const Node* var) {
  if (var->parent != within_ || !UnitFromClass(var, within_)) return false;
  const auto& kids = within_->children;
  for (size_t k = 0; k < kids.size(); ++k)
    if (kids[k].get() == var) {
      for (const auto& r : reads_)
        if (r.first == static_cast<int>(k)) return true;  // c[1] * c[2]: once
      reads_.emplace_back(static_cast<int>(k), var->decl);
      return true;
    }
  return false;
}

UVal UnitChecker::Bound(const ast::Expr& e, const ModValue& mv, bool binding) {
  const bool outer = factors_;
  factors_ = binding;
  const UVal v = Expr(e, mv.scope, mv.iters.get());
  factors_ = outer;
  return v;
}

UVal UnitChecker::Expr(const ast::Expr& e, const Node* scope, const Iters* iters) {
  if (depth_ >= kMaxCheckDepth) return UVal{};
  if (e.kind == ast::ExprKind::Number || e.kind == ast::ExprKind::Range) return UVal::Lit();
  // Counts this level while the answer is made in place (no copy of it on the way out).
  struct Level {
    int& depth;
    explicit Level(int& d) : depth(++d) {}
    ~Level() { --depth; }
  } level(depth_);
  switch (e.kind) {
    case ast::ExprKind::Ref: return Ref(e, scope, iters);
    case ast::ExprKind::Call: return Call(e, scope, iters);
    case ast::ExprKind::Unary:
    case ast::ExprKind::Binary: return Operator(e, scope, iters);
    case ast::ExprKind::Array: {
      UVal acc = UVal::Lit();
      bool mixed = false;
      for (const auto& a : e.args) Element(*a, scope, iters, &acc, &mixed);
      return mixed ? UVal{} : acc;
    }
    case ast::ExprKind::Matrix: {
      UVal acc = UVal::Lit();
      bool mixed = false;
      for (const auto& row : e.rows)
        for (const auto& x : row) Element(*x, scope, iters, &acc, &mixed);
      return mixed ? UVal{} : acc;
    }
    case ast::ExprKind::Comprehension: {
      UVal r = e.args.empty() ? UVal{} : Expr(*e.args[0], scope, nullptr);
      if (r.kind == UVal::Unknown && !e.args.empty() && e.args[0]->kind == ast::ExprKind::Ref &&
          e.args[0]->parts.size() == 1 && e.args[0]->parts[0].name == e.text)
        r = UVal::Lit();
      return r;
    }
    case ast::ExprKind::If: {
      UVal acc;
      const ast::Expr* acc_e = nullptr;
      for (size_t i = 0; i < e.args.size(); ++i) {
        const bool branch = i % 2 == 1 || i + 1 == e.args.size();
        UVal v = Expr(*e.args[i], scope, iters);
        if (!branch) continue;
        acc = acc_e ? Same(acc, acc_e, v, e.args[i].get(), e.args[i]->span, "the branches of the if-expression", scope) : v;
        acc_e = e.args[i].get();
      }
      return acc;
    }
    default: return UVal{};  // strings, Booleans, ':' and 'end' have no unit
  }
}

// A reference walked through the instance tree without evaluating subscripts: every
// element of an array has the unit of the array.
UVal UnitChecker::Ref(const ast::Expr& e, const Node* scope, const Iters* iters) {
  const ast::RefPart& head = e.parts[0];
  if (e.parts.size() == 1 && head.subscripts.empty() && iters && iters->count(head.name)) return UVal::Lit();
  for (const auto& p : e.parts)
    for (const auto& s : p.subscripts)
      if (s && s->kind != ast::ExprKind::Number) Expr(*s, scope, iters);  // operators inside subscripts are checked too
  const Node* n = scope ? scope->Child(head.name) : nullptr;
  if (!n) {
    if (e.parts.size() == 1 && head.name == "time") {
      UVal t = UVal::Of(Seconds());
      t.soft = true;
      return t;
    }
    if (e.parts.size() == 1 && head.name == "pi") return UVal::Lit();
    if (within_) ++impure_;  // the other instances' trees are not read: only units are compared
    return UVal{};
  }
  for (size_t i = 0; i < e.parts.size(); ++i) {
    if (i > 0) {
      const std::string& name = e.parts[i].name;
      if (n->kind == Node::kClass && n->prim == Prim::Frame) {
        if (within_) ++impure_;  // a redeclared component may be a frame in one instance only
        if (name == "r") return UVal::Of(Metres(1));
        if (name == "v") return UVal::Of(Metres(1) / Seconds());
        if (name == "w") return UVal::Of(Radians() / Seconds());
        if (name == "R") return UVal::Lit();
      }
      if (n->kind != Node::kClass) return UVal{};
      n = n->Child(name);
      if (!n) {
        if (within_) ++impure_;
        return UVal{};
      }
    }
    if (n->kind == Node::kArray) {
      if (n->elems.empty()) {
        if (within_) ++impure_;  // an array sized 0 in this instance only
        return UVal{};
      }
      n = n->elems[0].get();
    }
    if (n->kind == Node::kVar) return VarUnit(n);
  }
  return UVal{};
}

void UnitChecker::Element(const ast::Expr& x, const Node* scope, const Iters* iters, UVal* acc, bool* mixed) {
  // A literal (-0.5 too) joins any unit: no need to go down (where Expr would reach it).
  if (x.kind == ast::ExprKind::Number ? depth_ < kMaxCheckDepth : IsNumber(x) && depth_ + 1 < kMaxCheckDepth) return;
  const UVal v = Expr(x, scope, iters);
  if (v.kind == UVal::Unknown) *mixed = true;
  if (v.kind != UVal::Known) return;
  if (acc->kind != UVal::Known) *acc = v;
  else if (!acc->unit.Agrees(v.unit)) *mixed = true;  // an array of several units: allowed, unchecked
}

UVal UnitChecker::Same(const UVal& a, const ast::Expr* ea, const UVal& b, const ast::Expr* eb, Span at,
                       const char* what, const Node* scope) {
  if (a.kind == UVal::Known && b.kind == UVal::Known) {
    if (a.unit.Agrees(b.unit) || b.soft) {
      if (a.text || !b.text || b.soft || a.unit.twice != b.unit.twice) return a;
      UVal r = a;  // -k * x + F: the sum shown as F's declared unit ("N"), not in SI form
      r.text = b.text;
      return r;
    }
    if (a.soft) return b;
    if (ReportConflict(a, b, at) || ReportConflict(b, a, at)) return UVal{};
    auto& d = diags_.Error(DiagCode::UnitMismatch, at, std::string(what) + " have different units: " + Shown(a) + " and " + Shown(b));
    NoteOrigin(d, a);
    NoteOrigin(d, b);
    d.hint = a.unit.SameDimension(b.unit) ? "same dimension, different scale: convert one of them"
                                          : "both sides must be in one unit; check the operands' declarations";
    return UVal{};
  }
  if (a.kind == UVal::Known) {
    InferDown(eb, a, scope, at);
    return a;
  }
  if (b.kind == UVal::Known) {
    InferDown(ea, b, scope, at);
    return b;
  }
  return a.kind == UVal::Literal && b.kind == UVal::Literal ? UVal::Lit() : UVal{};
}

bool UnitChecker::ReportConflict(const UVal& inferred, const UVal& other, Span at) {
  if (!inferred.origin) return false;
  auto it = inferred_.find(inferred.origin);
  if (it == inferred_.end() || !it->second.from_use || !it->second.val.unit.Agrees(inferred.unit)) return false;
  const Node* n = inferred.origin;
  auto& d = diags_.Error(DiagCode::UnitConflict, at,
                         "'" + n->Path() + "' has no unit and is used here as " + Shown(other) + ", but earlier as " +
                             Shown(inferred));
  d.notes.push_back({it->second.where, "used as " + Shown(inferred) + " here"});
  NoteOrigin(d, other);
  d.hint = "declare its unit: " + n->name + "(unit = \"...\")";
  return true;
}

UVal UnitChecker::NeedDimensionless(const UVal& a, const ast::Expr& arg, const std::string& fn, UVal result) {
  if (a.kind == UVal::Literal) return UVal::Lit();
  if (a.kind == UVal::Known && a.soft) return result;  // sin(time): time read as a number, the sine one
  if (a.kind == UVal::Known && !(a.unit.Dimensionless() && a.unit.Agrees(Unit::One()) )) {
    // An angle in rad is dimensionless; one in deg is not a number sin can take (scale pi/180).
    Unit plain = a.unit;
    plain.twice[Unit::kRad] = 0;
    if (!(plain.Dimensionless() && a.unit.scale == 1)) {
      auto& d = diags_.Error(DiagCode::UnitMismatch, arg.span,
                             "'" + fn + "' needs a dimensionless argument (an angle in rad is one), but this has unit " +
                                 Shown(a));
      NoteOrigin(d, a);
      d.hint = a.unit.Dimensionless() ? "convert the angle to rad" : "divide by a quantity in " + Shown(a) + " first";
      return UVal{};  // reported once, not again where the result is used
    }
  }
  return result;
}

UVal UnitChecker::Call(const ast::Expr& e, const Node* scope, const Iters* iters) {
  static const std::string kNone;
  const std::string& fn = e.parts.empty() ? kNone : e.parts.back().name;
  SmallVec<UVal, 4> a;
  for (const auto& x : e.args) a.push_back(Expr(*x, scope, iters));
  for (const auto& na : e.named_args)
    if (na.value) Expr(*na.value, scope, iters);
  const UVal x = a.empty() ? UVal{} : a[0];
  switch (FnOf(fn)) {
    case Fn::Dimensionless: return a.empty() ? UVal{} : NeedDimensionless(x, *e.args[0], fn, UVal::Of(Unit::One()));
    case Fn::Inverse: return a.empty() ? UVal{} : NeedDimensionless(x, *e.args[0], fn, UVal::Of(Radians()));
    case Fn::Atan2:
      if (a.size() == 2) Same(a[0], e.args[0].get(), a[1], e.args[1].get(), e.span, "the two arguments of 'atan2'", scope);
      return UVal::Of(Radians());
    case Fn::Sqrt: {
      if (x.kind != UVal::Known) return x.kind == UVal::Literal ? UVal::Lit() : UVal{};
      for (auto t : x.unit.twice)
        if (t % 2) return UVal{};  // a quarter power: beyond what is kept
      UVal r = UVal::Of(x.unit.Pow(1, 2));
      r.soft = x.soft;
      return r;
    }
    case Fn::Der: return x.kind == UVal::Known ? UVal::Of(x.unit / Seconds()) : x;
    case Fn::Pair:
      if (a.size() == 2)
        return Same(a[0], e.args[0].get(), a[1], e.args[1].get(), e.span,
                    Is(fn, "min") ? "the arguments of 'min'" : Is(fn, "max") ? "the arguments of 'max'" : "the arguments of 'mod'",
                    scope);
      return x;
    case Fn::Keep: {
      if (x.kind != UVal::Known) return x;
      UVal r = UVal::Of(x.unit);
      r.soft = x.soft;
      return r;
    }
    case Fn::Fill: return x;
    case Fn::Product: {
      if (a.size() != 2 || a[0].kind == UVal::Unknown || a[1].kind == UVal::Unknown) return UVal{};
      if (a[0].kind == UVal::Literal && a[1].kind == UVal::Literal) return UVal::Lit();
      const Unit ua = a[0].kind == UVal::Known ? a[0].unit : Unit::One();
      const Unit ub = a[1].kind == UVal::Known ? a[1].unit : Unit::One();
      return UVal::Of(ua * ub);
    }
    case Fn::Plain: return UVal::Lit();
    case Fn::MeshVolume: return UVal::Of(Metres(3));
    case Fn::MeshCentre: return UVal::Of(Metres(1));
    case Fn::MeshInertia: return UVal::Of(Metres(5));
    case Fn::Cat: {  // the arguments were checked above; their units joined here
      UVal acc = UVal::Lit();
      bool mixed = false;
      for (size_t i = 1; i < a.size(); ++i) {
        if (a[i].kind == UVal::Unknown) mixed = true;
        if (a[i].kind != UVal::Known) continue;
        if (acc.kind != UVal::Known) acc = a[i];
        else if (!acc.unit.Agrees(a[i].unit)) mixed = true;
      }
      return mixed ? UVal{} : acc;
    }
    case Fn::Other: break;
  }
  return UVal{};
}

UVal UnitChecker::Operator(const ast::Expr& e, const Node* scope, const Iters* iters) {
  const Tok op = static_cast<Tok>(e.op);
  if (e.kind == ast::ExprKind::Unary) {
    UVal v = e.args.empty() ? UVal{} : Expr(*e.args[0], scope, iters);
    return op == Tok::KwNot ? UVal{} : v;
  }
  if (e.args.size() != 2) return UVal{};
  const ast::Expr& ea = *e.args[0];
  const ast::Expr& eb = *e.args[1];
  const UVal a = Expr(ea, scope, iters);
  if (op == Tok::Caret) {
    Expr(eb, scope, iters);
    if (a.kind != UVal::Known) return a;
    if (eb.kind != ast::ExprKind::Number) return a.unit.Dimensionless() && a.unit.scale == 1 ? a : UVal{};
    const double p = eb.number;
    if (!(std::abs(p) <= 64)) return UVal{};  // beyond any unit written in a model (and any int)
    UVal r;
    if (p == static_cast<int>(p)) {
      r = UVal::Of(a.unit.Pow(static_cast<int>(p), 1));
    } else if (2 * p == static_cast<int>(2 * p)) {
      for (auto t : a.unit.twice)
        if (t % 2) return UVal{};
      r = UVal::Of(a.unit.Pow(static_cast<int>(2 * p), 2));
    } else {
      return UVal{};
    }
    r.soft = a.soft;
    return r;
  }
  const UVal b = Expr(eb, scope, iters);
  switch (op) {
    case Tok::Plus:
    case Tok::Minus:
      return Same(a, &ea, b, &eb, e.span, op == Tok::Plus ? "the operands of '+'" : "the operands of '-'", scope);
    case Tok::Lt:
    case Tok::Le:
    case Tok::Gt:
    case Tok::Ge:
    case Tok::EqEq:
    case Tok::Ne: Same(a, &ea, b, &eb, e.span, "the compared values", scope); return UVal{};
    case Tok::Star:
    case Tok::Slash: {
      if (a.kind == UVal::Unknown || b.kind == UVal::Unknown) return UVal{};
      if (a.kind == UVal::Literal && b.kind == UVal::Literal) return UVal::Lit();
      // A number beside a quantity: in a binding or modifier a plain factor, unit "1"
      // (Modelica's unit inference: an operand of empty unit next to one of non-empty unit
      // is inferred as "1"), so L = 2 * mass is a mass. In an equation it may carry the
      // unit its context needs (a force law's coefficient, -0.3 * j.u as a torque, as
      // imported URDF dynamics write it), so that product is left open.
      if (a.kind == UVal::Literal || b.kind == UVal::Literal) {
        if (!factors_) return UVal{};
        const UVal& q = a.kind == UVal::Known ? a : b;
        const bool inverted = op == Tok::Slash && a.kind == UVal::Literal;  // 2 / t
        UVal r = q;
        if (inverted) {
          r.unit = Unit::One() / q.unit;
          r.text = nullptr;
        }
        return r;
      }
      const Unit ua = a.kind == UVal::Known ? a.unit : Unit::One();
      const Unit ub = b.kind == UVal::Known ? b.unit : Unit::One();
      UVal r = UVal::Of(op == Tok::Star ? ua * ub : ua / ub);
      r.origin = a.kind == UVal::Known ? a.origin : b.origin;
      r.soft = a.soft && b.soft;
      return r;
    }
    default: return UVal{};  // and, or
  }
}

UnitCheck::UnitCheck(const InstanceTree& tree, const Links& links, const SourceManager* sources)
    : found_(sources), checker_(std::make_unique<UnitChecker>(found_)) {
  checker_->SpringUnits(tree, links);
}

UnitCheck::~UnitCheck() = default;

void UnitCheck::Visit(Node* var) { checker_->Show(var); }

void UnitCheck::Finish(const InstanceTree& tree, Diagnostics& diags, flat::Mechanism* m) {
  checker_->Flush();
  if (diags.HasErrors()) return;
  // The messages, in the order found (the cap's message P105 becomes diags' own).
  for (const Diagnostic& d : found_.All()) {
    Diagnostic& copy = d.severity == Severity::Error ? diags.Error(d.code, d.span, d.message)
                                                     : diags.Warning(d.code, d.span, d.message);
    copy.notes = d.notes;
    copy.hint = d.hint;
  }
  // Outputs' units (for --units-in-header): the top-level model's output variables, named
  // by path, array elements "path[k]" (lang/elab_emit.cpp).
  const Node* root = tree.root.get();
  size_t i = 0;
  for (const auto& c : root->children) {
    if (!c->enabled || c->kind != Node::kVar || c->causality != ast::Causality::Output) continue;
    const UVal u = checker_->VarUnit(c.get());
    const std::string path = c->Path();
    auto named = [&](const std::string& n) {
      return n == path || (n.size() > path.size() && n.compare(0, path.size(), path) == 0 && n[path.size()] == '[');
    };
    for (; i < m->outputs.size() && named(m->outputs[i].name); ++i)
      if (u.kind == UVal::Known) m->outputs[i].unit = u.text ? *u.text : u.unit.ToString();
  }
  // Parameters and inputs that declare no unit take the inferred one (an FMU's variables and
  // UnitDefinitions, --emit flat, check): one pass, and only when something was inferred.
  const auto inferred = checker_->InferredByPath();
  if (inferred.empty()) return;
  for (size_t k = 0; k < m->params.size(); ++k) {
    flat::Param& p = m->params[k];
    if (!p.unit.empty() || p.type != flat::ParamType::Real) continue;
    if (auto it = inferred.find(m->ParamName(k)); it != inferred.end()) p.unit = it->second;
  }
  for (flat::Input& in : m->inputs)
    if (auto it = inferred.find(in.name); in.unit.empty() && it != inferred.end()) in.unit = it->second;
}

}  // namespace kanesim::lang::elab
