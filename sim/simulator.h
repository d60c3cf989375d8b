// The stepping core: a compiled program advanced by its caller step by step, the model's
// inputs set between steps (a controller in Python, an FMU's doStep). One integrator runs
// across the steps, its history carried (not a restart per step): each step sets the
// solver's stop time to its end, so that no step integrates past an instant where the inputs
// may change, and the solver goes on from there. docs/python.md "Stepping" describes what
// holds for each integrator:
//   - DOP853 (one-step): after an input change f(t, y) is evaluated again (the first stage);
//     the step size is kept.
//   - ARKODE-ERK: ERKStepReset at an input change (the step size kept, f evaluated again).
//   - CVODE (Adams, BDF), IDA: the multistep history is kept across an input change; the
//     corrector evaluates f with the new inputs and the error test shortens the step where
//     the jump matters.
// Under the automatic choice a DOP853 that finds the problem stiff hands over to CVODE-BDF as
// in a run (detail::HandOverStiff), whatever the caller's step; CVODE-BDF stays until Reset.
// Events: the run's own (sim/hybrid_ode.h: end stops and plane contacts with their graze
// guards and Zeno accumulation, exact stick-slip friction, rolling contacts' lift-off, when
// clauses with reinit and terminate), located by the solver inside a step, the jump, then a
// fresh solver from the right limit, as in a run; a terminate ends the step there.
// GetState / SetState: the state is (t, y, the inputs, the step size to try next, the modes:
// resting stops, accumulating bounces, stuck joints and their forces; a terminate). GetState
// restarts the solver at that instant from those, and SetState restarts it the same way, so
// the continuation after either is the same bit for bit. (CVODE's and IDA's history cannot
// be set through their public API; the restart costs them their order, which grows again
// within a few steps.)
//
// Not done while stepping: bridges over closed loops' singular configurations (a step that
// meets one fails), the output rows' energy checks (there are no rows).
#pragma once

#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "runtime/runtime.h"
#include "sim/integrator.h"
#include "sim/simulate.h"

namespace kanesim::sim {

struct SimulatorOptions {
  double start_time = std::numeric_limits<double>::quiet_NaN();  // NaN: rt::StartTime(program)
  double rtol = 1e-6;
  double atol = 1e-6;
  rt::Integrator integrator = rt::Integrator::Auto;  // Auto: rt::Summarize(program).integrator
  IdaLinearSolver ida_linear_solver = IdaLinearSolver::Auto;
  long max_steps = 100000;  // internal steps allowed in one step of the caller
  bool project_steps = false;
  std::vector<std::string> signals;  // the outputs; empty: rt::DefaultSignals(program)
  std::vector<double> initial_state;  // y0 (rt::StateSize); empty: rt::InitialState(program)
  std::vector<double> initial_inputs;  // the inputs at the start (rt::NumInputs); empty: 0
};

// What a step did: ok, or where and why the integration failed. A failed simulator refuses
// to step until Reset or SetState. terminated: a when clause's terminate("why") fired at
// Time() (before the step's end; cause is its message); the simulator refuses to step on
// until Reset or SetState.
struct StepResult {
  bool ok = true;
  double fail_time = 0.0;
  std::string cause;
  bool terminated = false;
};

// Everything a continuation needs (GetState / SetState). Values only: copy it, store it.
struct SimulatorState {
  double t = 0.0;
  std::vector<double> y;       // [q_free, u_free]  (rt::StateSize)
  std::vector<double> inputs;  // (rt::NumInputs)
  double next_step = 0.0;      // the step size the solver tries next (0: its own estimate)
  std::vector<double> modes;   // HybridOde::Modes (resting stops, stuck joints)
  bool terminated = false;     // a terminate fired (then its message)
  std::string terminate_message;
};

class Simulator {
 public:
  // Null with *error when the options cannot run (tolerances, signal names, a start past an
  // end stop or pulling on a rolling contact).
  static std::unique_ptr<Simulator> Make(std::shared_ptr<const rt::Program> program,
                                         const SimulatorOptions& options, std::string* error);
  ~Simulator();
  Simulator(const Simulator&) = delete;
  Simulator& operator=(const Simulator&) = delete;

  // Inputs, in rt::InputName order; 0 until set. A value must be finite.
  const std::vector<std::string>& InputNames() const { return input_names_; }
  int InputIndex(const std::string& name) const;  // -1 when none
  bool SetInput(int i, double value, std::string* error);
  const std::vector<double>& Inputs() const;

  // Integrates to t (>= Time()); Step(dt) to Time() + dt.
  StepResult AdvanceTo(double t);
  StepResult Step(double dt);
  double Time() const { return t_; }
  const std::vector<double>& State() const { return y_; }  // y at Time()

  // The signals (options.signals) at Time(), with the inputs as they are now.
  const std::vector<std::string>& OutputNames() const { return output_names_; }
  bool Outputs(double* values, std::string* error);

  SimulatorState GetState();
  bool SetState(const SimulatorState& state, std::string* error);
  // Back to the start: the initial state and inputs (0 unless given), a fresh solver.
  void Reset();

  // The events since the start (its own first), in time order, with their jumps (as a run's
  // SimStats::events); SetState keeps those up to its time. A terminate: its message.
  const std::vector<EventRecord>& Events() const { return events_; }
  bool Terminated(std::string* why) const;
  std::vector<double> Modes() const;  // HybridOde::Modes now (GetState without its restart)

  rt::Integrator Method() const;  // the one running: CVODE-BDF after a stiff hand-over
  IntegratorStats Stats() const;  // summed over the solvers since the last Reset

 private:
  struct Impl;
  explicit Simulator(std::unique_ptr<Impl> impl);
  void Restart(double next_step, const std::vector<double>& modes);
  StepResult Fail(double t, std::string cause);

  std::unique_ptr<Impl> impl_;
  std::vector<std::string> input_names_, output_names_;
  double t_ = 0.0;
  std::vector<double> y_;
  std::vector<EventRecord> events_;
};

}  // namespace kanesim::sim
