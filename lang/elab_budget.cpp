// The elaborator's bounds: the work budget and the nesting depth of evaluation.
#include "lang/elab_budget.h"

#include <pthread.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include "lang/elab_eval.h"

namespace kanesim::lang::elab {

// Reports the first time the budget runs out, at the place being evaluated; after that
// every evaluation returns an invalid value at once and every loop stops.
bool Evaluator::StepsRanOut(Span where) {
  if (!budget_reported_) {
    budget_reported_ = true;
    auto& d = diags_.Error(DiagCode::WorkLimit, where,
                           "elaborating the model takes more than " + std::to_string(kMaxElabWork) +
                               " steps; the limit was reached while evaluating this");
    d.hint =
        "nested comprehensions, loops and matrix products multiply their sizes; reduce them (the limit is stated "
        "in docs/language.md)";
  }
  return false;
}

// The expression pool holds every node the elaboration makes (about 33 bytes each, and a
// vector that doubles: up to three times that while it grows); bounding the nodes bounds
// the memory, which the steps alone do not (a product of two n x n matrices is n^3 steps
// but 2 n^3 nodes). `more` nodes about to be made are counted before they are made.
bool Evaluator::NodesRanOut(Span where) {
  if (!budget_reported_) {
    budget_reported_ = true;
    budget_.Spend(budget_.Limit() + 1);  // every evaluation stops from here on
    auto& d = diags_.Error(DiagCode::WorkLimit, where,
                           "elaborating the model makes more than " + std::to_string(kMaxExprNodes) +
                               " expression nodes (about " + std::to_string(kMaxExprNodes * 33 / 1000000) +
                               " MB); the limit was reached while evaluating this");
    d.hint =
        "a product of n x n matrices makes 2 n^3 nodes and nested comprehensions multiply their sizes; reduce them "
        "(the limit is stated in docs/language.md)";
  } else {
    budget_.Spend(budget_.Limit() + 1);
  }
  return false;
}

// The native stack this thread has left below `frame`; 0 when unknown. The main thread's
// stack is RLIMIT_STACK (8 MB unless changed) and `frame` sits near its top; another
// thread's bounds come from pthread (asked once per thread: for the main thread glibc
// would read /proc/self/maps to answer, which costs more than a small elaboration).
static std::size_t StackLeft(const char* frame) {
  if (getpid() == static_cast<pid_t>(syscall(SYS_gettid))) {
    rlimit rl{};
    if (getrlimit(RLIMIT_STACK, &rl) != 0 || rl.rlim_cur == RLIM_INFINITY) return std::size_t{8} << 20;
    return static_cast<std::size_t>(rl.rlim_cur);
  }
  thread_local const char* low = [] {
    pthread_attr_t attr;
    if (pthread_getattr_np(pthread_self(), &attr) != 0) return static_cast<const char*>(nullptr);
    void* addr = nullptr;
    std::size_t size = 0;
    const bool ok = pthread_attr_getstack(&attr, &addr, &size) == 0;
    pthread_attr_destroy(&attr);
    return ok ? static_cast<const char*>(addr) : nullptr;
  }();
  return low && frame > low ? static_cast<std::size_t>(frame - low) : 0;
}

StackGuard::StackGuard() : base_(static_cast<const char*>(__builtin_frame_address(0))) {
  // Evaluation may use half of what is left (the rest is for what it calls: diagnostics,
  // the allocator); 8 MB threads leave 4 MB, a sanitizer's larger frames reach it sooner.
  const std::size_t left = StackLeft(base_);
  budget_ = left > 0 ? left / 2 : std::size_t{1} << 20;
}

bool StackGuard::Exceeded() const {
  const char* here = static_cast<const char*>(__builtin_frame_address(0));
  return base_ > here && static_cast<std::size_t>(base_ - here) > budget_;
}

// Everything but operator chains recurses through here: sub-expressions (arguments,
// array elements, subscripts, if-branches) and, through GetVar, the parameters a value
// reads. The parser bounds the nesting of brackets; this bounds the sum of both.
Value Evaluator::EvalNested(const ast::Expr& e, const Ctx& ctx) {
  if (budget_.Exhausted()) return Value::Invalid();
  if (eval_depth_ >= kMaxEvalDepth || stack_.Exceeded()) {
    if (!depth_reported_) {
      depth_reported_ = true;
      const std::string what = eval_depth_ >= kMaxEvalDepth
                                   ? std::to_string(kMaxEvalDepth) + " levels"
                                   : std::to_string(eval_depth_) + " levels, more than this thread's stack allows";
      diags_.Error(DiagCode::EvalTooDeep, e.span,
                   "evaluation nested deeper than " + what +
                       " (expressions inside expressions, or parameters defined by parameters)")
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
