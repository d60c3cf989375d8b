// Is a compiled model conservative? The energy guard of a run (runtime/sim/energy_guard.h,
// docs/integrators.md "The energy guard") checks that T + V stays where it started, which is
// physics only when nothing in the model does work.
#pragma once

#include <string>

namespace kanesim::rt {

struct Program;

// "" when the model conserves the total energy that the kinetic_energy and
// potential_energy signals add up (T + V, V = gravity + line springs): ideal joints, closed
// loops and rolling contacts; gravity; springs of constant stiffness and free length.
// Otherwise the first element that does (or may do) work, in words: "the damper 'd1'",
// "the prescribed motion of joint 'crank'", "the force of joint 'j' (tau)", "the friction of
// joint 'pin'", "the force 'push'". An element the rule cannot vouch for (a stiffness given
// by an expression) makes the model not conservative: the guard never stops a correct run.
std::string NonConservativeCause(const Program& program);

}  // namespace kanesim::rt
