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

// The accelerations by the scene's path: reduced (closed loops), sparse, recursive or dense.
int SolveAccelerations(const Program& p, Workspace& ws);

// Coulomb friction depending on joint normal forces (runtime/kane/friction.cpp): iterates
// `path` (the scene's solve) with the friction forces in ws.Q until they agree.
int SolveWithFriction(const Program& p, Workspace& ws, int (*path)(const Program&, Workspace&));

// Compile time: the fixed pattern and the KLU symbolic analysis (reused when
// `p.sparse_symbolic` is already set by Rebind).
bool BuildSparse(Program& p, std::string* error);
// Workspace creation: value arrays for the pattern.
void InitSparseWorkspace(const Program& p, Workspace& ws);

}  // namespace kanesim::rt
