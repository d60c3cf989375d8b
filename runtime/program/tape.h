// User expressions lowered to a flat register tape: parameters and constant
// sub-expressions folded at compile time, no allocation or string look-up at run time.
//
// Registers [0, num_regs): constants live in `init` and are never overwritten; `time`
// and state refs are loaded by the caller; every instruction writes one register.
// EvalJet evaluates the same code on truncated Taylor jets (x, dx/dt, d2x/dt2) in time,
// which is how prescribed motions get their speed and acceleration (forward-mode, no
// symbolic differentiation).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "flat/expr.h"

namespace kanesim::rt {

struct TapeInstr {
  flat::Op op = flat::Op::Add;
  std::int32_t dst = 0, a = -1, b = -1, c = -1;
};

struct Tape {
  std::vector<TapeInstr> code;
  std::vector<double> init;                  // register image with folded constants
  int time_reg = -1;                         // -1 when no expression reads time
  std::vector<std::pair<int, int>> state_regs;  // (mech state ref index, register)
  std::vector<std::pair<int, int>> input_regs;  // (mech input index, register): loaded like time
  std::vector<int> roots;                    // result register per root
  std::vector<std::string> labels;           // what each root is, for error messages
  std::vector<std::string> texts;            // each root's expression, for error messages

  int num_regs() const { return static_cast<int>(init.size()); }
  // Evaluates the code on `regs` (size num_regs, constants already present).
  void Eval(double* regs) const;
  // Same on jets: regs holds 3 doubles per register (value, first, second derivative).
  void EvalJet(double* regs) const;
};

// Builds a tape from roots of `pool`, folding every node that reads neither time nor state.
class TapeBuilder {
 public:
  TapeBuilder(const flat::ExprPool& pool, const std::vector<double>& param_values);
  // A builder of another tape over the same pool and parameters that shares `folds_of`'s
  // folded values (a node folds to the same value in every tape): the compiler's tapes fold
  // each node once and make the per-node fold tables once. `folds_of` must outlive it.
  static TapeBuilder SharingFolds(TapeBuilder& folds_of);
  // Returns the root index in the finished tape.
  int AddRoot(flat::ExprId id, std::string label, std::string text);
  // True when `id` folds to a constant; *value receives it.
  bool Fold(flat::ExprId id, double* value);
  Tape Finish();

 private:
  // What folding learnt per node, for any tape of the pool.
  struct Folds {
    std::vector<signed char> known;    // -1 unknown, 0 not constant, 1 constant
    std::vector<double> value;         // folded value where known == 1
    std::vector<flat::ExprId> stack;   // Fold's explicit stack, kept between calls
  };
  Folds& folds() { return shared_ ? *shared_ : own_; }
  int RegisterOf(flat::ExprId id);
  const flat::ExprPool& pool_;
  const std::vector<double>& params_;
  Folds own_;
  Folds* shared_ = nullptr;          // another builder's folds, or null for own_
  std::vector<int> reg_;             // per expr node: register or -1
  std::vector<flat::ExprId> stack_;  // RegisterOf's explicit stack
  Tape tape_;
};

}  // namespace kanesim::rt
