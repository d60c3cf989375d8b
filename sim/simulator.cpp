#include "sim/simulator.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "sim/hybrid_ode.h"
#include "sim/input_table.h"
#include "sim/simulate.h"
#include "sim/stepper.h"

namespace kanesim::sim {

using WorkspacePtr = std::unique_ptr<rt::Workspace, void (*)(rt::Workspace*)>;

struct Simulator::Impl {
  Impl(std::shared_ptr<const rt::Program> p, int n_inputs)
      : program(std::move(p)), inputs(n_inputs), ws_out(nullptr, nullptr) {}
  std::shared_ptr<const rt::Program> program;
  IntegratorOptions iopt;                   // the solver's options (initial_step: next_step; CVODE-BDF
                                            // after a stiff hand-over)
  IntegratorOptions iopt_start;             // ... as made: Reset goes back to them
  std::shared_ptr<const rt::SignalPlan> plan;  // the outputs
  double rtol = 0.0, atol = 0.0;            // the events' (HybridOde)
  double t0 = 0.0;
  std::vector<double> y0;                   // the start (after its events: a start on a contact)
  std::vector<double> inputs0;              // ... its inputs
  std::vector<double> modes0;               // ... and its modes
  std::vector<EventRecord> events0;         // ... and events
  ConstantInputs inputs;                    // what the outputs' workspace reads
  WorkspacePtr ws_out;
  std::vector<double> y_out;                // an output row's state (scratch)
  std::unique_ptr<HybridOde> hybrid;        // the right-hand side and every event (the run's)
  std::unique_ptr<detail::GuardedRhs> rhs;
  std::unique_ptr<detail::Stepper> stepper;  // null until the next step (a restart)
  double next_step = 0.0;                    // the restarted solver's first step (0: its estimate)
  bool inputs_changed = false;               // since the stepper's last step
  bool failed = false;
  StepResult failure;
  bool terminated = false;                   // a terminate fired (its message)
  std::string terminate_message;
  IntegratorStats done;                      // of the solvers before this one

  // The solver that ends (a restart, an event): its counters into done, its last step and
  // order kept there for Stats() until the next one steps.
  void Retire() {
    const IntegratorStats s = stepper->Stats();
    detail::AddStats(&done, s);
    done.last_step = s.last_step;
    done.last_order = s.last_order;
    stepper.reset();
  }
  StepResult Refusal(double t_now) const {
    if (failed)
      return {false, failure.fail_time,
              "the simulator failed at t = " + FormatShortest(failure.fail_time) + " (" + failure.cause +
                  "); reset() or set_state() first"};
    return {false, t_now,
            "the model terminated at t = " + FormatShortest(t_now) + " (" + terminate_message +
                "); reset() or set_state() first"};
  }
};

std::unique_ptr<Simulator> Simulator::Make(std::shared_ptr<const rt::Program> program, const SimulatorOptions& options,
                                           std::string* error) {
  const rt::Program& p = *program;
  for (auto [name, tol] : {std::pair{"rtol", options.rtol}, {"atol", options.atol}})
    if (!(tol > 0.0) || !std::isfinite(tol)) {
      *error = std::string("the tolerance ") + name + " (" + FormatShortest(tol) + ") must be a positive finite number";
      return nullptr;
    }
  auto impl = std::make_unique<Impl>(program, rt::NumInputs(p));
  IntegratorOptions& io = impl->iopt;
  ResolveMethod(p, options.integrator, &io);
  io.run_end = INFINITY;  // the caller's end is unknown: a stiff DOP853 hands over whenever found
  io.rtol = options.rtol;
  io.atol = options.atol;
  io.max_steps = options.max_steps;
  io.ida_linear_solver = options.ida_linear_solver;
  io.project_steps = options.project_steps;
  io.bridge = false;            // no bridges while stepping (sim/simulator.h)
  io.row_energy_check = false;  // no rows
  impl->iopt_start = io;
  impl->rtol = options.rtol;
  impl->atol = options.atol;

  std::vector<std::string> names = options.signals.empty() ? rt::DefaultSignals(p) : options.signals;
  std::string plan_error;
  impl->plan = rt::PlanSignals(p, names, &plan_error);
  if (!impl->plan) {
    *error = plan_error.empty() ? "cannot compute the requested outputs" : plan_error;
    return nullptr;
  }
  impl->t0 = std::isnan(options.start_time) ? rt::StartTime(p) : options.start_time;
  if (!std::isfinite(impl->t0)) {
    *error = "the start time (" + FormatShortest(impl->t0) + ") is not a finite number";
    return nullptr;
  }
  const size_t n = static_cast<size_t>(rt::StateSize(p));
  impl->y0.assign(n, 0.0);
  if (options.initial_state.empty()) {
    rt::InitialState(p, impl->y0.data());
  } else if (options.initial_state.size() == n) {
    impl->y0 = options.initial_state;
  } else {
    *error = "the initial state has " + std::to_string(options.initial_state.size()) + " entries, not " + std::to_string(n);
    return nullptr;
  }
  impl->inputs0.assign(impl->inputs.values.size(), 0.0);
  if (options.initial_inputs.size() == impl->inputs0.size()) impl->inputs0 = options.initial_inputs;
  // The start's events (a start on a contact, friction stuck or sliding), as a run starts.
  HybridOde start(program, options.rtol, options.atol);
  start.SetInputs(impl->inputs0);
  if (std::string why = start.Start(impl->t0, impl->y0.data()); !why.empty()) {
    *error = why;
    return nullptr;
  }
  impl->modes0 = start.Modes();
  impl->events0 = start.StartEvents();
  std::unique_ptr<Simulator> s(new Simulator(std::move(impl)));
  s->output_names_ = std::move(names);
  for (int i = 0; i < rt::NumInputs(p); ++i) s->input_names_.push_back(rt::InputName(p, i));
  s->Reset();
  return s;
}

Simulator::Simulator(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Simulator::~Simulator() = default;

int Simulator::InputIndex(const std::string& name) const {
  for (size_t i = 0; i < input_names_.size(); ++i)
    if (input_names_[i] == name) return static_cast<int>(i);
  return -1;
}

bool Simulator::SetInput(int i, double value, std::string* error) {
  if (i < 0 || static_cast<size_t>(i) >= input_names_.size()) {
    *error = "no input number " + std::to_string(i);
    return false;
  }
  if (!std::isfinite(value)) {
    *error = "input '" + input_names_[static_cast<size_t>(i)] + "': " + FormatShortest(value) + " is not a finite number";
    return false;
  }
  double& v = impl_->inputs.values[static_cast<size_t>(i)];
  if (v != value) impl_->inputs_changed = true;
  v = value;
  return true;
}

const std::vector<double>& Simulator::Inputs() const { return impl_->inputs.values; }

// Fresh workspaces, system and solver state from (t_, y_) in these modes: what GetState and
// SetState share, so that their continuations are the same bit for bit.
void Simulator::Restart(double next_step, const std::vector<double>& modes) {
  Impl& m = *impl_;
  if (m.stepper) m.Retire();
  m.rhs.reset();
  m.ws_out = rt::MakeWorkspace(*m.program);
  rt::SetInputSource(*m.ws_out, &m.inputs);
  m.hybrid = std::make_unique<HybridOde>(m.program, m.rtol, m.atol);
  m.hybrid->SetInputs(m.inputs.values);
  m.hybrid->SetModes(modes);  // checked by SetState, made by HybridOde
  m.rhs = std::make_unique<detail::GuardedRhs>(m.hybrid->System());
  m.next_step = next_step;
  m.inputs_changed = false;
}

StepResult Simulator::Fail(double t, std::string cause) {
  impl_->failed = true;
  impl_->failure = {false, t, std::move(cause)};
  return impl_->failure;
}

StepResult Simulator::Step(double dt) {
  if (!(dt >= 0.0) || !std::isfinite(dt))
    return {false, t_, "the step (" + FormatShortest(dt) + ") must be a finite number >= 0"};
  return AdvanceTo(t_ + dt);
}

StepResult Simulator::AdvanceTo(double t) {
  Impl& m = *impl_;
  if (m.failed || m.terminated) return m.Refusal(t_);
  if (!(t >= t_) || !std::isfinite(t))
    return {false, t_, "cannot advance to t = " + FormatShortest(t) + ": the simulator is at t = " + FormatShortest(t_) +
                           " and does not step backwards"};
  if (t == t_) return {};
  if (y_.empty()) {  // nothing to integrate (0 degrees of freedom)
    t_ = t;
    return {};
  }
  std::string error;
  if (m.inputs_changed) m.hybrid->SetInputs(m.inputs.values);
  if (!m.stepper) {
    IntegratorOptions io = m.iopt;
    io.initial_step = m.next_step > 0.0 ? std::min(m.next_step, t - t_) : 0.0;
    m.rhs->Reset();
    m.stepper = detail::MakeStepper(*m.rhs, t_, y_.data(), t, io, &error);
    if (!m.stepper) return Fail(m.rhs->failed ? m.rhs->fail_time : t_, m.rhs->failed ? m.rhs->cause : error);
  } else {
    if (m.inputs_changed && m.stepper->InputsChanged() != 0)
      return Fail(t_, m.rhs->failed ? m.rhs->cause : "the solver could not take the new inputs");
    m.stepper->SetStopTime(t);
  }
  m.inputs_changed = false;
  for (;;) {
    m.rhs->ClearFailure();
    const int flag = m.stepper->Advance(t, y_.data());
    if (flag == detail::kStiffReached) {  // as in a run: CVODE-BDF from DOP853's last accepted step
      t_ = m.stepper->event_time;
      m.stepper = detail::HandOverStiff(*m.rhs, *m.stepper, y_.data(), t, &m.iopt, &m.done, &error);
      if (!m.stepper) return Fail(m.rhs->failed ? m.rhs->fail_time : t_, m.rhs->failed ? m.rhs->cause : error);
      continue;
    }
    if (flag == detail::kEventReached) {  // the run's jump, then a fresh solver from the right limit
      const double te = m.stepper->event_time;
      const size_t logged = m.hybrid->Events().size();
      const std::vector<double> left = y_;  // the left limit (StateJumped)
      if (m.hybrid->System().Event(te, y_.data(), m.stepper->event_index) != 0)
        return Fail(te, m.hybrid->FailureCause());
      events_.insert(events_.end(), m.hybrid->Events().begin() + static_cast<long>(logged), m.hybrid->Events().end());
      m.Retire();
      t_ = te;
      m.next_step = 0.0;  // a fresh solver after the jump estimates its own first step
      if (m.hybrid->Terminated(&m.terminate_message)) {
        m.terminated = true;
        StepResult r;
        r.terminated = true;
        r.cause = m.terminate_message;
        return r;
      }
      if (te >= t) return {};
      m.rhs->Reset();
      IntegratorOptions io = m.iopt;  // (an event at t itself: the next call's solver starts as any restart,
      io.after_event = true;          // so that GetState and SetState continue it bit for bit)
      io.after_jump = StateJumped(left.data(), y_.data(), y_.size(), io.rtol, io.atol);
      m.stepper = detail::MakeStepper(*m.rhs, te, y_.data(), t, io, &error);
      if (!m.stepper) return Fail(m.rhs->failed ? m.rhs->fail_time : te, m.rhs->failed ? m.rhs->cause : error);
      continue;
    }
    if (flag < 0) {
      const detail::StepFailure why = m.stepper->Explain(flag);
      if (m.rhs->fatal || (why.from_rhs && m.rhs->failed)) return Fail(m.rhs->fail_time, m.rhs->cause);
      std::string text = why.cause;
      if (m.rhs->failed) text += " (the right-hand side last failed with: " + m.rhs->cause + ")";
      return Fail(m.stepper->CurrentTime(), text);
    }
    t_ = t;
    return {};
  }
}

bool Simulator::Outputs(double* values, std::string* error) {
  Impl& m = *impl_;
  m.y_out = y_;
  if (std::string why = m.hybrid->ForOutputs(*m.ws_out, t_, m.y_out.data()); !why.empty()) {  // as the run's rows
    *error = why;
    return false;
  }
  if (rt::EvalSignals(*m.program, *m.plan, *m.ws_out, t_, m.y_out.data(), values) != 0) {
    *error = rt::ErrorMessage(*m.ws_out);
    if (error->empty()) *error = "an output signal could not be evaluated";
    return false;
  }
  return true;
}

SimulatorState Simulator::GetState() {
  Impl& m = *impl_;
  SimulatorState s;
  s.t = t_;
  s.y = y_;
  s.inputs = m.inputs.values;
  s.next_step = m.stepper ? m.stepper->NextStep() : m.next_step;
  s.modes = m.hybrid->Modes();
  s.terminated = m.terminated;
  s.terminate_message = m.terminate_message;
  if (!m.failed) Restart(s.next_step, s.modes);
  return s;
}

bool Simulator::SetState(const SimulatorState& s, std::string* error) {
  Impl& m = *impl_;
  if (s.y.size() != y_.size() || s.inputs.size() != m.inputs.values.size()) {
    *error = "the state is not one of this model's (its sizes differ)";
    return false;
  }
  if (!std::isfinite(s.t) || !(s.next_step >= 0.0)) {
    *error = "the state's time or step is not a finite number";
    return false;
  }
  for (double v : s.y)
    if (!std::isfinite(v)) {
      *error = "the state holds a number that is not finite";
      return false;
    }
  for (double v : s.inputs)
    if (!std::isfinite(v)) {
      *error = "the state holds an input that is not finite";
      return false;
    }
  if (!m.hybrid->SetModes(s.modes)) {  // checked before anything is set; Restart makes it anew
    *error = "the state's modes are not this model's (resting stops, stuck joints)";
    return false;
  }
  t_ = s.t;
  y_ = s.y;
  m.inputs.values = s.inputs;
  m.failed = false;
  m.terminated = s.terminated;
  m.terminate_message = s.terminate_message;
  while (!events_.empty() && events_.back().time > s.t) events_.pop_back();  // the log up to its time
  Restart(s.next_step, s.modes);
  return true;
}

void Simulator::Reset() {
  Impl& m = *impl_;
  t_ = m.t0;
  y_ = m.y0;
  m.inputs.values = m.inputs0;
  m.failed = false;
  m.terminated = false;
  m.terminate_message.clear();
  events_ = m.events0;
  m.stepper.reset();
  m.iopt = m.iopt_start;  // DOP853 again after a hand-over
  Restart(0.0, m.modes0);
  m.done = IntegratorStats{};
}

std::vector<double> Simulator::Modes() const { return impl_->hybrid->Modes(); }

bool Simulator::Terminated(std::string* why) const {
  if (impl_->terminated) *why = impl_->terminate_message;
  return impl_->terminated;
}

rt::Integrator Simulator::Method() const { return impl_->iopt.method; }

IntegratorStats Simulator::Stats() const {
  if (!impl_->stepper) return impl_->done;
  IntegratorStats s = impl_->stepper->Stats();
  detail::AddStats(&s, impl_->done);
  return s;
}

}  // namespace kanesim::sim
