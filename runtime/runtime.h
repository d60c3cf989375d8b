// The runtime's public face (the layer runtime/, kanesim_runtime): make a Workspace per
// thread for an immutable Program (compiler/compiler.h makes one), evaluate the equations of
// motion and the output signals, watch closed loops' branches. The integrators (sim/) see
// the runtime through this header only; the layers above also read the Program's fields
// (runtime/program/program.h, the runtime's other public header).
// kanesim-public: runtime/program/program.h
//
// State layout (the integrators' y): y = [q_free (nq), u_free (nu)], the coordinates and
// speeds of all joints in spanning-tree order, prescribed (rheonomic) coordinates removed.
#pragma once

#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "runtime/program/compile_options.h"
#include "flat/diagnostic_codes.h"
#include "flat/mechanism.h"

namespace kanesim::rt {

struct Program;    // immutable once compiled (compiler/compiler.h); share across threads
struct Workspace;  // mutable scratch for one thread; allocated once per Program
class InputSource;  // the model's inputs as functions of time (runtime/program/program.h)

// Facts for `kanesim check` and `--stats`.
struct ProgramSummary {
  int num_bodies = 0;          // rigid bodies after merging welded ones (world excluded)
  int num_joints = 0;          // articulated joints (welds excluded)
  int nq = 0, nu = 0;          // free coordinates and speeds
  int dof = 0;                 // degrees of freedom (nu minus independent constraints)
  int grubler_dof = 0;         // Grübler-style count from joint freedoms
  SolverPath solver = SolverPath::Dense;
  Integrator integrator = Integrator::IDA;
  std::string solver_reason;      // why this path
  std::string integrator_reason;  // why this integrator
  std::string equations;          // closed loops on the reduced path: how Kane's equations on beta are formed
  std::vector<std::string> cut_joints;
  std::vector<std::string> notes;
};
ProgramSummary Summarize(const Program& program);

std::unique_ptr<Workspace, void (*)(Workspace*)> MakeWorkspace(const Program& program);

int StateSize(const Program& program);  // nq + nu
// Per entry of y = [q_free; u_free], a group number (0, 1, ...): d(ydot_i)/d(y_j) can be
// non-zero only when i and j are in the same group (runtime/engine/coupling.cpp). One group per
// set of subtrees joined by forces, loops or force laws; one group in all for a chain.
std::vector<int> StateCouplingGroups(const Program& program);
int NumQ(const Program& program);
int NumU(const Program& program);

// The model's inputs (top-level `input Real u;`, flat::Mechanism::inputs; docs/language.md
// "Inputs"): values given at run time, read by force laws, prescribed motions and outputs.
// Every workspace that evaluates the model holds them: either constants (SetInputValues; 0
// until set) or a source evaluated at each t (rt::InputSource, runtime/program/program.h:
// a table, sim/input_table.h).
int NumInputs(const Program& program);
const std::string& InputName(const Program& program, int i);  // "u", "f[2]"
void SetInputSource(Workspace& ws, const InputSource* source);  // not owned; null: constants
void SetInputValues(Workspace& ws, const double* u);             // constants, rates 0; drops the source
double StartTime(const Program& program);  // from the experiment annotation
void InitialState(const Program& program, double* y);

// Status codes follow SUNDIALS callbacks: 0 ok, >0 recoverable (retry with a smaller
// step), <0 fatal. On failure, ErrorMessage(ws) says why (e.g. "singular mass matrix",
// "gimbal lock in joint 'ball' (Cardan angle q[2] = 1.5707963)", "NaN from expression ...").
int Derivative(const Program& program, Workspace& ws, double t, const double* y, double* ydot);

// Manifold projection per step (Hairer, Lubich & Wanner, Geometric Numerical Integration,
// 2nd ed., sec. IV.4; docs/constraints.md "Drift"). By default Derivative projects y onto
// the constraints at every evaluation (Newton on the dependent coordinates, then the
// dependent speeds) and adds a pull toward the projection. A one-step solver may instead
// project each accepted step with ProjectOntoConstraints and switch the workspace to
// SetStepProjection(ws, true): Derivative then takes positions and speeds as they are (off
// the manifold: an explicit Runge-Kutta stage's own error is O(h^2)), runs the kinematics
// in one pass as for a tree, and adds no pull: the reduced equations are a smooth ODE off
// the manifold as well. Available on the reduced path with constraint rows
// (StepProjectionAvailable); elsewhere the switch has no effect.
bool StepProjectionAvailable(const Program& program);
void SetStepProjection(Workspace& ws, bool on);
// y := its projection onto the position and velocity constraints. 0, or 1 (recoverable:
// the loop cannot be closed, or a singular configuration; ErrorMessage says which).
int ProjectOntoConstraints(const Program& program, Workspace& ws, double t, double* y);
// Closed loops on the reduced path: while held, Derivative keeps the independent-speed
// partition of the last evaluation even where its dependent block is degraded (it is
// re-chosen only at a singular one). For the perturbed evaluations of a difference-quotient
// Jacobian around the last evaluated state: the partition decides which coordinates the
// projection corrects, so columns taken with different partitions are derivatives of
// different functions (docs/constraints.md, "Singular configurations").
void HoldPartition(Workspace& ws, bool on);
// Closed loops on the reduced path (Derivative with the projection, not the step
// projection), for a difference-quotient Jacobian taken with the partition held: the
// state indices that Derivative does not read under the partition of the last evaluation,
// the dependent speeds (recomputed from the independent ones by the velocity constraints)
// and the coordinates of joints whose every speed is dependent (Newton-corrected from the
// independent ones); *diag is df_i/dy_i for each of them (the pull to the manifold, -k_drift),
// every other entry of their columns zero. False (none) on other paths.
bool ProjectedStates(const Program& program, const Workspace& ws, std::vector<int>* states, double* diag);
const std::string& ErrorMessage(const Workspace& ws);

// The mass matrix M(q, t) of Kane's equations M udot = f on the free speeds (Lesser eqs.
// 22-25; runtime/kane/kane_dense.cpp eq. 4) at the coordinates of y = [q_free; u_free] (its
// speeds are not read), whatever the solver path: symmetric, column-major into M (nu x nu).
// For trees; -1 on a program with constraint rows (ErrorMessage says so). Lesser's diagonal
// speeds (sim/diagonal_speeds.h) factor it.
int MassMatrix(const Program& program, Workspace& ws, double t, const double* y, double* M);
// The same M where the program has constraint rows A u = 0 (closed loops, rolling contacts,
// couplings): the tree's, the rows' reactions not in it (M du = A^T mu + F; sim/end_stops.cpp
// scales its reactions' round-off by it).
int UnconstrainedMassMatrix(const Program& program, Workspace& ws, double t, const double* y, double* M);

// Closed loops through singular configurations (runtime/engine/branch_monitor.cpp;
// docs/constraints.md "Singular configurations"). After each accepted step, CheckBranch(y)
// returns -1 (fatal; BranchMonitorError says why: the loop, the time and the turn) when the
// motion left its assembly branch near a change point (the velocity turned by a finite angle
// where the loop's rows nearly lost rank), else 0 and, in *step, what it measured. The bridge
// over a change point, which integrates, is the integrators' (sim/change_point_bridge.h); it
// reads the loops through the functions below.
struct BranchMonitor;
// How near closed loop `loop` (index into Program::loops) is to a change point at the
// configuration in ws (ConstraintJacobian done): rho = sigma_rank / sigma_max of its rows
// of ws.A, rank = its rank at the assembled start (its rows less the redundant ones),
// translation rows divided by *length so that rho does not depend on the unit of length
// (*length <= 0: taken here, the RMS lever arm of its rows, and stored). 1 for a loop
// without rows.
double LoopSingularRatio(const Program& program, const Workspace& ws, int loop, double* length);
bool BranchMonitorActive(const Program& program);  // the program has closed loops
std::unique_ptr<BranchMonitor, void (*)(BranchMonitor*)> MakeBranchMonitor(const Program& program);
// What CheckBranch measured at an accepted step (filled when it returns 0).
struct BranchStep {
  bool valid = false;    // y was a valid state (else nothing was measured: Derivative reports it)
  double rho = 1.0;      // sigma_min / sigma_max of the nearest-singular loop's rows
  int near_loops = 0;    // loops near singular (rho < 1e-2)
  bool near = false;     // rho < 1e-2: the step lies inside a near-singular zone
  int zone_loop = -1;    // inside a zone: its loop (the nearest-singular one at its first step),
  double zone_t = 0.0;   // ... the time of its first step
  double zone_rho = 1.0;  // ... and its smallest rho so far
};
int CheckBranch(const Program& program, BranchMonitor& monitor, double t, const double* y,
                BranchStep* step = nullptr);
const std::string& BranchMonitorError(const BranchMonitor& monitor);
// A jump of the speeds (a when clause's reinit): the next check takes its velocity as the
// reference, not the one before the jump (which may point anywhere else).
void ForgetBranchReference(BranchMonitor& monitor);
// The monitor's own workspace, its position Newton taken to round-off (Workspace
// newton_to_round_off): the bridge evaluates the equations close to a change point on it.
Workspace& MonitorWorkspace(BranchMonitor& monitor);
// rho of the nearest-singular loop at (t, y) on the monitor's workspace (the lengths of its
// first check), and the count of loops near singular when near_loops is given; -1 when y is
// not a valid state.
double SingularRatioAt(const Program& program, BranchMonitor& monitor, double t, const double* y,
                       int* near_loops = nullptr);
// The name of closed loop `loop` (its cut joint).
const std::string& LoopName(const Program& program, int loop);
// y projected by the partition, positions by Newton (on ws, so to round-off on the
// monitor's), the dependent speeds solved from the independent ones, into *z (StateSize).
// Nonzero (z untouched) when y is not valid or the projection fails.
int ProjectByPartition(const Program& program, Workspace& ws, double t, const double* y, double* z);
// The reduced form's speeds of y (a state ProjectOntoConstraints gave) replaced by y's plus the
// tangent-space correction closest to raw's in the kinetic metric, u = u_y + beta z with
// (beta^T M beta) z = beta^T M (u_raw - u_y): the change leaves the kinetic energy unchanged to
// first order, where the partition's own solve (an oblique projection, ill-conditioned near
// a change point) moves it by raw's error over rho (docs/constraints.md "Singular
// configurations"). Nonzero if the equations fail.
int ProjectSpeedsInKineticMetric(const Program& program, Workspace& ws, double t, const double* raw, double* y);

// "" when the model conserves T + V (the kinetic_energy and potential_energy signals; V =
// gravity + line springs): ideal joints, loops and rolling contacts, gravity, springs of
// constant stiffness and free length. Otherwise the first element that does or may do work,
// in words ("the damper 'd1'", "the prescribed motion of joint 'crank'", "the force of joint
// 'j' (tau)", "the friction of joint 'pin'", "the force 'push'"); one the rule cannot vouch
// for (a stiffness given by an expression) counts as doing work. The energy guard
// (sim/energy_guard.h) checks only conservative models. runtime/engine/energy_guard.cpp
std::string NonConservativeCause(const Program& program);

// End stops (stdlib q_min / q_max on Revolute and Prismatic joints; docs/integrators.md
// "End stops"): one entry per stop joint, in tree order; empty when the program has none (then
// no event machinery runs). runtime/engine/end_stops.cpp
struct EndStop {
  std::string joint;  // the joint's name
  int q = -1;         // its coordinate's index in y = [q_free; u_free]
  int u = -1;         // its speed's index among the free speeds (y[NumQ + u])
  double q_min = 0.0, q_max = 0.0;  // -inf / +inf: no stop on that side
  double restitution = 0.0;
};
std::vector<EndStop> EndStops(const Program& program);
// The speeds' response to a unit generalized impulse on free speed k at the state (t, y):
// x = M(q)^-1 e_k (nu entries), from the mass matrix of Kane's equations. An impulse lambda
// there changes the speeds by lambda x (M du = e_k lambda). With constraint rows A (closed
// loops, rolling contacts) their impulsive reactions join it, M du = A^T mu + e_k lambda with
// A du = 0: x is the column of the constrained inverse mass beta (beta^T M beta)^-1 beta^T.
// 0, or Derivative's status codes; -1 (ErrorMessage says why) with Coulomb friction, on the
// multiplier form (--solver sparse), or where the rows fix speed k (a dead point).
int InverseMassColumn(const Program& program, Workspace& ws, double t, const double* y, int k, double* x);
// Columns ks[0..m) of the same inverse mass from one factorization, X nu x m column-major
// (each column as InverseMassColumn gives it). m = 0: nothing evaluated.
int InverseMassColumns(const Program& program, Workspace& ws, double t, const double* y, const int* ks, int m,
                       double* X);
// The same columns with the friction mu N left out (the response to a force were it
// frictionless: a chord for the resting reactions beside mu, sim/end_stops_friction.cpp).
int FrictionlessInverseMassColumns(const Program& program, Workspace& ws, double t, const double* y, const int* ks,
                                   int m, double* X);
// The mass matrix M (nu x nu, column-major, as MassMatrix) that InverseMassColumns factored
// last in ws, when that was at t and y's coordinates (a tree): true, and M is MassMatrix's to
// the bit, without evaluating (ws's kinematics are left as they are); else false, M untouched.
bool KeptMassMatrix(const Program& program, const Workspace& ws, double t, const double* y, double* M);
// What ws evaluated so far: Derivative's evaluations, and the (constrained) inverse masses
// InverseMassColumn(s) factored (a factor is kept for the same t and q).
struct EvalCounts {
  long derivatives = 0, inverse_mass_factorizations = 0;
};
EvalCounts Counts(const Workspace& ws);
// The same for any generalized impulse F on the free speeds (nu entries): x = M(q)^-1 F.
// runtime/engine/plane_contacts.cpp
int InverseMassTimes(const Program& program, Workspace& ws, double t, const double* y, const double* F, double* x);
// ydot at (t, y) with the generalized forces F (nu entries) added on the free speeds: the
// resting contacts' reactions where Coulomb friction mu N makes the accelerations depend on
// them (sim/end_stops_friction.cpp); with constraint rows their reactions follow F too.
int DerivativeWithForces(const Program& program, Workspace& ws, double t, const double* y, const double* F,
                         double* ydot);

// Coulomb friction joints (stdlib `mu` on Revolute and Prismatic), in the order of the
// workspace's laws; runtime/engine/friction_modes.cpp.
struct FrictionJoint {
  std::string joint;
  int q = -1, u = -1;           // indices in y = [q_free; u_free] (u: among the free speeds)
  double mu = 0.0, mu_s = 0.0;  // kinetic and static coefficients
  double radius = 1.0;          // Revolute: pin radius (friction torque = radius x force)
  bool exact = false;           // stdlib friction_exact: stick-slip as events (sim/stick_slip.h)
  double c = 0.0, c_s = 0.0;    // constant friction, sliding and static (added to mu r N, mu_s r N)
};
std::vector<FrictionJoint> FrictionJoints(const Program& program);
// Friction joint i's law in ws: 0 -mu r N tanh(u / v) (the default), +1 / -1 sliding that way
// (-mu r N sign), 2 the force tau (stuck, held by it).
void SetFrictionMode(Workspace& ws, int i, int mode, double tau);
// Friction joint i's normal force N in the last evaluation of ws.
double FrictionNormal(const Workspace& ws, int i);
// Friction joint i's speed as the last evaluation took it: beside constraint rows a dependent
// speed is solved from the independent ones, not read from y.
double FrictionSpeed(const Program& program, const Workspace& ws, int i);
// The response to a generalized impulse F on the free speeds (nu entries) at (t, y), with the
// constraint rows' impulsive reactions (closed loops, rolling contacts, couplings: the jump
// keeps A du = 0): W (nu x nu, column-major), du = W F (M^-1 on a tree, the constrained
// inverse mass beta (beta^T M beta)^-1 beta^T with rows); N (3 nf x nu, column-major, nf the
// friction joints), per friction joint i, P[3i..3i+2] = (N F)[3i..3i+2] the impulse its
// parent side gives the subtree below it across its axis (world axes; the bodies' momentum
// jumps less the rows' impulses on the subtree): |P_i| is mu N's impulsive N. 0, Derivative's
// codes, or -1 (ErrorMessage says why: a singular mass, --solver sparse with rows, no motion
// left). runtime/engine/friction_impulse.cpp
int ImpulseResponse(const Program& program, Workspace& ws, double t, const double* y, double* W, double* N);
// Per rolling contact (Program::contacts order), the normal impulse P[i] (the plane pushing:
// > 0) of the jump du (nu) at (t, y) by the generalized impulse F (nu) on the free speeds:
// the rows' impulses mu of M du = F + A^T mu along the contact's normal. 0 or Derivative's
// codes. runtime/engine/friction_impulse.cpp
int ContactNormalImpulses(const Program& program, Workspace& ws, double t, const double* y, const double* du,
                          const double* F, double* P);

// Plane contacts (stdlib PlaneContact; docs/stdlib.md): one entry each, in source order; empty
// when the program has none. runtime/engine/plane_contacts.cpp
struct PlaneContact {
  std::string name;
  double restitution = 0.0;
};
std::vector<PlaneContact> PlaneContacts(const Program& program);
// Contact i at (t, y): its gap g = n . p_WO - d (>= 0 on the free side), its row J (nu
// entries: dg/dt = J u) and its bias c (d2g/dt2 = J udot + c). 0, or UnpackState's codes.
int PlaneContactRow(const Program& program, Workspace& ws, double t, const double* y, int i, double* gap, double* J,
                    double* bias);
// DerivativeWithForces with, besides F, contact i's normal force lambda[i] (one per contact,
// pushing: > 0) applied at its point: with Coulomb friction mu N the joints between its body
// and the ground carry it in their normal forces (with constraint rows, as the rows'
// reactions share it).
int DerivativeWithPlaneForces(const Program& program, Workspace& ws, double t, const double* y, const double* F,
                              const double* lambda, double* ydot);
// The contacts' impulses Lambda (one per contact, pushing: > 0) in the friction joints'
// normal impulses: P (3 per friction joint, FrictionImpulseNormals') less each Lambda_c n_c
// across the axis of every friction joint between contact c's body and the ground.
int PlaneImpulseNormals(const Program& program, Workspace& ws, double t, const double* y, const double* Lambda,
                        double* P);
// x = W F for a generalized force F (nu) on the free speeds, W the inverse mass with the
// friction mu N left out (M^-1 on a tree, the constrained inverse mass with constraint rows):
// the resting reactions' chord beside mu (sim/end_stops_friction.cpp). -1 where the rows fix
// F's motion (a dead point).
int FrictionlessInverseMassTimes(const Program& program, Workspace& ws, double t, const double* y, const double* F,
                                 double* x);

// When clauses (Program::whens; docs/events.md): the event tape evaluated at (t, y), its
// roots' values then in ws.event_regs[program.event_tape.roots[i]]. 0, or Derivative's
// status codes. runtime/engine/whens.cpp
int EvalEventTape(const Program& program, Workspace& ws, double t, const double* y);
double EventRoot(const Program& program, const Workspace& ws, int root);
// The names of y's entries: "j.q", "j.q[2]", ..., then "j.u", ...
std::vector<std::string> StateNames(const Program& program);

// Output signals. Names are dotted: "shoulder.q", "ball.q[2]", "kinetic_energy",
// "rod1.frame_b.r[1]", declared outputs by their name. Selection compiles the
// requested names into a plan so that only what is needed gets computed.
std::vector<std::string> AvailableSignals(const Program& program);
std::vector<std::string> DefaultSignals(const Program& program);  // joints' q,u + outputs
struct SignalPlan;
std::shared_ptr<const SignalPlan> PlanSignals(const Program& program, const std::vector<std::string>& names,
                                              std::string* error);
int EvalSignals(const Program& program, const SignalPlan& plan, Workspace& ws, double t, const double* y,
                double* out);
// The held contacts of a hybrid run (sim/end_stops.h, sim/stick_slip.h) in what EvalSignals
// computes on ws from now on: F (nu entries, null: none) generalized forces on the free speeds
// (a resting stop's reaction), `planes` (plane contact i, its normal force on its frame's
// origin), and the free `speeds` held at zero acceleration exactly. The accelerations, body
// accelerations, joint reactions and contact forces are then the held motion's, not the free
// one's (docs/events.md "Outputs"). Derivative never reads them. runtime/engine/end_stops.cpp
void SetHeldLoads(const Program& program, Workspace& ws, const double* F,
                  const std::vector<std::pair<int, double>>& planes, const std::vector<int>& speeds);
void ClearHeldLoads(Workspace& ws);

// Output rows near a change point (runtime/engine/output_rows.cpp; docs/constraints.md
// "Rows near a change point"). Whether the state y at time t is near one (some loop's
// rho < 1e-2; ws: a workspace of its own, so that the rows' own keeps the projection's
// state of the rows before it and the rows away from change points stay as they were).
bool RowNearChangePoint(const Program& program, Workspace& ws, double t, const double* y);
// How far the projection left in ws (after EvalSignals) moved the free speeds of y, in
// units of atol + max(rtol, 1e-8) |u| (max over the speeds).
double SpeedMove(const Program& program, const Workspace& ws, const double* y, double rtol, double atol);
// EvalSignals with the projection of least kinetic energy through a truncated
// pseudo-inverse instead of the partition's.
int EvalSignalsNearChangePoint(const Program& program, const SignalPlan& plan, Workspace& ws, double t,
                               const double* y, double* out);

// The signals among `names` (reaction and contact-force components) whose value the
// equations do not determine, in the order given; empty for a mechanism without redundant
// constraints. Decided at the assembled start (compiler/indeterminate.cpp).
std::vector<std::string> IndeterminateSignals(const Program& program, const std::vector<std::string>& names);

}  // namespace kanesim::rt
