// NonConservativeCause (runtime/runtime.h): which force element keeps a model from conserving T + V.
#include "runtime/runtime.h"

#include "runtime/program/program.h"

namespace kanesim::rt {

namespace {

bool Zero(const Scalar& s) { return s.root < 0 && s.value == 0.0; }
bool Constant(const Scalar& s) { return s.root < 0; }  // folded: no time, no state

std::string JointOfSpeed(const Program& p, int u) {
  const int j = p.joint_of_speed[static_cast<size_t>(u)];
  return j >= 0 ? p.joints[static_cast<size_t>(j)].name : "?";
}

}  // namespace

std::string NonConservativeCause(const Program& p) {
  if (!p.prescribed_u.empty()) return "the prescribed motion of joint '" + JointOfSpeed(p, p.prescribed_u.front()) + "'";
  for (int s : p.stop_joints)  // an impact with restitution e < 1 takes kinetic energy
    if (p.joints[static_cast<size_t>(s)].restitution < 1.0) return "the end stop of joint '" + p.joints[static_cast<size_t>(s)].name + "'";
  for (const WhenModel& w : p.whens)  // a reinit sets the state to what the model says
    if (!w.reinits.empty()) return "the reinit in " + w.name;
  for (const PlaneContactModel& c : p.plane_contacts)  // likewise
    if (c.restitution < 1.0) return "the plane contact '" + c.name + "'";
  for (const TreeJoint& j : p.joints)
    if (j.mu != 0.0) return "the friction of joint '" + j.name + "'";
  if (!p.friction_joints.empty()) return "the friction of joint '" + p.joints[static_cast<size_t>(p.friction_joints.front())].name + "'";
  for (int u = 0; u < p.nu_all; ++u)
    if (!Zero(p.joint_tau[static_cast<size_t>(u)])) return "the force of joint '" + JointOfSpeed(p, u) + "' (tau)";
  for (const LineForceModel& l : p.line_forces) {
    if (!Zero(l.d)) return "the damper '" + l.name + "'";
    if (!Constant(l.k) || !Constant(l.s0)) return "the spring '" + l.name + "' (its stiffness or free length is an expression)";
  }
  for (const WrenchModel& w : p.wrenches)
    for (int k = 0; k < 3; ++k)
      if (!Zero(w.force[k]) || !Zero(w.torque[k])) return "the force '" + w.name + "'";
  return "";
}

}  // namespace kanesim::rt
