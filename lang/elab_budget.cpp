// The elaborator's bounds: the work budget and the nesting depth of evaluation.
#include "lang/elab_budget.h"

#include "lang/elab_internal.h"

namespace kanesim::lang::elab {

// Reports the first time the budget runs out, at the place being evaluated; after that
// every evaluation returns an invalid value at once and every loop stops.
bool Elaborator::ChargeSteps(std::int64_t steps, Span where) {
  if (budget_.Spend(steps)) return true;
  if (!budget_reported_) {
    budget_reported_ = true;
    too_large_ = true;
    auto& d = diags_.Error(DiagCode::WorkLimit, where,
                           "elaborating the model takes more than " + std::to_string(kMaxElabWork) +
                               " steps; the limit was reached while evaluating this");
    d.hint =
        "nested comprehensions, loops and matrix products multiply their sizes; reduce them (the limit is stated "
        "in docs/language.md)";
  }
  return false;
}

bool Elaborator::Charge(const Value& v, Span where) {
  return ChargeSteps(static_cast<std::int64_t>(v.e.size()) + 1, where);
}

// Everything but operator chains recurses through here: sub-expressions (arguments,
// array elements, subscripts, if-branches) and, through GetVar, the parameters a value
// reads. The parser bounds the nesting of brackets; this bounds the sum of both.
Value Elaborator::EvalNested(const ast::Expr& e, const Ctx& ctx) {
  if (budget_.Exhausted()) return Value::Invalid();
  if (eval_depth_ >= kMaxEvalDepth) {
    if (!depth_reported_) {
      depth_reported_ = true;
      diags_.Error(DiagCode::EvalTooDeep, e.span,
                   "evaluation nested deeper than " + std::to_string(kMaxEvalDepth) +
                       " levels (expressions inside expressions, or parameters defined by parameters)")
          .hint = "define long sequences as arrays (parameter Real x[n] = {...}) instead of one parameter per step";
    }
    return Value::Invalid();
  }
  ++eval_depth_;
  Value v = EvalNode(e, ctx);
  --eval_depth_;
  Charge(v, e.span);
  return v;
}

}  // namespace kanesim::lang::elab
