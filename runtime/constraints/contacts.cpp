// Rolling contacts (runtime/constraints/contacts.h). Body B carries the contact frame F (origin C,
// rotation R_WF, angular velocity w); the plane has unit normal n and point p0.
//
// Contact point P:
//   sphere  P = C - r n                                                              (1)
//   disk    P = C - r g,  g = m / |m|,  m = n - (n . a) a,  a = R_WF axis (unit)     (2)
//           (the lowest point of the rim: g is the in-plane radius towards the plane)
//   knife   P = C (a point fixed in the body)                                        (3)
// Material velocity at P:  v_Pm = v_C + w x (P - C)                                  (4)
// Geometric velocity of P: sphere v_C; disk v_C - r gdot with
//   adot = w x a,  mdot = -(n . adot) a - (n . a) adot,  gdot = (mdot - g (g . mdot)) / |m|   (5)
// knife v_Pm.
// Rows d . v_Pm = 0 with d = n (normal; the exact derivative of phi = n . (P - p0)
// because the rim or surface is tangent to the plane at P), t1, t2 (rolling without
// slip) or l = n x e_W (knife edge: no lateral sliding). Differentiating with udot = 0
// (seed 000 eq. 11.17), o the body origin, r = P - o:
//   c = ddot . v_Pm + d . (a_o + alpha x r + w x (v_Pg - v_o)),                      (6)
//   ddot = n x (w x e_W) for the knife's l, 0 otherwise.
#include "runtime/constraints/contacts.h"

#include <cmath>

#include "runtime/kinematics/kinematics.h"

namespace kanesim::rt {

using flat::ContactType;

namespace {

// Below this |m| a disk lies flat on the plane: its contact point is undefined.
constexpr double kFlatDisk = 1e-12;

const ContactModel& Of(const Program& p, const ConstraintRow& row) {
  return p.contacts[static_cast<size_t>(row.contact)];
}

}  // namespace

ContactPoint ContactAt(const Program& p, const Workspace& ws, const ContactModel& c) {
  ContactPoint cp;
  Mat3 R;
  Vec3 v_C;
  FramePose(p, ws, c.frame, &cp.C, &R);
  FrameMotion(p, ws, c.frame, &v_C, &cp.w);
  cp.e_W = R * c.axis_F;
  const Vec3& n = c.n_W;
  switch (c.type) {
    case ContactType::RollingSphere:
      cp.P = cp.C - c.radius * n;  // (1)
      cp.vPg = v_C;
      break;
    case ContactType::RollingDisk: {
      const Vec3 a = cp.e_W;
      const Vec3 m = n - n.dot(a) * a;
      const double mn = std::max(m.norm(), kFlatDisk);
      const Vec3 g = m / mn;
      cp.P = cp.C - c.radius * g;  // (2)
      const Vec3 adot = cp.w.cross(a);
      const Vec3 mdot = -n.dot(adot) * a - n.dot(a) * adot;
      const Vec3 gdot = (mdot - g * g.dot(mdot)) / mn;  // (5)
      cp.vPg = v_C - c.radius * gdot;
      break;
    }
    case ContactType::KnifeEdge:
    case ContactType::Plane:  // never a ContactModel (Program::plane_contacts)
      cp.P = cp.C;
      break;  // (3)
  }
  cp.vPm = v_C + cp.w.cross(cp.P - cp.C);  // (4)
  if (c.type == ContactType::KnifeEdge) cp.vPg = cp.vPm;
  return cp;
}

Vec3 ContactRowDirection(const ContactModel& c, const ConstraintRow& row, const ContactPoint& cp, Vec3* d_dot) {
  if (d_dot) d_dot->setZero();
  switch (row.kind) {
    case RowKind::ContactNormal: return c.n_W;
    case RowKind::ContactTangent: return row.d_a;  // t1 or t2, stored in world axes
    case RowKind::ContactLateral:
      if (d_dot) *d_dot = c.n_W.cross(cp.w.cross(cp.e_W));
      return c.n_W.cross(cp.e_W);
    default: return Vec3::Zero();
  }
}

double ContactResidual(const Program& p, const ConstraintRow& row, const ContactPoint& cp) {
  if (row.kind != RowKind::ContactNormal) return 0.0;
  const ContactModel& c = Of(p, row);
  return c.n_W.dot(cp.P - c.p0_W);
}

double ContactJacobianRow(const Program& p, Workspace& ws, const ConstraintRow& row, int i, const ContactPoint& cp) {
  const ContactModel& c = Of(p, row);
  const Vec3 d = ContactRowDirection(c, row, cp, nullptr);
  if (c.body >= 0 && i >= 0)
    for (int s : p.bodies[static_cast<size_t>(c.body)].path_speeds) {
      const auto h = ws.H_W.col(s);
      const Vec3 o = ws.p_WB[static_cast<size_t>(p.joint_of_speed[static_cast<size_t>(s)])];
      ws.A(i, p.u_free_of[static_cast<size_t>(s)]) += d.dot(h.head<3>() + h.tail<3>().cross(cp.P - o));
    }
  return d.dot(cp.vPm);
}

double ContactColumn(const Program& p, const Workspace& ws, const ConstraintRow& row, int s) {
  const ContactModel& c = Of(p, row);
  const int J = p.joint_of_speed[static_cast<size_t>(s)];
  bool moves = false;
  for (int L = c.body; L >= 0; L = p.joints[static_cast<size_t>(L)].parent) moves = moves || L == J;
  if (!moves) return 0.0;
  const ContactPoint cp = ContactAt(p, ws, c);
  const Vec3 d = ContactRowDirection(c, row, cp, nullptr);
  const auto h = ws.H_W.col(s);
  return d.dot(h.head<3>() + h.tail<3>().cross(cp.P - ws.p_WB[static_cast<size_t>(J)]));
}

double ContactBias(const Program& p, const Workspace& ws, const ConstraintRow& row, const ContactPoint& cp) {
  const ContactModel& c = Of(p, row);
  if (c.body < 0) return 0.0;
  Vec3 d_dot;
  const Vec3 d = ContactRowDirection(c, row, cp, &d_dot);
  const auto B = static_cast<size_t>(c.body);
  const Vec3 r = cp.P - ws.p_WB[B];
  const Vec3 a = ws.a_bias_o[B] + ws.alpha_bias[B].cross(r) + ws.w_WB[B].cross(cp.vPg - ws.v_WBo[B]);
  return d_dot.dot(cp.vPm) + d.dot(a);  // (6)
}

void ContactDirections(const ContactModel& c, const ContactPoint& cp, Vec3* lon, Vec3* lat) {
  const Vec3& n = c.n_W;
  Vec3 l = Vec3::Zero();
  switch (c.type) {
    case ContactType::RollingDisk: l = n.cross(cp.e_W); break;  // rolling direction
    case ContactType::RollingSphere: l = cp.vPg - n * n.dot(cp.vPg); break;
    case ContactType::KnifeEdge: l = cp.e_W - n * n.dot(cp.e_W); break;
    case ContactType::Plane: break;  // never a ContactModel
  }
  *lon = l.norm() > 1e-12 ? Vec3(l.normalized()) : c.t1_W;
  *lat = n.cross(*lon);
}

}  // namespace kanesim::rt
