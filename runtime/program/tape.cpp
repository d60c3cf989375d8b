#include "runtime/program/tape.h"

#include <algorithm>
#include <cmath>

namespace kanesim::rt {

using flat::ExprId;
using flat::ExprNode;
using flat::Op;

namespace {

// The per-node tables are made on the first node asked for (covering the pool, as a node's
// children have smaller ids than it): a builder asked for nothing (a model without outputs
// or whens) clears no tables.
template <class T>
void Cover(const flat::ExprPool& pool, ExprId id, std::vector<T>& table, T fill) {
  if (static_cast<size_t>(id) < table.size()) return;
  table.resize(std::max(pool.size(), static_cast<size_t>(id) + 1), fill);
}

}  // namespace

TapeBuilder::TapeBuilder(const flat::ExprPool& pool, const std::vector<double>& param_values)
    : pool_(pool), params_(param_values) {}

TapeBuilder TapeBuilder::SharingFolds(TapeBuilder& folds_of) {
  TapeBuilder b(folds_of.pool_, folds_of.params_);
  b.shared_ = &folds_of.folds();
  return b;
}

// Post-order over the sub-DAG of `id` (children have smaller ids, so an explicit stack
// terminates); a node folds when it reads neither time nor state.
bool TapeBuilder::Fold(ExprId id, double* value) {
  Folds& f = folds();
  Cover(pool_, id, f.known, static_cast<signed char>(-1));
  Cover(pool_, id, f.value, 0.0);
  std::vector<signed char>& known = f.known;
  std::vector<double>& folded = f.value;
  std::vector<ExprId>& stack = f.stack;
  stack.assign(1, id);
  while (!stack.empty()) {
    ExprId e = stack.back();
    auto ue = static_cast<size_t>(e);
    if (known[ue] >= 0) {
      stack.pop_back();
      continue;
    }
    const ExprNode& n = pool_[e];
    bool ready = true;
    for (ExprId ch : {n.a, n.b, n.c})
      if (ch >= 0 && known[static_cast<size_t>(ch)] < 0) {
        stack.push_back(ch);
        ready = false;
      }
    if (!ready) continue;
    stack.pop_back();
    switch (n.op) {
      case Op::Const:
        known[ue] = 1;
        folded[ue] = n.value;
        break;
      case Op::Param:
        known[ue] = 1;
        folded[ue] = (n.index >= 0 && static_cast<size_t>(n.index) < params_.size())
                         ? params_[static_cast<size_t>(n.index)]
                         : std::nan("");
        break;
      case Op::Time:
      case Op::State:
      case Op::Input: known[ue] = 0; break;
      default: {
        bool all = true;
        double v[3] = {0.0, 0.0, 0.0};
        const ExprId ch[3] = {n.a, n.b, n.c};
        for (int i = 0; i < 3; ++i)
          if (ch[i] >= 0) {
            all = all && known[static_cast<size_t>(ch[i])] == 1;
            v[i] = folded[static_cast<size_t>(ch[i])];
          }
        // if-then-else with a constant condition folds to the taken branch's status.
        if (n.op == Op::IfElse && known[static_cast<size_t>(n.a)] == 1) {
          ExprId taken = v[0] != 0.0 ? n.b : n.c;
          known[ue] = known[static_cast<size_t>(taken)];
          folded[ue] = folded[static_cast<size_t>(taken)];
          break;
        }
        known[ue] = all ? 1 : 0;
        if (all) folded[ue] = flat::ApplyOp(n.op, v[0], v[1], v[2]);
      }
    }
  }
  *value = folded[static_cast<size_t>(id)];
  return known[static_cast<size_t>(id)] == 1;
}

int TapeBuilder::RegisterOf(ExprId id) {
  double unused;
  Fold(id, &unused);  // also makes the fold tables
  Cover(pool_, id, reg_, -1);
  const std::vector<signed char>& known = folds().known;
  const std::vector<double>& folded = folds().value;
  std::vector<ExprId>& stack = stack_;
  stack.assign(1, id);
  while (!stack.empty()) {
    ExprId e = stack.back();
    auto ue = static_cast<size_t>(e);
    if (reg_[ue] >= 0) {
      stack.pop_back();
      continue;
    }
    const ExprNode& n = pool_[e];
    if (known[ue] == 1) {
      reg_[ue] = static_cast<int>(tape_.init.size());
      tape_.init.push_back(folded[ue]);
      stack.pop_back();
      continue;
    }
    if (n.op == Op::Time) {
      if (tape_.time_reg < 0) {
        tape_.time_reg = static_cast<int>(tape_.init.size());
        tape_.init.push_back(0.0);
      }
      reg_[ue] = tape_.time_reg;
      stack.pop_back();
      continue;
    }
    if (n.op == Op::Input) {
      int r = -1;
      for (const auto& [in, reg] : tape_.input_regs)
        if (in == n.index) r = reg;
      if (r < 0) {
        r = static_cast<int>(tape_.init.size());
        tape_.init.push_back(0.0);
        tape_.input_regs.emplace_back(n.index, r);
      }
      reg_[ue] = r;
      stack.pop_back();
      continue;
    }
    if (n.op == Op::State) {
      int r = -1;
      for (const auto& [ref, reg] : tape_.state_regs)
        if (ref == n.index) r = reg;
      if (r < 0) {
        r = static_cast<int>(tape_.init.size());
        tape_.init.push_back(0.0);
        tape_.state_regs.emplace_back(n.index, r);
      }
      reg_[ue] = r;
      stack.pop_back();
      continue;
    }
    // A constant-condition if folds to the taken branch.
    if (n.op == Op::IfElse && known[static_cast<size_t>(n.a)] == 1) {
      ExprId taken = folded[static_cast<size_t>(n.a)] != 0.0 ? n.b : n.c;
      if (reg_[static_cast<size_t>(taken)] < 0) {
        stack.push_back(taken);
        continue;
      }
      reg_[ue] = reg_[static_cast<size_t>(taken)];
      stack.pop_back();
      continue;
    }
    bool ready = true;
    for (ExprId ch : {n.a, n.b, n.c})
      if (ch >= 0 && reg_[static_cast<size_t>(ch)] < 0) {
        stack.push_back(ch);
        ready = false;
      }
    if (!ready) continue;
    stack.pop_back();
    TapeInstr in;
    in.op = n.op;
    in.dst = static_cast<int>(tape_.init.size());
    tape_.init.push_back(0.0);
    in.a = n.a >= 0 ? reg_[static_cast<size_t>(n.a)] : -1;
    in.b = n.b >= 0 ? reg_[static_cast<size_t>(n.b)] : -1;
    in.c = n.c >= 0 ? reg_[static_cast<size_t>(n.c)] : -1;
    reg_[ue] = in.dst;
    tape_.code.push_back(in);
  }
  return reg_[static_cast<size_t>(id)];
}

int TapeBuilder::AddRoot(ExprId id, std::string label, std::string text) {
  tape_.roots.push_back(RegisterOf(id));
  tape_.labels.push_back(std::move(label));
  tape_.texts.push_back(std::move(text));
  return static_cast<int>(tape_.roots.size() - 1);
}

Tape TapeBuilder::Finish() { return std::move(tape_); }

void Tape::Eval(double* r) const {
  for (const TapeInstr& in : code) {
    double a = in.a >= 0 ? r[in.a] : 0.0;
    double b = in.b >= 0 ? r[in.b] : 0.0;
    double c = in.c >= 0 ? r[in.c] : 0.0;
    r[in.dst] = flat::ApplyOp(in.op, a, b, c);
  }
}

namespace {

// A second-order jet in time: x, x', x''.
struct Jet {
  double v, d1, d2;
};

// Chain rule for y = f(x): y' = f'(x) x', y'' = f''(x) x'^2 + f'(x) x''.
Jet Chain(const Jet& x, double f, double fp, double fpp) {
  return {f, fp * x.d1, fpp * x.d1 * x.d1 + fp * x.d2};
}

Jet Unary(Op op, const Jet& x) {
  double v = x.v;
  switch (op) {
    case Op::Neg: return {-x.v, -x.d1, -x.d2};
    case Op::Sin: return Chain(x, std::sin(v), std::cos(v), -std::sin(v));
    case Op::Cos: return Chain(x, std::cos(v), -std::sin(v), -std::cos(v));
    case Op::Tan: {
      double t = std::tan(v), s2 = 1.0 + t * t;
      return Chain(x, t, s2, 2.0 * t * s2);
    }
    case Op::Asin: {
      double w = 1.0 - v * v;
      return Chain(x, std::asin(v), 1.0 / std::sqrt(w), v / (w * std::sqrt(w)));
    }
    case Op::Acos: {
      double w = 1.0 - v * v;
      return Chain(x, std::acos(v), -1.0 / std::sqrt(w), -v / (w * std::sqrt(w)));
    }
    case Op::Atan: {
      double w = 1.0 + v * v;
      return Chain(x, std::atan(v), 1.0 / w, -2.0 * v / (w * w));
    }
    case Op::Sinh: return Chain(x, std::sinh(v), std::cosh(v), std::sinh(v));
    case Op::Cosh: return Chain(x, std::cosh(v), std::sinh(v), std::cosh(v));
    case Op::Tanh: {
      double t = std::tanh(v), s = 1.0 - t * t;
      return Chain(x, t, s, -2.0 * t * s);
    }
    case Op::Exp: {
      double e = std::exp(v);
      return Chain(x, e, e, e);
    }
    case Op::Log: return Chain(x, std::log(v), 1.0 / v, -1.0 / (v * v));
    case Op::Sqrt: {
      double s = std::sqrt(v);
      return Chain(x, s, 0.5 / s, -0.25 / (s * v));
    }
    case Op::Abs: {
      double sg = v > 0.0 ? 1.0 : (v < 0.0 ? -1.0 : 0.0);
      return {std::fabs(v), sg * x.d1, sg * x.d2};
    }
    default:  // piecewise constant: not, sign, floor, ceil
      return {flat::ApplyOp(op, v, 0.0, 0.0), 0.0, 0.0};
  }
}

Jet Binary(Op op, const Jet& a, const Jet& b) {
  switch (op) {
    case Op::Add: return {a.v + b.v, a.d1 + b.d1, a.d2 + b.d2};
    case Op::Sub: return {a.v - b.v, a.d1 - b.d1, a.d2 - b.d2};
    case Op::Mul: return {a.v * b.v, a.d1 * b.v + a.v * b.d1, a.d2 * b.v + 2.0 * a.d1 * b.d1 + a.v * b.d2};
    case Op::Div: {
      // y b = a  =>  y' = (a' - y b') / b,  y'' = (a'' - 2 y' b' - y b'') / b.
      double y = a.v / b.v;
      double y1 = (a.d1 - y * b.d1) / b.v;
      return {y, y1, (a.d2 - 2.0 * y1 * b.d1 - y * b.d2) / b.v};
    }
    case Op::Pow: {
      if (b.d1 == 0.0 && b.d2 == 0.0) {
        double p = b.v;
        return Chain(a, std::pow(a.v, p), p * std::pow(a.v, p - 1.0), p * (p - 1.0) * std::pow(a.v, p - 2.0));
      }
      // a^b = exp(b log a).
      Jet l = Unary(Op::Log, a);
      return Unary(Op::Exp, Binary(Op::Mul, b, l));
    }
    case Op::Atan2: {
      // theta = atan2(a, b): theta' = (b a' - a b') / (a^2 + b^2) = n / d.
      double d = a.v * a.v + b.v * b.v;
      double n = b.v * a.d1 - a.v * b.d1;
      double n1 = b.v * a.d2 - a.v * b.d2;
      double d1 = 2.0 * (a.v * a.d1 + b.v * b.d1);
      return {std::atan2(a.v, b.v), n / d, (n1 * d - n * d1) / (d * d)};
    }
    case Op::Min: return a.v < b.v ? a : b;
    case Op::Max: return a.v > b.v ? a : b;
    case Op::Mod: {
      double k = std::floor(a.v / b.v);
      return {a.v - k * b.v, a.d1 - k * b.d1, a.d2 - k * b.d2};
    }
    default:  // comparisons and logic: piecewise constant
      return {flat::ApplyOp(op, a.v, b.v, 0.0), 0.0, 0.0};
  }
}

}  // namespace

void Tape::EvalJet(double* r) const {
  auto at = [r](int i) { return Jet{r[3 * i], r[3 * i + 1], r[3 * i + 2]}; };
  for (const TapeInstr& in : code) {
    Jet y;
    int arity = flat::OpArity(in.op);
    if (in.op == Op::IfElse)
      y = r[3 * in.a] != 0.0 ? at(in.b) : at(in.c);
    else if (arity == 1)
      y = Unary(in.op, at(in.a));
    else
      y = Binary(in.op, at(in.a), at(in.b));
    r[3 * in.dst] = y.v;
    r[3 * in.dst + 1] = y.d1;
    r[3 * in.dst + 2] = y.d2;
  }
}

}  // namespace kanesim::rt
