// Compile stage: joints that move no mass. A free speed s of tree joint L whose subtree
// (L and every body beyond it) has no mass and no inertia has a zero column in the mass
// matrix, M_ss = h_s^T Ic_L h_s = 0 with Ic_L the subtree's composite spatial inertia
// (kane_dense.cpp eq. (4)), in every configuration: M is singular from the start and no
// integrator can take a step. In an open tree that is a modelling mistake (a joint whose
// frame_b carries nothing), reported here at the joint instead of as a numerical failure
// at t = 0. With closed loops or contacts the constraints may fix such a speed (a
// massless coupler), so there only the run can tell — except when no body at all has mass
// or inertia and the assembled loops leave a degree of freedom (CheckAnyMassMoves).
#include "compiler/compile_internal.h"
#include "compiler/compiler.h"

namespace kanesim::rt {

void CheckMovesMass(const Program& p, std::vector<CompileMessage>* errors) {
  if (!p.rows.empty()) return;
  const size_t K = p.bodies.size();
  // Bodies are numbered parents first (compile.cpp Topology), so one pass from the leaves
  // adds every subtree into its root.
  std::vector<char> carries(K, 0);
  for (size_t L = K; L-- > 0;) {
    const TreeBody& b = p.bodies[L];
    if (b.mass != 0.0 || !b.I_BBcm_B.isZero(0.0)) carries[L] = 1;
    const int parent = p.joints[L].parent;
    if (carries[L] && parent >= 0) carries[static_cast<size_t>(parent)] = 1;
  }
  for (size_t L = 0; L < K; ++L) {
    const TreeJoint& j = p.joints[L];
    bool free_speed = false;
    for (int k = 0; k < j.nu; ++k) free_speed = free_speed || p.u_free_of[static_cast<size_t>(j.u0 + k)] >= 0;
    if (carries[L] || !free_speed) continue;
    // Only the joint nearest the world of a massless subtree: the ones beyond it follow.
    if (j.parent >= 0 && !carries[static_cast<size_t>(j.parent)]) {
      const TreeJoint& up = p.joints[static_cast<size_t>(j.parent)];
      bool up_free = false;
      for (int k = 0; k < up.nu; ++k) up_free = up_free || p.u_free_of[static_cast<size_t>(up.u0 + k)] >= 0;
      if (up_free) continue;
    }
    errors->push_back(Msg(flat::DiagCode::MovesNoMass,
                          "joint '" + j.name + "' moves no mass: nothing with mass or inertia is attached beyond it, so "
                              "its motion has no inertia (the mass matrix is singular)",
                          j.loc,
                          "attach a body (Body, Rod, Box, ...) to the side of the joint away from the world, or "
                          "prescribe its motion, or remove it"));
  }
}

void CheckAnyMassMoves(const Program& p, std::vector<CompileMessage>* errors) {
  if (p.dof <= 0) return;
  for (const TreeBody& b : p.bodies)
    if (b.mass != 0.0 || !b.I_BBcm_B.isZero(0.0)) return;
  for (const TreeJoint& j : p.joints)
    for (int k = 0; k < j.nu; ++k)
      if (p.u_free_of[static_cast<size_t>(j.u0 + k)] >= 0) {
        errors->push_back(Msg(flat::DiagCode::MovesNoMass,
                              "joint '" + j.name + "' moves no mass: the mechanism has " + std::to_string(p.dof) +
                                  " degree(s) of freedom but no body with mass or inertia",
                              j.loc, "attach a body (Body, Rod, Box, ...) to the moving links, or prescribe the motion"));
        return;
      }
}

}  // namespace kanesim::rt
