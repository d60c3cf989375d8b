#include "flat/expr.h"

#include <array>
#include <cmath>
#include <cstdio>

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
  std::uint8_t reads = (n.op == Op::Time || n.op == Op::Input) ? kReadsTime : n.op == Op::State ? kReadsState : 0;
  for (ExprId c : {n.a, n.b, n.c})
    if (c >= 0) reads |= reads_[static_cast<size_t>(c)];
  nodes_.push_back(n);
  reads_.push_back(reads);
  return static_cast<ExprId>(nodes_.size() - 1);
}

// Constants and parameters (most of the pool) are leaves that read neither time nor
// state: pushed without Push's look at children.
ExprId ExprPool::Constant(double v) {
  ExprNode& n = nodes_.emplace_back();
  n.op = Op::Const;
  n.value = v;
  reads_.push_back(0);
  return static_cast<ExprId>(nodes_.size() - 1);
}

ExprId ExprPool::Parameter(std::int32_t index) {
  ExprNode& n = nodes_.emplace_back();
  n.op = Op::Param;
  n.index = index;
  reads_.push_back(0);
  return static_cast<ExprId>(nodes_.size() - 1);
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

ExprId ExprPool::Input(std::int32_t input_index) {
  ExprNode n;
  n.op = Op::Input;
  n.index = input_index;
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

bool ExprPool::DependsOnTimeOrState(ExprId id) const {
  return id >= 0 && (reads_[static_cast<size_t>(id)] & (kReadsTime | kReadsState)) != 0;
}

bool ExprPool::DependsOnState(ExprId id) const {
  return id >= 0 && (reads_[static_cast<size_t>(id)] & kReadsState) != 0;
}

double ApplyOp(Op op, double a, double b, double c) {
  switch (op) {
    case Op::Const:
    case Op::Param:
    case Op::Time:
    case Op::State:
    case Op::Input:
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

namespace {

// One pending piece of ExprPool::ToString's output: a node to print or literal text.
struct PrintItem {
  ExprId node = kNoExpr;  // kNoExpr: emit `text`
  const char* text = nullptr;
  int depth = 0;
};

// Names from two tables (ToString's vector form); an index outside a table has none.
class TableNames : public ExprNames {
 public:
  TableNames(const std::vector<std::string>* pn, const std::vector<std::string>* sn) : pn_(pn), sn_(sn) {}
  bool Param(int i, std::string* out) const override { return Lookup(pn_, i, out); }
  bool State(int i, std::string* out) const override { return Lookup(sn_, i, out); }

 private:
  static bool Lookup(const std::vector<std::string>* t, int i, std::string* out) {
    if (!t || i < 0 || static_cast<size_t>(i) >= t->size()) return false;
    out->append((*t)[static_cast<size_t>(i)]);
    return true;
  }
  const std::vector<std::string>* pn_;
  const std::vector<std::string>* sn_;
};

// Appends the text of one leaf node: a constant as "%.17g" (what a stream of precision 17
// prints), a parameter or state by its name or as "param#3".
void AppendLeaf(const ExprNode& n, const ExprNames& names, std::string* out) {
  switch (n.op) {
    case Op::Const: {
      char buf[40];
      int len = std::snprintf(buf, sizeof buf, "%.17g", n.value);
      out->append(buf, static_cast<size_t>(len));
      break;
    }
    case Op::Param:
      if (!names.Param(n.index, out)) out->append("param#").append(std::to_string(n.index));
      break;
    case Op::Time: out->append("time"); break;
    case Op::Input: out->append("input#").append(std::to_string(n.index)); break;
    case Op::State:
      if (!names.State(n.index, out)) out->append("state#").append(std::to_string(n.index));
      break;
    default: break;
  }
}

}  // namespace

// Prints with an explicit stack (no recursion over the expression's depth): a node
// pushes its pieces in reverse order. Deeper than kMaxDepth levels or longer than
// max_chars, the text ends with "...".
std::string ExprPool::ToString(ExprId id, const std::vector<std::string>* pn, const std::vector<std::string>* sn,
                               std::size_t max_chars) const {
  return ToString(id, TableNames(pn, sn), max_chars);
}

std::string ExprPool::ToString(ExprId id, const ExprNames& names, std::size_t max_chars) const {
  if (id < 0) return "<none>";
  constexpr int kMaxDepth = 200;
  std::string out;
  std::vector<PrintItem> stack{{id, nullptr, 0}};
  while (!stack.empty()) {
    if (out.size() > max_chars) {
      out += "...";
      break;
    }
    PrintItem it = stack.back();
    stack.pop_back();
    if (it.node == kNoExpr) {
      out += it.text;
      continue;
    }
    if (it.depth > kMaxDepth) {
      out += "...";
      continue;
    }
    const ExprNode& n = (*this)[it.node];
    int arity = OpArity(n.op);
    if (arity == 0) {
      AppendLeaf(n, names, &out);
      continue;
    }
    // Pieces in reading order (at most 7, an if-expression's), pushed reversed below; a
    // fixed array, as a vector here cost up to four allocations per node.
    std::array<PrintItem, 7> parts;
    std::size_t num_parts = 0;
    auto text = [&](const char* t) { parts[num_parts++] = {kNoExpr, t, 0}; };
    auto child = [&](ExprId c) { parts[num_parts++] = {c, nullptr, it.depth + 1}; };
    bool infix = arity == 2 && (n.op <= Op::Or && n.op >= Op::Add);
    if (n.op == Op::IfElse) {
      text("(if "), child(n.a), text(" then "), child(n.b), text(" else "), child(n.c), text(")");
    } else if (n.op == Op::Neg) {
      text("(-"), child(n.a), text(")");
    } else if (n.op == Op::Not) {
      text("(not "), child(n.a), text(")");
    } else if (infix) {
      text("("), child(n.a), text(" "), text(OpSpelling(n.op)), text(" "), child(n.b), text(")");
    } else {
      text(OpSpelling(n.op)), text("("), child(n.a);
      if (arity == 2) text(", "), child(n.b);
      text(")");
    }
    while (num_parts > 0) stack.push_back(parts[--num_parts]);
  }
  return out;
}

}  // namespace kanesim::flat
