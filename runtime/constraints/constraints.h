// Closed kinematic loops and rolling contacts as constraint rows: the cut joints' position
// constraints phi(q) = 0, their velocity form A(q) u + b(q, t) = 0 (Lesser §4c eq. 48), the
// acceleration bias, and the partition of the free speeds into dependent and independent
// ones (Lesser eqs. 49-51). docs/constraints.md. Kinematics only: the equations of motion
// on these rows (the reduced form, the multiplier form, the projection in the kinetic
// metric) are kane/'s, one layer up (kane/kane.h).
//
// Stages, as Derivative calls them after VelocityKinematics:
//   ProjectState (kane.h)  Newton on the dependent coordinates (phi = 0), then the
//                          dependent speeds (A u + b = 0): the right-hand side is always
//                          evaluated on the constraint manifold, so the loops cannot drift.
//   SolveConstrained (kane.h)  after AppliedForces: M udot = f restricted to beta.
// None allocates.
#pragma once

#include "runtime/program/program.h"

namespace kanesim::rt {

// ws.phi from the current poses (after PositionKinematics).
void ConstraintResiduals(const Program& p, Workspace& ws);

// ws.A (free speeds; the active rows, Program::active_rows), ws.psi = A u + b (every
// row), after VelocityKinematics.
void ConstraintJacobian(const Program& p, Workspace& ws);

// Column of the constraint Jacobian for full speed r (free or prescribed), into *col (n_c).
void ConstraintColumn(const Program& p, const Workspace& ws, int r, Eigen::VectorXd* col);

// ws.cbias: d/dt (A u + b) with free udot = 0 (after BiasAccelerations).
void ConstraintBias(const Program& p, Workspace& ws);

// Chooses (or keeps) the dependent speeds by column pivoting and factors A_dep.
// Returns 0, or 1 (recoverable, ws.error) at a singular configuration.
int FactorDependent(const Program& p, Workspace& ws);

// The active rows' entries of a per-row vector (phi, psi, cbias, a column): n_c -> n_a.
void GatherActive(const Program& p, const Eigen::VectorXd& full, Eigen::VectorXd* active);

// x = A_dep^+ v (n_a -> rank) with the factorization of FactorDependent; v is kept. Only
// x(0:rank) is the solution (the entries after it hold the rest of Q^T v).
void SolveDependent(const Workspace& ws, const Eigen::VectorXd& v, Eigen::VectorXd* x);

// q += N(q) du for a full-speed step du (quaternions renormalized).
void ApplyCoordinateStep(const Program& p, Workspace& ws, const Eigen::VectorXd& du_full);

// Newton on the dependent coordinates, then the dependent speeds; leaves the position
// and velocity kinematics of the projected state in ws. 0, or 1 (recoverable). The
// reduced form's projection; kane.h ProjectState chooses it or the multiplier form's.
int ProjectStateByPartition(const Program& p, Workspace& ws);

// Pieces of the projections (kane_sparse.cpp's uses them too).
// Newton on positions iterates to round-off (kProjectTight, relative to the loops' length)
// so that the right-hand side is a smooth function of y for difference-quotient
// Jacobians, at most kProjectMaxNewton steps.
constexpr double kProjectTight = 1e-13;
constexpr int kProjectMaxNewton = 8;
// 1 (recoverable, ws.error) when a row of ws.phi is still above the loose limit.
int CheckLoopsClosed(const Program& p, Workspace& ws);

// Loop `loop`'s active rows of ws.A at the current positions (after PositionKinematics;
// the other rows untouched), for a choice among them.
void LoopJacobianRows(const Program& p, Workspace& ws, int loop);

// The length that makes loop `loop`'s translation rows of ws.A (m per unit speed)
// commensurate with its alignment rows (per radian): the RMS lever arm, sqrt(mean |A_i|^2
// over its translation rows / mean over its alignment rows); 1 with rows of one kind only,
// where a common scale does not change which rows are independent or their ratio of
// singular values. A mechanism scaled by s has s times the lever arm.
double LoopLeverArm(const Program& p, const Workspace& ws, int loop);
// q += N(q) ws.du_full, and the position and velocity kinematics of the new positions.
void StepCoordinates(const Program& p, Workspace& ws);
// With ws.error: -1 (fatal) when a rolling disk lies flat, 1 (recoverable) when a step went
// through flat (after the positions are projected; ws.psi of the integrator's speeds).
int CheckDisksUpright(const Program& p, Workspace& ws);
// The cut joints and contacts with rows, for messages: "'coupler_rocker'".
std::string LoopOwners(const Program& p);

// The bodies a row reads: frame a's and frame b's for a loop row, (the contact's body, -1)
// for a contact row; -1 for the world.
void RowBodies(const Program& p, int row, int* body_a, int* body_b);
// Row i's rate as a function of those bodies' mass-centre twists [v_cm; w]:
//   d/dt phi_i (or the velocity row) = Ja . V_a + Jb . V_b.
void RowJacobians(const Program& p, const Workspace& ws, int row, Vec6* Ja, Vec6* Jb);

// For solvers that project their steps (runtime/runtime.h SetStepProjection): the constraint
// Jacobian A at the positions as they are and its dependent block's factorization, what
// the reduced equations need, and the rolling disks' check (ws.psi = A u + b of the
// speeds as they are). Nothing is projected: off the manifold the reduced equations are
// still a smooth ODE (docs/constraints.md, "Projecting once per step"). 0, or 1
// (recoverable), or -1. Not on the sparse path.
int FactorConstraintsAsIs(const Program& p, Workspace& ws);

// ws.psi only (A u + b without forming A), after VelocityKinematics.
void ConstraintRates(const Program& p, Workspace& ws);

// Workspace creation: the loop arrays.
void InitConstraintWorkspace(const Program& p, Workspace& ws);

}  // namespace kanesim::rt
