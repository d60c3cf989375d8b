// The compiler's public face (the layer compiler/, kanesim_compiler): a flat mechanism in,
// an immutable runtime Program out: the spanning tree, the tangent basis by kinematic
// differentials, the complement basis, closed loops and contacts (docs/architecture.md).
// Rebind gives an existing Program new parameter values; the warnings below are the
// compiler's findings about a compiled model, for `kanesim check` and the pipeline.
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "flat/flat.h"
#include "runtime/runtime.h"

namespace kanesim::rt {

// A model error found by the compiler (not the parser), with a code of the one table
// (flat/diagnostic_codes.h); pipeline::AddCompileMessage turns it into a language
// diagnostic (file:line:col, caret, notes, hint) rendered by the same renderer.
struct CompileMessage {
  flat::DiagCode code = flat::DiagCode::WorldMissing;
  std::string message;
  std::string hint;     // may be empty
  flat::SourceLoc loc;
  std::vector<std::pair<flat::SourceLoc, std::string>> notes;
};

struct CompileResult {
  std::shared_ptr<const Program> program;  // null when errors is non-empty
  std::vector<CompileMessage> errors;
};

CompileResult Compile(const flat::Mechanism& mech, const CompileOptions& options);
// The same without a copy of the mechanism: the program shares `mech` (Program::mech).
// The first form copies it once into the program; pipeline::LoadModel uses this one.
CompileResult Compile(std::shared_ptr<const flat::Mechanism> mech, const CompileOptions& options);
// The same with the parameters' values given (index-aligned with mech->params) instead of
// evaluated (flat::EvaluateParams): a mechanism just elaborated has them already
// (flat::ElaboratedParamValues). A wrong number of values is an error, as Rebind's.
CompileResult Compile(std::shared_ptr<const flat::Mechanism> mech, std::vector<double> param_values,
                      const CompileOptions& options);

// Same structure, new numeric parameter values (index-aligned with mech.params);
// reuses every pattern and symbolic analysis. Used by sweeps. On failure (a negative
// mass, a singular assembly, a wrong number of values) `errors` says why, as Compile's do.
CompileResult Rebind(const Program& program, const std::vector<double>& param_values);

// Warning W313 for `signals` (from IndeterminateSignals, not empty): names them and the
// redundant constraints with their source locations, and says how they are written
// (NaN, or the minimum-norm share, per CompileOptions::indeterminate).
CompileMessage IndeterminateWarning(const Program& program, const std::vector<std::string>& signals);

// Warning W314, or a message with an empty message when there is nothing to say: Coulomb
// friction in a joint whose normal force is statically indeterminate follows the
// minimum-norm share of that force (compiler/indeterminate.cpp).
CompileMessage FrictionIndeterminateWarning(const Program& program);

// Warning W315, or a message with an empty message when there is nothing to say: the
// start speeds violated the velocity constraints and the assembly changed a speed given a
// non-zero start value (compiler/loops.cpp): names the constraints, the speeds
// changed (from -> to) and the largest change.
CompileMessage StartSpeedsWarning(const Program& program);

// Warnings W316, one per joint whose two frames are on the same rigid body (the world, or
// bodies a weld or fixed element merged): such a joint cannot move, so the program has
// neither a speed nor a constraint for it (compiler/loops.cpp LockedJoint).
std::vector<CompileMessage> LockedJointWarnings(const Program& program);

}  // namespace kanesim::rt
