// Time integration of an ODE y' = f(t, y) with SUNDIALS or our DOP853, generic over the right-hand
// side so that it can be tested on closed-form ODEs without a mechanism.
//
// Output instants come from the integrator's own dense output: each solver is run in
// NORMAL mode toward the next output time, past which it may step and then interpolate
// back; the stop time is set so that it never steps past the last instant and the last
// row is exactly `stop`. No step-size hacks (no forced steps onto output instants).
//
// Methods and their linear algebra:
// - IDA: variable-order (1-5) variable-step BDF on the residual F(t, y, y') = y' - f(t, y).
//   Newton iteration on dF/dy + cj dF/dy' = cj I - df/dy, formed by our own column-
//   grouped difference quotients (sim/dq_jacobian.cpp) and factored by dense
//   LU or by KLU. The block structure comes from `coupling` (rt::StateCouplingGroups):
//   d(ydot_i)/d(y_j) = 0 unless i and j share a group. In minimal coordinates a chain is
//   one group (u' = M(q)^-1 f couples every speed of a subtree), so KLU pays only for
//   scenes made of several independent or weakly joined subsystems; columns of different
//   groups are perturbed together, so a Jacobian costs (largest group) evaluations of f,
//   not n.
// - CVODE Adams: variable-order (1-12) Adams-Moulton with fixed-point (functional)
//   iteration: no Jacobian, no linear solves; for non-stiff scenes.
// - CVODE BDF: variable-order (1-5) BDF, Newton with dense LU and DQ Jacobian (IDA's grouped
//   difference quotients where they cost fewer evaluations: integrator_cvode.cpp).
// - ARKODE ERK: explicit Runge-Kutta (ERKStep), Verner 6(5) (8 stages, order 6) by
//   default, made first-same-as-last (SUNDIALS 6.4 reused a stale first stage otherwise).
//   Each output instant ends a step; events are located on ARKODE's Hermite interpolant of
//   degree 5, too low for Fehlberg 8(7)'s steps (docs/benchmarks/2026-11-29_arkode_fsal.md).
// - DOP853: our own Dormand-Prince 8(5,3) (sim/integrator_dop853.cpp; Hairer,
//   Norsett & Wanner, Solving ODEs I, sec. II.10): 12 evaluations of f per step (the
//   13th stage is the next step's first), error estimate from its 5th- and 3rd-order
//   embedded solutions, and its 7th-order dense output, which costs 3 evaluations of f
//   once per step that holds output instants (not per instant).
#pragma once

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "runtime/program/compile_options.h"  // rt::Integrator: the one integrator enum

namespace kanesim::sim {

// The right-hand side. Status codes follow SUNDIALS callbacks: 0 ok, >0 recoverable
// (the solver retries with a smaller step), <0 fatal (integration stops).
class OdeSystem {
 public:
  virtual ~OdeSystem() = default;
  virtual int Size() const = 0;
  // ydot = f(t, y); y and ydot have Size() entries.
  virtual int Rhs(double t, const double* y, double* ydot) = 0;
  // Why the last non-zero return of Rhs or Project happened ("singular mass matrix", ...).
  virtual std::string FailureCause() const { return "the right-hand side reported a failure"; }
  // Manifold projection (Hairer, Lubich & Wanner, Geometric Numerical Integration, sec.
  // IV.4) for a system whose states obey constraints. A one-step solver (DOP853) that can
  // project calls EnableStepProjection once before its first Rhs, then Project on every
  // accepted step; the system may then skip its own projection inside Rhs. Project
  // returns Rhs's status codes.
  virtual bool CanProject() const { return false; }
  virtual void EnableStepProjection() {}
  virtual int Project(double /*t*/, double* /*y*/) { return 0; }
  // y := its projection as Project's, computed aside: nothing that a later Rhs or Project
  // reads is touched (a measurement of how far a solver's state drifted; ARKODE). Rhs's
  // status codes; -1 when the system offers none (the engine: closed loops on the reduced
  // form only).
  virtual int ProjectAside(double /*t*/, double* /*y*/) { return -1; }
  // The same on the multiplier form's closed loops only (-1 elsewhere): CVODE's drift
  // measurement (integrator_cvode.cpp), where that form's kinetic-metric projection of
  // all the speeds carries a drift of y into y*.
  virtual int ProjectAsideMultiplierForm(double /*t*/, double* /*y*/) { return -1; }
  // A check of each accepted step (closed loops: the branch monitor and the bridge,
  // sim/change_point_bridge.h CheckStep). Solvers call StepAccepted(t, y) after every accepted step when
  // ChecksSteps(): 0 goes on, > 0 asks to take the step again shorter (DOP853; the
  // SUNDIALS solvers, which cannot take back an accepted step, stop as for < 0), < 0 stops
  // the run with FailureCause().
  virtual bool ChecksSteps() const { return false; }
  virtual int StepAccepted(double /*t*/, const double* /*y*/) { return 0; }
  // A bridge over a singular configuration (closed loops through a change point;
  // docs/constraints.md "Singular configurations"): after a failed solver step, a state
  // y_b (Size()) at *t_b past it from which a fresh solver goes on, and BridgeState(t, y),
  // the bridged motion on [*t_from, *t_b] for the output instants in the gap. False when
  // there is none (the failure stands).
  virtual bool Bridge(double /*rtol*/, double /*atol*/, double* /*t_from*/, double* /*t_b*/, double* /*y_b*/) {
    return false;
  }
  virtual void BridgeState(double /*t*/, double* /*y*/) {}
  // Whether the last accepted step lies inside a near-singular zone (closed loops: the
  // branch monitor's rho < 1e-2). The output rows of such steps are held until the zone is
  // left (written as they are) or bridged (those in the bridge's interval recomputed from
  // BridgeState): docs/constraints.md "Rows held through a zone".
  virtual bool InZone() const { return false; }
  // A solver's difference-quotient Jacobian: on before its perturbed evaluations of Rhs
  // around the state of the last one, off after them. The system may hold there whatever
  // discrete choices the last evaluation made (closed loops: the speed partition,
  // rt::HoldPartition), so that every column differentiates the same function.
  virtual void HoldForJacobian(bool /*on*/) {}
  // While held: the states the last evaluation's f does not depend on (closed loops on the
  // reduced form: rt::ProjectedStates), ascending, and df_i/dy_i for each (*diag; every
  // other entry of their columns is zero), so a Jacobian need not perturb them. False: none.
  virtual bool ProjectedStates(std::vector<int>* /*states*/, double* /*diag*/) { return false; }
  // r >= 0 when df/dy = -c I + (a matrix of rank at most r) for some constant c, else -1:
  // closed loops on the multiplier form, where f(y) = g(P(y)) + k (P(y) - y) and the
  // projection P maps onto the state manifold (r = its dimension, 2 dof for nq = nu). The
  // Newton matrices of the BDF integrators are then identity + rank r, which GMRES solves
  // in r + 1 products J*v (sim/newton_krylov.h).
  virtual int NewtonRank() const { return -1; }
  // The kinetic and potential energy of the state y at t as the output rows compute them
  // (projected), for a system that conserves T + V and whose interpolated output instants
  // the solvers check against the energies of the steps around them (closed loops:
  // docs/constraints.md "Rows checked against the energy"). Evaluated aside: nothing a
  // later Rhs reads is touched. HasEnergy false: never called.
  // Events (end stops; docs/integrators.md "End stops"): NumEvents() functions g_i(t, y), each
  // positive while nothing happens; an event is a g_i crossing zero downwards, which every
  // solver locates (SUNDIALS' root finding; DOP853 on its dense output) and stops at. Integrate
  // then writes the row at the event's left limit, lets Event(t, y, i) jump y (an impact, a
  // stop taken or left; Rhs's status codes), writes the right limit and goes on with a fresh
  // solver. NumEvents() == 0: none of this runs.
  virtual int NumEvents() const { return 0; }
  virtual int EventFunctions(double /*t*/, const double* /*y*/, double* /*g*/) { return 0; }
  virtual int Event(double /*t*/, double* /*y*/, int /*i*/) { return 0; }
  // Graze guards (docs/integrators.md "End stops"): event function i >= 0 may only mark where
  // another one, Paired(i), has a minimum (minus a gap's rate). At its crossing the solvers
  // look at that other function there: positive, nothing happens and the run goes on (no
  // rows); not, it dipped below zero and back inside one step, and its crossing before the
  // minimum is the event. -1: an event of its own.
  virtual int Paired(int /*i*/) const { return -1; }
  // After an Event: true when it ends the run there (a when clause's terminate), *why its
  // message. Integrate then writes the right limit's row and stops, successfully.
  virtual bool Terminated(std::string* /*why*/) const { return false; }
  // A row is held (a joint stuck by exact friction, a stop or contact resting): the state may
  // stand still while the forces that end the hold change with time, which no error estimate
  // sees. Integrate then bounds each step by the output interval, so that a window where the
  // hold must end is not stepped over (a stuck gear's slip at 0.243 s, DOP853 steps growing
  // six-fold: tests/compiler/held_step_test.cpp).
  virtual bool Holding() const { return false; }
  // The event functions of the held rows (a stuck joint's friction bound minus its needed
  // force, a resting stop's or contact's reaction), ascending; empty when none is held. Every
  // solver then bounds each step by what their values, rates and curvatures foretell
  // (sim/release_bound.h), in a run and in the stepping API alike.
  virtual void HeldEvents(std::vector<int>* events) const { events->clear(); }
  // Rhs ends an inner iteration at a tolerance, not at round-off (exact friction's mu N fixed
  // point, runtime/kane/friction.cpp: ~1e-11 of the friction forces, depending on the last
  // call's): a difference quotient's increment must then be at least the error weights'
  // scale 1/w (IDA's rule), never CVODE's own (min_inc / w: 2e-22 at a restart at rest, where
  // that noise made df/dy -1e11 and CVODE-BDF froze a slipping joint's speed near zero).
  virtual bool IteratedRhs() const { return false; }
  virtual bool HasEnergy() const { return false; }
  virtual int Energy(double /*t*/, const double* /*y*/, double* /*T*/, double* /*V*/) { return -1; }
};

// The methods above are rt::Integrator's (runtime/program/compile_options.h); Auto, the
// compiler's choice, is resolved before integrating (Simulate), and Integrate takes it as IDA.
const char* MethodName(rt::Integrator m);         // "IDA", "CVODE-Adams", ...
const char* MethodDescription(rt::Integrator m);  // one line: order, iteration, linear solver

enum class ErkTable { Verner65, Fehlberg87 };

// The Newton iteration's linear solver of IDA (all four) and CVODE-BDF (Auto, Dense, Krylov;
// Klu is dense LU there). Auto: matrix-free GMRES (Krylov) where the system's NewtonRank r
// is small against n (sim/newton_krylov.cpp); else, for IDA, KLU when the
// Jacobian's block pattern fills at most kKluMaxFill of the n x n matrix and n >=
// kKluMinStates (measured in bench/ida_linear_solver.cpp), dense LU otherwise.
enum class IdaLinearSolver { Auto, Dense, Klu, Krylov };
inline constexpr double kKluMaxFill = 0.25;
inline constexpr int kKluMinStates = 20;

struct IntegratorOptions {
  rt::Integrator method = rt::Integrator::IDA;
  double rtol = 1e-6;
  double atol = 1e-6;              // scalar absolute tolerance on every state
  long max_steps = 100000;         // internal steps allowed between two output instants
  double max_step = 0.0;           // |h| bound; 0 = none
  double initial_step = 0.0;       // 0 = the solver's estimate
  bool after_event = false;        // a fresh solver at an event's right limit (CVODE-Adams: CarefulFirstStep)
  bool after_jump = false;         // ... where the event jumped the state beyond its tolerance (StateJumped;
                                   // CVODE-BDF: RestartWeights)
  ErkTable erk_table = ErkTable::Verner65;
  IdaLinearSolver ida_linear_solver = IdaLinearSolver::Auto;
  bool project_steps = false;      // DOP853: project accepted steps (OdeSystem::Project)
  std::vector<int> coupling;       // per state: its group (empty: one group, a dense df/dy)
  bool bridge = true;              // restart past a singular configuration (OdeSystem::Bridge)
  bool dense_check = true;         // DOP853: retake a step whose dense-output stages are not smooth
  bool row_energy_check = true;    // check interpolated output instants' T + V (OdeSystem::Energy)
  bool check_steps = true;         // DOP853: call OdeSystem::StepAccepted (off: recomputing one row)
  bool switch_when_stiff = false;  // DOP853 under the automatic choice: go on with CVODE-BDF when stiff
  double run_end = -INFINITY;      // ... where the whole run ends when later than the solver's stop time
                                   // (the stepping core, whose stop is each step's end: +inf, unknown)
};

// Whether an event moved some entry of y from `before` by more than the error test's
// tolerance rtol |y_i| + atol (an impact's or a reinit's jump; not a law's change, nor a
// speed set to zero from its location's residual).
bool StateJumped(const double* before, const double* after, size_t n, double rtol, double atol);

// Counters from the solver (cumulative over the run).
struct IntegratorStats {
  long steps = 0;
  long rhs_evals = 0;          // f evaluations by the method itself
  long rhs_evals_jac = 0;      // f evaluations spent on difference-quotient Jacobians
  long event_evals = 0;        // evaluations of the event functions by the solvers (root finding,
                               // DOP853's search of its dense output, graze guards); 0 without events
  long jac_evals = 0;          // Jacobian (re)computations
  long lin_setups = 0;         // linear-solver setups = LU factorizations
  long err_test_fails = 0;     // local error test failures
  long dense_rejects = 0;      // DOP853: steps whose dense output was rejected (stages not smooth)
  long energy_rejects = 0;     // output instants whose interpolated T + V was off (OdeSystem::Energy):
                               // DOP853's step taken again onto it, SUNDIALS' instant integrated again
  long energy_reject_rhs = 0;  // f evaluations of those SUNDIALS re-integrations (DOP853's are in rhs_evals)
  long nonlin_iters = 0;       // Newton or fixed-point iterations
  long nonlin_conv_fails = 0;  // nonlinear convergence failures
  long lin_iters = 0;          // Krylov iterations (matrix-free Newton; 0 otherwise)
  long lin_conv_fails = 0;     // ... and their convergence failures
  double last_step = 0.0;      // last step size taken
  int last_order = 0;          // last method order used (0 for ERK)
  const char* linear_solver = "none";  // "dense LU", "KLU", "GMRES, matrix-free" (IDA, CVODE-BDF), "none"
  long jac_nonzeros = 0;       // structural non-zeros of the Newton matrix (IDA)
  double stiff_time = NAN;     // DOP853: where it found the problem stiff (NaN: never)
  double stiff_h_lambda = 0.0; // ... its last estimate of h |lambda| there
  bool switched = false;       // ... and the run went on with CVODE-BDF from there
  bool switch_allowed = false; // ... under the automatic choice (not switched: too few steps were left)
};

// Output instants: t_k = start + k * interval for k = 0 .. n-1 (computed as start + k / N
// when interval = 1/N for an integer N, so that 0.1 steps print as 0.3, not
// 0.30000000000000004), the last one replaced by
// exactly `stop` (it may then be closer than `interval` to the one before). An instant
// within 1e-9 interval of stop is merged into it, so rounding never adds a sliver row.
//
// Limits (Check): finite times, stop >= start, a positive finite interval of at least
// kMinIntervalFraction of the largest |t| (so that consecutive instants differ in double
// precision and a solver can step between them), and at most kMaxOutputRows rows.
inline constexpr long kMaxOutputRows = 100'000'000;
inline constexpr double kMinIntervalFraction = 1e-12;

struct OutputGrid {
  double start = 0.0;
  double stop = 1.0;
  double interval = 0.0;  // > 0
  // Why this grid cannot be run, in words ("" when it can).
  std::string Check() const;
  // Number of rows, >= 1; for a grid that fails Check, at most kMaxOutputRows + 1 (never
  // an overflowed conversion).
  long Count() const;
  double Time(long k) const;
};

// Receives the state at each output instant. Return 0 to go on; non-zero stops the run
// as a failure at that instant with `cause`.
using RowCallback = std::function<int(double t, const double* y, std::string* cause)>;

struct IntegrateResult {
  bool ok = true;
  double fail_time = 0.0;  // where it failed (the failing f evaluation, else the solver's time)
  std::string cause;       // why, for "numerical failure at t = ...: <cause>"
  long rows = 0;           // rows handed to the callback
  long bridges = 0;        // singular configurations stepped over (OdeSystem::Bridge)
  long events = 0;         // events handled (OdeSystem::Event), each with two rows
  bool terminated = false; // an event ended the run (OdeSystem::Terminated) at terminate_time
  double terminate_time = 0.0;
  std::string terminate_message;
  IntegratorStats stats;
};

// Integrates from grid.start (state y0) to grid.stop and calls `row` at every instant,
// the first with y0 itself.
IntegrateResult Integrate(OdeSystem& system, const double* y0, const OutputGrid& grid,
                          const IntegratorOptions& options, const RowCallback& row);

}  // namespace kanesim::sim
