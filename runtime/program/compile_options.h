// What the user chooses for Compile: the solver path, the integrator, and how undetermined
// reaction components are reported. Kept apart from the engine facade (runtime/runtime.h) so
// that the Program (runtime/program/program.h), which stores them, sits below the facade.
#pragma once

namespace kanesim::rt {

enum class SolverPath { Auto, Dense, Sparse, Recursive };
// The time integrators (sim/integrator.h describes each; `--integrator auto|ida|cvode|
// cvode-bdf|arkode|dop853`), the one enum for them in every layer. Auto: the compiler's
// choice, IDA for stiff force elements, else DOP853 (Summarize says which and why).
enum class Integrator { Auto, IDA, CvodeAdams, CvodeBdf, ArkodeErk, Dop853 };

// What reaction and contact-force signals report for a component the equations leave
// undetermined (redundant constraints make it statically indeterminate,
// docs/constraints.md "Indeterminate constraint forces"): NaN, or the share of the
// minimum-norm multipliers (`kanesim run --reactions min-norm`).
enum class IndeterminateReactions { NaN, MinNorm };

struct CompileOptions {
  SolverPath solver = SolverPath::Auto;
  Integrator integrator = Integrator::Auto;
  IndeterminateReactions indeterminate = IndeterminateReactions::NaN;
};

}  // namespace kanesim::rt
