// Constraint forces on request (runtime/constraints/reactions.h).
//
// Loop multipliers (Lesser eq. 27 on the complement of the loop's tangent space): on the
// sparse path they are unknowns of its system (kane_sparse.cpp eq. 4); on the reduced
// path they are recovered afterwards. The reduced equations leave the residual of the
// full equations in the loop directions,
//   M udot - f = A^T lambda                                                         (1)
// and with A_dep = Q R (constraints.cpp) the dependent rows give R^T Q1^T lambda = g_dep,
// whose minimum-norm solution is lambda = Q [R^-T g_dep; 0]                         (2)
// (redundant rows get the minimum-norm share: statically indeterminate; when they are
// not among the active rows, Program::active_rows, their multipliers are zero, another
// particular solution with the same determinate components).
// The loop force of row i acts between the cut joint's bodies at p_b (virtual work of
// lambda_i delta phi_i, constraints.cpp eqs. 1-2):
//   translation row:  force lambda_i d on B, -lambda_i d on A, both at p_b           (3)
//   alignment row:    torque lambda_i k on B, -lambda_i k on A,  k = n x e             (4)
// A coupling row (constraints.cpp eq. 11) is a generalized force lambda on the follower's
// speed and -ratio lambda on the leader's: on each coupled joint's child body a torque
// (Revolute) or force (Prismatic) tau h along its axis at o_L, h the joint's twist
// generator, and the opposite on its parent                                          (4a)
// Tree joints: Newton-Euler of the subtree below joint L (Lesser eqs. 26-29 summed):
//   lambda_L = sum_{B in subtree(L)} X_{B->o_L} ( [m_B a_B - F_B;
//              I_B alpha_B + w_B x I_B w_B - T_B] - loop wrenches on B )           (5)
// the wrench the parent side exerts on the subtree at o_L.
#include "runtime/constraints/reactions.h"

#include "runtime/constraints/constraints.h"
#include "runtime/constraints/contacts.h"
#include "runtime/kinematics/kinematics.h"

namespace kanesim::rt {

namespace {

inline Vec6 MoveWrench(const Vec6& w, const Vec3& from, const Vec3& to) {
  Vec6 x = w;
  x.tail<3>() += (from - to).cross(w.head<3>());
  return x;
}

// (3)-(4): the loop force of cut joint `l` on its body B, at p_b.
Vec6 CutWrenchOnB(const Program& p, const Workspace& ws, const LoopClosure& l) {
  Vec3 pa, pb;
  Mat3 Ra, Rb;
  FramePose(p, ws, l.frame_a, &pa, &Ra);
  FramePose(p, ws, l.frame_b, &pb, &Rb);
  Vec6 w = Vec6::Zero();
  for (int i = l.row0; i < l.row0 + l.nrows; ++i) {
    const ConstraintRow& row = p.rows[static_cast<size_t>(i)];
    const double lam = ws.lambda_c[i];
    if (row.kind == RowKind::Translation)
      w.head<3>() += lam * (Ra * row.d_a);
    else
      w.tail<3>() += lam * (Rb * row.n_b).cross(Ra * row.d_a);
  }
  return w;
}

}  // namespace

// The plane's force on the body at P: F = sum_i lambda_i d_i over the contact's rows.
Vec3 ContactForce(const Program& p, const Workspace& ws, int contact, ContactPoint* cp_out) {
  const ContactModel& c = p.contacts[static_cast<size_t>(contact)];
  const ContactPoint cp = ContactAt(p, ws, c);
  Vec3 F = Vec3::Zero();
  for (int i = c.row0; i < c.row0 + c.nrows; ++i)
    F += ws.lambda_c[i] * ContactRowDirection(c, p.rows[static_cast<size_t>(i)], cp, nullptr);
  if (cp_out) *cp_out = cp;
  return F;
}

void LoopMultipliers(const Program& p, Workspace& ws) {
  // The sparse path solved for them with the accelerations (kane_sparse.cpp eq. 4).
  if (p.solver == SolverPath::Sparse) return;
  const int rank = p.loop_rank;
  ws.lambda_c.setZero();
  if (p.rows.empty() || rank == 0) return;
  for (int k = 0; k < rank; ++k)
    ws.g_dep[k] = DriveForce(p, ws, p.u_free[static_cast<size_t>(ws.dep[static_cast<size_t>(k)])]);
  // (2): R^T w = g_dep, lambda = Q [w; 0].
  ws.lambda_active.setZero();
  ws.lambda_active.head(rank) = ws.g_dep.head(rank);
  ws.qr_dep.SolveRt(ws.lambda_active.data());
  ws.qr_dep.ApplyQ(&ws.lambda_active);
  for (size_t k = 0; k < p.active_rows.size(); ++k) ws.lambda_c[p.active_rows[k]] = ws.lambda_active[static_cast<Eigen::Index>(k)];
}

namespace {

// (4a): generalized force tau on tree joint L's speed, as wrenches on its child (+) and
// parent (-) at o_L, subtracted from their terms of (5).
void SubtractJointForce(const Program& p, Workspace& ws, int L, double tau) {
  const TreeJoint& j = p.joints[static_cast<size_t>(L)];
  const auto h = ws.H_W.col(j.u0);
  Vec6 w = Vec6::Zero();
  if (j.type == flat::JointType::Prismatic)
    w.head<3>() = tau * h.head<3>();
  else
    w.tail<3>() = tau * h.tail<3>();
  ws.reaction_W[static_cast<size_t>(L)] -= w;
  if (j.parent >= 0) ws.reaction_W[static_cast<size_t>(j.parent)] += MoveWrench(w, ws.p_WB[static_cast<size_t>(L)], ws.p_WB[static_cast<size_t>(j.parent)]);
}

// (5), the multipliers' part: the loop forces on both bodies of every cut joint, the
// planes' forces on the contacts' bodies and the couplings' joint forces, subtracted from
// the bodies' own terms.
void SubtractMultiplierWrenches(const Program& p, Workspace& ws) {
  for (const CouplingModel& c : p.couplings) {
    const double lam = ws.lambda_c[c.row];
    SubtractJointForce(p, ws, c.follower, lam);
    SubtractJointForce(p, ws, c.leader, -c.ratio * lam);
  }
  for (const LoopClosure& l : p.loops) {
    const Vec6 wb = CutWrenchOnB(p, ws, l);
    Vec3 pb;
    Mat3 Rb;
    FramePose(p, ws, l.frame_b, &pb, &Rb);
    const int A = p.frames[static_cast<size_t>(l.frame_a)].body, B = p.frames[static_cast<size_t>(l.frame_b)].body;
    if (B >= 0) ws.reaction_W[static_cast<size_t>(B)] -= MoveWrench(wb, pb, ws.p_WB[static_cast<size_t>(B)]);
    if (A >= 0) ws.reaction_W[static_cast<size_t>(A)] += MoveWrench(wb, pb, ws.p_WB[static_cast<size_t>(A)]);
  }
  for (size_t ci = 0; ci < p.contacts.size(); ++ci) {
    ContactPoint cp;
    Vec6 w = Vec6::Zero();
    w.head<3>() = ContactForce(p, ws, static_cast<int>(ci), &cp);
    const auto B = static_cast<size_t>(p.contacts[ci].body);
    ws.reaction_W[B] -= MoveWrench(w, cp.P, ws.p_WB[B]);
  }
}

// (5), the sum over the subtree: children before parents (tree order reversed).
void AccumulateSubtrees(const Program& p, Workspace& ws) {
  for (size_t L = p.bodies.size(); L-- > 0;) {
    const int P = p.joints[L].parent;
    if (P >= 0)
      ws.reaction_W[static_cast<size_t>(P)] += MoveWrench(ws.reaction_W[L], ws.p_WB[L], ws.p_WB[static_cast<size_t>(P)]);
  }
}

}  // namespace

void JointReactions(const Program& p, Workspace& ws) {
  const size_t K = p.bodies.size();
  for (size_t L = 0; L < K; ++L) {
    const TreeBody& b = p.bodies[L];
    Vec6 w;
    w.head<3>() = b.mass * ws.a_bias_cm[L] - ws.F_W[L];
    w.tail<3>() = ws.I_W[L] * ws.alpha_bias[L] + ws.w_WB[L].cross(ws.I_W[L] * ws.w_WB[L]) - ws.T_W[L];
    ws.reaction_W[L] = MoveWrench(w, ws.p_WBcm[L], ws.p_WB[L]);  // (5), own term
  }
  SubtractMultiplierWrenches(p, ws);
  AccumulateSubtrees(p, ws);
}

void MultiplierReactions(const Program& p, Workspace& ws) {
  for (Vec6& w : ws.reaction_W) w.setZero();
  SubtractMultiplierWrenches(p, ws);
  AccumulateSubtrees(p, ws);
}

Vec6 JointReactionInFrameB(const Program& p, const Workspace& ws, int flat_joint) {
  const flat::Joint& fj = p.mech->joints[static_cast<size_t>(flat_joint)];
  Vec3 pa, pb;
  Mat3 Ra, Rb;
  FramePose(p, ws, fj.frame_a, &pa, &Ra);
  FramePose(p, ws, fj.frame_b, &pb, &Rb);
  Vec6 w = Vec6::Zero();  // on the frame_b side, at p_b, world axes
  const int L = p.joint_of_flat[static_cast<size_t>(flat_joint)];
  if (L >= 0) {
    const TreeJoint& j = p.joints[static_cast<size_t>(L)];
    const Vec6& lam = ws.reaction_W[static_cast<size_t>(L)];
    w = j.inverted ? Vec6(MoveWrench(-lam, pa, pb)) : lam;  // inverted: the child is frame a's side
  } else {
    for (const LoopClosure& l : p.loops)
      if (l.flat_index == flat_joint) w = CutWrenchOnB(p, ws, l);
  }
  Vec6 out;
  out.head<3>() = Rb.transpose() * w.head<3>();
  out.tail<3>() = Rb.transpose() * w.tail<3>();
  return out;
}

double ConstraintPower(const Program& p, Workspace& ws) {
  double P = 0.0;
  for (size_t L = 0; L < p.bodies.size(); ++L) {
    const TreeJoint& j = p.joints[L];
    const Vec6& lam = ws.reaction_W[L];
    P += lam.head<3>().dot(ws.v_rel[L]) + lam.tail<3>().dot(ws.w_rel[L]);
    for (int k = 0; k < j.nu; ++k) {
      const int s = j.u0 + k;
      const double applied = p.u_free_of[static_cast<size_t>(s)] >= 0 ? ws.Q[s] : LoopDriveForce(p, ws, s);
      P -= applied * ws.u[s];
    }
  }
  if (!p.rows.empty()) {
    ConstraintJacobian(p, ws);
    P += ws.lambda_c.dot(ws.psi);
  }
  return P;
}

}  // namespace kanesim::rt
