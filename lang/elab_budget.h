// Bounds on the work of one elaboration (stated in docs/language.md).
//
// Every size the language lets a user write is checked on its own (kMaxArraySize,
// kMaxInstances), but sizes multiply: a comprehension inside a comprehension, a loop
// inside a loop, a matrix power. WorkBudget counts the steps of the whole elaboration
// (values produced, loop iterations, multiply-adds of matrix products) against one
// limit, so that no combination of legal parts can run for hours or exhaust memory.
#pragma once

#include <cstddef>
#include <cstdint>

namespace kanesim::lang::elab {

class WorkBudget {
 public:
  explicit WorkBudget(std::int64_t limit) : limit_(limit) {}
  // Adds `steps`; returns false once the total exceeds the limit.
  bool Spend(std::int64_t steps) {
    used_ += steps;
    return used_ <= limit_;
  }
  bool Exhausted() const { return used_ > limit_; }
  std::int64_t Used() const { return used_; }
  std::int64_t Limit() const { return limit_; }

 private:
  std::int64_t limit_;
  std::int64_t used_ = 0;
};

// How much native stack the evaluation below the guard's creation has used, against a
// budget of half the stack the thread has left there. kMaxEvalDepth bounds the nesting
// the same way on every machine; this guard catches a smaller stack (a thread made with
// a small one, a sanitizer's larger frames) before it overflows.
class StackGuard {
 public:
  StackGuard();
  bool Exceeded() const;

 private:
  const char* base_;
  std::size_t budget_ = 0;
};

}  // namespace kanesim::lang::elab
