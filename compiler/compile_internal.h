// Stages of Compile shared between the files of compiler/.
#pragma once

#include <string>
#include <vector>

#include "compiler/compiler.h"
#include "runtime/program/program.h"
#include "runtime/program/tape.h"

namespace kanesim::rt {

// A compiler message at a source location (every compile stage reports through it).
inline CompileMessage Msg(flat::DiagCode code, const std::string& text, const flat::SourceLoc& loc,
                          const std::string& hint = "") {
  CompileMessage e;
  e.code = code;
  e.message = text;
  e.hint = hint;
  e.loc = loc;
  return e;
}


// Runs every compile stage on the shared mechanism `mech` (Program::mech keeps it).
CompileResult CompileWithParams(std::shared_ptr<const flat::Mechanism> mech, std::vector<double> pv,
                                const CompileOptions& options, const Program* reuse);

// Eq. (1)-(3) of compile/inertia.cpp: "" when the central inertia I of one body can be
// that of a rigid body (symmetric, positive semi-definite, triangle inequality, within
// kInertiaTol of |I_11| + |I_22| + |I_33|), and then *symmetric = (I + I^T) / 2; else
// what is wrong ("its inertia is not symmetric: ...").
inline constexpr double kInertiaTol = 1e-6;
std::string CheckInertia(const Mat3& I, Mat3* symmetric);

// Joint axes and placements, q/u allocation, prescribed motions, start values.
void CompileJointsAndState(Program& p, TapeBuilder& folder, std::vector<CompileMessage>* errors);
// Fills bodies[body].path_speeds (a body that a loop frame or a contact sits on).
void EnsurePathSpeeds(Program& p, int body);

// When clauses -> Program::whens and the event tape (compiler/whens.cpp); K321 for a reinit
// the mechanism cannot take. After the loops, contacts and forces.
void CompileWhens(Program& p, TapeBuilder& folder, std::vector<CompileMessage>* errors);

// Cut joints (flat indices) -> Program::loops and ::rows (their constrained directions).
void CompileLoops(Program& p, const std::vector<int>& cut_flat, TapeBuilder& folder,
                  std::vector<CompileMessage>* errors);

// Rolling contacts -> Program::contacts and their rows (runtime/constraints/contacts.h).
void CompileContacts(Program& p, TapeBuilder& folder, std::vector<CompileMessage>* errors);

// Joint couplings -> Program::couplings and their rows (compiler/couplings.cpp).
void CompileCouplings(Program& p, TapeBuilder& folder, std::vector<CompileMessage>* errors);
// Before assembly: each follower's start (q and u) from its leader's, by eq. 11, unless the
// follower's start is held (`fixed = true`) or prescribed; then the assembly's Newton
// moves the leader (and the loops' joints) instead.
void StartOnCouplings(const Program& p, Workspace& ws);
// PlaneContact -> Program::plane_contacts (events, no rows). Also refuses, at the element,
// the combinations the events cannot handle yet: plane contacts or end stops together with
// constraint rows (closed loops, rolling contacts) or Coulomb friction.
void CompilePlaneContacts(Program& p, TapeBuilder& folder, std::vector<CompileMessage>* errors);

// Assembly at the start time: Newton to a consistent q and u (coordinates marked fixed
// held), the rank of the constraint Jacobian, DOF, redundant constraints; y0 updated.
void AssembleLoops(Program& p, std::vector<CompileMessage>* errors);

// The reduced (dense) or multiplier (sparse) path for a scene with constraints, after
// AssembleLoops; auto takes the multiplier form from this many free speeds on
// (bench/loop_solvers.cpp).
inline constexpr int kSparseLoopMinSpeeds = 60;
void ChooseLoopSolver(Program& p);

// Relative threshold on |R_ii| / max |R_ii| of column-pivoted QR below which the
// constraint Jacobian counts as rank deficient (assembly, DOF, redundant rows).
inline constexpr double kRankTol = 1e-9;

// Program::reaction_indeterminate and ::contact_indeterminate from the null space of
// A^T at the assembled start (ws: positions, velocities and A of that state).
void FindIndeterminateReactions(Program& p, Workspace& ws);

// K309 for each tree joint with a free speed whose subtree has no mass and no inertia, in
// a model without constraints (compile/massless.cpp).
void CheckMovesMass(const Program& p, std::vector<CompileMessage>* errors);
// K309 when the assembled mechanism has degrees of freedom but no body has mass or
// inertia (closed loops of fixed elements only; after AssembleLoops).
void CheckAnyMassMoves(const Program& p, std::vector<CompileMessage>* errors);

// Ranges of user numbers (compile/ranges.cpp): "" when x is 0 or within [lo, hi], else
// "<what> <x> <unit> is out of range: ...". Lengths by their largest component.
inline constexpr double kMinMass = 1e-100, kMaxMass = 1e100;      // kg, and kg m^2 for inertia entries
inline constexpr double kMinLength = 1e-50, kMaxLength = 1e50;    // m
std::string OutOfRange(const std::string& what, double x, double lo, double hi, const char* unit);
std::string LengthOutOfRange(const std::string& what, const Vec3& r);
const char* RangeHint();

// Gravity, joint forces, line forces, wrenches (force tape) and outputs (output tape).
void CompileForcesAndOutputs(Program& p, TapeBuilder& folder, std::vector<CompileMessage>* errors);

// The solution path and the integrator, with reasons (Summarize prints them).
void ChooseSolver(Program& p);
void ChooseIntegrator(Program& p);

}  // namespace kanesim::rt
