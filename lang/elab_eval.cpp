// Expression evaluation for the elaborator: AST expressions become Values (arrays of
// scalar flat expressions). Parameters stay symbolic (Param nodes) so that a sweep can
// change them without elaborating again; constants fold. Operators are in
// lang/elab_operators.cpp, built-in functions in lang/elab_builtins.cpp.
#include <cmath>
#include <cstdio>
#include <functional>

#include "lang/elab_eval.h"
#include "lang/lexer.h"

namespace kanesim::lang::elab {

using flat::Op;

const char* VTypeName(VType t) {
  switch (t) {
    case VType::Real: return "Real";
    case VType::Integer: return "Integer";
    case VType::Boolean: return "Boolean";
    case VType::String: return "String";
  }
  return "?";
}

size_t Value::Size() const {
  size_t n = 1;
  for (int d : shape) n *= static_cast<size_t>(d);
  return n;
}

Evaluator::Evaluator(flat::Mechanism* m, const SourcePlaces& places, Diagnostics& diags)
    : m_(m), places_(places), diags_(diags) {}

Value Evaluator::Const(double x, VType t) {
  Value v;
  v.type = t;
  v.elements.push_back(m_->exprs.Constant(x));
  return v;
}

Value Evaluator::Scalar(ExprId e, VType t) {
  Value v;
  v.type = t;
  v.elements.push_back(e);
  return v;
}

// Marks every parameter that `id` reads as structural. Nodes already walked are marked
// in structural_seen_ and never walked again, so all calls together cost O(pool size).
void Evaluator::MarkStructural(ExprId id) {
  const auto& pool = m_->exprs;
  if (structural_seen_.size() < pool.size()) structural_seen_.resize(pool.size(), 0);
  std::vector<ExprId>& stack = structural_stack_;  // scratch, empty between calls
  stack.assign(1, id);
  while (!stack.empty()) {
    ExprId x = stack.back();
    stack.pop_back();
    if (x < 0 || structural_seen_[static_cast<size_t>(x)]) continue;
    structural_seen_[static_cast<size_t>(x)] = 1;
    const auto& n = pool[x];
    if (n.op == Op::Param) m_->params[static_cast<size_t>(n.index)].structural = true;
    for (ExprId c : {n.a, n.b, n.c})
      if (c >= 0) stack.push_back(c);
  }
}

bool Evaluator::Structural(const Value& v, Span span, double* out, const char* what) {
  if (!v.valid) return false;
  if (v.type == VType::String || v.Size() != 1 || !v.shape.empty()) {
    diags_.Error(DiagCode::TypeMismatch, span, std::string(what) + " must be a scalar number");
    return false;
  }
  ExprId e = v.elements[0];
  if (m_->exprs.DependsOnTimeOrState(e)) {
    diags_.Error(DiagCode::NotConstantExpr, span,
                 std::string(what) + " must be known before the simulation starts, but it depends on time or state")
        .hint = "use parameters and constants only";
    return false;
  }
  MarkStructural(e);
  *out = param_eval_.Eval(e);
  if (!std::isfinite(*out)) {
    diags_.Error(DiagCode::BadValue, span, std::string(what) + " is not a finite number");
    return false;
  }
  return true;
}

namespace {
// A number as a user wrote it (%.15g: 3, 2.5, 1e+28), not std::to_string's fixed six decimals.
std::string ShortNumber(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.15g", x);
  return buf;
}
}  // namespace

bool Evaluator::StructuralInt(const Value& v, Span span, long* out, const char* what) {
  double x = 0;
  if (!Structural(v, span, &x, what)) return false;
  if (std::fabs(x) > 9e15 || x != std::floor(x)) {
    diags_.Error(DiagCode::TypeMismatch, span, std::string(what) + " must be an Integer, got " + ShortNumber(x));
    return false;
  }
  *out = static_cast<long>(x);
  return true;
}

bool Evaluator::LiteralStructuralInt(const ast::Expr& e, long* out) {
  if (e.kind != ast::ExprKind::Number || !e.is_integer || std::fabs(e.number) > 9e15) return false;
  if (budget_.Exhausted() || eval_depth_ >= kMaxEvalDepth || stack_.Exceeded()) return false;
  // What EvalNested does with it: a constant node, charged as a one-element value. The
  // node reads no parameter (nothing to mark structural) and is its own value.
  m_->exprs.Constant(e.number);
  ChargeSteps(2, e.span);
  *out = static_cast<long>(e.number);
  return true;
}

Evaluator::Numbers Evaluator::StructuralList(const Value& v, Span span, const char* what) {
  Numbers out;
  if (!v.valid) return out;
  if (v.type == VType::String) {
    diags_.Error(DiagCode::TypeMismatch, span, std::string(what) + " must be numbers");
    return out;
  }
  for (ExprId e : v.elements) {
    double x = 0;
    if (!Structural(Scalar(e, v.type), span, &x, what)) return {};
    out.push_back(x);
  }
  return out;
}

// ---------------------------------------------------------------------------------------

// Operator chains (a + b + ... , - - x) are evaluated with an explicit stack by
// EvalOperators (lang/elab_operators.cpp); every other kind recurses through EvalNested,
// whose depth the parser's nesting limit and kMaxEvalDepth bound.
Value Evaluator::Eval(const ast::Expr& e, const Ctx& ctx) {
  if (e.kind == ast::ExprKind::Unary || e.kind == ast::ExprKind::Binary) return EvalOperators(e, ctx);
  return EvalNested(e, ctx);
}

Value Evaluator::EvalNode(const ast::Expr& e, const Ctx& ctx) {
  switch (e.kind) {
    case ast::ExprKind::Number: return Const(e.number, e.is_integer ? VType::Integer : VType::Real);
    case ast::ExprKind::Bool: return Const(e.number, VType::Boolean);
    case ast::ExprKind::String: {
      Value v;
      v.type = VType::String;
      v.strings.push_back(e.text);
      v.elements.push_back(flat::kNoExpr);
      return v;
    }
    case ast::ExprKind::End:
      if (!end_stack_.empty()) return Const(end_stack_.back(), VType::Integer);
      [[fallthrough]];
    case ast::ExprKind::Colon:
      diags_.Error(DiagCode::ExpectedToken, e.span, "':' and 'end' are only allowed in subscripts");
      return Value::Invalid();
    case ast::ExprKind::Ref: return EvalRef(e, ctx);
    case ast::ExprKind::Array: return EvalArray(e, ctx);
    case ast::ExprKind::Comprehension: return EvalComprehension(e, ctx);
    case ast::ExprKind::Matrix: return EvalMatrix(e, ctx);
    case ast::ExprKind::Range: return EvalRange(e, ctx);
    case ast::ExprKind::If: return EvalIf(e, ctx);
    case ast::ExprKind::Call: return EvalCall(e, ctx);
    case ast::ExprKind::Unary:
    case ast::ExprKind::Binary: return EvalOperators(e, ctx);
  }
  return Value::Invalid();
}

Value Evaluator::EvalRef(const ast::Expr& e, const Ctx& ctx) {
  const ast::RefPart& head = e.parts[0];
  const bool bare = e.parts.size() == 1 && head.subscripts.empty();
  // Loop iterators shadow everything.
  if (bare && ctx.iters) {
    auto it = ctx.iters->find(head.name);
    if (it != ctx.iters->end())
      return Const(it->second, it->second == std::floor(it->second) ? VType::Integer : VType::Real);
  }
  Node* n = ctx.scope ? ctx.scope->Child(head.name) : nullptr;
  if (!n && bare) {
    if (head.name == "time") return Scalar(m_->exprs.Time());
    if (head.name == "pi") return Const(M_PI);
  }
  if (!n) {
    ReportUnknownName(head, ctx);
    return Value::Invalid();
  }
  // Walk the reference through the instance tree.
  for (size_t pi = 0; pi < e.parts.size(); ++pi) {
    const ast::RefPart& part = e.parts[pi];
    if (pi > 0) {
      if (IsFrameMotion(n, part.name)) return FrameMotion(e, pi, n, ctx);
      n = Member(n, part);
      if (!n) return Value::Invalid();
    }
    if (!n->enabled) {
      diags_.Error(DiagCode::UnknownName, part.span,
                   "'" + n->Path() + "' is disabled by its condition and cannot be used");
      return Value::Invalid();
    }
    if (n->kind == Node::kArray) {
      n = ArrayElement(n, part, ctx);
      if (!n) return Value::Invalid();
      continue;
    }
    if (n->kind == Node::kVar) return VarReference(e, pi, n, ctx);
    if (!part.subscripts.empty()) {
      diags_.Error(DiagCode::TypeMismatch, part.span, "'" + n->Path() + "' is not an array");
      return Value::Invalid();
    }
  }
  diags_.Error(DiagCode::TypeMismatch, e.span,
               "'" + n->Path() + "' is a component, not a value")
      .hint = "components are used in connect(); their parameters and variables are values";
  return Value::Invalid();
}

void Evaluator::ReportUnknownName(const ast::RefPart& head, const Ctx& ctx) {
  std::vector<std::string> cands{"time", "pi"};
  if (ctx.scope)
    for (auto& c : ctx.scope->children) cands.push_back(c->decl ? c->decl->name : c->name);
  if (ctx.iters)
    for (auto& [k, v] : *ctx.iters) cands.push_back(k);
  auto& d = diags_.Error(DiagCode::UnknownName, head.span, "unknown name '" + head.name + "'");
  std::string best = ClosestName(head.name, cands);
  if (!best.empty()) d.hint = "did you mean '" + best + "'?";
}

// Frame connectors expose their motion: r (position), R (orientation), v (velocity),
// w (angular velocity), all resolved in the world.
bool Evaluator::IsFrameMotion(const Node* n, const std::string& name) {
  return n->kind == Node::kClass && n->prim == Prim::Frame &&
         (name == "r" || name == "R" || name == "v" || name == "w");
}

Value Evaluator::FrameMotion(const ast::Expr& e, size_t pi, const Node* frame, const Ctx& ctx) {
  const ast::RefPart& part = e.parts[pi];
  Value v;
  flat::StateKind kind = part.name == "r"   ? flat::StateKind::FramePosition
                         : part.name == "R" ? flat::StateKind::FrameRotation
                         : part.name == "v" ? flat::StateKind::FrameVelocity
                                            : flat::StateKind::FrameAngVel;
  int count = part.name == "R" ? 9 : 3;
  v.shape = part.name == "R" ? Dims{3, 3} : Dims{3};
  for (int k = 0; k < count; ++k)
    v.elements.push_back(m_->exprs.State(m_->AddStateRef({kind, frame->prim_index, k})));
  if (pi + 1 != e.parts.size()) {
    diags_.Error(DiagCode::UnknownName, e.parts[pi + 1].span, "'" + part.name + "' has no members");
    return Value::Invalid();
  }
  if (part.subscripts.empty()) return v;
  return SubscriptFrameMotion(v, part, ctx);
}

Value Evaluator::SubscriptFrameMotion(const Value& v, const ast::RefPart& part, const Ctx& ctx) {
  std::vector<std::vector<int>> idx;
  std::vector<bool> keep;
  for (size_t d = 0; d < part.subscripts.size() && d < v.shape.size(); ++d) {
    const ast::Expr& s = *part.subscripts[d];
    std::vector<int> list;
    if (s.kind == ast::ExprKind::Colon) {
      for (int k = 0; k < v.shape[d]; ++k) list.push_back(k);
      keep.push_back(true);
    } else {
      long k = 0;
      if (!StructuralInt(Eval(s, ctx), s.span, &k, "a subscript")) return Value::Invalid();
      if (k < 1 || k > v.shape[d]) {
        diags_.Error(DiagCode::IndexOutOfRange, s.span,
                     "index " + std::to_string(k) + " is out of range 1.." + std::to_string(v.shape[d]));
        return Value::Invalid();
      }
      list.push_back(static_cast<int>(k - 1));
      keep.push_back(false);
    }
    idx.push_back(list);
  }
  if (part.subscripts.size() > v.shape.size()) {
    diags_.Error(DiagCode::IndexOutOfRange, part.span, "too many subscripts");
    return Value::Invalid();
  }
  Value out;
  out.type = VType::Real;
  if (v.shape.size() == 1) {
    for (int i : idx[0]) out.elements.push_back(v.elements[static_cast<size_t>(i)]);
    if (keep[0]) out.shape = {static_cast<int>(idx[0].size())};
    return out;
  }
  std::vector<int> cols;
  if (idx.size() > 1) cols = idx[1];
  else for (int k = 0; k < 3; ++k) cols.push_back(k);
  bool keepc = idx.size() > 1 ? keep[1] : true;
  for (int i : idx[0])
    for (int j : cols) out.elements.push_back(v.elements[static_cast<size_t>(i * 3 + j)]);
  if (keep[0]) out.shape.push_back(static_cast<int>(idx[0].size()));
  if (keepc) out.shape.push_back(static_cast<int>(cols.size()));
  return out;
}

Node* Evaluator::Member(Node* n, const ast::RefPart& part) {
  if (n->kind != Node::kClass) {
    diags_.Error(DiagCode::UnknownName, part.span, "'" + n->Path() + "' has no member '" + part.name + "'");
    return nullptr;
  }
  Node* c = n->Child(part.name);
  if (c) return c;
  std::vector<std::string> cands;
  for (auto& ch : n->children) cands.push_back(ch->decl ? ch->decl->name : ch->name);
  if (n->prim == Prim::Frame) cands.insert(cands.end(), {"r", "R", "v", "w"});
  auto& d = diags_.Error(DiagCode::UnknownName, part.span, "'" + n->Path() + "' has no member '" + part.name + "'");
  std::string best = ClosestName(part.name, cands);
  if (!best.empty()) d.hint = "did you mean '" + best + "'?";
  return nullptr;
}

Node* Evaluator::ArrayElement(Node* array, const ast::RefPart& part, const Ctx& ctx) {
  if (part.subscripts.size() != 1) {
    diags_.Error(DiagCode::TypeMismatch, part.span,
                 "'" + array->Path() + "' is an array of components; index it with one subscript");
    return nullptr;
  }
  long k = 0;
  end_stack_.push_back(static_cast<int>(array->elems.size()));
  Value kv = Eval(*part.subscripts[0], ctx);
  end_stack_.pop_back();
  if (!StructuralInt(kv, part.subscripts[0]->span, &k, "a subscript")) return nullptr;
  if (k < 1 || k > static_cast<long>(array->elems.size())) {
    diags_.Error(DiagCode::IndexOutOfRange, part.subscripts[0]->span,
                 "index " + std::to_string(k) + " is out of range 1.." + std::to_string(array->elems.size()) +
                     " of '" + array->Path() + "'");
    return nullptr;
  }
  return array->elems[static_cast<size_t>(k - 1)].get();
}

Value Evaluator::VarReference(const ast::Expr& e, size_t pi, Node* var, const Ctx& ctx) {
  const ast::RefPart& part = e.parts[pi];
  Value v = GetVar(var, part.span);
  if (!v.valid) return v;
  if (pi + 1 != e.parts.size()) {
    diags_.Error(DiagCode::UnknownName, e.parts[pi + 1].span, "'" + var->Path() + "' is a variable and has no members");
    return Value::Invalid();
  }
  if (part.subscripts.empty()) return v;
  return SubscriptValue(v, part, var, ctx);
}

Value Evaluator::SubscriptValue(const Value& v, const ast::RefPart& part, const Node* var, const Ctx& ctx) {
  if (part.subscripts.size() > v.shape.size()) {
    diags_.Error(DiagCode::IndexOutOfRange, part.span,
                 "'" + var->Path() + "' has " + std::to_string(v.shape.size()) + " dimension(s)");
    return Value::Invalid();
  }
  // Each dimension's 0-based indices, one list after another in `all` (dimension d's from
  // first[d] to first[d + 1]): no heap allocation for the usual x[i] and R[i, j].
  const size_t dims = v.shape.size();
  SubscriptList all;
  SmallVec<std::uint32_t, 4> first;
  Value r;
  r.type = v.type;
  for (size_t d = 0; d < dims; ++d) {
    first.push_back(static_cast<std::uint32_t>(all.size()));
    bool kp = true;
    if (d < part.subscripts.size() && part.subscripts[d]->kind != ast::ExprKind::Colon) {
      if (!SubscriptIndices(*part.subscripts[d], v.shape[d], var, ctx, &all, &kp)) return Value::Invalid();
    } else {
      for (int k = 0; k < v.shape[d]; ++k) all.push_back(k);
    }
    if (kp) r.shape.push_back(static_cast<int>(all.size() - first[d]));
  }
  first.push_back(static_cast<std::uint32_t>(all.size()));
  for (size_t d = 0; d < dims; ++d)
    if (first[d] == first[d + 1]) return r;  // nothing selected
  SmallVec<size_t, 4> strides;
  strides.assign(dims, 1);
  for (size_t d = dims; d-- > 1;) strides[d - 1] = strides[d] * static_cast<size_t>(v.shape[d]);
  // The cartesian product of the lists, the last dimension fastest (row-major).
  SmallVec<std::uint32_t, 4> at;
  at.assign(dims, 0);
  while (true) {
    size_t off = 0;
    for (size_t d = 0; d < dims; ++d) off += static_cast<size_t>(all[first[d] + at[d]]) * strides[d];
    r.elements.push_back(v.elements[off]);
    if (v.type == VType::String) r.strings.push_back(v.strings[off]);
    size_t d = dims;
    for (; d > 0; --d) {
      if (++at[d - 1] < first[d] - first[d - 1]) break;
      at[d - 1] = 0;
    }
    if (d == 0) break;
  }
  return r;
}

bool Evaluator::SubscriptIndices(const ast::Expr& s, int size, const Node* var, const Ctx& ctx, SubscriptList* list,
                                 bool* keep) {
  if (s.kind == ast::ExprKind::End) {
    list->push_back(size - 1);
    *keep = false;
    return true;
  }
  end_stack_.push_back(size);
  Value sv = Eval(s, ctx);
  end_stack_.pop_back();
  if (!sv.valid) return false;
  const Numbers ks = StructuralList(sv, s.span, "a subscript");
  if (ks.empty()) return false;
  *keep = !sv.shape.empty();
  for (double kd : ks) {
    // Compare as doubles first: casting an out-of-range double is undefined.
    if (!(kd == std::floor(kd) && kd >= 1 && kd <= size)) {
      diags_.Error(DiagCode::IndexOutOfRange, s.span,
                   "index " + ShortNumber(kd) + " is out of range 1.." + std::to_string(size) + " of '" +
                       var->Path() + "'");
      return false;
    }
    list->push_back(static_cast<int>(kd) - 1);
  }
  return true;
}

Value Evaluator::EvalArray(const ast::Expr& e, const Ctx& ctx) {
  Value r;
  r.type = VType::Integer;
  bool first = true;
  Dims elem_shape;
  for (const auto& a : e.args) {
    Value v = Eval(*a, ctx);
    if (!v.valid) return Value::Invalid();
    if (first) {
      elem_shape = v.shape;
      r.type = v.type;
      first = false;
    } else {
      if (v.shape != elem_shape) {
        diags_.Error(DiagCode::SizeMismatch, a->span, "array elements have different sizes (" +
                                                          ShapeStr(elem_shape) + " and " + ShapeStr(v.shape) + ")")
            .hint = "{a, b} makes each element a row of a new dimension; to join arrays end to end write "
                    "cat(1, a, b) or [a; b]";
        return Value::Invalid();
      }
      if ((r.type == VType::String) != (v.type == VType::String) ||
          (r.type == VType::Boolean) != (v.type == VType::Boolean)) {
        diags_.Error(DiagCode::TypeMismatch, a->span, "array elements have different types");
        return Value::Invalid();
      }
      r.type = r.type == VType::String || r.type == VType::Boolean ? r.type : Promote(r.type, v.type);
    }
    r.elements.insert(r.elements.end(), v.elements.begin(), v.elements.end());
    r.strings.insert(r.strings.end(), v.strings.begin(), v.strings.end());
  }
  if (e.args.empty()) r.type = VType::Real;
  r.shape.push_back(static_cast<int>(e.args.size()));
  r.shape.insert(r.shape.end(), elem_shape.begin(), elem_shape.end());
  if (r.Size() > static_cast<size_t>(kMaxArraySize)) {
    diags_.Error(DiagCode::ArrayTooLarge, e.span, "array too large");
    return Value::Invalid();
  }
  return r;
}

Value Evaluator::EvalComprehension(const ast::Expr& e, const Ctx& ctx) {
  Value range = Eval(*e.args[1], ctx);
  if (!range.valid) return Value::Invalid();
  if (range.Size() > static_cast<size_t>(kMaxArraySize)) {
    diags_.Error(DiagCode::ArrayTooLarge, e.args[1]->span,
                 "range has " + std::to_string(range.Size()) + " elements; the limit is " +
                     std::to_string(kMaxArraySize));
    return Value::Invalid();
  }
  const Numbers xs = StructuralList(range, e.args[1]->span, "the iteration range");
  Iters local = ctx.iters ? *ctx.iters : Iters{};
  Value r;
  r.type = VType::Integer;
  Dims elem_shape;
  for (size_t i = 0; i < xs.size(); ++i) {
    if (!ChargeSteps(1, e.span)) return Value::Invalid();
    local[e.text] = xs[i];
    Ctx c2{ctx.scope, &local};
    Value v = Eval(*e.args[0], c2);
    if (!v.valid) return Value::Invalid();
    if (i == 0) {
      elem_shape = v.shape;
      r.type = v.type;
    } else if (v.shape != elem_shape) {
      diags_.Error(DiagCode::SizeMismatch, e.args[0]->span, "comprehension elements have different sizes");
      return Value::Invalid();
    } else if (r.type != VType::String && r.type != VType::Boolean) {
      r.type = Promote(r.type, v.type);
    }
    r.elements.insert(r.elements.end(), v.elements.begin(), v.elements.end());
    r.strings.insert(r.strings.end(), v.strings.begin(), v.strings.end());
    if (r.elements.size() > static_cast<size_t>(kMaxArraySize)) {
      diags_.Error(DiagCode::ArrayTooLarge, e.span,
                   "the comprehension has more than " + std::to_string(kMaxArraySize) + " elements");
      return Value::Invalid();
    }
  }
  if (xs.empty()) r.type = VType::Real;
  r.shape.push_back(static_cast<int>(xs.size()));
  r.shape.insert(r.shape.end(), elem_shape.begin(), elem_shape.end());
  return r;
}

// EvalMatrix ([a, b; c, d]) is in elab_concat.cpp, with cat().

Value Evaluator::EvalRange(const ast::Expr& e, const Ctx& ctx) {
  auto& pool = m_->exprs;
  std::vector<double> xs;
  double a = 0, b = 0, step = 1;
  Value va = Eval(*e.args[0], ctx);
  if (!Structural(va, e.args[0]->span, &a, "a range bound")) return Value::Invalid();
  if (e.args.size() == 3) {
    if (!Structural(Eval(*e.args[1], ctx), e.args[1]->span, &step, "a range step")) return Value::Invalid();
    if (!Structural(Eval(*e.args[2], ctx), e.args[2]->span, &b, "a range bound")) return Value::Invalid();
  } else {
    if (!Structural(Eval(*e.args[1], ctx), e.args[1]->span, &b, "a range bound")) return Value::Invalid();
  }
  if (step == 0) {
    diags_.Error(DiagCode::BadValue, e.span, "range step is zero");
    return Value::Invalid();
  }
  double count = std::floor((b - a) / step + 1e-10) + 1;
  if (!(count <= static_cast<double>(kMaxArraySize))) {  // also NaN: never cast an unchecked double
    char n[32];
    std::snprintf(n, sizeof n, "%.4g", count);
    diags_.Error(DiagCode::ArrayTooLarge, e.span,
                 std::string("range has ") + n + " elements; the limit is " + std::to_string(kMaxArraySize));
    return Value::Invalid();
  }
  bool integer = a == std::floor(a) && step == std::floor(step);
  Value r;
  r.type = integer ? VType::Integer : VType::Real;
  long n = count > 0 ? static_cast<long>(count) : 0;
  for (long i = 0; i < n; ++i) r.elements.push_back(pool.Constant(a + static_cast<double>(i) * step));
  r.shape = {static_cast<int>(n)};
  return r;
}

Value Evaluator::EvalIf(const ast::Expr& e, const Ctx& ctx) {
  auto& pool = m_->exprs;
  // Evaluate from the last else backwards, building IfElse nodes.
  Value acc = Eval(*e.args.back(), ctx);
  if (!acc.valid) return Value::Invalid();
  for (size_t i = e.args.size() - 1; i >= 2; i -= 2) {
    const ast::Expr& ce = *e.args[i - 2];
    Value c = Eval(ce, ctx);
    Value t = Eval(*e.args[i - 1], ctx);
    if (!c.valid || !t.valid) return Value::Invalid();
    if (c.type != VType::Boolean || !c.shape.empty()) {
      diags_.Error(DiagCode::TypeMismatch, ce.span, "the condition must be a scalar Boolean");
      return Value::Invalid();
    }
    if (t.shape != acc.shape || (t.type == VType::String) != (acc.type == VType::String)) {
      // Branches of different sizes: the condition decides structure.
      double cv = 0;
      if (!Structural(c, ce.span, &cv, "the condition of an if-expression with branches of different sizes"))
        return Value::Invalid();
      if (cv != 0) acc = t;
      continue;
    }
    if (t.type == VType::String) {
      double cv = 0;
      if (!Structural(c, ce.span, &cv, "the condition choosing a String")) return Value::Invalid();
      if (cv != 0) acc = t;
      continue;
    }
    Value r;
    r.type = (t.type == VType::Boolean && acc.type == VType::Boolean) ? VType::Boolean : Promote(t.type, acc.type);
    r.shape = t.shape;
    for (size_t k = 0; k < t.elements.size(); ++k)
      r.elements.push_back(pool.IfElse(c.elements[0], t.elements[k], acc.elements[k]));
    acc = r;
  }
  return acc;
}

}  // namespace kanesim::lang::elab
