// Compile stage: joint couplings (stdlib JointCoupling, a URDF <mimic>). Each becomes one
// constraint row on the coordinates of its two joints (runtime/constraints/constraints.cpp
// eqs. 11-13),  q_follower = ratio q_leader + offset,  kept exactly like a loop's rows: the
// assembly starts on it, the projection keeps the state on it, and the reduced equations
// make one of the two speeds dependent.
#include <cmath>

#include "compiler/compile_internal.h"
#include "compiler/compiler.h"

namespace kanesim::rt {

void CompileCouplings(Program& p, TapeBuilder& folder, std::vector<CompileMessage>* errors) {
  const flat::Mechanism& m = *p.mech;
  const std::string hint = "a JointCoupling joins the drive flanges of two Revolute or Prismatic joints of the "
                           "spanning tree (not a loop's cut joint, not a locked joint)";
  for (const flat::JointCoupling& fc : m.couplings) {
    CouplingModel c;
    c.name = fc.name;
    c.loc = fc.loc;
    bool ok = true;
    for (auto [flat_joint, tree_joint] : {std::pair{fc.leader, &c.leader}, std::pair{fc.follower, &c.follower}}) {
      const flat::Joint& fj = m.joints[static_cast<size_t>(flat_joint)];
      *tree_joint = p.joint_of_flat[static_cast<size_t>(flat_joint)];
      const bool scalar = fj.type == flat::JointType::Revolute || fj.type == flat::JointType::Prismatic;
      if (*tree_joint < 0 || !scalar) {
        errors->push_back(Msg(flat::DiagCode::BadCoupling,
                              "coupling '" + fc.name + "': joint '" + fj.name + "' " +
                                  (!scalar ? "has no single coordinate" : "is not a joint of the spanning tree (it closes a loop or cannot move)"),
                              fc.loc, hint));
        ok = false;
      }
    }
    if (!folder.Fold(fc.ratio, &c.ratio) || !folder.Fold(fc.offset, &c.offset)) {
      errors->push_back(Msg(flat::DiagCode::NotFixed, "coupling '" + fc.name + "': ratio and offset must not depend on time or state", fc.loc));
      ok = false;
    }
    if (ok && (!std::isfinite(c.ratio) || !std::isfinite(c.offset))) {
      errors->push_back(Msg(flat::DiagCode::BadCoupling, "coupling '" + fc.name + "': ratio and offset must be finite", fc.loc, hint));
      ok = false;
    }
    if (!ok) continue;
    c.row = static_cast<int>(p.rows.size());
    ConstraintRow r;
    r.kind = RowKind::Coupling;
    r.coupling = static_cast<int>(p.couplings.size());
    r.what = "coupling of '" + p.joints[static_cast<size_t>(c.follower)].name + "' to '" +
             p.joints[static_cast<size_t>(c.leader)].name + "'";
    p.rows.push_back(r);
    p.couplings.push_back(c);
    p.grubler_dof -= 1;
  }
}

void StartOnCouplings(const Program& p, Workspace& ws) {
  const flat::Mechanism& m = *p.mech;
  for (const CouplingModel& c : p.couplings) {
    const TreeJoint& f = p.joints[static_cast<size_t>(c.follower)];
    const TreeJoint& l = p.joints[static_cast<size_t>(c.leader)];
    const flat::Joint& ff = m.joints[static_cast<size_t>(f.flat_index)];
    const bool held = !ff.q_start_fixed.empty() && ff.q_start_fixed[0];
    if (held || p.u_free_of[static_cast<size_t>(f.u0)] < 0) continue;
    ws.q[f.q0] = c.ratio * ws.q[l.q0] + c.offset;
    ws.u[f.u0] = c.ratio * ws.u[l.u0];
  }
}

}  // namespace kanesim::rt
