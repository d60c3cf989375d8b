// Constraint forces on request (Lesser §3c, eqs. 26-29): joint reaction wrenches of tree
// and cut joints, loop multipliers, and the power of all constraint forces. Computed by
// EvalSignals only when a signal asks, after the accelerations are known (the
// right-hand side never calls these). None allocates.
#pragma once

#include "runtime/program/program.h"

namespace kanesim::rt {

// Loop multipliers lambda (n_c) with A^T lambda = M udot - f on the free speeds: the
// minimum-norm solution from the dependent block, lambda = Q [R^-T g_dep; 0]; along
// redundant rows (statically indeterminate) it is the minimum-norm choice.
// Needs the accelerations (SolveAccelerations, BiasAccelerations with include_free).
void LoopMultipliers(const Program& p, Workspace& ws);

// ws.reaction_W[L]: the wrench the parent side exerts on tree body L's subtree through
// joint L, at o_L, world axes (Newton-Euler of the subtree, loop forces included).
void JointReactions(const Program& p, Workspace& ws);

// ws.reaction_W from the multipliers ws.lambda_c alone (the bodies' inertia and applied
// forces left out): the linear map lambda -> reactions whose null space decides which
// reaction components are statically indeterminate (compiler/indeterminate.cpp).
// Needs the positions only.
void MultiplierReactions(const Program& p, Workspace& ws);

// Reaction of flat joint `flat_joint` on its frame_b side, at frame_b's origin, resolved
// in frame_b: [force; torque]. Includes the joint's own applied force (tau, drive).
Vec6 JointReactionInFrameB(const Program& p, const Workspace& ws, int flat_joint);

// The generalized force a prescribed speed r needs (signals.cpp): on the tree, and with
// the loops' dependent speeds (the `.drive` signal). For a free r: (M udot - f)_r.
double DriveForce(const Program& p, const Workspace& ws, int r);
double LoopDriveForce(const Program& p, Workspace& ws, int r);

// The plane's force on a contact's body, at its contact point (world axes; after
// LoopMultipliers); *cp receives the contact point's geometry when not null.
struct ContactPoint;
Vec3 ContactForce(const Program& p, const Workspace& ws, int contact, ContactPoint* cp);

// Power of every ideal constraint force: sum over joints of (reaction wrench) . (joint
// relative twist) minus the joints' applied generalized forces times their speeds, plus
// the loop forces' lambda . (A u + b). Zero on admissible motions.
double ConstraintPower(const Program& p, Workspace& ws);

}  // namespace kanesim::rt
