// The unit check's expressions (lang/elab_units_checker.h): an expression's unit, bottom-up,
// each operator's, function's and if-branch's operands compared where they must agree.
#include "lang/elab_units_checker.h"

namespace kanesim::lang::elab {

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

}  // namespace kanesim::lang::elab
