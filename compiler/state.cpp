// Compile stage: joint numbers, q/u allocation in tree order, prescribed motions and
// start values; the pattern of the tangent basis (each body's path of speeds).
#include <cmath>

#include "compiler/compile_internal.h"
#include "runtime/kinematics/joint_kinematics.h"
#include "compiler/compiler.h"

namespace kanesim::rt {

using flat::JointType;
using flat::kNoExpr;

namespace {


bool ScalarCoordinates(JointType t) {
  return t == JointType::Revolute || t == JointType::Prismatic || t == JointType::Cylindrical ||
         t == JointType::Universal || t == JointType::Planar;
}

bool NeedsAxis(JointType t) { return t != JointType::Spherical && t != JointType::Free && t != JointType::Weld; }

// A joint's end stops (stdlib q_min, q_max, restitution) into the tree joint; the joint joins
// p->stop_joints when it has one. Only a free Revolute or Prismatic joint takes them.
template <class Num>
void CompileEndStops(const flat::Joint& fj, TreeJoint* j, Program* p, Num& num, std::vector<CompileMessage>* errors) {
  if (fj.q_min == kNoExpr && fj.q_max == kNoExpr) return;
  j->q_min = num(fj.q_min, -INFINITY, "lower end stop of ", j->name, "", fj.loc);
  j->q_max = num(fj.q_max, INFINITY, "upper end stop of ", j->name, "", fj.loc);
  j->restitution = num(fj.restitution, 0.0, "restitution of ", j->name, "", fj.loc);
  const bool prescribed = !fj.prescribed.empty() && fj.prescribed[0] != kNoExpr;
  std::string why;
  if (j->type != JointType::Prismatic && j->type != JointType::Revolute)
    why = "end stops need a revolute or prismatic joint";
  else if (prescribed)
    why = "a prescribed joint cannot have end stops";
  else if (std::isnan(j->q_min) || std::isnan(j->q_max) || !(j->q_min < j->q_max))
    why = "q_min must be less than q_max";
  else if (!(j->restitution >= 0.0 && j->restitution <= 1.0))
    why = "restitution must be in [0, 1]";
  if (!why.empty()) {
    errors->push_back(Msg(flat::DiagCode::BadStop, "joint '" + j->name + "': " + why, fj.loc));
    return;
  }
  p->stop_joints.push_back(j->child);
}

}  // namespace

void CompileJointsAndState(Program& p, TapeBuilder& folder, std::vector<CompileMessage>* errors) {
  const flat::Mechanism& m = *p.mech;
  auto text = [&](flat::ExprId id) { return m.ExprText(id); };  // of a prescribed motion
  // The value of a parameter expression; its name for the message is what + of + ".q"
  // (built only for the message).
  auto num = [&](flat::ExprId id, double dflt, const char* what, const std::string& of, const char* suffix,
                 const flat::SourceLoc& loc) {
    if (id == kNoExpr) return dflt;
    double v = 0.0;
    if (!folder.Fold(id, &v)) {
      errors->push_back(
          Msg(flat::DiagCode::NotFixed, std::string(what) + of + suffix + " must not depend on time or state", loc));
      return dflt;
    }
    return v;
  };
  const std::string none;
  auto num3 = [&](const flat::Vec3E& e, const char* what, const flat::SourceLoc& loc) {
    return Vec3(num(e[0], 0.0, what, none, "", loc), num(e[1], 0.0, what, none, "", loc),
                num(e[2], 0.0, what, none, "", loc));
  };

  TapeBuilder presc = TapeBuilder::SharingFolds(folder);
  std::vector<double> q_start_all, u_start_all;
  for (TreeJoint& j : p.joints) {
    const flat::Joint& fj = m.joints[static_cast<size_t>(j.flat_index)];
    if (NeedsAxis(j.type)) {
      Vec3 a = num3(fj.axis, "joint axis", fj.loc);
      if (!NormalizeScaled(&a)) {
        errors->push_back(Msg(flat::DiagCode::Degenerate, "joint '" + j.name + "': its axis " + WhyNoDirection(a.data(), 3),
                              fj.loc, "an axis is a direction: any non-zero finite vector (it is normalized)"));
        a = Vec3::UnitZ();
      }
      j.axis = a;
    }
    if (j.type == JointType::Universal || j.type == JointType::Planar) {
      Vec3 a2 = num3(fj.axis2, "joint axis2", fj.loc);
      // Planar: e1 is axis2 with its normal component removed (Gram-Schmidt), e2 = n x e1.
      if (j.type == JointType::Planar) a2 -= j.axis * j.axis.dot(a2);
      // Relative to axis2 as given: a Planar axis2 along the normal leaves only round-off.
      const Vec3 given = num3(fj.axis2, "joint axis2", fj.loc);
      const double big = given.cwiseAbs().maxCoeff();
      if (!(a2.cwiseAbs().maxCoeff() > 1e-12 * big) || !NormalizeScaled(&a2)) {
        errors->push_back(Msg(flat::DiagCode::Degenerate, "joint '" + j.name + "' has a zero or degenerate axis2 (" +
                                  (given.allFinite() ? "zero, or along the axis" : "not finite") + ")",
                              fj.loc));
        a2 = j.axis.unitOrthogonal();
      }
      j.axis2 = a2;
      j.axis3 = j.axis.cross(j.axis2);
    }
    const int parent_frame = j.inverted ? fj.frame_b : fj.frame_a;
    j.p_PJ = p.frames[static_cast<size_t>(parent_frame)].p_BF;
    j.R_PJ = p.frames[static_cast<size_t>(parent_frame)].R_BF;
    PrepareJointConstants(&j);
    j.q0 = p.nq_all;
    j.u0 = p.nu_all;
    p.nq_all += j.nq;
    p.nu_all += j.nu;
    for (int k = 0; k < j.nu; ++k) p.joint_of_speed.push_back(j.child);
    p.grubler_dof += j.nu;

    // Start values; a quaternion with no start is the identity.
    const bool quat = (j.type == JointType::Spherical || j.type == JointType::Free) &&
                      j.rotation == flat::RotationCoords::Quaternion;
    const int rot0 = j.type == JointType::Free ? 3 : 0;
    bool any_rot_start = false;
    for (int k = 0; k < j.nq; ++k) {
      flat::ExprId e = static_cast<size_t>(k) < fj.q_start.size() ? fj.q_start[static_cast<size_t>(k)] : kNoExpr;
      if (quat && k >= rot0 && e != kNoExpr) any_rot_start = true;
      q_start_all.push_back(num(e, 0.0, "start value of ", j.name, ".q", fj.loc));
    }
    if ((j.type == JointType::Spherical || j.type == JointType::Free) && !quat) {
      const double b = q_start_all[static_cast<size_t>(j.q0 + rot0 + 1)];
      j.chart0 = j.rotation == flat::RotationCoords::CardanXYZ ? std::floor((b + M_PI / 2) / M_PI) : std::floor(b / M_PI);
    }
    if (quat) {
      double* qq = &q_start_all[static_cast<size_t>(j.q0 + rot0)];
      if (!any_rot_start) qq[0] = 1.0;
      if (!NormalizeScaled(qq, 4)) {  // scaled: {1e200, 1e200, 0, 0} is a 90-degree turn, not zeros
        errors->push_back(Msg(flat::DiagCode::Degenerate,
                              "joint '" + j.name + "' starts with a quaternion that " + WhyNoDirection(qq, 4), fj.loc,
                              "the start quaternion {w, x, y, z} is normalized; give any non-zero finite one "
                              "({1, 0, 0, 0}: no rotation)"));
        qq[0] = 1.0;
        qq[1] = qq[2] = qq[3] = 0.0;
      }
    }
    for (int k = 0; k < j.nu; ++k) {
      flat::ExprId e = static_cast<size_t>(k) < fj.u_start.size() ? fj.u_start[static_cast<size_t>(k)] : kNoExpr;
      u_start_all.push_back(num(e, 0.0, "start value of ", j.name, ".u", fj.loc));
    }

    // Coulomb friction (runtime/kane/friction.cpp): a free Prismatic or Revolute joint.
    if (fj.friction_mu != kNoExpr) {
      j.mu = num(fj.friction_mu, 0.0, "friction coefficient of ", j.name, "", fj.loc);
      j.mu_radius = num(fj.friction_radius, 1.0, "friction radius of ", j.name, "", fj.loc);
      j.mu_v = num(fj.friction_v, 1e-3, "friction speed scale of ", j.name, "", fj.loc);
      j.friction_exact = fj.friction_exact;
      j.mu_s = fj.friction_exact ? num(fj.friction_mu_s, j.mu, "static friction coefficient of ", j.name, "", fj.loc) : j.mu;
      j.friction_c = num(fj.friction_c, 0.0, "constant friction of ", j.name, "", fj.loc);
      j.friction_c_s = fj.friction_exact ? num(fj.friction_c_s, j.friction_c, "static constant friction of ", j.name, "", fj.loc)
                                         : j.friction_c;
      const bool prescribed = !fj.prescribed.empty() && fj.prescribed[0] != kNoExpr;
      if ((j.type != JointType::Prismatic && j.type != JointType::Revolute) || prescribed || !(j.mu >= 0.0) ||
          !(j.mu_v > 0.0) || !(j.mu_s >= 0.0) || !(j.friction_c >= 0.0) || !(j.friction_c_s >= 0.0))
        errors->push_back(Msg(flat::DiagCode::BadFriction,
                              "joint '" + j.name +
                                  "': Coulomb friction needs a free prismatic or revolute joint, mu >= 0, a constant "
                                  "friction >= 0 and a positive speed scale",
                              fj.loc));
      else if (j.mu > 0.0 || j.friction_c > 0.0)
        p.friction_joints.push_back(j.child);
    }

    CompileEndStops(fj, &j, &p, num, errors);

    // Prescribed (rheonomic) coordinates: q_k(time), speed and acceleration from jets.
    for (int k = 0; k < j.nq && static_cast<size_t>(k) < fj.prescribed.size(); ++k) {
      flat::ExprId e = fj.prescribed[static_cast<size_t>(k)];
      if (e == kNoExpr) continue;
      std::string label = std::string("prescribed motion ").append(j.name).append(".q").append(j.nq > 1 ? Index1(k) : "");
      if (!ScalarCoordinates(j.type)) {
        errors->push_back(Msg(flat::DiagCode::BadPrescribed, label + ": only joints whose speeds are coordinate rates can be prescribed",
                              fj.loc, "prescribe a revolute, prismatic, cylindrical, universal or planar joint"));
        continue;
      }
      if (m.exprs.DependsOnState(e)) {
        errors->push_back(Msg(flat::DiagCode::NotFixed, label + " may depend on time and parameters only", fj.loc));
        continue;
      }
      presc.AddRoot(e, label, text(e));
      p.q_prescribed.push_back(j.q0 + k);
      p.prescribed_u.push_back(j.u0 + k);
    }
  }
  p.prescribed_tape = presc.Finish();
  p.grubler_dof -= static_cast<int>(p.q_prescribed.size());

  // Free coordinates and speeds: everything not prescribed, in tree order.
  std::vector<char> q_is_presc(static_cast<size_t>(p.nq_all), 0), u_is_presc(static_cast<size_t>(p.nu_all), 0);
  for (int i : p.q_prescribed) q_is_presc[static_cast<size_t>(i)] = 1;
  for (int i : p.prescribed_u) u_is_presc[static_cast<size_t>(i)] = 1;
  p.u_free_of.assign(static_cast<size_t>(p.nu_all), -1);
  for (int i = 0; i < p.nq_all; ++i)
    if (!q_is_presc[static_cast<size_t>(i)]) p.q_free.push_back(i);
  for (int i = 0; i < p.nu_all; ++i)
    if (!u_is_presc[static_cast<size_t>(i)]) {
      p.u_free_of[static_cast<size_t>(i)] = static_cast<int>(p.u_free.size());
      p.u_free.push_back(i);
    }
  p.nq = static_cast<int>(p.q_free.size());
  p.nu = static_cast<int>(p.u_free.size());
  p.y0.clear();
  for (int i : p.q_free) p.y0.push_back(q_start_all[static_cast<size_t>(i)]);
  for (int i : p.u_free) p.y0.push_back(u_start_all[static_cast<size_t>(i)]);
}

// Pattern of the tangent basis: body L moves with the speeds of the joints root..L.
std::vector<int> PathSpeeds(const Program& p, int body) {
  std::vector<int> joints;
  for (int L = body; L >= 0; L = p.joints[static_cast<size_t>(L)].parent) joints.push_back(L);
  std::vector<int> out;
  for (size_t i = joints.size(); i-- > 0;) {
    const TreeJoint& j = p.joints[static_cast<size_t>(joints[i])];
    for (int k = 0; k < j.nu; ++k)
      if (p.u_free_of[static_cast<size_t>(j.u0 + k)] >= 0) out.push_back(j.u0 + k);
  }
  return out;
}

void EnsurePathSpeeds(Program& p, int body) {
  if (body >= 0) p.bodies[static_cast<size_t>(body)].path_speeds = PathSpeeds(p, body);
}

}  // namespace kanesim::rt
