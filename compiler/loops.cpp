// Compile stage: closed loops. Each cut joint (a joint whose two sides the spanning tree
// already connects; `cut = true` makes a joint the preferred cut) becomes position
// constraints, one per direction it does NOT allow — the complement of its motion
// subspace — between its frames a and b (rows of runtime/constraints/constraints.cpp, eqs. 1-2):
//
//   joint        rows (n = axis in a, e1 = n.unitOrthogonal(), e2 = n x e1)
//   Revolute     translation along x, y, z of a;  tilt: e1 . n_b, e2 . n_b
//   Prismatic    translation along e1, e2;        rotation: a_y . b_z, a_z . b_x, a_x . b_y
//   Cylindrical  translation along e1, e2;        tilt about e1, e2
//   Universal    translation along x, y, z;       n1 . (R_ab n2) = n1 . n2
//   Spherical    translation along x, y, z
//   Planar       translation along n;             tilt about e1, e2
//   Free         none
//
// Assembly (AssembleLoops) at the start time: Gauss-Newton with minimum-norm steps over
// the speeds not held (coordinates marked `fixed = true` are held, with their speeds),
//   du = -A_S^+ phi,  q += N(q) du                                              (1)
// until |phi| <= kAssemblyTol; then the speeds du = -A_S^+ (A u + b). The rank of A
// (column-pivoted QR, relative threshold kRankTol) gives the DOF = nu - rank; rows
// that pivoted QR of A^T leaves out are redundant (a planar loop from spatial joints)
// and are named with their joint's source location.
#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "compiler/compile_internal.h"
#include "runtime/constraints/constraints.h"
#include "runtime/kane/kane.h"
#include "runtime/kinematics/joint_kinematics.h"
#include "runtime/kinematics/kinematics.h"
#include "compiler/compiler.h"

namespace kanesim::rt {

using flat::JointType;
using flat::kNoExpr;

namespace {

constexpr double kAssemblyTol = 1e-12;  // position residual (relative to the loop length scale)
constexpr int kAssemblyIters = 50;

std::string LocText(const flat::SourceLoc& l) {
  return l.file.str() + ":" + std::to_string(l.line) + ":" + std::to_string(l.col);
}

ConstraintRow Trans(const Vec3& d, const std::string& what) {
  ConstraintRow r;
  r.kind = RowKind::Translation;
  r.d_a = d;
  r.what = what;
  return r;
}
ConstraintRow Align(const Vec3& e, const Vec3& n, double offset, const std::string& what) {
  ConstraintRow r;
  r.kind = RowKind::Alignment;
  r.d_a = e;
  r.n_b = n;
  r.offset = offset;
  r.what = what;
  return r;
}

// Who owns a row, for messages: the cut joint, the contact or the coupling.
const std::string& RowOwner(const Program& p, const ConstraintRow& row) {
  if (row.coupling >= 0) return p.couplings[static_cast<size_t>(row.coupling)].name;
  return row.contact >= 0 ? p.contacts[static_cast<size_t>(row.contact)].name : p.loops[static_cast<size_t>(row.loop)].name;
}
const flat::SourceLoc& RowLoc(const Program& p, const ConstraintRow& row) {
  if (row.coupling >= 0) return p.couplings[static_cast<size_t>(row.coupling)].loc;
  return row.contact >= 0 ? p.contacts[static_cast<size_t>(row.contact)].loc : p.loops[static_cast<size_t>(row.loop)].loc;
}
// "contact 'disk'", "coupling 'mimic'", "the loop closed by 'rocker'".
std::string RowOwnerWords(const Program& p, const ConstraintRow& row) {
  const char* kind = row.coupling >= 0 ? "coupling '" : row.contact >= 0 ? "contact '" : "the loop closed by '";
  return kind + RowOwner(p, row) + "'";
}

// Warning W315 (compiler/compiler.h StartSpeedsWarning): the start speeds u0 violated the velocity
// constraints (residuals psi0) and the minimum-norm correction moved a speed the model
// gave a non-zero start value. Speeds that start at zero and move are the dependent ones
// left to the assembly (a start of 0 is also the library's default, so the two cannot be
// told apart) and are named only alongside. A change counts above 1e-9 of the largest
// start speed (at least 1e-9): consistent starts computed in floating point move by
// round-off.
void DescribeStartSpeedChange(Program& p, const Eigen::VectorXd& psi0, const Eigen::VectorXd& u0,
                              const Eigen::VectorXd& u1) {
  const double tol = 1e-9 * std::max(1.0, u0.cwiseAbs().maxCoeff());
  struct Change {
    int s;
    double du;
  };
  std::vector<Change> changed;
  bool given_changed = false;
  for (int i = 0; i < p.nu; ++i) {
    const int s = p.u_free[static_cast<size_t>(i)];
    const double du = u1[s] - u0[s];
    if (!(std::fabs(du) > tol)) continue;
    changed.push_back({s, du});
    given_changed = given_changed || u0[s] != 0.0;
  }
  if (!given_changed) return;
  std::sort(changed.begin(), changed.end(),
            [](const Change& a, const Change& b) { return std::fabs(a.du) > std::fabs(b.du); });
  auto name = [&](int s) {
    const TreeJoint& j = p.joints[static_cast<size_t>(p.joint_of_speed[static_cast<size_t>(s)])];
    return j.name + ".u" + (j.nu > 1 ? Index1(s - j.u0) : std::string());
  };
  // The constraints whose start residual was above the tolerance, the largest first.
  struct Owner {
    double res;
    std::string who;
    flat::SourceLoc loc;
  };
  std::vector<Owner> owners;
  for (Eigen::Index r = 0; r < psi0.size(); ++r) {
    const double res = std::fabs(psi0[r]);
    if (!(res > tol)) continue;
    const ConstraintRow& row = p.rows[static_cast<size_t>(r)];
    const std::string who = RowOwnerWords(p, row);
    auto it = std::find_if(owners.begin(), owners.end(), [&](const Owner& o) { return o.who == who; });
    if (it == owners.end())
      owners.push_back({res, who, RowLoc(p, row)});
    else
      it->res = std::max(it->res, res);
  }
  std::sort(owners.begin(), owners.end(), [](const Owner& a, const Owner& b) { return a.res > b.res; });
  if (!owners.empty()) p.start_speeds_loc = owners.front().loc;
  std::ostringstream msg;
  msg.precision(6);
  msg << "start speeds violate the velocity constraints of ";
  for (size_t k = 0; k < owners.size(); ++k)
    msg << (k ? ", " : "") << (owners.size() > 1 && k + 1 == owners.size() ? "and " : "") << owners[k].who;
  msg << " (largest residual " << (owners.empty() ? 0.0 : owners.front().res)
      << ") and were projected onto them: ";
  const size_t shown = std::min<size_t>(changed.size(), 6);
  for (size_t k = 0; k < shown; ++k)
    msg << (k ? ", " : "") << name(changed[k].s) << " " << u0[changed[k].s] << " -> " << u1[changed[k].s];
  if (changed.size() > shown) msg << " and " << changed.size() - shown << " more";
  msg << "; largest change " << std::fabs(changed.front().du) << " (" << name(changed.front().s) << ")";
  p.start_speeds_changed = msg.str();
}

// A cut joint whose frames a and b are both on one rigid body B (Topology put them in one
// rigid group: the world, or bodies merged by a weld or a fixed element) can never move.
// Its rows (1)-(2) of constraints.cpp are constants in B's axes,
//   phi = d_aB . (p_BFb - p_BFa)   and   phi = d_aB . n_bB - offset,
// with a zero Jacobian: no speed moves them. When they hold, the joint is locked in a pose
// it allows and is dropped (warning W316: no speed, no row); else the frames are held in
// a pose the joint cannot take and the model cannot be assembled (K310).
constexpr double kLockedTol = 1e-9;  // of the larger frame distance from B's origin (at least 1 m)

std::string BodyWords(const Program& p, int body) {
  return body < 0 ? "the world" : "body '" + p.bodies[static_cast<size_t>(body)].name + "'";
}

void LockJoint(Program& p, const flat::Joint& fj, const std::vector<ConstraintRow>& rows,
               std::vector<CompileMessage>* errors) {
  const FramePlace& A = p.frames[static_cast<size_t>(fj.frame_a)];
  const FramePlace& B = p.frames[static_cast<size_t>(fj.frame_b)];
  const double scale = std::max({1.0, A.p_BF.norm(), B.p_BF.norm()});
  const ConstraintRow* worst = nullptr;
  double worst_res = 0.0;
  for (const ConstraintRow& r : rows) {
    const double res = r.kind == RowKind::Translation ? std::fabs(r.d_aB.dot(B.p_BF - A.p_BF)) / scale
                                                      : std::fabs(r.d_aB.dot(r.n_bB) - r.offset);
    if (!(res <= worst_res)) {  // NaN counts as the worst
      worst = &r;
      worst_res = res;
    }
  }
  Program::LockedJoint lj;
  lj.name = fj.name;
  lj.loc = fj.loc;
  lj.body = BodyWords(p, A.body);
  for (const flat::Joint& w : p.mech->joints)
    if (w.type == JointType::Weld && w.frame_a >= 0 && p.frames[static_cast<size_t>(w.frame_a)].body == A.body)
      lj.by.push_back({w.loc, "weld '" + w.name + "' joins its frames to " + lj.body});
  if (worst != nullptr && !(worst_res <= kLockedTol)) {
    std::ostringstream msg;
    msg.precision(6);
    msg << "joint '" << fj.name << "' cannot move (both its frames are fixed to " << lj.body
        << ") and its frames are not in a pose it allows: " << worst->what << " off by "
        << worst_res * (worst->kind == RowKind::Translation ? scale : 1.0);
    CompileMessage e = Msg(flat::DiagCode::CannotAssemble, msg.str(), fj.loc,
                           "connect the joint's frame_b to the body it should move; a joint between two frames of "
                           "one rigid body (joined by welds or fixed elements) holds nothing");
    e.notes = lj.by;
    errors->push_back(std::move(e));
    return;
  }
  p.locked_joints.push_back(std::move(lj));
}

}  // namespace

std::vector<CompileMessage> LockedJointWarnings(const Program& p) {
  std::vector<CompileMessage> out;
  for (const Program::LockedJoint& lj : p.locked_joints) {
    CompileMessage w = Msg(flat::DiagCode::LockedJoint,
                           "joint '" + lj.name + "' cannot move: both its frames are fixed to " + lj.body +
                               ", so it adds no degree of freedom",
                           lj.loc,
                           "if the joint should move, connect its frame_b to the body it moves and remove the weld "
                           "that holds it; a joint held on purpose can stay (it is ignored)");
    w.notes = lj.by;
    out.push_back(std::move(w));
  }
  return out;
}

CompileMessage StartSpeedsWarning(const Program& p) {
  CompileMessage w;
  if (p.start_speeds_changed.empty()) return w;
  w.code = flat::DiagCode::StartSpeedsProjected;
  w.message = p.start_speeds_changed;
  w.loc = p.start_speeds_loc;
  w.hint = "the run starts from the projected speeds (the smallest change in the sum of squares of the speeds "
           "not held); give start speeds that satisfy the constraints, or leave the dependent ones at 0";
  return w;
}

// Contacts (runtime/constraints/contacts.cpp): rows d . v_P = 0 with
//   RollingSphere, RollingDisk  n (position constraint too), t1, t2 (velocity only)
//   KnifeEdge                   n (position constraint too), l = n x e (velocity only)
void CompileContacts(Program& p, TapeBuilder& folder, std::vector<CompileMessage>* errors) {
  const flat::Mechanism& m = *p.mech;
  auto num = [&](flat::ExprId id, double dflt, const flat::SourceLoc& loc) {
    double v = dflt;
    if (id != kNoExpr && !folder.Fold(id, &v))
      errors->push_back(Msg(flat::DiagCode::NotFixed, "contact geometry must not depend on time or state", loc));
    return v;
  };
  auto num3 = [&](const flat::Vec3E& e, const flat::SourceLoc& loc) {
    return Vec3(num(e[0], 0.0, loc), num(e[1], 0.0, loc), num(e[2], 0.0, loc));
  };
  for (const flat::Contact& fc : m.contacts) {
    if (fc.type == flat::ContactType::Plane) continue;  // unilateral: CompilePlaneContacts
    ContactModel c;
    c.name = fc.name;
    c.loc = fc.loc;
    c.type = fc.type;
    c.frame = fc.frame;
    if (fc.frame < 0 || p.frames[static_cast<size_t>(fc.frame)].body < -1) {
      errors->push_back(Msg(flat::DiagCode::BadContact, "contact '" + fc.name + "' is not connected to the mechanism", fc.loc));
      continue;
    }
    c.body = p.frames[static_cast<size_t>(fc.frame)].body;
    EnsurePathSpeeds(p, c.body);
    if (c.body < 0) {
      errors->push_back(Msg(flat::DiagCode::BadContact, "contact '" + fc.name + "' is attached to the ground", fc.loc,
                            "connect its frame to a moving body"));
      continue;
    }
    c.radius = num(fc.radius, 0.0, fc.loc);
    c.axis_F = num3(fc.axis, fc.loc);
    c.n_W = num3(fc.plane_normal, fc.loc);
    c.p0_W = num3(fc.plane_point, fc.loc);
    // Directions, normalized without overflow (joint_kinematics.h NormalizeScaled).
    const bool has_axis = fc.type != flat::ContactType::RollingSphere;
    const bool normal_ok = NormalizeScaled(&c.n_W);
    const bool axis_ok = NormalizeScaled(&c.axis_F) || !has_axis;  // a sphere's axis is not used
    if (!normal_ok || !axis_ok) {
      const Vec3& bad = normal_ok ? c.axis_F : c.n_W;
      errors->push_back(Msg(flat::DiagCode::BadContact,
                            "contact '" + fc.name + "': its " + (normal_ok ? "axis " : "plane normal ") +
                                WhyNoDirection(bad.data(), 3),
                            fc.loc, "a normal or an axis is a direction: any non-zero finite vector (it is normalized)"));
      continue;
    }
    if (fc.type != flat::ContactType::KnifeEdge && !(c.radius > 0.0)) {
      errors->push_back(Msg(flat::DiagCode::BadContact, "contact '" + fc.name + "' needs a positive radius", fc.loc));
      continue;
    }
    c.t1_W = c.n_W.unitOrthogonal();
    c.t2_W = c.n_W.cross(c.t1_W);
    const int ci = static_cast<int>(p.contacts.size());
    c.row0 = static_cast<int>(p.rows.size());
    auto add = [&](RowKind k, const Vec3& d, const std::string& what) {
      ConstraintRow r;
      r.contact = ci;
      r.kind = k;
      r.d_a = d;
      r.what = what;
      p.rows.push_back(r);
    };
    add(RowKind::ContactNormal, c.n_W, "contact along the normal");
    if (fc.type == flat::ContactType::KnifeEdge) {
      add(RowKind::ContactLateral, Vec3::Zero(), "lateral sliding");
    } else {
      add(RowKind::ContactTangent, c.t1_W, "slip along t1");
      add(RowKind::ContactTangent, c.t2_W, "slip along t2");
    }
    c.nrows = static_cast<int>(p.rows.size()) - c.row0;
    p.contacts.push_back(c);
    p.grubler_dof -= c.nrows;
  }
}

void CompileLoops(Program& p, const std::vector<int>& cut_flat, TapeBuilder& folder,
                  std::vector<CompileMessage>* errors) {
  const flat::Mechanism& m = *p.mech;
  auto num3 = [&](const flat::Vec3E& e, const flat::SourceLoc& loc) {
    Vec3 v = Vec3::Zero();
    for (int k = 0; k < 3; ++k) {
      const flat::ExprId id = e[static_cast<size_t>(k)];
      if (id != kNoExpr && !folder.Fold(id, &v[k]))
        errors->push_back(Msg(flat::DiagCode::NotFixed, "joint axis must not depend on time or state", loc));
    }
    return v;
  };
  for (int fi : cut_flat) {
    const flat::Joint& fj = m.joints[static_cast<size_t>(fi)];
    if (fj.q_min != kNoExpr || fj.q_max != kNoExpr)  // a cut joint has no coordinate to stop
      errors->push_back(Msg(flat::DiagCode::BadStop,
                            "joint '" + fj.name + "' closes a loop (it is a cut joint) and cannot have end stops", fj.loc,
                            "put the stop on another joint of the loop, or mark another joint `cut = true`"));
    LoopClosure l;
    l.name = fj.name;
    l.loc = fj.loc;
    l.flat_index = fi;
    l.frame_a = fj.frame_a;
    l.frame_b = fj.frame_b;
    l.row0 = static_cast<int>(p.rows.size());
    const int loop = static_cast<int>(p.loops.size());
    Vec3 n = Vec3::UnitZ(), n2 = Vec3::UnitX();
    if (fj.type != JointType::Spherical && fj.type != JointType::Free) {
      n = num3(fj.axis, fj.loc);
      if (!NormalizeScaled(&n)) {
        errors->push_back(Msg(flat::DiagCode::Degenerate, "joint '" + fj.name + "': its axis " + WhyNoDirection(n.data(), 3),
                              fj.loc, "an axis is a direction: any non-zero finite vector (it is normalized)"));
        n = Vec3::UnitZ();
      }
    }
    if (fj.type == JointType::Universal) {
      n2 = num3(fj.axis2, fj.loc);
      if (!NormalizeScaled(&n2)) n2 = n.unitOrthogonal();
    }
    const Vec3 e1 = n.unitOrthogonal(), e2 = n.cross(e1);
    const Vec3 X = Vec3::UnitX(), Y = Vec3::UnitY(), Z = Vec3::UnitZ();
    std::vector<ConstraintRow> rows;
    auto xyz = [&]() {
      rows.push_back(Trans(X, "translation along x"));
      rows.push_back(Trans(Y, "translation along y"));
      rows.push_back(Trans(Z, "translation along z"));
    };
    auto tilt = [&]() {
      rows.push_back(Align(e1, n, 0.0, "tilt of the axis towards e1"));
      rows.push_back(Align(e2, n, 0.0, "tilt of the axis towards e2"));
    };
    switch (fj.type) {
      case JointType::Revolute: xyz(); tilt(); break;
      case JointType::Prismatic:
        rows.push_back(Trans(e1, "translation across the axis (e1)"));
        rows.push_back(Trans(e2, "translation across the axis (e2)"));
        rows.push_back(Align(Y, Z, 0.0, "rotation about x"));
        rows.push_back(Align(Z, X, 0.0, "rotation about y"));
        rows.push_back(Align(X, Y, 0.0, "rotation about z"));
        break;
      case JointType::Cylindrical:
        rows.push_back(Trans(e1, "translation across the axis (e1)"));
        rows.push_back(Trans(e2, "translation across the axis (e2)"));
        tilt();
        break;
      case JointType::Universal: xyz(); rows.push_back(Align(n, n2, n.dot(n2), "twist about the cross axis")); break;
      case JointType::Spherical: xyz(); break;
      case JointType::Planar: rows.push_back(Trans(n, "translation along the normal")); tilt(); break;
      case JointType::Free:
      case JointType::Weld: break;
    }
    bool connected = true;
    for (int f : {l.frame_a, l.frame_b})
      if (f < 0 || p.frames[static_cast<size_t>(f)].body < -1) {
        errors->push_back(Msg(flat::DiagCode::NotConnectedToWorld, "cut joint '" + fj.name + "' is not connected to the mechanism", fj.loc));
        connected = false;
      }
    for (auto& r : rows) {
      r.loop = loop;
      if (connected) {  // the directions in the bodies' axes (constraints.cpp FrameState)
        r.d_aB = p.frames[static_cast<size_t>(l.frame_a)].R_BF * r.d_a;
        r.n_bB = p.frames[static_cast<size_t>(l.frame_b)].R_BF * r.n_b;
      }
    }
    if (connected && p.frames[static_cast<size_t>(l.frame_a)].body == p.frames[static_cast<size_t>(l.frame_b)].body) {
      LockJoint(p, fj, rows, errors);  // closes no loop through any speed
      continue;
    }
    if (connected)
      for (int f : {l.frame_a, l.frame_b}) EnsurePathSpeeds(p, p.frames[static_cast<size_t>(f)].body);
    for (const auto& r : rows) p.rows.push_back(r);
    l.nrows = static_cast<int>(rows.size());
    p.loops.push_back(l);
  }
  p.grubler_dof -= static_cast<int>(p.rows.size());
}

void AssembleLoops(Program& p, std::vector<CompileMessage>* errors) {
  const flat::Mechanism& m = *p.mech;
  p.solver = SolverPath::Dense;  // assembly works on the reduced path's arrays, every row
  p.loop_rank = 0;
  p.active_rows.resize(p.rows.size());
  p.active_of_row.resize(p.rows.size());
  for (size_t i = 0; i < p.rows.size(); ++i) p.active_rows[i] = p.active_of_row[i] = static_cast<int>(i);
  auto wsp = MakeWorkspace(p);
  Workspace& ws = *wsp;
  const auto nc = static_cast<Eigen::Index>(p.rows.size());
  const double t0 = StartTime(p);
  if (UnpackState(p, ws, t0, p.y0.data()) != 0) {
    errors->push_back(Msg(flat::DiagCode::CannotAssemble, "prescribed motion not finite at the start time", RowLoc(p, p.rows[0])));
    return;
  }
  StartOnCouplings(p, ws);
  PositionKinematics(p, ws);
  VelocityKinematics(p, ws);
  double len = 1.0;
  for (const Vec3& x : ws.p_WB) len = std::max(len, x.norm());
  p.loop_length = len;

  // Held speeds: those of coordinates marked fixed (scalar joints per coordinate; a
  // rotation block of a spherical or free joint when any of its coordinates is).
  std::vector<int> S;  // free speed indices that assembly may move
  for (int i = 0; i < p.nu; ++i) {
    const int s = p.u_free[static_cast<size_t>(i)];
    const TreeJoint& j = p.joints[static_cast<size_t>(p.joint_of_speed[static_cast<size_t>(s)])];
    const flat::Joint& fj = m.joints[static_cast<size_t>(j.flat_index)];
    const int k = s - j.u0;
    bool held = false;
    const bool rot_block = j.type == JointType::Spherical || (j.type == JointType::Free && k >= 3);
    if (!rot_block) {
      held = static_cast<size_t>(k) < fj.q_start_fixed.size() && fj.q_start_fixed[static_cast<size_t>(k)];
    } else {
      for (int c = j.type == JointType::Free ? 3 : 0; c < j.nq; ++c)
        held = held || (static_cast<size_t>(c) < fj.q_start_fixed.size() && fj.q_start_fixed[static_cast<size_t>(c)]);
    }
    if (!held) S.push_back(i);
  }
  Eigen::MatrixXd AS(nc, static_cast<Eigen::Index>(S.size()));
  auto gather = [&]() {
    for (size_t c = 0; c < S.size(); ++c) AS.col(static_cast<Eigen::Index>(c)) = ws.A.col(S[c]);
  };
  auto step = [&](const Eigen::VectorXd& dx, double scale) {
    ws.du_full.setZero();
    for (size_t c = 0; c < S.size(); ++c) ws.du_full[p.u_free[static_cast<size_t>(S[c])]] = scale * dx[static_cast<Eigen::Index>(c)];
  };
  const double tol = kAssemblyTol * len;
  double r = 0.0;
  int it = 0;
  for (;; ++it) {
    ConstraintResiduals(p, ws);
    ConstraintJacobian(p, ws);
    r = ws.phi.cwiseAbs().maxCoeff();
    if (r <= tol || it == kAssemblyIters || S.empty()) break;
    gather();
    Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(AS);
    cod.setThreshold(kRankTol);
    const Eigen::VectorXd dx = cod.solve(-ws.phi);
    // Backtracking: halve the step until the residual decreases (far from the solution).
    const Eigen::VectorXd q_old = ws.q;
    double scale = 1.0;
    for (int h = 0; h < 30; ++h, scale *= 0.5) {
      ws.q = q_old;
      step(dx, scale);
      ApplyCoordinateStep(p, ws, ws.du_full);
      PositionKinematics(p, ws);
      ConstraintResiduals(p, ws);
      if (ws.phi.cwiseAbs().maxCoeff() < r) break;
    }
    PositionKinematics(p, ws);
    VelocityKinematics(p, ws);
  }
  if (r > tol) {
    Eigen::Index worst = 0;
    ws.phi.cwiseAbs().maxCoeff(&worst);
    const ConstraintRow& row = p.rows[static_cast<size_t>(worst)];
    std::ostringstream msg;
    if (row.contact >= 0)
      msg << "contact '" << RowOwner(p, row) << "' cannot be assembled on its plane: ";
    else if (row.coupling >= 0)
      msg << "coupling '" << RowOwner(p, row) << "' cannot be satisfied: ";
    else
      msg << "joint '" << RowOwner(p, row) << "' closes a kinematic loop that cannot be assembled: ";
    msg << row.what << " residual " << r << " after " << it << " Newton iterations";
    errors->push_back(Msg(flat::DiagCode::CannotAssemble, msg.str(), RowLoc(p, row),
                          "check the link lengths and the start values; mark the coordinates you know with "
                          "`fixed = true` and leave the others free"));
    return;
  }
  // Speeds: minimum-norm correction over the speeds not held.
  ConstraintJacobian(p, ws);
  p.start_speeds_changed.clear();
  if (!S.empty()) {
    gather();
    Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(AS);
    cod.setThreshold(kRankTol);
    const Eigen::VectorXd psi0 = ws.psi, u0 = ws.u;
    const Eigen::VectorXd dx = cod.solve(-ws.psi);
    for (size_t c = 0; c < S.size(); ++c) ws.u[p.u_free[static_cast<size_t>(S[c])]] += dx[static_cast<Eigen::Index>(c)];
    VelocityKinematics(p, ws);
    ConstraintJacobian(p, ws);
    DescribeStartSpeedChange(p, psi0, u0, ws.u);
  }
  const double rv = ws.psi.size() ? ws.psi.cwiseAbs().maxCoeff() : 0.0;
  if (rv > 1e-9 * (1.0 + ws.u.cwiseAbs().maxCoeff()) * len) {
    Eigen::Index worst = 0;
    ws.psi.cwiseAbs().maxCoeff(&worst);
    const ConstraintRow& row = p.rows[static_cast<size_t>(worst)];
    errors->push_back(Msg(flat::DiagCode::CannotAssemble, "the start speeds cannot satisfy the constraints of '" + RowOwner(p, row) +
                                      "' (velocity residual " + std::to_string(rv) + ")",
                          RowLoc(p, row), "leave more start speeds free (not fixed)"));
    return;
  }

  // Rank, DOF and redundant rows at the assembled configuration.
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(ws.A);
  qr.setThreshold(kRankTol);
  p.loop_rank = static_cast<int>(qr.rank());
  p.dof = p.nu - p.loop_rank;
  p.reduce_by_passes = PassesCheaper(p.dof);
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qrt(ws.A.transpose());
  qrt.setThreshold(kRankTol);
  const auto& perm = qrt.colsPermutation().indices();
  p.redundant_rows.clear();
  for (Eigen::Index k = qrt.rank(); k < nc; ++k) p.redundant_rows.push_back(perm[k]);
  std::sort(p.redundant_rows.begin(), p.redundant_rows.end());
  FindIndeterminateReactions(p, ws);
  for (size_t li = 0; li < p.loops.size(); ++li) {
    const LoopClosure& l = p.loops[li];
    std::string redundant;
    for (Eigen::Index k = qrt.rank(); k < nc; ++k) {
      const ConstraintRow& row = p.rows[static_cast<size_t>(perm[k])];
      if (row.loop != static_cast<int>(li)) continue;
      redundant += (redundant.empty() ? "" : ", ") + row.what;
    }
    std::string note = "loop closed by joint '" + l.name + "' (" + LocText(l.loc) + "): " +
                       std::to_string(l.nrows) + " constraint(s)";
    if (!redundant.empty())
      note += "; redundant (indeterminate constraint-force components): " + redundant;
    p.notes.push_back(note);
  }
  for (size_t ci = 0; ci < p.contacts.size(); ++ci) {
    const ContactModel& c = p.contacts[ci];
    std::string redundant;
    for (Eigen::Index k = qrt.rank(); k < nc; ++k) {
      const ConstraintRow& row = p.rows[static_cast<size_t>(perm[k])];
      if (row.contact == static_cast<int>(ci)) redundant += (redundant.empty() ? "" : ", ") + row.what;
    }
    std::string note = "contact '" + c.name + "' (" + LocText(c.loc) + "): " + std::to_string(c.nrows) +
                       " velocity constraint(s), 1 of them also on positions";
    if (!redundant.empty()) note += "; redundant (already enforced by the joints): " + redundant;
    p.notes.push_back(note);
  }
  for (const CouplingModel& c : p.couplings) {
    std::ostringstream note;
    note.precision(17);
    note << "coupling '" << c.name << "' (" << LocText(c.loc) << "): " << p.joints[static_cast<size_t>(c.follower)].name
         << ".q = " << c.ratio << " * " << p.joints[static_cast<size_t>(c.leader)].name << ".q + " << c.offset
         << " (1 constraint)";
    if (std::binary_search(p.redundant_rows.begin(), p.redundant_rows.end(), c.row)) note << "; redundant";
    p.notes.push_back(note.str());
  }
  std::ostringstream dof;
  dof << "degrees of freedom " << p.dof << " = " << p.nu << " free speeds - rank " << p.loop_rank
      << " of the " << nc << "-row constraint Jacobian at the assembled start";
  p.notes.push_back(dof.str());
  // From here on the redundant rows hold with the others: the reduced path leaves them
  // out (docs/constraints.md "Redundant rows"), unless the minimum-norm multipliers are
  // needed, which take every row. Only a loop row that is zero at the start (a planar
  // loop's out-of-plane rows: zero at every configuration of the loop's plane) is left
  // out; a redundant loop row that is not zero is a combination of the others that changes
  // along the motion (an overconstrained linkage: Bricard, Bennett, Sarrus), so any fixed
  // choice of rows to leave out loses rank somewhere on the motion (the orthogonal
  // Bricard's at the odd joints' angle +-2 pi / 3, where every row stays: rank 4 of 5,
  // sigma_4 / sigma_1 ~ 0.5) and the loop keeps every row. Contact rows as before.
  const bool min_norm = p.options.indeterminate == IndeterminateReactions::MinNorm || !p.friction_joints.empty();
  if (!min_norm && !p.redundant_rows.empty()) {
    const double a_max = ws.A.size() ? ws.A.cwiseAbs().maxCoeff() : 0.0;
    auto left_out = [&](int i) {
      if (!std::binary_search(p.redundant_rows.begin(), p.redundant_rows.end(), i)) return false;
      const ConstraintRow& row = p.rows[static_cast<size_t>(i)];
      return row.contact >= 0 || row.coupling >= 0 || ws.A.row(i).cwiseAbs().maxCoeff() <= kRankTol * a_max;
    };
    p.active_rows.clear();
    for (size_t i = 0; i < p.rows.size(); ++i) {
      const bool out = left_out(static_cast<int>(i));
      p.active_of_row[i] = out ? -1 : static_cast<int>(p.active_rows.size());
      if (!out) p.active_rows.push_back(static_cast<int>(i));
    }
  }
  // The assembled start: the state the integrators begin from.
  PackState(p, ws, p.y0.data());
}

namespace {
// Whether the reduced form factors the dependent block at the assembled start in the
// banded order (constraints.cpp BandedOrder: a chain of loops, each coupled to its
// neighbours only), where its QR grows linearly with the loops instead of as rank^3.
bool DependentBlockBanded(const Program& p) {
  auto wsp = MakeWorkspace(p);
  Workspace& ws = *wsp;
  if (UnpackState(p, ws, StartTime(p), p.y0.data()) != 0) return false;
  PositionKinematics(p, ws);
  VelocityKinematics(p, ws);  // the partial velocities the Jacobian is made of
  return FactorConstraintsAsIs(p, ws) == 0 && ws.dep_banded;
}

// A when clause that sets a speed (an impulse, like an impact).
bool ReinitsASpeed(const Program& p) {
  for (const WhenModel& w : p.whens)
    for (const WhenReinit& r : w.reinits)
      if (r.speed) return true;
  return false;
}
}  // namespace

// The path for a scene with constraints (after AssembleLoops: it needs the redundant
// rows). Measured by bench/loop_solvers.cpp on ladders of N four-bars (docs/constraints.md
// "Reduced or multiplier form"): the reduced form costs O(nu^3) per evaluation, the
// multiplier form O(bodies + rows) but with a larger constant; the multiplier form wins
// from kSparseLoopMinSpeeds free speeds on — unless the dependent block is banded (a chain
// of loops), where the reduced form's factorization is linear too and the reduced form
// stays cheaper (chain of 40 parallelograms, 81 free speeds: 56 against 233 us per
// right-hand side; docs/benchmarks.md "Change points").
void ChooseLoopSolver(Program& p) {
  const std::string counts = std::to_string(p.loops.size()) + " closed loop(s), " + std::to_string(p.contacts.size()) +
                             " contact(s), " + (p.couplings.empty() ? "" : std::to_string(p.couplings.size()) + " joint coupling(s), ") +
                             std::to_string(p.nu) + " free speeds";
  const std::string reduced = ": reduced form: Kane's equations on the constrained basis (Lesser eq. 51)";
  const std::string sparse = ": sparse K-vector system with a multiplier per independent constraint row, KLU";
  // The multipliers of the sparse path are one particular solution where constraints are
  // redundant; the minimum-norm share and friction that reads it need the reduced path.
  std::string blocked;
  if (!p.couplings.empty())  // a coupling row reads four bodies' twists (constraints.cpp RowJacobians)
    blocked = "the multiplier form does not take joint couplings";
  if (!p.redundant_rows.empty() && p.options.indeterminate == IndeterminateReactions::MinNorm)
    blocked = "--reactions min-norm needs the reduced path";
  if (!p.redundant_rows.empty() && !p.friction_joints.empty())
    blocked = "Coulomb friction with redundant constraints reads the minimum-norm normal force of the reduced path";
  // An impulse keeps the rows through the tangent basis beta (rt::InverseMassColumn); the
  // multiplier form has none, so it would fail at the first impact instead of running.
  if (!p.stop_joints.empty() || !p.plane_contacts.empty() || ReinitsASpeed(p))
    blocked = "impacts (end stops, plane contacts, reinit of a speed) need the reduced form's tangent basis";
  const SolverPath want = p.options.solver;
  const bool banded = want == SolverPath::Auto && blocked.empty() && p.nu >= kSparseLoopMinSpeeds &&
                      DependentBlockBanded(p);
  if (want == SolverPath::Sparse && blocked.empty()) {
    p.solver = SolverPath::Sparse;
    p.solver_reason = counts + sparse + " (forced by --solver)";
  } else if (want == SolverPath::Auto && blocked.empty() && p.nu >= kSparseLoopMinSpeeds && !banded) {
    p.solver = SolverPath::Sparse;
    p.solver_reason = counts + sparse + " (measured cheaper than the reduced form from " +
                      std::to_string(kSparseLoopMinSpeeds) + " free speeds on)";
  } else {
    p.solver = SolverPath::Dense;
    p.solver_reason = counts + reduced;
    if (want == SolverPath::Sparse) p.solver_reason += "; --solver sparse is ignored here: " + blocked;
    if (want == SolverPath::Recursive) p.solver_reason += "; --solver recursive applies to open trees only and is ignored here";
    if (want == SolverPath::Auto && p.nu < kSparseLoopMinSpeeds)
      p.solver_reason += " (measured cheaper than the multiplier form below " + std::to_string(kSparseLoopMinSpeeds) +
                         " free speeds)";
    if (banded)
      p.solver_reason += " (the dependent block is banded, a chain of loops: its factorization grows linearly, "
                         "measured cheaper than the multiplier form)";
  }
}

}  // namespace kanesim::rt
