// Rolling contacts against a fixed plane: RollingDisk, RollingSphere, KnifeEdge
// (flat::Contact). Each gives rows d . v_P = 0 on the velocity of the body's material
// point P at the contact (Lesser §4c eq. 48, A u + b = 0). Only the normal row is also a
// position constraint (the body stays on the plane); the tangential and lateral rows
// are not integrable and are never turned into position constraints.
#pragma once

#include "runtime/program/program.h"

namespace kanesim::rt {

// Where the contact is and how it moves (after Position/VelocityKinematics).
struct ContactPoint {
  Vec3 P = Vec3::Zero();    // contact point (on the plane when the constraint holds)
  Vec3 C = Vec3::Zero();    // frame origin: disk or sphere centre, knife point
  Vec3 vPm = Vec3::Zero();  // velocity of the body's material point at P
  Vec3 vPg = Vec3::Zero();  // velocity of the geometric contact point
  Vec3 e_W = Vec3::Zero();  // disk axis / blade direction, world
  Vec3 w = Vec3::Zero();    // angular velocity of the body
};
ContactPoint ContactAt(const Program& p, const Workspace& ws, const ContactModel& c);

// The row's direction d (world) and its rate (zero unless it turns with the body).
Vec3 ContactRowDirection(const ContactModel& c, const ConstraintRow& row, const ContactPoint& cp, Vec3* d_dot);

// Per row, with cp = ContactAt of the row's contact (computed once for all its rows):
// phi of a contact row (n . (P - p0) for the normal row, 0 otherwise).
double ContactResidual(const Program& p, const ConstraintRow& row, const ContactPoint& cp);
// Adds the row's Jacobian into ws.A row i (none when i < 0) and returns its velocity
// residual d . v_P.
double ContactJacobianRow(const Program& p, Workspace& ws, const ConstraintRow& row, int i, const ContactPoint& cp);
// d/dt (d . v_P) with free udot = 0 (after BiasAccelerations).
double ContactBias(const Program& p, const Workspace& ws, const ConstraintRow& row, const ContactPoint& cp);
// Value of the row's velocity for the unit pseudo-speed of full speed s.
double ContactColumn(const Program& p, const Workspace& ws, const ConstraintRow& row, int s);

// Longitudinal and lateral unit directions in the plane: a disk's rolling direction and
// its axis' projection; a sphere's centre velocity direction (t1 at rest); a knife
// edge's blade and its normal.
void ContactDirections(const ContactModel& c, const ContactPoint& cp, Vec3* longitudinal, Vec3* lateral);

}  // namespace kanesim::rt
