// Which entries of the state can influence which derivatives: the block structure of
// df/dy that IDA's and CVODE-BDF's Newton matrices inherit (sim/dq_jacobian.cpp).
//
// In minimal coordinates every speed of a subtree hanging from the world is coupled to
// every other through the subtree's mass matrix, so a group is at least such a subtree
// (all its free q and u). Groups merge when something acts across them:
// - a spring, damper or line force between frames of two subtrees;
// - a closed loop whose cut joint joins two subtrees, a joint coupling across two;
// - a force law (joint force, line-force parameter, frame wrench) whose expression reads
//   the state of another subtree than the one it acts on. Each tape register carries one
//   representative of the subtrees it depends on; an instruction joining two operands
//   merges their subtrees, which can only over-merge (never miss a dependency).
// Contacts and prescribed motion act between a body and the world and join nothing.
#include "runtime/runtime.h"
#include "flat/union_find.h"
#include "runtime/program/program.h"

namespace kanesim::rt {
namespace {

// Joins the sets of a and b, either of which may be -1 (nothing to join); returns the
// set's root or -1.
int Join(flat::UnionFind& uf, int a, int b) {
  if (a < 0) return b < 0 ? -1 : uf.Find(b);
  if (b < 0) return uf.Find(a);
  return uf.Unite(a, b);
}

}  // namespace

std::vector<int> StateCouplingGroups(const Program& p) {
  const size_t K = p.bodies.size();
  // Bodies are numbered like the tree joints that move them; the set of a body starts as
  // the subtree root above it.
  flat::UnionFind uf(K);
  for (size_t b = 0; b < K; ++b) {
    int root = static_cast<int>(b);
    while (p.joints[static_cast<size_t>(root)].parent >= 0) root = p.joints[static_cast<size_t>(root)].parent;
    Join(uf, root, static_cast<int>(b));
  }
  auto body_of_frame = [&](int frame) {
    if (frame < 0 || static_cast<size_t>(frame) >= p.frames.size()) return -1;
    int b = p.frames[static_cast<size_t>(frame)].body;
    return b >= 0 && static_cast<size_t>(b) < K ? b : -1;
  };
  auto body_of_ref = [&](int ref) {
    const flat::StateRef& r = p.mech->state_refs[static_cast<size_t>(ref)];
    if (r.kind == flat::StateKind::JointQ || r.kind == flat::StateKind::JointU) {
      if (r.target < 0 || static_cast<size_t>(r.target) >= p.joint_of_flat.size()) return -1;
      return p.joint_of_flat[static_cast<size_t>(r.target)];
    }
    return body_of_frame(r.target);
  };

  for (const LineForceModel& l : p.line_forces) Join(uf, body_of_frame(l.frame_a), body_of_frame(l.frame_b));
  for (const LoopClosure& l : p.loops) Join(uf, body_of_frame(l.frame_a), body_of_frame(l.frame_b));
  for (const CouplingModel& c : p.couplings) Join(uf, c.leader, c.follower);  // joint L moves body L

  // Force laws: the subtrees each tape root depends on join the body it acts on.
  const Tape& tape = p.force_tape;
  std::vector<int> dep(static_cast<size_t>(tape.num_regs()), -1);
  for (const auto& [ref, reg] : tape.state_regs) dep[static_cast<size_t>(reg)] = body_of_ref(ref);
  for (const TapeInstr& in : tape.code) {
    int d = -1;
    for (int operand : {in.a, in.b, in.c})
      if (operand >= 0) d = Join(uf, d, dep[static_cast<size_t>(operand)]);
    dep[static_cast<size_t>(in.dst)] = d;
  }
  auto root_dep = [&](const Scalar& s) { return s.root >= 0 ? dep[static_cast<size_t>(tape.roots[static_cast<size_t>(s.root)])] : -1; };
  for (size_t s = 0; s < p.joint_tau.size(); ++s) {
    int d = root_dep(p.joint_tau[s]);
    if (d >= 0) Join(uf, p.joint_of_speed[s], d);
  }
  for (const LineForceModel& l : p.line_forces)
    for (const Scalar* s : {&l.k, &l.d, &l.s0}) {
      int d = root_dep(*s);
      if (d < 0) continue;
      Join(uf, body_of_frame(l.frame_a), d);
      Join(uf, body_of_frame(l.frame_b), d);
    }
  for (const WrenchModel& w : p.wrenches)
    for (int k = 0; k < 3; ++k)
      for (const Scalar* s : {&w.force[k], &w.torque[k]}) {
        int d = root_dep(*s);
        if (d >= 0) Join(uf, body_of_frame(w.frame), d);
      }

  // Number the groups densely in order of first appearance along y = [q_free; u_free].
  std::vector<int> joint_of_q(static_cast<size_t>(p.nq_all), -1);
  for (size_t j = 0; j < p.joints.size(); ++j)
    for (int k = 0; k < p.joints[j].nq; ++k) joint_of_q[static_cast<size_t>(p.joints[j].q0 + k)] = static_cast<int>(j);
  std::vector<int> number(K, -1);
  int next = 0;
  std::vector<int> groups;
  groups.reserve(static_cast<size_t>(p.nq + p.nu));
  auto add = [&](int body) {
    int r = uf.Find(body);
    if (number[static_cast<size_t>(r)] < 0) number[static_cast<size_t>(r)] = next++;
    groups.push_back(number[static_cast<size_t>(r)]);
  };
  for (int i : p.q_free) add(joint_of_q[static_cast<size_t>(i)]);
  for (int i : p.u_free) add(p.joint_of_speed[static_cast<size_t>(i)]);
  return groups;
}

}  // namespace kanesim::rt
