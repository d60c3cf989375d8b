// Which knowns each unknown of an exported FMU depends on: the `dependencies` of
// ModelStructure (docs/fmi.md "Dependencies"), from the compiled program's structure.
//
// A listed dependency may be spurious (the partial derivative happens to be zero), a missing
// one would be a bug: FMI masters use the lists to order the evaluation of connected FMUs and
// to find algebraic loops. The rules, per unknown:
//   der(q)  the kinematic differential equations qdot = N(q) u of its joint
//           (rt::JointKinematicDifferential): exactly the coordinates and speeds of that joint
//           it reads; dependenciesKind "constant" where qdot_k = u_k. In a mechanism whose
//           derivative projects onto constraints (closed loops, rolling contacts, couplings),
//           every state of the coupled group instead.
//   der(u)  Kane's equations M(q) udot = f(q, u, t, inputs) of its group: a tree rooted at
//           the world, merged with every other tree a line force, a constraint row or a
//           shared solve (friction, end stops, plane contacts) connects it to; all of the
//           group's states, and whatever the forces acting on the group read (the force
//           tape's state references, inputs and time, traced register by register).
//   outputs what their expressions read (the output tape), a joint's q or u directly, a
//           frame's pose or motion through the coordinates and speeds of its body's path to
//           the world (all of the group's when it projects).
// Prescribed motions q(t) read time and whatever inputs their expressions read.
#pragma once

#include <vector>

#include "fmi/variables.h"
#include "runtime/program/program.h"

namespace kanesim::fmi {

struct Dependency {
  int var = -1;           // the known: its index in the variable table (a state or an input)
  bool constant = false;  // it enters with a constant factor (der(q) = u): dependenciesKind "constant"
};

struct UnknownDependencies {
  std::vector<Dependency> knowns;  // states and inputs it reads, ascending by variable index
  bool time = false;               // it reads time (an expression's `time`, a prescribed motion)
  bool parameters = false;         // it may read tunable parameters (folded into the program)
};

// Per variable of `vars` (ListVariables of `p`'s model); filled for derivatives and outputs,
// empty for the other kinds.
std::vector<UnknownDependencies> ModelDependencies(const rt::Program& p, const std::vector<Variable>& vars);

}  // namespace kanesim::fmi
