// Operators of the elaborator: unary and binary operators on Values, and the explicit-
// stack evaluation of operator chains. A left-deep sum `1 + 1 + ... + 1` of any length
// (or a chain of unary signs) is one loop here, not one native stack frame per term.
#include "lang/elab_eval.h"
#include "lang/lexer.h"

namespace kanesim::lang::elab {

using flat::Op;

namespace {

bool SameShape(const Value& a, const Value& b) { return a.shape == b.shape; }

bool IsOperator(const ast::Expr& e) { return e.kind == ast::ExprKind::Unary || e.kind == ast::ExprKind::Binary; }

}  // namespace

// Post-order over the operator nodes of `root` with an explicit stack: an operator node
// is visited twice (first to push its operands, then to combine their values); operands
// that are not operators are evaluated by EvalNested. Operands are evaluated left to
// right, as a recursive evaluator would, so diagnostics come in source order.
Value Evaluator::EvalOperators(const ast::Expr& root, const Ctx& ctx) {
  // One operator over operands that are not operators (-0.5, L / 2, m * g: nearly all of
  // them): evaluated here, in the loop's order and with its charges, without its stacks.
  const auto& args = root.args;
  if (root.kind == ast::ExprKind::Unary && args.size() == 1 && args[0] && !IsOperator(*args[0])) {
    Value r = UnaryOp(root, EvalNested(*args[0], ctx));
    Charge(r, root.span);
    return r;
  }
  if (root.kind == ast::ExprKind::Binary && args.size() == 2 && args[0] && args[1] && !IsOperator(*args[0]) &&
      !IsOperator(*args[1])) {
    const Value a = EvalNested(*args[0], ctx);
    const Value b = EvalNested(*args[1], ctx);
    Value r = BinaryOp(root, a, b);
    Charge(r, root.span);
    return r;
  }
  // The stacks are the Evaluator's, shared with the evaluations this one nests (an
  // operand may hold an operator chain of its own): this call owns what lies above the
  // sizes they had on entry, and leaves them at those sizes.
  std::vector<OpItem>& work = op_work_;
  std::vector<Value>& values = op_values_;
  const size_t work_base = work.size();
  const size_t value_base = values.size();
  work.push_back({&root, false});
  while (work.size() > work_base) {
    OpItem it = work.back();
    work.pop_back();
    const ast::Expr& e = *it.e;
    if (!IsOperator(e)) {
      Value v = EvalNested(e, ctx);  // may use the stacks above their current sizes
      values.push_back(std::move(v));
      continue;
    }
    if (!it.combine) {
      work.push_back({&e, true});
      for (size_t k = e.args.size(); k-- > 0;) work.push_back({e.args[k].get(), false});
      continue;
    }
    if (e.kind == ast::ExprKind::Unary) {
      Value v = std::move(values.back());
      values.back() = UnaryOp(e, std::move(v));
    } else {
      Value b = std::move(values.back());
      values.pop_back();
      Value a = std::move(values.back());
      values.back() = BinaryOp(e, a, b);
    }
    Charge(values.back(), e.span);
  }
  Value result = std::move(values.back());
  values.resize(value_base);
  return result;
}

Value Evaluator::Elementwise2(const Value& a, const Value& b, Op op, VType rt, Span sp) {
  auto& pool = m_->exprs;
  if (!a.valid || !b.valid) return Value::Invalid();
  if (a.type == VType::String || b.type == VType::String) {
    diags_.Error(DiagCode::TypeMismatch, sp, std::string("operator '") + flat::OpSpelling(op) +
                                                 "' is not defined for String");
    return Value::Invalid();
  }
  Value r;
  r.type = rt;
  if (a.shape.empty()) {
    r.shape = b.shape;
    for (ExprId y : b.elements) r.elements.push_back(pool.Binary(op, a.elements[0], y));
  } else if (b.shape.empty()) {
    r.shape = a.shape;
    for (ExprId x : a.elements) r.elements.push_back(pool.Binary(op, x, b.elements[0]));
  } else if (SameShape(a, b)) {
    r.shape = a.shape;
    for (size_t i = 0; i < a.elements.size(); ++i) r.elements.push_back(pool.Binary(op, a.elements[i], b.elements[i]));
  } else {
    diags_.Error(DiagCode::SizeMismatch, sp, "operands have sizes " + ShapeStr(a.shape) + " and " +
                                                 ShapeStr(b.shape));
    return Value::Invalid();
  }
  return r;
}

Value Evaluator::UnaryOp(const ast::Expr& e, Value v) {
  auto& pool = m_->exprs;
  if (!v.valid) return Value::Invalid();
  Tok op = static_cast<Tok>(e.op);
  if (op == Tok::Plus) return v;
  if (v.type == VType::String) {
    diags_.Error(DiagCode::TypeMismatch, e.span, "unary operator on a String");
    return Value::Invalid();
  }
  if (op == Tok::KwNot && v.type != VType::Boolean) {
    diags_.Error(DiagCode::TypeMismatch, e.span, "'not' needs a Boolean, got " + std::string(VTypeName(v.type)));
    return Value::Invalid();
  }
  for (auto& x : v.elements) x = pool.Unary(op == Tok::KwNot ? Op::Not : Op::Neg, x);
  return v;
}

Value Evaluator::BinaryOp(const ast::Expr& e, const Value& a, const Value& b) {
  if (!a.valid || !b.valid) return Value::Invalid();
  Tok op = static_cast<Tok>(e.op);
  switch (op) {
    case Tok::Plus:
    case Tok::Minus:
      if (!a.shape.empty() != !b.shape.empty() && !(a.shape.empty() && b.shape.empty())) {
        diags_.Error(DiagCode::SizeMismatch, e.span,
                     std::string("'") + TokSpelling(op) + "' needs operands of equal size, got " +
                         ShapeStr(a.shape) + " and " + ShapeStr(b.shape));
        return Value::Invalid();
      }
      return Elementwise2(a, b, op == Tok::Plus ? Op::Add : Op::Sub, Promote(a.type, b.type), e.span);
    case Tok::Star:
      if (a.shape.empty() || b.shape.empty())
        return Elementwise2(a, b, Op::Mul, Promote(a.type, b.type), e.span);
      return MatrixProduct(e, a, b);
    case Tok::Slash:
      if (!b.shape.empty()) {
        diags_.Error(DiagCode::SizeMismatch, e.span, "division by an array");
        return Value::Invalid();
      }
      return Elementwise2(a, b, Op::Div, VType::Real, e.span);
    case Tok::Caret:
      if (!a.shape.empty() || !b.shape.empty()) {
        diags_.Error(DiagCode::SizeMismatch, e.span, "'^' needs scalar operands");
        return Value::Invalid();
      }
      return Elementwise2(a, b, Op::Pow, VType::Real, e.span);
    case Tok::KwAnd:
    case Tok::KwOr:
      if (a.type != VType::Boolean || b.type != VType::Boolean) {
        diags_.Error(DiagCode::TypeMismatch, e.span,
                     std::string("'") + TokSpelling(op) + "' needs Boolean operands");
        return Value::Invalid();
      }
      return Elementwise2(a, b, op == Tok::KwAnd ? Op::And : Op::Or, VType::Boolean, e.span);
    default: return Comparison(e, a, b);
  }
}

// a * b of arrays (Modelica semantics): matrix products; vector*vector = scalar product.
Value Evaluator::MatrixProduct(const ast::Expr& e, const Value& a, const Value& b) {
  auto& pool = m_->exprs;
  auto dotp = [&](const std::vector<ExprId>& x, const std::vector<ExprId>& y) {
    ExprId s = pool.Binary(Op::Mul, x[0], y[0]);
    for (size_t i = 1; i < x.size(); ++i) s = pool.Binary(Op::Add, s, pool.Binary(Op::Mul, x[i], y[i]));
    return s;
  };
  int ar = a.shape.size() == 2 ? a.shape[0] : 1, ac = a.shape.back();
  int br = b.shape[0], bc = b.shape.size() == 2 ? b.shape[1] : 1;
  if (a.shape.size() > 2 || b.shape.size() > 2 || ac != br) {
    diags_.Error(DiagCode::SizeMismatch, e.span, "cannot multiply sizes " + ShapeStr(a.shape) + " and " + ShapeStr(b.shape));
    return Value::Invalid();
  }
  const std::int64_t multiply_adds = static_cast<std::int64_t>(ar) * bc * ac;
  if (!ChargeSteps(multiply_adds, e.span) || !ChargeNodes(2 * multiply_adds, e.span)) return Value::Invalid();
  Value r;
  r.type = Promote(a.type, b.type);
  for (int i = 0; i < ar; ++i)
    for (int j = 0; j < bc; ++j) {
      std::vector<ExprId> x, y;
      for (int k = 0; k < ac; ++k) {
        x.push_back(a.elements[static_cast<size_t>(i * ac + k)]);
        y.push_back(b.elements[static_cast<size_t>(k * bc + j)]);
      }
      r.elements.push_back(dotp(x, y));
    }
  if (a.shape.size() == 2) r.shape.push_back(ar);
  if (b.shape.size() == 2) r.shape.push_back(bc);
  return r;
}

// a < b, a == b, ...: scalars; Strings with == and <> only.
Value Evaluator::Comparison(const ast::Expr& e, const Value& a, const Value& b) {
  Tok op = static_cast<Tok>(e.op);
  if (!a.shape.empty() || !b.shape.empty()) {
    diags_.Error(DiagCode::SizeMismatch, e.span, "comparison of arrays");
    return Value::Invalid();
  }
  if (a.type == VType::String && b.type == VType::String) {
    if (op != Tok::EqEq && op != Tok::Ne) {
      diags_.Error(DiagCode::TypeMismatch, e.span, "Strings compare only with == and <>");
      return Value::Invalid();
    }
    bool eq = a.strings[0] == b.strings[0];
    return Const((op == Tok::EqEq) == eq ? 1 : 0, VType::Boolean);
  }
  Op fop = op == Tok::Lt ? Op::Lt : op == Tok::Le ? Op::Le : op == Tok::Gt ? Op::Gt
           : op == Tok::Ge ? Op::Ge : op == Tok::EqEq ? Op::Eq : Op::Ne;
  return Elementwise2(a, b, fop, VType::Boolean, e.span);
}

}  // namespace kanesim::lang::elab
