// Scalar expression IR shared by the elaborator (which writes it) and the compiler
// (which folds and lowers it). Vector-valued user expressions are scalarized by the
// elaborator, so every node here yields one double.
//
// Nodes live in an ExprPool and refer to each other by index (ExprId); the pool is
// append-only, so a child always has a smaller index than its parent and a pool can be
// evaluated in index order.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace kanesim::flat {

using ExprId = std::int32_t;
inline constexpr ExprId kNoExpr = -1;

// Names of parameters and state references for ExprPool::ToString, made on demand:
// each appends the name of leaf `index` to *out and returns false when it has none.
class ExprNames {
 public:
  virtual ~ExprNames() = default;
  virtual bool Param(int index, std::string* out) const = 0;
  virtual bool State(int index, std::string* out) const = 0;
};

// The one table of operators. X(name, arity, spelling); spelling is what the user
// writes for functions (and what diagnostics print).
#define KANESIM_EXPR_OPS(X)                                                           \
  X(Const, 0, "const")                                                                \
  X(Param, 0, "param")   /* index = parameter index                          */      \
  X(Time, 0, "time")                                                                  \
  X(State, 0, "state")   /* index = StateRef index into Mechanism::state_refs */     \
  X(Input, 0, "input")   /* index = input index into Mechanism::inputs           */     \
  X(Neg, 1, "-")                                                                      \
  X(Not, 1, "not")                                                                    \
  X(Sin, 1, "sin")                                                                    \
  X(Cos, 1, "cos")                                                                    \
  X(Tan, 1, "tan")                                                                    \
  X(Asin, 1, "asin")                                                                  \
  X(Acos, 1, "acos")                                                                  \
  X(Atan, 1, "atan")                                                                  \
  X(Sinh, 1, "sinh")                                                                  \
  X(Cosh, 1, "cosh")                                                                  \
  X(Tanh, 1, "tanh")                                                                  \
  X(Exp, 1, "exp")                                                                    \
  X(Log, 1, "log")                                                                    \
  X(Sqrt, 1, "sqrt")                                                                  \
  X(Abs, 1, "abs")                                                                    \
  X(Sign, 1, "sign")                                                                  \
  X(Floor, 1, "floor")                                                                \
  X(Ceil, 1, "ceil")                                                                  \
  X(Add, 2, "+")                                                                      \
  X(Sub, 2, "-")                                                                      \
  X(Mul, 2, "*")                                                                      \
  X(Div, 2, "/")                                                                      \
  X(Pow, 2, "^")                                                                      \
  X(Lt, 2, "<")                                                                       \
  X(Le, 2, "<=")                                                                      \
  X(Gt, 2, ">")                                                                       \
  X(Ge, 2, ">=")                                                                      \
  X(Eq, 2, "==")                                                                      \
  X(Ne, 2, "<>")                                                                      \
  X(And, 2, "and")                                                                    \
  X(Or, 2, "or")                                                                      \
  X(Atan2, 2, "atan2")                                                                \
  X(Min, 2, "min")                                                                    \
  X(Max, 2, "max")                                                                    \
  X(Mod, 2, "mod")                                                                    \
  X(IfElse, 3, "if")

enum class Op : std::uint8_t {
#define KANESIM_X(name, arity, spelling) name,
  KANESIM_EXPR_OPS(KANESIM_X)
#undef KANESIM_X
};

int OpArity(Op op);
const char* OpSpelling(Op op);

struct ExprNode {
  Op op = Op::Const;
  ExprId a = kNoExpr, b = kNoExpr, c = kNoExpr;  // children (by arity)
  double value = 0.0;                             // Const
  std::int32_t index = -1;                        // Param / State
};

// What a State node reads. The runtime computes only the quantities some expression
// or output refers to ("skip what a scene doesn't need").
enum class StateKind : std::uint8_t {
  JointQ,          // joint coordinate q[k] of `joint`
  JointU,          // joint speed u[k] of `joint`
  FramePosition,   // world position of `frame`, component k (0..2), resolved in world
  FrameRotation,   // orientation matrix R_WF entry (k / 3, k % 3)
  FrameVelocity,   // world velocity of frame origin, component k, resolved in world
  FrameAngVel,     // angular velocity of frame in world, component k, resolved in world
};

struct StateRef {
  StateKind kind = StateKind::JointQ;
  std::int32_t target = -1;  // joint index or frame index
  std::int32_t k = 0;        // component
  bool operator==(const StateRef& o) const {
    return kind == o.kind && target == o.target && k == o.k;
  }
};

class ExprPool {
 public:
  ExprId Constant(double v);
  ExprId Parameter(std::int32_t index);
  ExprId Time();
  ExprId State(std::int32_t state_ref_index);
  // A model input (Mechanism::inputs): a function of time given at run time, so it counts as
  // reading time (DependsOnTimeOrState) but not the state.
  ExprId Input(std::int32_t input_index);
  ExprId Unary(Op op, ExprId a);
  ExprId Binary(Op op, ExprId a, ExprId b);
  ExprId IfElse(ExprId cond, ExprId then_e, ExprId else_e);

  // Room for n nodes in all, made ahead (the elaborator knows about how many it will push).
  void Reserve(size_t n) {
    nodes_.reserve(n);
    reads_.reserve(n);
  }
  const ExprNode& operator[](ExprId id) const { return nodes_[static_cast<size_t>(id)]; }
  size_t size() const { return nodes_.size(); }
  const std::vector<ExprNode>& nodes() const { return nodes_; }

  // True when the expression is a Const node (after the elaborator's own folding).
  bool IsConstant(ExprId id) const { return id >= 0 && (*this)[id].op == Op::Const; }

  // True when the expression (transitively) reads time or state. O(1): every node
  // records what its sub-DAG reads when it is pushed.
  bool DependsOnTimeOrState(ExprId id) const;
  bool DependsOnState(ExprId id) const;

  // Human-readable form for `kanesim check --emit flat` and messages; params and state
  // refs by index unless names are provided. A shared sub-expression prints once per
  // use, so the text of a DAG can be exponentially longer than the DAG: the text stops
  // with "..." after `max_chars` characters (kToStringChars by default).
  static constexpr std::size_t kToStringChars = 20000;
  std::string ToString(ExprId id, const std::vector<std::string>* param_names = nullptr,
                       const std::vector<std::string>* state_names = nullptr,
                       std::size_t max_chars = kToStringChars) const;
  // The same text, with each leaf's name asked of `names` as it is printed (the compiler
  // prints a few expressions of a model of thousands of parameters: no table of names).
  std::string ToString(ExprId id, const ExprNames& names, std::size_t max_chars = kToStringChars) const;

 private:
  enum : std::uint8_t { kReadsTime = 1, kReadsState = 2 };
  ExprId Push(const ExprNode& n);
  std::vector<ExprNode> nodes_;
  std::vector<std::uint8_t> reads_;  // per node: kReadsTime | kReadsState of its sub-DAG
};

// Evaluates one op on already-evaluated operands (used by every evaluator so the
// semantics of `mod`, `sign`, comparisons etc. are defined once).
double ApplyOp(Op op, double a, double b, double c);

}  // namespace kanesim::flat
