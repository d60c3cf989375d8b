// A when clause's speed jump in a mechanism with Coulomb friction proportional to the
// normal force (`mu` of Revolute and Prismatic; docs/events.md "Friction in a jump"). The
// jump's impulse carries an impulsive normal force in the joints, so their friction acts
// impulsively too: a joint's friction impulse P_f obeys Coulomb's law on impulses,
// |P_f| <= mu_s r |P_N| where the joint ends at rest (it sticks), P_f = -mu r |P_N| sign(u+)
// where it slides on (u+ its speed after the jump), P_N the joint's normal impulse.
#pragma once

#include <string>
#include <vector>

#include "runtime/runtime.h"

namespace kanesim::sim {

// The most friction joints the jump's case enumeration (3^n cases) takes.
constexpr int kMaxFrictionImpulseJoints = 6;

// True when a jump in `program` meets friction impulses (a joint with mu > 0).
bool HasFrictionImpulses(const rt::Program& program);

// du (nu entries): the free speeds `rows` change by `targets`, the friction joints (mu > 0,
// not among `rows`) by their Coulomb impulses, every other speed follows through M^-1.
// *stuck: the free speeds of the joints that stick (their speed after the jump is 0).
// 0, Derivative's codes, or -1 with *why (no case satisfies the law, too many joints, a
// singular mass matrix).
// planes: plane contacts' rows J du = target (an impact or a resting contact), their impulses
// c J^T acting at the contacts, so the joints between a contact and the ground carry them in
// their normal impulses. *impulses (may be null): the rows' impulses, `rows` then `planes`.
struct PlaneJumpRow {
  int contact = -1;       // index among rt::PlaneContacts
  std::vector<double> J;  // nu entries
  double target = 0.0;
};
int FrictionSpeedJump(const rt::Program& program, rt::Workspace& ws, double t, const double* y,
                      const std::vector<int>& rows, const std::vector<double>& targets, double* du,
                      std::vector<int>* stuck, std::string* why, const std::vector<PlaneJumpRow>& planes = {},
                      std::vector<double>* impulses = nullptr);

}  // namespace kanesim::sim
