// What the user chooses for Compile: the solver path, the integrator, and how undetermined
// reaction components are reported. Kept apart from the engine facade (runtime/runtime.h) so
// that the Program (runtime/program/program.h), which stores them, sits below the facade.
#pragma once

namespace kanesim::rt {

enum class SolverPath { Auto, Dense, Sparse, Recursive };
enum class IntegratorKind { Auto, IDA, CVODE, ARKODE, DOP853 };

// What reaction and contact-force signals report for a component the equations leave
// undetermined (redundant constraints make it statically indeterminate,
// docs/constraints.md "Indeterminate constraint forces"): NaN, or the share of the
// minimum-norm multipliers (`kanesim run --reactions min-norm`).
enum class IndeterminateReactions { NaN, MinNorm };

struct CompileOptions {
  SolverPath solver = SolverPath::Auto;
  IntegratorKind integrator = IntegratorKind::Auto;
  IndeterminateReactions indeterminate = IndeterminateReactions::NaN;
};

}  // namespace kanesim::rt
