// Built-in functions, in one table {name, arity, lowering}. EvalCall evaluates the
// arguments, finds the name in the table, checks the number of arguments when it is fixed,
// and calls the lowering, which turns the argument Values into pool expressions
// (parameters stay symbolic, constants fold). A name not in the table is diagnosed with
// the closest one from the table as a suggestion.
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "lang/elab_eval.h"

namespace kanesim::lang::elab {

using flat::Op;

namespace {

// One call being lowered, with the checks its lowering shares with others (each reports
// its diagnostic and returns false).
struct Call {
  Evaluator& el;
  Diagnostics& diags;
  flat::ExprPool& pool;
  const ast::Expr& expr;
  const std::string& fn;
  const std::vector<Value>& args;
  const Ctx& ctx;
  Op op;  // the table's operation, for lowerings shared by several functions

  flat::ExprPool& Pool() const { return pool; }
  bool Want(size_t n) const {
    if (args.size() == n) return true;
    diags.Error(DiagCode::BadCall, expr.span,
                    "'" + fn + "' takes " + std::to_string(n) + " argument(s), got " + std::to_string(args.size()));
    return false;
  }
  bool Numeric(const Value& v) const {
    if (v.type != VType::String) return true;
    diags.Error(DiagCode::TypeMismatch, expr.span, "'" + fn + "' needs numbers");
    return false;
  }
  bool Vec3(const Value& v) const {
    if (v.shape == Dims{3} && v.type != VType::String) return true;
    diags.Error(DiagCode::SizeMismatch, expr.span, "'" + fn + "' needs 3-vectors, got " + ShapeStr(v.shape));
    return false;
  }
};

// sin(x), abs(x), ...: elementwise; abs keeps Integer, the others give Real.
Value LowerUnary(Call& c) {
  if (!c.Numeric(c.args[0])) return Value::Invalid();
  Value r = c.args[0];
  r.type = (c.op == Op::Abs && r.type == VType::Integer) ? VType::Integer : VType::Real;
  if (c.op == Op::Sign || c.op == Op::Floor || c.op == Op::Ceil) r.type = VType::Real;
  for (auto& x : r.elements) x = c.Pool().Unary(c.op, x);
  return r;
}

// atan2(a, b), mod(a, b), min(a, b), max(a, b): elementwise.
Value LowerBinary(Call& c) {
  if (!c.Numeric(c.args[0]) || !c.Numeric(c.args[1])) return Value::Invalid();
  VType t = c.op == Op::Atan2 ? VType::Real : Promote(c.args[0].type, c.args[1].type);
  return c.el.Elementwise2(c.args[0], c.args[1], c.op, t, c.expr.span);
}

// sum(A), min(A), max(A): over the elements of A.
Value LowerReduce(Call& c) {
  if (!c.Numeric(c.args[0])) return Value::Invalid();
  const Value& v = c.args[0];
  if (v.elements.empty()) return c.el.Const(0);
  ExprId acc = v.elements[0];
  for (size_t i = 1; i < v.elements.size(); ++i) acc = c.Pool().Binary(c.op, acc, v.elements[i]);
  return c.el.Scalar(acc, v.type == VType::Integer ? VType::Integer : VType::Real);
}

// min and max take two arguments (elementwise) or one (over its elements).
Value LowerMinMax(Call& c) {
  if (c.args.size() == 2) return LowerBinary(c);
  if (!c.Want(1)) return Value::Invalid();
  return LowerReduce(c);
}

Value LowerInteger(Call& c) {
  if (!c.Numeric(c.args[0])) return Value::Invalid();
  Value r = c.args[0];
  for (auto& x : r.elements) x = c.Pool().Unary(Op::Floor, x);
  r.type = VType::Integer;
  return r;
}

Value LowerCross(Call& c) {
  if (!c.Vec3(c.args[0]) || !c.Vec3(c.args[1])) return Value::Invalid();
  auto& pool = c.Pool();
  const auto& a = c.args[0].elements;
  const auto& b = c.args[1].elements;
  Value r;
  r.shape = {3};
  auto m = [&](int i, int j) { return pool.Binary(Op::Mul, a[static_cast<size_t>(i)], b[static_cast<size_t>(j)]); };
  r.elements = {pool.Binary(Op::Sub, m(1, 2), m(2, 1)), pool.Binary(Op::Sub, m(2, 0), m(0, 2)),
         pool.Binary(Op::Sub, m(0, 1), m(1, 0))};
  return r;
}

Value LowerSkew(Call& c) {
  if (!c.Vec3(c.args[0])) return Value::Invalid();
  auto& pool = c.Pool();
  const auto& a = c.args[0].elements;
  ExprId z = pool.Constant(0);
  Value r;
  r.shape = {3, 3};
  r.elements = {z, pool.Unary(Op::Neg, a[2]), a[1], a[2], z, pool.Unary(Op::Neg, a[0]),
                pool.Unary(Op::Neg, a[1]), a[0], z};
  return r;
}

// sum_i a_i b_i into *s, for dot and norm.
bool InnerProduct(Call& c, const Value& a, const Value& b, ExprId* s) {
  if (a.shape.size() != 1 || a.shape != b.shape || !c.Numeric(a) || !c.Numeric(b)) {
    c.diags.Error(DiagCode::SizeMismatch, c.expr.span, "'" + c.fn + "' needs vectors of equal length");
    return false;
  }
  auto& pool = c.Pool();
  *s = pool.Binary(Op::Mul, a.elements[0], b.elements[0]);
  for (size_t i = 1; i < a.elements.size(); ++i)
    *s = pool.Binary(Op::Add, *s, pool.Binary(Op::Mul, a.elements[i], b.elements[i]));
  return true;
}

Value LowerDot(Call& c) {
  ExprId s = 0;
  if (!InnerProduct(c, c.args[0], c.args[1], &s)) return Value::Invalid();
  return c.el.Scalar(s, Promote(c.args[0].type, c.args[1].type));
}

Value LowerNorm(Call& c) {
  ExprId s = 0;
  if (!InnerProduct(c, c.args[0], c.args[0], &s)) return Value::Invalid();
  return c.el.Scalar(c.Pool().Unary(Op::Sqrt, s), VType::Real);
}

Value LowerOuterProduct(Call& c) {
  const Value& a = c.args[0];
  const Value& b = c.args[1];
  if (a.shape.size() != 1 || b.shape.size() != 1) {
    c.diags.Error(DiagCode::SizeMismatch, c.expr.span, "'outerProduct' needs vectors");
    return Value::Invalid();
  }
  Value r;
  r.type = Promote(a.type, b.type);
  r.shape = {a.shape[0], b.shape[0]};
  for (ExprId x : a.elements)
    for (ExprId y : b.elements) r.elements.push_back(c.Pool().Binary(Op::Mul, x, y));
  return r;
}

Value LowerTranspose(Call& c) {
  const Value& a = c.args[0];
  if (a.shape.size() != 2) {
    c.diags.Error(DiagCode::SizeMismatch, c.expr.span, "'transpose' needs a matrix, got " + ShapeStr(a.shape));
    return Value::Invalid();
  }
  Value r = a;
  r.shape = {a.shape[1], a.shape[0]};
  for (int i = 0; i < a.shape[0]; ++i)
    for (int j = 0; j < a.shape[1]; ++j)
      r.elements[static_cast<size_t>(j * a.shape[0] + i)] = a.elements[static_cast<size_t>(i * a.shape[1] + j)];
  return r;
}

Value LowerVector(Call& c) {
  Value r = c.args[0];
  r.shape = {static_cast<int>(r.elements.size())};
  return r;
}

// The n-by-n matrix with `diag` on its diagonal (ones when null), zeros elsewhere.
Value DiagonalMatrix(Call& c, long n, VType type, const Elements* diag) {
  if (n < 0 || n > kMaxArraySize || n * n > kMaxArraySize) {
    c.diags.Error(DiagCode::ArrayTooLarge, c.expr.span, "matrix size out of range");
    return Value::Invalid();
  }
  auto& pool = c.Pool();
  Value r;
  r.type = type;
  r.shape = {static_cast<int>(n), static_cast<int>(n)};
  ExprId z = pool.Constant(0), one = pool.Constant(1);
  for (long i = 0; i < n; ++i)
    for (long j = 0; j < n; ++j) r.elements.push_back(i != j ? z : (diag ? (*diag)[static_cast<size_t>(i)] : one));
  return r;
}

Value LowerIdentity(Call& c) {
  long n = 0;
  if (!c.el.StructuralInt(c.args[0], c.expr.args[0]->span, &n, "the size")) return Value::Invalid();
  return DiagonalMatrix(c, n, VType::Integer, nullptr);
}

Value LowerDiagonal(Call& c) {
  if (c.args[0].shape.size() != 1 || !c.Numeric(c.args[0])) {
    c.diags.Error(DiagCode::SizeMismatch, c.expr.span, "'diagonal' needs a vector");
    return Value::Invalid();
  }
  return DiagonalMatrix(c, c.args[0].shape[0], c.args[0].type, &c.args[0].elements);
}

// The dimensions given by arguments first, first + 1, ... into r->shape.
bool Dimensions(Call& c, size_t first, Value* r) {
  if (c.args.size() <= first) {
    c.diags.Error(DiagCode::BadCall, c.expr.span, "'" + c.fn + "' needs dimensions");
    return false;
  }
  long total = 1;
  for (size_t i = first; i < c.args.size(); ++i) {
    long n = 0;
    if (!c.el.StructuralInt(c.args[i], c.expr.args[i]->span, &n, "a dimension")) return false;
    if (n < 0 || n > kMaxArraySize || (total *= (n == 0 ? 1 : n)) > kMaxArraySize) {
      c.diags.Error(DiagCode::ArrayTooLarge, c.expr.args[i]->span, "array too large");
      return false;
    }
    r->shape.push_back(static_cast<int>(n));
  }
  return true;
}

// zeros(n1, n2, ...) and ones(...): Integer arrays of one constant.
Value ConstantArray(Call& c, double x) {
  Value r;
  r.type = VType::Integer;
  if (!Dimensions(c, 0, &r)) return Value::Invalid();
  r.elements.assign(r.Size(), c.Pool().Constant(x));
  return r;
}

Value LowerZeros(Call& c) { return ConstantArray(c, 0); }
Value LowerOnes(Call& c) { return ConstantArray(c, 1); }

// fill(x, n1, n2, ...)
Value LowerFill(Call& c) {
  Value r;
  r.type = c.args.empty() ? VType::Integer : c.args[0].type;
  if (!Dimensions(c, 1, &r)) return Value::Invalid();
  size_t count = r.Size();
  if (!c.args[0].shape.empty()) {
    c.diags.Error(DiagCode::SizeMismatch, c.expr.span, "'fill' needs a scalar value");
    return Value::Invalid();
  }
  r.elements.assign(count, c.args[0].elements[0]);
  if (c.args[0].type == VType::String) r.strings.assign(count, c.args[0].strings[0]);
  return r;
}

// size(A): the vector of A's dimensions; size(A, k): its k-th.
Value LowerSize(Call& c) {
  if (c.args.size() == 1) {
    Value r;
    r.type = VType::Integer;
    for (int d : c.args[0].shape) r.elements.push_back(c.Pool().Constant(d));
    r.shape = {static_cast<int>(c.args[0].shape.size())};
    return r;
  }
  if (!c.Want(2)) return Value::Invalid();
  long k = 0;
  if (!c.el.StructuralInt(c.args[1], c.expr.args[1]->span, &k, "a dimension index")) return Value::Invalid();
  if (k < 1 || k > static_cast<long>(c.args[0].shape.size())) {
    c.diags.Error(DiagCode::IndexOutOfRange, c.expr.args[1]->span, "dimension index out of range");
    return Value::Invalid();
  }
  return c.el.Const(c.args[0].shape[static_cast<size_t>(k - 1)], VType::Integer);
}

// meshVolume / meshCentre / meshInertia(file, scale): lang/elab_mesh.cpp.
Value LowerMesh(Call& c) { return c.el.EvalMeshCall(c.fn, c.expr, c.args, c.ctx); }

// cat(k, A, B, ...): lang/elab_concat.cpp.
Value LowerCat(Call& c) { return c.el.EvalCat(c.expr, c.args); }

// `arity`: the number of arguments, checked before the lowering runs. kOwnArity: the
// function takes several counts (min, max, size, zeros, ones, fill, cat) or words its own
// message (the mesh functions), and the lowering checks.
constexpr int kOwnArity = -1;

struct Builtin {
  const char* name;
  int arity;
  Value (*lower)(Call&);
  Op op = Op::Const;  // for lowerings shared by several functions
};

// pre(x): x's value at an event's left limit. Every signal a when clause may read is
// continuous between events, and the clause's expressions are evaluated at that limit, so
// pre(x) is x there (docs/events.md); elsewhere it is refused.
Value LowerPre(Call& c) {
  if (c.el.InWhen()) return c.args[0];
  c.diags.Error(DiagCode::BadCall, c.expr.span, "'pre' is read only inside a when clause")
      .hint = "kanesim has no discrete variables: outside a when clause pre(x) would be x";
  return Value::Invalid();
}

// edge(b), change(b): only as a when clause's condition (lang/elab_when.cpp reads them there).
Value LowerEdge(Call& c) {
  c.diags.Error(DiagCode::BadCall, c.expr.span, "'" + c.fn + "' is only a when clause's condition")
      .hint = "write 'when " + c.fn + "(b) then', or 'when {" + c.fn + "(b), ...} then'";
  return Value::Invalid();
}

// The order is the order of suggestions among equally close names.
const Builtin kBuiltins[] = {
    {"sin", 1, LowerUnary, Op::Sin},
    {"cos", 1, LowerUnary, Op::Cos},
    {"tan", 1, LowerUnary, Op::Tan},
    {"asin", 1, LowerUnary, Op::Asin},
    {"acos", 1, LowerUnary, Op::Acos},
    {"atan", 1, LowerUnary, Op::Atan},
    {"atan2", 2, LowerBinary, Op::Atan2},
    {"sinh", 1, LowerUnary, Op::Sinh},
    {"cosh", 1, LowerUnary, Op::Cosh},
    {"tanh", 1, LowerUnary, Op::Tanh},
    {"exp", 1, LowerUnary, Op::Exp},
    {"log", 1, LowerUnary, Op::Log},
    {"sqrt", 1, LowerUnary, Op::Sqrt},
    {"abs", 1, LowerUnary, Op::Abs},
    {"sign", 1, LowerUnary, Op::Sign},
    {"min", kOwnArity, LowerMinMax, Op::Min},
    {"max", kOwnArity, LowerMinMax, Op::Max},
    {"floor", 1, LowerUnary, Op::Floor},
    {"ceil", 1, LowerUnary, Op::Ceil},
    {"mod", 2, LowerBinary, Op::Mod},
    {"cross", 2, LowerCross},
    {"dot", 2, LowerDot},
    {"norm", 1, LowerNorm},
    {"transpose", 1, LowerTranspose},
    {"identity", 1, LowerIdentity},
    {"diagonal", 1, LowerDiagonal},
    {"zeros", kOwnArity, LowerZeros},
    {"ones", kOwnArity, LowerOnes},
    {"fill", kOwnArity, LowerFill},
    {"size", kOwnArity, LowerSize},
    {"sum", 1, LowerReduce, Op::Add},
    {"integer", 1, LowerInteger},
    {"skew", 1, LowerSkew},
    {"outerProduct", 2, LowerOuterProduct},
    {"vector", 1, LowerVector},
    {"meshVolume", kOwnArity, LowerMesh},
    {"meshCentre", kOwnArity, LowerMesh},
    {"meshInertia", kOwnArity, LowerMesh},
    {"cat", kOwnArity, LowerCat},
    {"pre", 1, LowerPre},
    {"edge", 1, LowerEdge},
    {"change", 1, LowerEdge},
};

// The table's entry named `fn`, or null: a hash map made once per process (a scan of the
// table compared up to 39 names per call).
const Builtin* FindBuiltin(std::string_view fn) {
  static const std::unordered_map<std::string_view, const Builtin*> by_name = [] {
    std::unordered_map<std::string_view, const Builtin*> m;
    for (const Builtin& b : kBuiltins) m.emplace(b.name, &b);
    return m;
  }();
  auto it = by_name.find(fn);
  return it == by_name.end() ? nullptr : it->second;
}

}  // namespace

Value Evaluator::EvalCall(const ast::Expr& e, const Ctx& ctx) {
  // The function's name: most are one part (`sin`), read in place; a qualified one is joined.
  std::string joined;
  if (e.parts.size() > 1) {
    std::vector<std::string> v;
    for (auto& p : e.parts) v.push_back(p.name);
    joined = ast::JoinName(v);
  }
  const std::string& fn = e.parts.size() == 1 ? e.parts[0].name : joined;
  if (!e.named_args.empty()) {
    diags_.Error(DiagCode::BadCall, e.named_args[0].span, "'" + fn + "' takes no named arguments");
    return Value::Invalid();
  }
  std::vector<Value> args;
  args.reserve(e.args.size());
  for (const auto& a : e.args) {
    args.push_back(Eval(*a, ctx));
    if (!args.back().valid) return Value::Invalid();
  }
  if (const Builtin* b = FindBuiltin(fn)) {
    Call call{*this, diags_, m_->exprs, e, fn, args, ctx, b->op};
    if (b->arity != kOwnArity && !call.Want(static_cast<size_t>(b->arity))) return Value::Invalid();
    return b->lower(call);
  }
  std::vector<std::string> cands;
  for (const Builtin& b : kBuiltins) cands.push_back(b.name);
  auto& d = diags_.Error(DiagCode::BadCall, e.span, "unknown function '" + fn + "'");
  std::string best = ClosestName(fn, cands);
  if (fn == "der") d.hint = "derivatives are not written by hand: joints provide q and u";
  else if (!best.empty()) d.hint = "did you mean '" + best + "'?";
  return Value::Invalid();
}

}  // namespace kanesim::lang::elab
