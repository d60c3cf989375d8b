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

#include <cstddef>
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

// One known of a ModelStructure list: its value reference (vars.size() is FMI 3's `time`)
// and whether it enters with a constant factor (dependenciesKind "constant").
struct ListedKnown {
  size_t vr = 0;
  bool constant = false;
};

// The knowns of the unknown vars[v] as ModelStructure lists them (`kanesim export` writes
// them, fmi3GetVariableDependencies returns them: one source), ascending by value reference.
// Runtime (initial = false): what it reads, in FMI 3 with time and the tunable parameters,
// which FMI 3 counts among the knowns. Initialization: every tunable parameter besides (the
// start state may be computed from any); only "dependent" there.
struct StructureLists {
  const std::vector<Variable>& vars;
  std::vector<UnknownDependencies> deps;  // ModelDependencies
  int version = 2;                        // 2 or 3
};
std::vector<ListedKnown> ListedKnowns(const StructureLists& s, size_t v, bool initial);
// Every known of a section (the standard's meaning of an unknown without a list).
std::vector<ListedKnown> AllKnowns(const StructureLists& s, bool initial);
// Whether the description leaves out v's list: it would name every known (FMI 3's time, a
// spurious dependency then, aside) without a constant factor; then v depends on AllKnowns.
bool ListOmitted(const StructureLists& s, size_t v, bool initial);

}  // namespace kanesim::fmi
