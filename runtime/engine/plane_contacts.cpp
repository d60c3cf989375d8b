// Plane contacts (runtime/runtime.h PlaneContacts, PlaneContactRow, InverseMassTimes): what the
// integrators' events (sim/end_stops.cpp) read of a unilateral contact of a frame's origin O
// with the plane n . x = d. For the speeds u of the tree (seed 000 eq. 11.16, contacts.cpp (4)):
//   g     = n . p_WO - d                                                              (1)
//   dg/dt = J u,      J_s = n . (H^v_s + H^w_s x (p_WO - p_WJs))   (J_s: the joint of speed s)   (2)
//   d2g/dt2 = J udot + c,  c = n . (a_o + alpha x r + w x (v_O - v_o)) with free udot = 0,
//             r = p_WO - p_WB (o: the origin of O's body B)                           (3)
// With Coulomb friction mu N a contact's normal force lambda n (or impulse) is a force at O on
// B, not only the generalized force J^T lambda: every joint between B and the ground carries
// it in its reaction, so it enters those joints' normal forces N (friction.cpp (1)).
#include <algorithm>
#include <cmath>
#include <vector>

#include "runtime/engine/branch_monitor_internal.h"
#include "runtime/kane/kane.h"
#include "runtime/kinematics/kinematics.h"
#include "runtime/program/program.h"
#include "runtime/runtime.h"

namespace kanesim::rt {

std::vector<PlaneContact> PlaneContacts(const Program& p) {
  std::vector<PlaneContact> out;
  for (const PlaneContactModel& c : p.plane_contacts) out.push_back({c.name, c.restitution});
  return out;
}

int PlaneContactRow(const Program& p, Workspace& ws, double t, const double* y, int i, double* gap, double* J,
                    double* bias) {
  const PlaneContactModel& c = p.plane_contacts[static_cast<size_t>(i)];
  if (int s = UnpackState(p, ws, t, y); s != 0) return s;
  MotionKinematics(p, ws);
  Vec3 p_WO, v_WO, w_WB;
  Mat3 R_WO;
  FramePose(p, ws, c.frame, &p_WO, &R_WO);
  FrameMotion(p, ws, c.frame, &v_WO, &w_WB);
  const Vec3& n = c.n_W;
  *gap = n.dot(p_WO) - c.d;  // (1)
  std::fill(J, J + p.nu, 0.0);
  for (int s : p.bodies[static_cast<size_t>(c.body)].path_speeds) {
    const auto h = ws.H_W.col(s);
    const Vec3 o = ws.p_WB[static_cast<size_t>(p.joint_of_speed[static_cast<size_t>(s)])];
    const int f = p.u_free_of[static_cast<size_t>(s)];
    if (f >= 0) J[f] += n.dot(h.head<3>() + h.tail<3>().cross(p_WO - o));  // (2)
  }
  const auto B = static_cast<size_t>(c.body);
  const Vec3 r = p_WO - ws.p_WB[B];
  *bias = n.dot(ws.a_bias_o[B] + ws.alpha_bias[B].cross(r) + ws.w_WB[B].cross(v_WO - ws.v_WBo[B]));  // (3)
  return 0;
}

void AddPlaneForces(const Program& p, Workspace& ws, const double* lambda) {
  for (size_t i = 0; i < p.plane_contacts.size(); ++i) {
    if (lambda[i] == 0.0) continue;
    const PlaneContactModel& c = p.plane_contacts[i];
    Vec3 p_WO;
    Mat3 R_WO;
    FramePose(p, ws, c.frame, &p_WO, &R_WO);
    const auto B = static_cast<size_t>(c.body);
    const Vec3 f = lambda[i] * c.n_W;  // at O: its generalized force is J^T lambda (2)
    ws.F_W[B] += f;
    ws.T_W[B] += (p_WO - ws.p_WBcm[B]).cross(f);
  }
}

// Derivative's stages with F on the speeds and the contacts' forces on their bodies (with
// constraint rows: at the state projected onto them, their reactions following the forces,
// the pull to the manifold included, as for any applied force).
int DerivativeWithPlaneForces(const Program& p, Workspace& ws, double t, const double* y, const double* F,
                              const double* lambda, double* ydot) {
  ws.added_forces = F;
  ws.added_plane_forces = lambda;
  const int s = Derivative(p, ws, t, y, ydot);
  ws.added_forces = nullptr;
  ws.added_plane_forces = nullptr;
  return s;
}

int FrictionlessInverseMassTimes(const Program& p, Workspace& ws, double t, const double* y, const double* F, double* x) {
  if (!p.rows.empty()) return ConstrainedInverseMassTimes(p, ws, t, y, F, "the motion along a contact's normal", x);
  std::vector<int> ks(static_cast<size_t>(p.nu));
  for (int k = 0; k < p.nu; ++k) ks[static_cast<size_t>(k)] = k;
  std::vector<double> cols(static_cast<size_t>(p.nu) * static_cast<size_t>(p.nu));
  if (int s = FrictionlessInverseMassColumns(p, ws, t, y, ks.data(), p.nu, cols.data()); s != 0) return s;
  std::fill(x, x + p.nu, 0.0);
  for (int k = 0; k < p.nu; ++k)
    if (F[k] != 0.0)
      for (int i = 0; i < p.nu; ++i) x[i] += F[k] * cols[static_cast<size_t>(k) * static_cast<size_t>(p.nu) + static_cast<size_t>(i)];
  return 0;
}

// Impulsive: the parent side of joint L gives L's subtree its momentum jump less the external
// impulses on it (friction_impulse.cpp (1)); a contact's impulse Lambda n is one on every
// subtree that holds its body.
int PlaneImpulseNormals(const Program& p, Workspace& ws, double t, const double* y, const double* Lambda, double* P) {
  if (int s = UnpackState(p, ws, t, y); s != 0) return s;
  PositionKinematics(p, ws);
  std::vector<int> friction_of(p.bodies.size(), -1);
  for (size_t i = 0; i < p.friction_joints.size(); ++i) friction_of[static_cast<size_t>(p.friction_joints[i])] = static_cast<int>(i);
  for (size_t c = 0; c < p.plane_contacts.size(); ++c) {
    if (Lambda[c] == 0.0) continue;
    const Vec3 f = Lambda[c] * p.plane_contacts[c].n_W;
    for (int L = p.plane_contacts[c].body; L >= 0; L = p.joints[static_cast<size_t>(L)].parent) {
      const int i = friction_of[static_cast<size_t>(L)];
      if (i < 0) continue;
      const Vec3 a = ws.R_WB[static_cast<size_t>(L)] * p.joints[static_cast<size_t>(L)].axis;
      const Vec3 n = f - f.dot(a) * a;  // across the axis, as friction_impulse.cpp (2)
      for (int k = 0; k < 3; ++k) P[3 * static_cast<size_t>(i) + static_cast<size_t>(k)] -= n[k];
    }
  }
  return 0;
}

// Kane's equations are affine in the applied generalized forces: udot(Q + s F) - udot(Q)
// = s M^-1 F exactly. The second pass takes s so large that the difference is not lost
// in the rounding of udot(Q) (relative error ~ 1e-3 eps).
int InverseMassTimes(const Program& p, Workspace& ws, double t, const double* y, const double* F, double* x) {
  if (FrictionReadsNormalForce(p)) {
    ws.error = "an impulse in a mechanism with Coulomb friction mu N is not supported yet";
    return -1;
  }
  double f_max = 0.0;
  for (int i = 0; i < p.nu; ++i) f_max = std::max(f_max, std::abs(F[i]));
  if (!(f_max > 0.0) || !std::isfinite(f_max)) {
    std::fill(x, x + p.nu, 0.0);
    return f_max == 0.0 ? 0 : -1;
  }
  if (!p.rows.empty()) return ConstrainedInverseMassTimes(p, ws, t, y, F, "the motion along a contact's normal", x);
  std::vector<double> ydot(static_cast<size_t>(p.nq + p.nu));
  if (int s = Derivative(p, ws, t, y, ydot.data()); s != 0) return s;
  const double* a0 = ydot.data() + p.nq;
  double a_max = 0.0;
  for (int i = 0; i < p.nu; ++i) a_max = std::max(a_max, std::abs(a0[i]));
  double scale = 1.0;  // of the unit force F / f_max
  for (int pass = 0; pass < 2; ++pass) {
    if (int s = AppliedForces(p, ws); s != 0) return s;
    for (int i = 0; i < p.nu; ++i) ws.Q[p.u_free[static_cast<size_t>(i)]] += scale * F[i] / f_max;
    if (int s = SolveAccelerations(p, ws); s != 0) return s;
    double xF = 0.0, x_max = 0.0;
    for (int i = 0; i < p.nu; ++i) {
      x[i] = (ws.udot[p.u_free[static_cast<size_t>(i)]] - a0[i]) / scale;
      xF += x[i] * F[i] / f_max;
      x_max = std::max(x_max, std::abs(x[i]));
    }
    if (!(xF > 0.0)) {  // M is positive definite: F^T M^-1 F > 0
      ws.error = "the mass matrix is singular for an impulse";
      return -1;
    }
    scale = std::max(1.0, 1e3 * a_max / x_max);
  }
  for (int i = 0; i < p.nu; ++i) x[i] *= f_max;
  return 0;
}

}  // namespace kanesim::rt
