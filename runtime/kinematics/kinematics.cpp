#include "runtime/kinematics/kinematics.h"

#include <cmath>

#include "runtime/kinematics/joint_kinematics.h"

namespace kanesim::rt {

namespace {

// NaN-or-infinity message for a prescribed motion (error path: may allocate).
int PrescribedNotFinite(const Program& p, Workspace& ws, size_t i) {
  ws.error = "NaN from expression: " + p.prescribed_tape.labels[i] + " = " + p.prescribed_tape.texts[i] +
             " at time " + std::to_string(ws.t);
  return -1;
}

// Orientation of the joint's frame a in W. Frame a is on the parent side (R_WP R_PJ) for
// a joint in tree direction and is the child's own frame for an inverted one.
Mat3 R_WFa(const Program& p, const Workspace& ws, int L) {
  const TreeJoint& j = p.joints[static_cast<size_t>(L)];
  if (j.inverted) return ws.R_WB[static_cast<size_t>(L)];
  return j.parent < 0 ? j.R_PJ : Mat3(ws.R_WB[static_cast<size_t>(j.parent)] * j.R_PJ);
}

void JointRelativeMotion(const Program& p, Workspace& ws, size_t L);
void PlaceBody(const Program& p, Workspace& ws, size_t L);

}  // namespace

void PackState(const Program& p, const Workspace& ws, double* y) {
  for (int i = 0; i < p.nq; ++i) y[i] = ws.q[p.q_free[static_cast<size_t>(i)]];
  for (int i = 0; i < p.nu; ++i) y[p.nq + i] = ws.u[p.u_free[static_cast<size_t>(i)]];
}

int UnpackState(const Program& p, Workspace& ws, double t, const double* y) {
  ws.t = t;
  // The inputs at t (a table's time outside its rows is fatal: the caller checked the span).
  if (ws.input_source && ws.input_source->Values(t, ws.inputs.data(), ws.input_rates.data(), &ws.error) != 0)
    return -1;
  ws.sparse_ready = false;  // new positions: the sparse path factors again
  for (int i = 0; i < p.nq; ++i) ws.q[p.q_free[static_cast<size_t>(i)]] = y[i];
  for (int i = 0; i < p.nu; ++i) ws.u[p.u_free[static_cast<size_t>(i)]] = y[p.nq + i];
  if (p.q_prescribed.empty()) return 0;
  // Prescribed q(t): evaluate its tape on jets seeded with time = (t, 1, 0).
  const Tape& tape = p.prescribed_tape;
  double* r = ws.jet_regs.data();
  if (tape.time_reg >= 0) {
    r[3 * tape.time_reg] = t;
    r[3 * tape.time_reg + 1] = 1.0;
    r[3 * tape.time_reg + 2] = 0.0;
  }
  // An input's jet: its value and rate (a table's slope; 0 when held), no curvature.
  for (const auto& [in, reg] : tape.input_regs) {
    r[3 * reg] = ws.inputs[static_cast<size_t>(in)];
    r[3 * reg + 1] = ws.input_rates[static_cast<size_t>(in)];
    r[3 * reg + 2] = 0.0;
  }
  tape.EvalJet(r);
  for (size_t i = 0; i < p.q_prescribed.size(); ++i) {
    const int reg = tape.roots[i];
    const double q = r[3 * reg], qd = r[3 * reg + 1], qdd = r[3 * reg + 2];
    if (!std::isfinite(q) || !std::isfinite(qd) || !std::isfinite(qdd)) return PrescribedNotFinite(p, ws, i);
    ws.q[p.q_prescribed[i]] = q;
    ws.u[p.prescribed_u[i]] = qd;
    ws.udot[p.prescribed_u[i]] = qdd;
  }
  return 0;
}

// Seed 000 eq. 11.9 (positions), per joint in tree order, P = parent, J = parent-side
// joint frame, B = child body frame (= child-side joint frame):
//   R_WJ = R_WP R_PJ,  p_WJ = p_WP + R_WP p_PJ
//   in tree direction (J = a, B = b):  R_WB = R_WJ R_ab,    p_WB = p_WJ + R_WJ p_ab
//   inverted          (J = b, B = a):  R_WB = R_WJ R_ab^T,  p_WB = p_WJ - R_WB p_ab
namespace {
inline void PositionStep(const Program& p, Workspace& ws, size_t L) {
  const TreeJoint& j = p.joints[L];
  const TreeBody& b = p.bodies[L];
  Mat3& R_WB = ws.R_WB[L];
  Vec3& p_WB = ws.p_WB[L];
  if (j.single_axis && j.axis_index >= 0 && j.type == flat::JointType::Revolute) {
    // The most common joint: a revolute joint about a coordinate axis e_k of its frame a.
    // R_ab turns columns i, j = k+1, k+2 (mod 3) by the angle, so R_WB = R_WJ R_ab is
    // R_WJ with those two columns turned: no 3x3 product.
    const int k = j.axis_index, i1 = (k + 1) % 3, i2 = (k + 2) % 3;
    // (R_ab and p_ab are not written: only the general joint path reads them.)
    const double a = ws.q[j.q0], s = std::sin(a), c = std::cos(a);
    if (j.parent >= 0) {
      const auto P = static_cast<size_t>(j.parent);
      const Mat3& R_WP = ws.R_WB[P];
      if (j.R_PJ_identity)
        R_WB = R_WP;
      else
        R_WB.noalias() = R_WP * j.R_PJ;
      p_WB = ws.p_WB[P] + R_WP * j.p_PJ;
    } else {
      R_WB = j.R_PJ;
      p_WB = j.p_PJ;
    }
    const Vec3 ci = R_WB.col(i1), cj = R_WB.col(i2);
    R_WB.col(i1) = c * ci + s * cj;
    R_WB.col(i2) = c * cj - s * ci;
  } else {
    PlaceBody(p, ws, L);
  }
  ws.p_WBcm[L] = p_WB + R_WB * b.p_BBcm;
  // I_W = R I R^T, symmetric: T = R I, then the six entries T_i . R_k.
  const Mat3 T = b.I_diagonal ? Mat3(R_WB * b.I_BBcm_B.diagonal().asDiagonal()) : Mat3(R_WB * b.I_BBcm_B);
  Mat3& I = ws.I_W[L];
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k <= i; ++k) I(i, k) = I(k, i) = T.row(i).dot(R_WB.row(k));
}
}  // namespace

void PositionKinematics(const Program& p, Workspace& ws) {
  for (size_t L = 0; L < p.bodies.size(); ++L) PositionStep(p, ws, L);
}

namespace {
// Eq. 11.9 for any joint: its relative pose from JointPose, then the body's pose.
void PlaceBody(const Program& p, Workspace& ws, size_t L) {
  const TreeJoint& j = p.joints[L];
  Mat3& R_WB = ws.R_WB[L];
  Vec3& p_WB = ws.p_WB[L];
  if (j.type == flat::JointType::Revolute) {  // p_ab = 0: no JointPose
    ws.R_ab[L] = RotationAboutAxis(j, ws.q[j.q0]);
    ws.p_ab[L].setZero();
  } else {
    JointPose(j, ws.q.data() + j.q0, &ws.p_ab[L], &ws.R_ab[L]);
  }
  const Mat3& R_ab = ws.R_ab[L];
  Mat3 R_WJ_own;
  const Mat3* R_WJ = &j.R_PJ;
  if (j.parent >= 0) {
    const auto P = static_cast<size_t>(j.parent);
    R_WJ = &ws.R_WB[P];
    if (!j.R_PJ_identity) {
      R_WJ_own.noalias() = ws.R_WB[P] * j.R_PJ;
      R_WJ = &R_WJ_own;
    }
    p_WB = ws.p_WB[P] + ws.R_WB[P] * j.p_PJ;
  } else {
    p_WB = j.p_PJ;
  }
  const bool translates = j.type != flat::JointType::Revolute && !ws.p_ab[L].isZero(0.0);
  if (!j.inverted) {
    R_WB.noalias() = *R_WJ * R_ab;
    if (translates) p_WB += *R_WJ * ws.p_ab[L];
  } else {
    R_WB.noalias() = *R_WJ * R_ab.transpose();
    if (translates) p_WB -= R_WB * ws.p_ab[L];
  }
}
}  // namespace

// Velocities (seed 000 eqs. 11.15-11.16; Lesser eqs. 44-47). Column r of H_W is the twist
// of body L (= joint child) at its origin o_L for the unit pseudo-speed u = e_r:
//   in tree direction:  H_r = [R_WFa Hv_r;  R_WFa Hw_r]
//   inverted:           H_r = [-R_WFa Hv_r + (R_WFa Hw_r) x d;  -R_WFa Hw_r],  d = p_WFb - p_WFa
// (the motion of a seen from b: w_ba = -w_ab, v = -v_ab + w_ab x d). Then
//   w_WB = w_WP + sum_r H^w_r u_r                                  (1)
//   v_WBo = v_WPo + w_WP x (p_WB - p_WP) + sum_r H^v_r u_r          (2)
//   v_WBcm = v_WBo + w_WB x (p_WBcm - p_WB)                         (3)
// and the relative accelerations with udot = 0, seen from the parent:
//   tree direction:  alpha_rel = R_WFa cw,  a_rel = R_WFa cv
//   inverted:        alpha_rel = -R_WFa cw,
//                    a_rel = -R_WFa cv + (R_WFa cw) x d + 2 w_r x v_r - w_r x (w_r x d)   (4)
// where w_r = R_WFa Hw u, v_r = R_WFa Hv u are the motion of b seen from a.
namespace {
inline void VelocityStep(const Program& p, Workspace& ws, size_t L) {
  const TreeJoint& j = p.joints[L];
  Vec3 w_P = Vec3::Zero(), v_Po = Vec3::Zero(), p_WP = Vec3::Zero();
  if (j.parent >= 0) {
    const auto P = static_cast<size_t>(j.parent);
    w_P = ws.w_WB[P];
    v_Po = ws.v_WBo[P];
    p_WP = ws.p_WB[P];
  }
  if (j.single_axis) {  // Revolute or Prismatic in tree direction: one column, no bias terms
    // A revolute joint about e_k leaves column k of R_WJ as it is: h = R_WB e_k.
    const Vec3 h = j.axis_index >= 0 && j.type == flat::JointType::Revolute ? Vec3(ws.R_WB[L].col(j.axis_index))
                   : j.parent >= 0 ? Vec3(ws.R_WB[static_cast<size_t>(j.parent)] * j.axis_P)
                                   : j.axis_P;
    const double uk = ws.u[j.u0];
    auto col = ws.H_W.col(j.u0);  // (alpha_rel and a_rel stay 0 from MakeWorkspace)
    if (j.type == flat::JointType::Revolute) {
      col.head<3>().setZero();
      col.tail<3>() = h;
      ws.w_rel[L] = h * uk;
      ws.v_rel[L].setZero();
    } else {
      col.head<3>() = h;
      col.tail<3>().setZero();
      ws.w_rel[L].setZero();
      ws.v_rel[L] = h * uk;
    }
  } else {
    JointRelativeMotion(p, ws, L);
  }
  ws.w_WB[L] = w_P + ws.w_rel[L];                                   // (1)
  ws.v_WBo[L] = v_Po + w_P.cross(ws.p_WB[L] - p_WP) + ws.v_rel[L];  // (2)
  ws.v_WBcm[L] = ws.v_WBo[L] + ws.w_WB[L].cross(ws.p_WBcm[L] - ws.p_WB[L]);  // (3)
}
}  // namespace

void VelocityKinematics(const Program& p, Workspace& ws) {
  for (size_t L = 0; L < p.bodies.size(); ++L) VelocityStep(p, ws, L);
}

namespace {
// The general joint's columns of H_W, its relative twist seen from the parent and that
// twist's derivative with udot = 0, eq. (4).
void JointRelativeMotion(const Program& p, Workspace& ws, size_t L) {
  const TreeJoint& j = p.joints[L];
  Mat36 Hv, Hw;
  Vec3 cv, cw;
  const Mat3 R = R_WFa(p, ws, static_cast<int>(L));
  JointMotion(j, ws.q.data() + j.q0, ws.u.data() + j.u0, ws.R_ab[L], &Hv, &Hw, &cv, &cw);
  Vec3 w_rel = Vec3::Zero(), v_rel = Vec3::Zero();
  const Vec3 d = R * ws.p_ab[L];
  Vec3 w_r = Vec3::Zero(), v_r = Vec3::Zero();
  for (int k = 0; k < j.nu; ++k) {
    const Vec3 hw = R * Hw.col(k), hv = R * Hv.col(k);
    auto col = ws.H_W.col(j.u0 + k);
    if (!j.inverted) {
      col.head<3>() = hv;
      col.tail<3>() = hw;
    } else {
      col.head<3>() = -hv + hw.cross(d);
      col.tail<3>() = -hw;
    }
    const double uk = ws.u[j.u0 + k];
    v_rel += col.head<3>() * uk;
    w_rel += col.tail<3>() * uk;
    w_r += hw * uk;
    v_r += hv * uk;
  }
  ws.w_rel[L] = w_rel;
  ws.v_rel[L] = v_rel;
  if (!j.inverted) {
    ws.alpha_rel[L] = R * cw;
    ws.a_rel[L] = R * cv;
  } else {
    const Vec3 alpha_r = R * cw;
    ws.alpha_rel[L] = -alpha_r;
    ws.a_rel[L] = -(R * cv) + alpha_r.cross(d) + 2.0 * w_r.cross(v_r) - w_r.cross(w_r.cross(d));  // (4)
  }
}
}  // namespace

// Seed 000 eq. 11.17: accelerations with the free udot = 0 (prescribed udot included):
//   alpha_B = alpha_P + w_P x w_rel + alpha_rel + sum_presc H^w_r udot_r                 (5)
//   a_Bo = a_Po + alpha_P x r + w_P x (w_P x r) + 2 w_P x v_rel + a_rel
//          + sum_presc H^v_r udot_r,   r = p_WB - p_WP                                    (6)
//   a_Bcm = a_Bo + alpha_B x c + w_B x (w_B x c),   c = p_WBcm - p_WB                     (7)
namespace {
inline void BiasStep(const Program& p, Workspace& ws, size_t L, bool include_free) {
  const TreeJoint& j = p.joints[L];
  Vec3 w_P = Vec3::Zero(), alpha_P = Vec3::Zero(), a_Po = Vec3::Zero(), p_WP = Vec3::Zero();
  if (j.parent >= 0) {
    const auto P = static_cast<size_t>(j.parent);
    w_P = ws.w_WB[P];
    alpha_P = ws.alpha_bias[P];
    a_Po = ws.a_bias_o[P];
    p_WP = ws.p_WB[P];
  }
  const Vec3 r = ws.p_WB[L] - p_WP;
  Vec3 alpha, a;
  if (j.single_axis && j.type == flat::JointType::Revolute) {  // v_rel = alpha_rel = a_rel = 0
    alpha = alpha_P + w_P.cross(ws.w_rel[L]);                        // (5)
    a = a_Po + alpha_P.cross(r) + w_P.cross(w_P.cross(r));           // (6)
  } else {
    alpha = alpha_P + w_P.cross(ws.w_rel[L]) + ws.alpha_rel[L];                                           // (5)
    a = a_Po + alpha_P.cross(r) + w_P.cross(w_P.cross(r)) + 2.0 * w_P.cross(ws.v_rel[L]) + ws.a_rel[L];  // (6)
  }
  for (int k = 0; k < j.nu; ++k) {
    if (!include_free && p.u_free_of[static_cast<size_t>(j.u0 + k)] >= 0) continue;
    const double ud = ws.udot[j.u0 + k];
    a += ws.H_W.col(j.u0 + k).head<3>() * ud;
    alpha += ws.H_W.col(j.u0 + k).tail<3>() * ud;
  }
  ws.alpha_bias[L] = alpha;
  ws.a_bias_o[L] = a;
  const Vec3 c = ws.p_WBcm[L] - ws.p_WB[L];
  ws.a_bias_cm[L] = a + alpha.cross(c) + ws.w_WB[L].cross(ws.w_WB[L].cross(c));  // (7)
}
}  // namespace

void BiasAccelerations(const Program& p, Workspace& ws, bool include_free) {
  for (size_t L = 0; L < p.bodies.size(); ++L) BiasStep(p, ws, L, include_free);
}

namespace {
// The three steps of a revolute joint about the coordinate axis e_k of its frame a, in
// tree direction (the common joint), in one: PositionStep's turned columns (eq. 11.9),
// VelocityStep's (1)-(3) with H = [0; h], h = R_WB e_k, and BiasStep's (5)-(7) with
// v_rel = alpha_rel = a_rel = 0. The parent's values are read once and body L's are
// reused from registers; c = p_WBcm - p_WB = R_WB p_BBcm is formed once.
template <int k>
void RevoluteStep(const Program& p, Workspace& ws, size_t L) {
  constexpr int i1 = (k + 1) % 3, i2 = (k + 2) % 3;
  const TreeJoint& j = p.joints[L];
  const TreeBody& b = p.bodies[L];
  // R_WJ, its columns e_k (the axis, kept by the rotation) and e_1, e_2 (k+1, k+2 mod 3).
  Mat3 R_WJ_own;
  const Mat3* R_WJ = &j.R_PJ;
  Vec3 o, o_P = Vec3::Zero(), w_P = Vec3::Zero(), v_P = Vec3::Zero(), alpha_P = Vec3::Zero(), a_P = Vec3::Zero();
  if (j.parent >= 0) {
    const auto P = static_cast<size_t>(j.parent);
    const Mat3& R_WP = ws.R_WB[P];
    R_WJ = &R_WP;
    if (!j.R_PJ_identity) {
      R_WJ_own.noalias() = R_WP * j.R_PJ;
      R_WJ = &R_WJ_own;
    }
    o_P = ws.p_WB[P];
    o = o_P + R_WP * j.p_PJ;
    w_P = ws.w_WB[P];
    v_P = ws.v_WBo[P];
    alpha_P = ws.alpha_bias[P];
    a_P = ws.a_bias_o[P];
  } else {
    o = j.p_PJ;
  }
  const double q = ws.q[j.q0], s = std::sin(q), cq = std::cos(q);
  // R_WB = R_WJ R_ab: columns e_1, e_2 turned by q. The columns stay in registers as
  // Vec3s (a Mat3 built column by column would be stored in pieces and read back whole).
  const Vec3 h = R_WJ->col(k), e1 = R_WJ->col(i1), e2 = R_WJ->col(i2);
  const Vec3 n1 = cq * e1 + s * e2, n2 = cq * e2 - s * e1;
  Mat3& R_WB = ws.R_WB[L];
  R_WB.col(k) = h;
  R_WB.col(i1) = n1;
  R_WB.col(i2) = n2;
  ws.p_WB[L] = o;
  // Column m of R_WB for m = 0, 1, 2.
  const Vec3& C0 = k == 0 ? h : i1 == 0 ? n1 : n2;
  const Vec3& C1 = k == 1 ? h : i1 == 1 ? n1 : n2;
  const Vec3& C2 = k == 2 ? h : i1 == 2 ? n1 : n2;
  const Vec3 c = C0 * b.p_BBcm.x() + C1 * b.p_BBcm.y() + C2 * b.p_BBcm.z();  // R_WB p_BBcm
  ws.p_WBcm[L] = o + c;
  Mat3& I = ws.I_W[L];
  if (b.I_diagonal) {  // I_W = sum_m I_m C_m C_m^T, symmetric
    const double I0 = b.I_BBcm_B(0, 0), I1 = b.I_BBcm_B(1, 1), I2 = b.I_BBcm_B(2, 2);
    const Vec3 T0 = I0 * C0, T1 = I1 * C1, T2 = I2 * C2;
    for (int i = 0; i < 3; ++i)
      for (int m = 0; m <= i; ++m) I(i, m) = I(m, i) = T0[i] * C0[m] + T1[i] * C1[m] + T2[i] * C2[m];
  } else {  // as in PositionStep
    const Mat3 T = R_WB * b.I_BBcm_B;
    for (int i = 0; i < 3; ++i)
      for (int m = 0; m <= i; ++m) I(i, m) = I(m, i) = T.row(i).dot(R_WB.row(m));
  }
  // Velocities (1)-(3).
  auto col = ws.H_W.col(j.u0);
  col.head<3>().setZero();
  col.tail<3>() = h;
  const Vec3 w_rel = h * ws.u[j.u0];
  ws.w_rel[L] = w_rel;
  ws.v_rel[L].setZero();
  const Vec3 r = o - o_P;
  const Vec3 w = w_P + w_rel;         // (1)
  const Vec3 v = v_P + w_P.cross(r);  // (2)
  ws.w_WB[L] = w;
  ws.v_WBo[L] = v;
  ws.v_WBcm[L] = v + w.cross(c);  // (3)
  // Accelerations with free udot = 0 (5)-(7).
  Vec3 alpha = alpha_P + w_P.cross(w_rel);                          // (5)
  const Vec3 a = a_P + alpha_P.cross(r) + w_P.cross(w_P.cross(r));  // (6)
  if (p.u_free_of[static_cast<size_t>(j.u0)] < 0) alpha += h * ws.udot[j.u0];  // prescribed
  ws.alpha_bias[L] = alpha;
  ws.a_bias_o[L] = a;
  ws.a_bias_cm[L] = a + alpha.cross(c) + w.cross(w.cross(c));  // (7)
}
}  // namespace

// PositionKinematics, VelocityKinematics and BiasAccelerations in one pass: each step of
// body L reads only its own earlier steps and its parent's (P < L), so per body they can
// follow one another; the parent's values are then fresh in cache and the loop runs once.
void MotionKinematics(const Program& p, Workspace& ws) {
  for (size_t L = 0; L < p.bodies.size(); ++L) {
    const TreeJoint& j = p.joints[L];
    if (j.single_axis && j.type == flat::JointType::Revolute) {
      switch (j.axis_index) {
        case 0: RevoluteStep<0>(p, ws, L); continue;
        case 1: RevoluteStep<1>(p, ws, L); continue;
        case 2: RevoluteStep<2>(p, ws, L); continue;
        default: break;
      }
    }
    PositionStep(p, ws, L);
    VelocityStep(p, ws, L);
    BiasStep(p, ws, L, false);
  }
}

int KinematicDifferentials(const Program& p, Workspace& ws) {
  for (const TreeJoint& j : p.joints) {
    if (j.single_axis) {  // qdot = u
      ws.qdot[j.q0] = ws.u[j.u0];
      continue;
    }
    if (!JointKinematicDifferential(j, ws.q.data() + j.q0, ws.u.data() + j.u0, ws.qdot.data() + j.q0, &ws.error))
      return -1;
  }
  return 0;
}

// Lesser eq. 22 with a unit pseudo-speed: the column r of body L's tangent block is the
// twist H_r carried rigidly from the joint point o_J to L's mass centre:
//   tau_{L,r} = [H^v_r + H^w_r x (p_WLcm - p_WJo);  H^w_r].
Vec6 TangentColumn(const Program& p, const Workspace& ws, int body, int full_speed) {
  Vec6 t = Vec6::Zero();
  const int J = p.joint_of_speed[static_cast<size_t>(full_speed)];
  for (int L = body; L >= 0; L = p.joints[static_cast<size_t>(L)].parent) {
    if (L != J) continue;
    const auto h = ws.H_W.col(full_speed);
    t.head<3>() = h.head<3>() + h.tail<3>().cross(ws.p_WBcm[static_cast<size_t>(body)] - ws.p_WB[static_cast<size_t>(J)]);
    t.tail<3>() = h.tail<3>();
    break;
  }
  return t;
}

void FramePose(const Program& p, const Workspace& ws, int frame, Vec3* p_WF, Mat3* R_WF) {
  const FramePlace& F = p.frames[static_cast<size_t>(frame)];
  if (F.body < 0) {
    *p_WF = F.p_BF;
    *R_WF = F.R_BF;
    return;
  }
  const auto B = static_cast<size_t>(F.body);
  *p_WF = ws.p_WB[B] + ws.R_WB[B] * F.p_BF;
  *R_WF = ws.R_WB[B] * F.R_BF;
}

void PointMotion(const Workspace& ws, int body, const Vec3& rho, Vec3* v_WP, Vec3* w_WB) {
  if (body < 0) {
    v_WP->setZero();
    w_WB->setZero();
    return;
  }
  const auto B = static_cast<size_t>(body);
  *w_WB = ws.w_WB[B];
  *v_WP = ws.v_WBo[B] + ws.w_WB[B].cross(rho);
}

void FrameMotion(const Program& p, const Workspace& ws, int frame, Vec3* v_WF, Vec3* w_WF) {
  const FramePlace& F = p.frames[static_cast<size_t>(frame)];
  const Vec3 rho = F.body < 0 ? Vec3::Zero() : Vec3(ws.R_WB[static_cast<size_t>(F.body)] * F.p_BF);
  PointMotion(ws, F.body, rho, v_WF, w_WF);
}

void EvalStateRefs(const Program& p, Workspace& ws, const std::vector<int>& refs) {
  for (int idx : refs) {
    const flat::StateRef& r = p.mech->state_refs[static_cast<size_t>(idx)];
    double v = 0.0;
    switch (r.kind) {
      case flat::StateKind::JointQ:
      case flat::StateKind::JointU: {
        const TreeJoint& j = p.joints[static_cast<size_t>(p.joint_of_flat[static_cast<size_t>(r.target)])];
        v = r.kind == flat::StateKind::JointQ ? ws.q[j.q0 + r.k] : ws.u[j.u0 + r.k];
        break;
      }
      case flat::StateKind::FramePosition:
      case flat::StateKind::FrameRotation: {
        Vec3 pos;
        Mat3 R;
        FramePose(p, ws, r.target, &pos, &R);
        v = r.kind == flat::StateKind::FramePosition ? pos[r.k] : R(r.k / 3, r.k % 3);
        break;
      }
      case flat::StateKind::FrameVelocity:
      case flat::StateKind::FrameAngVel: {
        Vec3 vel, w;
        FrameMotion(p, ws, r.target, &vel, &w);
        v = r.kind == flat::StateKind::FrameVelocity ? vel[r.k] : w[r.k];
        break;
      }
    }
    ws.state_values[static_cast<size_t>(idx)] = v;
  }
}

}  // namespace kanesim::rt
