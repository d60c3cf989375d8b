#include "runtime/flat/expr.h"

#include <cmath>
#include <sstream>

namespace kanesim::flat {

int OpArity(Op op) {
  switch (op) {
#define KANESIM_X(name, arity, spelling) \
  case Op::name:                         \
    return arity;
    KANESIM_EXPR_OPS(KANESIM_X)
#undef KANESIM_X
  }
  return 0;
}

const char* OpSpelling(Op op) {
  switch (op) {
#define KANESIM_X(name, arity, spelling) \
  case Op::name:                         \
    return spelling;
    KANESIM_EXPR_OPS(KANESIM_X)
#undef KANESIM_X
  }
  return "?";
}

ExprId ExprPool::Push(const ExprNode& n) {
  nodes_.push_back(n);
  return static_cast<ExprId>(nodes_.size() - 1);
}

ExprId ExprPool::Constant(double v) {
  ExprNode n;
  n.op = Op::Const;
  n.value = v;
  return Push(n);
}

ExprId ExprPool::Parameter(std::int32_t index) {
  ExprNode n;
  n.op = Op::Param;
  n.index = index;
  return Push(n);
}

ExprId ExprPool::Time() {
  ExprNode n;
  n.op = Op::Time;
  return Push(n);
}

ExprId ExprPool::State(std::int32_t state_ref_index) {
  ExprNode n;
  n.op = Op::State;
  n.index = state_ref_index;
  return Push(n);
}

ExprId ExprPool::Unary(Op op, ExprId a) {
  if (IsConstant(a)) return Constant(ApplyOp(op, (*this)[a].value, 0.0, 0.0));
  ExprNode n;
  n.op = op;
  n.a = a;
  return Push(n);
}

ExprId ExprPool::Binary(Op op, ExprId a, ExprId b) {
  if (IsConstant(a) && IsConstant(b))
    return Constant(ApplyOp(op, (*this)[a].value, (*this)[b].value, 0.0));
  ExprNode n;
  n.op = op;
  n.a = a;
  n.b = b;
  return Push(n);
}

ExprId ExprPool::IfElse(ExprId cond, ExprId then_e, ExprId else_e) {
  if (IsConstant(cond)) return (*this)[cond].value != 0.0 ? then_e : else_e;
  ExprNode n;
  n.op = Op::IfElse;
  n.a = cond;
  n.b = then_e;
  n.c = else_e;
  return Push(n);
}

static bool DependsOn(const ExprPool& p, ExprId id, bool include_time) {
  if (id < 0) return false;
  // Children have smaller indices; an explicit stack avoids deep recursion.
  std::vector<ExprId> stack{id};
  while (!stack.empty()) {
    ExprId e = stack.back();
    stack.pop_back();
    const ExprNode& n = p[e];
    if (n.op == Op::State) return true;
    if (include_time && n.op == Op::Time) return true;
    if (n.a >= 0) stack.push_back(n.a);
    if (n.b >= 0) stack.push_back(n.b);
    if (n.c >= 0) stack.push_back(n.c);
  }
  return false;
}

bool ExprPool::DependsOnTimeOrState(ExprId id) const { return DependsOn(*this, id, true); }
bool ExprPool::DependsOnState(ExprId id) const { return DependsOn(*this, id, false); }

double ApplyOp(Op op, double a, double b, double c) {
  switch (op) {
    case Op::Const:
    case Op::Param:
    case Op::Time:
    case Op::State:
      return a;
    case Op::Neg: return -a;
    case Op::Not: return a == 0.0 ? 1.0 : 0.0;
    case Op::Sin: return std::sin(a);
    case Op::Cos: return std::cos(a);
    case Op::Tan: return std::tan(a);
    case Op::Asin: return std::asin(a);
    case Op::Acos: return std::acos(a);
    case Op::Atan: return std::atan(a);
    case Op::Sinh: return std::sinh(a);
    case Op::Cosh: return std::cosh(a);
    case Op::Tanh: return std::tanh(a);
    case Op::Exp: return std::exp(a);
    case Op::Log: return std::log(a);
    case Op::Sqrt: return std::sqrt(a);
    case Op::Abs: return std::fabs(a);
    case Op::Sign: return a > 0.0 ? 1.0 : (a < 0.0 ? -1.0 : 0.0);
    case Op::Floor: return std::floor(a);
    case Op::Ceil: return std::ceil(a);
    case Op::Add: return a + b;
    case Op::Sub: return a - b;
    case Op::Mul: return a * b;
    case Op::Div: return a / b;
    case Op::Pow: return std::pow(a, b);
    case Op::Lt: return a < b ? 1.0 : 0.0;
    case Op::Le: return a <= b ? 1.0 : 0.0;
    case Op::Gt: return a > b ? 1.0 : 0.0;
    case Op::Ge: return a >= b ? 1.0 : 0.0;
    case Op::Eq: return a == b ? 1.0 : 0.0;
    case Op::Ne: return a != b ? 1.0 : 0.0;
    case Op::And: return (a != 0.0 && b != 0.0) ? 1.0 : 0.0;
    case Op::Or: return (a != 0.0 || b != 0.0) ? 1.0 : 0.0;
    case Op::Atan2: return std::atan2(a, b);
    case Op::Min: return a < b ? a : b;
    case Op::Max: return a > b ? a : b;
    // Modelica's mod: a - floor(a/b)*b (result has the sign of b).
    case Op::Mod: return a - std::floor(a / b) * b;
    case Op::IfElse: return a != 0.0 ? b : c;
  }
  return 0.0;
}

static void Print(const ExprPool& p, ExprId id, const std::vector<std::string>* pn,
                  const std::vector<std::string>* sn, std::ostringstream& os, int depth) {
  if (depth > 200) {
    os << "...";
    return;
  }
  const ExprNode& n = p[id];
  switch (n.op) {
    case Op::Const: {
      std::ostringstream v;
      v.precision(17);
      v << n.value;
      os << v.str();
      return;
    }
    case Op::Param:
      if (pn && n.index >= 0 && static_cast<size_t>(n.index) < pn->size())
        os << (*pn)[static_cast<size_t>(n.index)];
      else
        os << "param#" << n.index;
      return;
    case Op::Time: os << "time"; return;
    case Op::State:
      if (sn && n.index >= 0 && static_cast<size_t>(n.index) < sn->size())
        os << (*sn)[static_cast<size_t>(n.index)];
      else
        os << "state#" << n.index;
      return;
    case Op::IfElse:
      os << "(if ";
      Print(p, n.a, pn, sn, os, depth + 1);
      os << " then ";
      Print(p, n.b, pn, sn, os, depth + 1);
      os << " else ";
      Print(p, n.c, pn, sn, os, depth + 1);
      os << ")";
      return;
    default: break;
  }
  int arity = OpArity(n.op);
  bool infix = arity == 2 && (n.op <= Op::Or && n.op >= Op::Add);
  if (n.op == Op::Neg || n.op == Op::Not) {
    os << "(" << OpSpelling(n.op) << (n.op == Op::Not ? " " : "");
    Print(p, n.a, pn, sn, os, depth + 1);
    os << ")";
  } else if (infix) {
    os << "(";
    Print(p, n.a, pn, sn, os, depth + 1);
    os << " " << OpSpelling(n.op) << " ";
    Print(p, n.b, pn, sn, os, depth + 1);
    os << ")";
  } else {
    os << OpSpelling(n.op) << "(";
    Print(p, n.a, pn, sn, os, depth + 1);
    if (arity == 2) {
      os << ", ";
      Print(p, n.b, pn, sn, os, depth + 1);
    }
    os << ")";
  }
}

std::string ExprPool::ToString(ExprId id, const std::vector<std::string>* param_names,
                               const std::vector<std::string>* state_names) const {
  if (id < 0) return "<none>";
  std::ostringstream os;
  Print(*this, id, param_names, state_names, os, 0);
  return os.str();
}

}  // namespace kanesim::flat
