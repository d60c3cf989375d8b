// Impulsive normal forces of the Coulomb joints (runtime/runtime.h FrictionImpulseNormals):
// what a when clause's speed jump with `mu` friction (sim/friction_impulse.cpp) reads. During
// an impulse the bodies' forces and velocity terms are bounded, so the Newton-Euler sum of
// reactions.cpp (5) keeps only the momentum jumps: the impulse the parent side gives the
// subtree below joint L through the joint is
//   P_L = sum_{B in subtree(L)} m_B dv_cm,B                                          (1)
// (a tree: no loop or contact impulses act on a body; the joints' generalized impulses, a
// reinit's, a stop's or friction's, act along their joints' axes, between two bodies of the
// same subtree or on L's own axis, and so add nothing across L's axis). Its part across the
// axis a is the joint's normal impulse, as friction.cpp (1) takes N from the reaction force:
//   P_N,L = P_L - (P_L . a) a                                                        (2)
#include <vector>

#include "runtime/kinematics/kinematics.h"
#include "runtime/program/program.h"
#include "runtime/runtime.h"

namespace kanesim::rt {

int FrictionImpulseNormals(const Program& p, Workspace& ws, double t, const double* y, const double* du, double* P) {
  if (!p.rows.empty()) {
    ws.error = "an impulse with Coulomb friction mu N in a mechanism with closed loops or contacts is not supported";
    return -1;
  }
  const size_t K = p.bodies.size();
  std::vector<double> y1(y, y + p.nq + p.nu);
  for (int i = 0; i < p.nu; ++i) y1[static_cast<size_t>(p.nq + i)] += du[i];
  if (int s = UnpackState(p, ws, t, y); s != 0) return s;
  PositionKinematics(p, ws);
  VelocityKinematics(p, ws);
  const std::vector<Vec3> v0 = ws.v_WBcm;
  if (int s = UnpackState(p, ws, t, y1.data()); s != 0) return s;
  PositionKinematics(p, ws);
  VelocityKinematics(p, ws);  // the velocities are affine in u: the difference is du's alone
  std::vector<Vec3> mom(K);
  for (size_t L = 0; L < K; ++L) mom[L] = p.bodies[L].mass * (ws.v_WBcm[L] - v0[L]);
  for (size_t L = K; L-- > 0;)  // (1): children before parents (tree order reversed)
    if (const int parent = p.joints[L].parent; parent >= 0) mom[static_cast<size_t>(parent)] += mom[L];
  for (size_t i = 0; i < p.friction_joints.size(); ++i) {
    const auto L = static_cast<size_t>(p.friction_joints[i]);
    const Vec3 a = ws.R_WB[L] * p.joints[L].axis;  // the axis is fixed in both joint frames
    const Vec3 n = mom[L] - mom[L].dot(a) * a;     // (2)
    for (int k = 0; k < 3; ++k) P[3 * i + static_cast<size_t>(k)] = n[k];
  }
  return 0;
}

}  // namespace kanesim::rt
