// Internal to sim: matrix-free Newton-Krylov for IDA and CVODE-BDF (SUNDIALS'
// SPGMR, no preconditioner, the integrator's own difference-quotient J*v).
//
// Where it pays: closed loops on the multiplier form. There f(y) = g(P(y)) + k (P(y) - y)
// (runtime/engine/engine.cpp, k = 10 1/s), P the projection onto the position and velocity
// constraints, whose image is the state manifold of dimension r (2 dof for joints with
// nq = nu), so df/dy = -k I + (g' + k I) P' is -k I plus a matrix of rank r
// (OdeSystem::NewtonRank). The Newton matrices, cj I - df/dy (IDA) and I - gamma df/dy
// (CVODE), are a multiple of the identity plus rank r: GMRES solves them in r + 1
// iterations, one evaluation of f each, where the dense difference-quotient Jacobian costs
// n evaluations and an O(n^3) LU. Measured on the chain of 40 equal-link parallelograms
// (n = 162, r = 2): docs/integrators.md "Newton-Krylov".
#pragma once

#include <sundials/sundials_context.h>
#include <sundials/sundials_linearsolver.h>
#include <sundials/sundials_nvector.h>

#include "sim/integrator.h"
#include "sim/stepper.h"

namespace kanesim::sim::detail {

// Whether the Newton iteration goes matrix-free: options.ida_linear_solver Krylov, or Auto
// where the system's Newton rank r (GuardedRhs::NewtonRank) is known and r + 1 is at most
// n / kKrylovMinRatio, or where `projected_bdf` (CVODE-BDF projecting every step on the
// multiplier form: closed loops or rolling contacts; there CVODE's dense difference-quotient
// Newton matrix fails to converge at loose tolerances and the run drifts off the motion,
// docs/integrators.md "Newton-Krylov"). *maxl: the Krylov dimension (r + 1 plus a margin,
// at most n).
bool UseKrylov(const IntegratorOptions& options, GuardedRhs& rhs, int* maxl, bool projected_bdf = false);

// SPGMR without preconditioner on vectors like y (null when it cannot be made).
SUNLinearSolver MakeKrylovSolver(N_Vector y, int maxl, SUNContext ctx);

// IntegratorStats::linear_solver of a matrix-free Newton iteration.
inline constexpr const char* kKrylovName = "GMRES, matrix-free";

}  // namespace kanesim::sim::detail
