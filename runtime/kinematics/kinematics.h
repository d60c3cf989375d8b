// The kinematic stages of the right-hand side, in the order Derivative calls them:
//   UnpackState -> PositionKinematics -> VelocityKinematics -> KinematicDifferentials
//   -> BiasAccelerations (for a tree the three kinematic passes fused: MotionKinematics).
// Each reads the Program and writes only the Workspace fields its comment in
// program.h names. None allocates.
#pragma once

#include "runtime/program/program.h"

namespace kanesim::rt {

// Full q, u from y = [q_free, u_free]; prescribed q, qdot, qddot from the time jet.
// Returns 0, or -1 (ws.error) when a prescribed motion is not finite.
int UnpackState(const Program& p, Workspace& ws, double t, const double* y);
// The inverse: y = [q_free, u_free] from ws.q, ws.u (after a projection, for instance).
void PackState(const Program& p, const Workspace& ws, double* y);

// Body poses, joint relative poses, world inertias (seed 000 eq. 11.9: positions).
void PositionKinematics(const Program& p, Workspace& ws);

// The tangent generators H_W (one twist per full speed, at the child body's origin) and
// body velocities: with unit pseudo-speeds u = e_r the velocity of every body is the
// column tau_r (seed 000 eqs. 11.15-11.16).
void VelocityKinematics(const Program& p, Workspace& ws);

// Accelerations with free udot = 0 and prescribed udot from the jet (seed 000 eq. 11.17).
// With `include_free` the free udot in ws.udot are included too: the body accelerations
// themselves (used by signals that need reactions).
void BiasAccelerations(const Program& p, Workspace& ws, bool include_free = false);

// PositionKinematics, VelocityKinematics and BiasAccelerations (free udot = 0) at once,
// for a tree: the same results in one pass over the bodies. (Closed loops project the
// speeds between velocities and accelerations, so they call the three one by one, unless
// the solver projects its steps instead: runtime/runtime.h SetStepProjection.)
void MotionKinematics(const Program& p, Workspace& ws);

// qdot = N(q) u for every joint (Lesser eqs. 44-47). Returns -1 at gimbal lock.
int KinematicDifferentials(const Program& p, Workspace& ws);

// Partial velocity of body L's mass centre and partial angular velocity for full speed
// r: [v_{L,r}; w_{L,r}] (Lesser eq. 22). Zero unless r's joint lies on L's path.
Vec6 TangentColumn(const Program& p, const Workspace& ws, int body, int full_speed);

// World pose and motion of a flat frame (after Position/VelocityKinematics).
void FramePose(const Program& p, const Workspace& ws, int frame, Vec3* p_WF, Mat3* R_WF);
void FrameMotion(const Program& p, const Workspace& ws, int frame, Vec3* v_WF, Vec3* w_WF);
// The same for a point fixed on body B (-1: the world) at rho = p_WP - p_WB (world axes),
// when the caller has rho already (closed loops' frames, constraints.cpp).
void PointMotion(const Workspace& ws, int body, const Vec3& rho, Vec3* v_WP, Vec3* w_WB);

// Fills ws.state_values for the listed mech state refs.
void EvalStateRefs(const Program& p, Workspace& ws, const std::vector<int>& refs);

}  // namespace kanesim::rt
