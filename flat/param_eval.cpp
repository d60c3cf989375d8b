#include "flat/param_eval.h"

#include <algorithm>
#include <cmath>

namespace kanesim::flat {

ParamEvaluator::ParamEvaluator(const ExprPool& pool, const std::vector<double>& param_values)
    : pool_(pool), params_(param_values) {}

void ParamEvaluator::Reserve(size_t n) {
  known_.reserve(n);
  value_.reserve(n);
}

// Post-order over the not yet known part of the sub-DAG, with an explicit stack
// (children have smaller ids than parents, so it terminates; no recursion over the
// expression's depth). A node is pushed again only while its children are pending.
double ParamEvaluator::Eval(ExprId id) {
  if (id < 0) return 0.0;
  const auto uid = static_cast<size_t>(id);
  if (uid < known_.size() && known_[uid]) return value_[uid];
  const ExprNode& node = pool_[id];
  if (node.op == Op::Const) return node.value;  // a literal: nothing to walk or keep
  // A parameter (a binding to another: `m = m`): its value, which never changes once read.
  if (node.op == Op::Param && node.index >= 0 && static_cast<size_t>(node.index) < params_.size())
    return params_[static_cast<size_t>(node.index)];
  if (known_.size() < pool_.size()) {  // doubled at least: the pool grows between calls
    const size_t n = std::max({pool_.size(), 2 * known_.size(), known_.capacity()});
    known_.resize(n, 0);
    value_.resize(n, 0.0);
  }
  stack_.assign(1, id);
  while (!stack_.empty()) {
    const ExprId e = stack_.back();
    const auto ue = static_cast<size_t>(e);
    if (known_[ue]) {
      stack_.pop_back();
      continue;
    }
    const ExprNode& n = pool_[e];
    bool ready = true;
    for (ExprId c : {n.a, n.b, n.c})
      if (c >= 0 && !known_[static_cast<size_t>(c)]) {
        stack_.push_back(c);
        ready = false;
      }
    if (!ready) continue;
    stack_.pop_back();
    double r = 0.0;
    switch (n.op) {
      case Op::Const: r = n.value; break;
      case Op::Param:
        r = (n.index >= 0 && static_cast<size_t>(n.index) < params_.size()) ? params_[static_cast<size_t>(n.index)]
                                                                           : std::nan("");
        break;
      case Op::Time:
      case Op::State:
      case Op::Input: r = std::nan(""); break;
      default: {
        const double a = n.a >= 0 ? value_[static_cast<size_t>(n.a)] : 0.0;
        const double b = n.b >= 0 ? value_[static_cast<size_t>(n.b)] : 0.0;
        const double c = n.c >= 0 ? value_[static_cast<size_t>(n.c)] : 0.0;
        r = ApplyOp(n.op, a, b, c);
      }
    }
    value_[ue] = r;
    known_[ue] = 1;
  }
  return value_[static_cast<size_t>(id)];
}

}  // namespace kanesim::flat
