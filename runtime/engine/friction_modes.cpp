// Friction laws per joint (runtime/runtime.h FrictionJoints, SetFrictionMode, FrictionNormal):
// what exact stick-slip (sim/stick_slip.cpp) reads of and sets in a program's Coulomb joints.
#include <algorithm>

#include "runtime/program/program.h"
#include "runtime/runtime.h"

namespace kanesim::rt {

std::vector<FrictionJoint> FrictionJoints(const Program& p) {
  std::vector<FrictionJoint> out;
  for (int b : p.friction_joints) {
    const TreeJoint& j = p.joints[static_cast<size_t>(b)];
    FrictionJoint f;
    f.joint = j.name;
    f.q = static_cast<int>(std::find(p.q_free.begin(), p.q_free.end(), j.q0) - p.q_free.begin());
    f.u = p.u_free_of[static_cast<size_t>(j.u0)];
    f.mu = j.mu;
    f.mu_s = j.mu_s;
    f.radius = j.type == flat::JointType::Revolute ? j.mu_radius : 1.0;
    f.exact = j.friction_exact;
    f.c = j.friction_c;
    f.c_s = j.friction_c_s;
    out.push_back(f);
  }
  return out;
}

void SetFrictionMode(Workspace& ws, int i, int mode, double tau) {
  ws.friction_mode[static_cast<size_t>(i)] = mode;
  ws.friction_fixed[static_cast<size_t>(i)] = tau;
}

double FrictionNormal(const Workspace& ws, int i) { return ws.friction_N[static_cast<size_t>(i)]; }

double FrictionSpeed(const Program& p, const Workspace& ws, int i) {
  return ws.u[p.joints[static_cast<size_t>(p.friction_joints[static_cast<size_t>(i)])].u0];
}

}  // namespace kanesim::rt
