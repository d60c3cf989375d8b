// A jump of the speeds by a generalized impulse through the mass matrix (Kane's impulsive
// form M du = J^T lambda with J the rows of chosen speeds): the jump that sets those speeds'
// changes to given targets, every other speed following (docs/events.md).
#pragma once

#include <string>
#include <vector>

#include "runtime/runtime.h"

namespace kanesim::sim {

// du (nu entries) = X c with X = [M^-1 e_r for r in rows] and c from (X c)_rows = targets:
// the speeds `rows` (free-speed indices) change by `targets`, the others by the impulse's
// response. 0, Derivative's status codes, or -1 when the rows' block of M^-1 is singular
// (ErrorMessage(ws) then says why where the runtime did).
// A c = b for the small dense A (m x m, row-major), Gaussian elimination with partial
// pivoting. False when A is singular.
bool SolveSmall(std::vector<double> A, std::vector<double> b, std::vector<double>* c);

// A c = b for a held set's A = J M^-1 J^T (m x m, row-major, symmetric positive
// semi-definite), whose rows may be dependent: a box resting flat on four corner contacts
// (four rows, rank three) or two stops holding one motion. Where the rows are independent
// (every pivot of A scaled to a unit diagonal above kDependentPivot), c is SolveSmall's, to
// the bit. Where they are dependent to round-off, the motion is determined but c is not:
// then c is the solution least in sum_i A_ii c_i^2 (each impulse weighted by its row's
// inverse effective mass; the minimum-norm solution of the scaled system, by a complete
// orthogonal decomposition) and *dependent (non-null) is set. False when there is no
// solution: dependent rows whose targets disagree by more than their round-off
// (kConsistentRows of A c's and b's terms, plus `slack`: the caller's absolute round-off of
// b; two dependent contacts with different restitutions), or A not finite.
bool SolveHeld(const std::vector<double>& A, const std::vector<double>& b, std::vector<double>* c,
               bool* dependent = nullptr, double slack = 0.0);

// F (non-null): the jump's generalized impulse on the free speeds (nu entries), sum c_j e_rows_j.
int SpeedJump(const rt::Program& program, rt::Workspace& ws, double t, const double* y, const std::vector<int>& rows,
              const std::vector<double>& targets, double* du, std::vector<double>* F = nullptr);

// A jump du by the generalized impulse F (nu entries each) at (t, y) whose rolling contact
// (RollingDisk, RollingSphere, KnifeEdge) takes a tensile normal impulse beyond round-off:
// the plane would pull the body onto it, as the continuous case's LiftOffGuard stops for.
// "" when none does (or the program has no contacts); else the cause naming the contact.
// *status: 0, or Derivative's codes (then the cause is ErrorMessage's).
std::string PullingContact(const rt::Program& program, rt::Workspace& ws, double t, const double* y,
                           const std::vector<double>& du, const std::vector<double>& F, int* status);

}  // namespace kanesim::sim
