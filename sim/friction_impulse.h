// A jump of the speeds in a mechanism with Coulomb friction proportional to the normal force
// (`mu` of Revolute and Prismatic; docs/events.md "Friction in a jump"): a when clause's
// reinit of a speed, an end stop's impact. The jump's impulse carries an impulsive normal
// force in the joints, so their friction acts impulsively too: a joint's friction impulse
// P_f obeys Coulomb's law on impulses, |P_f| <= mu_s r |P_N| where the joint ends at rest
// (it sticks), P_f = -mu r |P_N| sign(u+) where it slides on (u+ its speed after the jump),
// P_N the joint's normal impulse. Trees, closed loops, joint couplings and rolling contacts
// alike: the constraint rows' impulses keep A du = 0 and enter the normal impulses.
#pragma once

#include <string>
#include <vector>

#include "runtime/runtime.h"

namespace kanesim::sim {

// The most friction joints the jump's case enumeration (3^n cases) takes.
constexpr int kMaxFrictionImpulseJoints = 6;

// True when a jump in `program` meets friction impulses (a joint with mu > 0).
bool HasFrictionImpulses(const rt::Program& program);

struct FrictionJumpResult {
  std::vector<double> du;       // nu: the free speeds' jump (A du = 0 with constraint rows)
  std::vector<double> impulse;  // per row of J: its impulse c (the rows' generalized impulse J^T c)
  std::vector<int> stuck;       // the free speeds of the friction joints that stick (u+ = 0)
  std::vector<double> friction, normal;  // per friction joint (rt::FrictionJoints order): P_f, |P_N|
  std::vector<double> generalized;       // nu: the joints' generalized impulse J^T c + sum P_f e_i
};

// The jump at (t, y) whose rows J (m x nu, row-major, on the free speeds) change by
// `targets` (J du = targets) by the impulse J^T c, the friction joints (mu > 0, prescribed
// ones and those whose speed is itself a row, +-e_k, left out) by their Coulomb impulses,
// the constraint rows (closed loops, couplings, rolling contacts) by their reactions:
//   M du = J^T c + sum_i P_f,i e_i + A^T mu,   A du = 0,   J du = targets.
// A row for an end stop's impact is +-e_k (its impulse c >= 0 pushes: the caller's check);
// a reinit's is e_k. 0, Derivative's codes, or -1 with *why (the rows constrain the same
// motion, a dead point of the loops, no case satisfies the law, too many joints).
// row_normals (3 nf x m, column-major; empty: none): per row, what its unit impulse adds to the
// friction joints' normal impulses beyond N J^T (a plane contact's impulse acts at its point,
// so every joint between it and the ground carries it: rt::PlaneImpulseNormals).
int FrictionJump(const rt::Program& program, rt::Workspace& ws, double t, const double* y,
                 const std::vector<double>& J, const std::vector<double>& targets, FrictionJumpResult* out,
                 std::string* why, const std::vector<double>& row_normals = {});

// FrictionJump for rows e_k, k in `rows` (free-speed indices): du (nu entries) and *stuck.
int FrictionSpeedJump(const rt::Program& program, rt::Workspace& ws, double t, const double* y,
                      const std::vector<int>& rows, const std::vector<double>& targets, double* du,
                      std::vector<int>* stuck, std::string* why, std::vector<double>* F = nullptr);

}  // namespace kanesim::sim
