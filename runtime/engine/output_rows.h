// Output rows near a change point (docs/constraints.md "Rows near a change point").
#pragma once

#include "runtime/program/program.h"

namespace kanesim::rt {

// Whether the configuration in ws (PositionKinematics done) is near a change point: some
// closed loop's rows have rho = sigma_min/sigma_max below kRowZone. Forms ws.A.
bool RowNearChangePoint(const Program& p, Workspace& ws);

// The projection of an output row near a change point, instead of ProjectState: positions
// and speeds corrected by the least change in the kinetic-energy metric (Gauss-Newton on
// the positions, then one step on the speeds), through a truncated pseudo-inverse of the
// constraint Jacobian in that metric (Bayo & Ledesma 1996), so that the directions a
// nearly singular Jacobian leaves undetermined keep the integrator's own values instead
// of an amplified solve through a nearly singular dependent block. Leaves the position
// and velocity kinematics of the projected state in ws, and (reduced form) the dependent
// block factored for the accelerations (1 with ws.error when `accelerations` are asked for
// and that block is singular: at the crossing itself). 0, or 1 (ws.error).
int ProjectRowNearChangePoint(const Program& p, Workspace& ws, bool accelerations);

}  // namespace kanesim::rt
