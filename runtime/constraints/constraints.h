// Closed kinematic loops: the cut joints' position constraints phi(q) = 0, their
// velocity form A(q) u + b(q, t) = 0 (Lesser §4c eq. 48) and the reduced Kane's
// equations on the constrained basis beta (Lesser eqs. 49-51). docs/constraints.md.
//
// Stages, as Derivative calls them after VelocityKinematics:
//   ProjectState      Newton on the dependent coordinates (phi = 0), then the dependent
//                     speeds (A u + b = 0): the right-hand side is always evaluated on the
//                     constraint manifold, so the loops cannot drift.
//   SolveConstrained  after AppliedForces: M udot = f restricted to beta.
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
// and velocity kinematics of the projected state in ws. 0, or 1 (recoverable).
// On the sparse (multiplier) path the steps are instead the kinetic-metric corrections
// of kane.h SparseCorrection, and the factorization is left for SolveSparse.
int ProjectState(const Program& p, Workspace& ws);

// The bodies a row reads: frame a's and frame b's for a loop row, (the contact's body, -1)
// for a contact row; -1 for the world.
void RowBodies(const Program& p, int row, int* body_a, int* body_b);
// Row i's rate as a function of those bodies' mass-centre twists [v_cm; w]:
//   d/dt phi_i (or the velocity row) = Ja . V_a + Jb . V_b.
void RowJacobians(const Program& p, const Workspace& ws, int row, Vec6* Ja, Vec6* Jb);

// For solvers that project their steps (engine.h SetStepProjection): the constraint
// Jacobian A at the positions as they are and its dependent block's factorization, what
// the reduced equations need, and the rolling disks' check (ws.psi = A u + b of the
// speeds as they are). Nothing is projected: off the manifold the reduced equations are
// still a smooth ODE (docs/constraints.md, "Projecting once per step"). 0, or 1
// (recoverable), or -1. Not on the sparse path.
int FactorConstraintsAsIs(const Program& p, Workspace& ws);

// ws.psi only (A u + b without forming A), after VelocityKinematics.
void ConstraintRates(const Program& p, Workspace& ws);

// Reduced Kane's equations (beta^T M beta) z = beta^T (f - M udot_p); writes ws.udot.
int SolveConstrained(const Program& p, Workspace& ws);
// Whether forming them by velocity passes on the columns of beta (one per degree of
// freedom) is cheaper than through the composite mass matrix: the compiler's choice of
// Program::reduce_by_passes, up to kPassesMaxDof degrees of freedom. bench/loop_solvers,
// minimum of 3-4 alternating rounds, passes / through M: four-bar 0.86-0.90, rolling disk
// 0.97, slider-crank 1.01, ladder of N loops (N DOF) 0.82-0.90 for N = 1-8, 0.96 at 16,
// 1.06 at 20, 32 and 64.
constexpr int kPassesMaxDof = 16;
bool PassesCheaper(int dof);

// Workspace creation: the loop arrays.
void InitConstraintWorkspace(const Program& p, Workspace& ws);

}  // namespace kanesim::rt
