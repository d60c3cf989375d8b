// Kane's equations: applied forces, then one of three solution paths for udot (dense,
// sparse, recursive: runtime/kane/kane_tree.h).
#pragma once

#include <string>

#include "runtime/kane/kane_tree.h"
#include "runtime/program/program.h"

namespace kanesim::rt {

// Gravity, line forces, wrenches and joint forces per body at its mass centre, and the
// joint generalized forces Q. Returns -1 (ws.error) when an expression gives NaN.
int AppliedForces(const Program& p, Workspace& ws);
// Only the force tape (for potential energy); the value of a force-element number.
int EvalForceTape(const Program& p, Workspace& ws);
double ForceValue(const Program& p, const Workspace& ws, const Scalar& s);

// Dense path: M = tau^T Mb tau, f = tau^T (F - Mb a_bias - gyro) + Q, Cholesky/LDLT.
// Writes the free entries of ws.udot. Returns -1 on a singular mass matrix.
int SolveDense(const Program& p, Workspace& ws);
// Its first half: ws.M (lower triangle) and ws.f, eqs. (4) and (5) of kane_dense.cpp.
void AssembleDense(const Program& p, Workspace& ws);
// Its mass part alone: the composite inertias ws.Ic and the lower triangle of *M (nu x nu),
// eq. (4) of kane_dense.cpp, after PositionKinematics and VelocityKinematics.
void AssembleMass(const Program& p, Workspace& ws, Eigen::MatrixXd* M);
// Body L's bracketed wrench at its mass centre, eq. (2) of kane_dense.cpp with the free
// udot = 0: [F_L - m_L a_bias_L;  T_L - I_L alpha_bias_L - w_L x I_L w_L].
Vec6 BiasBracket(const Program& p, const Workspace& ws, int L);

// Sparse path: the K-vector Newton-Euler system with per-joint tangent and complement
// blocks, and a multiplier per independent constraint row (closed loops, contacts), KLU.
// Also fills ws.lambda_W (joint reaction wrenches) and, with constraints, ws.lambda_c.
// Factors first unless ws.sparse_ready (the factorization is of the current positions).
int SolveSparse(const Program& p, Workspace& ws);
// Its position-dependent half: complement bases, matrix values, KLU (re)factorization.
// Returns -1 (ws.error) when the matrix is singular; sets ws.sparse_ready.
int FactorSparse(const Program& p, Workspace& ws);
bool SparseHasFactor(const Workspace& ws);
// With the current factorization (possibly of nearby positions): the free-speed step
// du_full (full speed indices, prescribed zero) of least kinetic energy with
// A du = -residual on the kept constraint rows (kane_sparse.cpp eqs. 3-4).
int SparseCorrection(const Program& p, Workspace& ws, const Eigen::VectorXd& residual, Eigen::VectorXd* du_full);
// ProjectState (below) on this path: steps of SparseCorrection.
int ProjectStateSparse(const Program& p, Workspace& ws);

// Closed loops and rolling contacts (the rows of runtime/constraints/constraints.h).
// ProjectState: onto the constraint manifold, positions then speeds; leaves the position
// and velocity kinematics of the projected state in ws. 0, or 1 (recoverable). On the
// reduced form Newton on the dependent coordinates (constraints.h
// ProjectStateByPartition); on the sparse (multiplier) path the steps are the
// kinetic-metric corrections of SparseCorrection, and the factorization is left for
// SolveSparse (kane_sparse.cpp).
int ProjectState(const Program& p, Workspace& ws);
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


// The accelerations by the scene's path: reduced (closed loops), sparse, recursive or dense.
int SolveAccelerations(const Program& p, Workspace& ws);

// Coulomb friction depending on joint normal forces (runtime/kane/friction.cpp): iterates
// `path` (the scene's solve) with the friction forces in ws.Q until they agree.
int SolveWithFriction(const Program& p, Workspace& ws, int (*path)(const Program&, Workspace&));
// Whether a friction joint's force reads its normal force (mu != 0): then an impulse or a
// reaction is not M^-1 alone. A constant friction (friction_torque) does not.
bool FrictionReadsNormalForce(const Program& p);

// Compile time: the fixed pattern and the KLU symbolic analysis (reused when
// `p.sparse_symbolic` is already set by Rebind).
bool BuildSparse(Program& p, std::string* error);
// Workspace creation: value arrays for the pattern.
void InitSparseWorkspace(const Program& p, Workspace& ws);

}  // namespace kanesim::rt
