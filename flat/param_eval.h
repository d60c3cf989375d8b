// Values of parameter expressions, each pool node evaluated once.
//
// The pool is a DAG: a node can be shared by many parents (a matrix power A*A*...*A
// reuses every entry of the previous product three times), so a walk that treats it as
// a tree costs exponential time. ParamEvaluator memoizes every node it has evaluated;
// evaluating all the parameters of a mechanism costs O(pool size) in total.
#pragma once

#include <cstdint>
#include <vector>

#include "flat/expr.h"

namespace kanesim::flat {

class ParamEvaluator {
 public:
  // `param_values` may grow while the evaluator lives (the elaborator appends a value
  // per new parameter) but a value once read must not change: it is memoized.
  ParamEvaluator(const ExprPool& pool, const std::vector<double>& param_values);
  // Value of `id`; NaN where it reads time or state, 0 for kNoExpr.
  double Eval(ExprId id);
  // Room for a pool of n nodes, made ahead (the elaborator knows about how many it pushes):
  // the tables are then filled once instead of doubled and copied as the pool grows.
  void Reserve(size_t n);

 private:
  const ExprPool& pool_;
  const std::vector<double>& params_;
  std::vector<double> value_;       // per node, valid where known_ is set
  std::vector<std::uint8_t> known_;
  std::vector<ExprId> stack_;       // scratch of Eval
};

}  // namespace kanesim::flat
