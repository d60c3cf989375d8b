#include "sim/simulate.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "sim/change_point_bridge.h"
#include "sim/end_stops.h"
#include "sim/lift_off.h"
#include "sim/stick_slip.h"
#include "sim/when_events.h"
#include "sim/test_hooks.h"

namespace kanesim::sim {
namespace {

using Clock = std::chrono::steady_clock;

double Seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

// The engine's equations of motion as an ODE: y = [q, u], y' = rt::Derivative.
class EngineOde final : public OdeSystem {
 public:
  EngineOde(const rt::Program& program, rt::Workspace& ws, bool row_energy)
      : program_(program), ws_(ws) {
    bridge_ = MakeChangePointBridge(program);
    // Closed loops on the multiplier form: P maps onto the state manifold, of dimension
    // (nq - nu) + 2 dof (OdeSystem::NewtonRank).
    if (bridge_ && !CanProject()) {
      const rt::ProgramSummary s = rt::Summarize(program);
      newton_rank_ = s.nq - s.nu + 2 * s.dof;
    }
    // Rows checked against the energy: closed loops (where change points are) in a model
    // that conserves T + V.
    if (row_energy && bridge_ && rt::NonConservativeCause(program).empty()) {
      std::string error;
      energy_plan_ = rt::PlanSignals(program, {"kinetic_energy", "potential_energy"}, &error);
    }
  }
  int Size() const override { return rt::StateSize(program_); }
  int Rhs(double t, const double* y, double* ydot) override {
    from_monitor_ = false;
    int s = stick_ ? stick_->Rhs(ws_, t, y, ydot) : rt::Derivative(program_, ws_, t, y, ydot);
    if (stops_ && s == 0) s = stops_->Hold(ws_, t, y, ydot);
    if (fault_ && s == 0) fault_(t, y, ydot);
    return s;
  }
  // Events: the end stops' and plane contacts' (sim/end_stops.h) or the rolling contacts'
  // normal forces (sim/lift_off.h; the compiler never lets both in one model), then the when
  // clauses' (sim/when_events.h); none without any.
  void SetStops(EndStopEvents* stops) { stops_ = stops; }
  void SetLiftOff(LiftOffGuard* lift) { lift_ = lift; }
  // Exact stick-slip friction (sim/stick_slip.h): its laws in the right-hand side, its events.
  void SetStickSlip(StickSlipEvents* stick) { stick_ = stick; }
  void SetWhens(WhenEvents* whens) {
    whens_ = whens;
    state_names_ = rt::StateNames(program_);
  }
  // The first events: stick-slip's, the stops' and plane contacts', or lift-off's (never two
  // in one model); then the when clauses'.
  int NumStops() const {
    return stops_ ? stops_->Count() : lift_ ? lift_->Count() : stick_ ? stick_->Count() : 0;
  }
  int NumEvents() const override { return NumStops() + (whens_ ? whens_->Count() : 0); }
  int EventFunctions(double t, const double* y, double* g) override {
    if (NumStops() > 0) {
      const int s = stick_ ? stick_->Functions(ws_, t, y, g)
                    : stops_ ? stops_->Functions(ws_, t, y, g)
                             : lift_->Functions(t, y, g);
      if (s != 0) return s;
    }
    return whens_ ? whens_->Functions(ws_, t, y, g + NumStops()) : 0;
  }
  int Event(double t, double* y, int i) override {
    if (i < NumStops() && stick_) return stick_->Event(ws_, t, y, i);  // logged by stick_ (Simulate)
    if (i < NumStops() && !stops_) {
      event_cause_ = lift_->Cause(t, y, i);  // a rolling contact would pull: the run stops
      return -1;
    }
    std::vector<double> before(y, y + Size());
    const size_t logged = stops_ ? stops_->Log().size() : 0;
    int s = 0;
    if (i < NumStops()) {
      s = stops_->Event(ws_, t, y, i);
      events_.insert(events_.end(), stops_->Log().begin() + static_cast<long>(logged), stops_->Log().end());
    } else {
      s = whens_->Event(ws_, t, y, i - NumStops(), stops_ ? stops_->RestingSpeeds() : std::vector<int>{});
      events_.push_back(whens_->Last());
    }
    if (s == 0 && !events_.empty() && !state_names_.empty())  // the jump, on the event's first record
      for (size_t k = 0; k < before.size(); ++k)
        if (y[k] != before[k]) events_[events_.size() - 1].changes.push_back({state_names_[k], before[k], y[k]});
    return s;
  }
  bool Terminated(std::string* why) const override {
    if (!whens_ || !whens_->Terminated()) return false;
    *why = whens_->Message();
    return true;
  }
  const std::vector<EventRecord>& Events() const { return events_; }
  void SetFault(std::function<void(double, const double*, double*)> f) { fault_ = std::move(f); }
  bool ChecksSteps() const override { return bridge_ != nullptr; }
  int StepAccepted(double t, const double* y) override {
    const int s = CheckStep(program_, *bridge_, t, y);
    from_monitor_ = s != 0;
    return s;
  }
  std::string FailureCause() const override {
    if (!event_cause_.empty()) return event_cause_;
    if (from_monitor_) return BridgeError(*bridge_);
    const std::string& m = rt::ErrorMessage(ws_);
    return m.empty() ? "the equations of motion could not be evaluated" : m;
  }
  bool Bridge(double rtol, double atol, double* t_from, double* t_b, double* y_b) override {
    return bridge_ && BridgeChangePoint(program_, *bridge_, rtol, atol, t_from, t_b, y_b) == 0;
  }
  void BridgeState(double t, double* y) override { BridgedState(*bridge_, t, y); }
  bool InZone() const override { return hold_rows_ && bridge_ && bridge_->in_zone; }
  void SetHoldRows(bool on) { hold_rows_ = on; }
  void EnableEarlyBridge(double rtol, double atol, const BridgeSwitches& switches) {
    if (bridge_) {
      bridge_->switches = switches;
      sim::EnableEarlyBridge(*bridge_, rtol, atol);
    }
  }
  void PassageCounts(long* checked, long* unchecked) const {
    *checked = bridge_ ? bridge_->passages_checked : 0;
    *unchecked = bridge_ ? bridge_->passages_unchecked : 0;
  }
  bool CanProject() const override { return rt::StepProjectionAvailable(program_); }
  void EnableStepProjection() override { rt::SetStepProjection(ws_, true); }
  void HoldForJacobian(bool on) override { rt::HoldPartition(ws_, on); }
  bool ProjectedStates(std::vector<int>* states, double* diag) override {
    return rt::ProjectedStates(program_, ws_, states, diag);
  }
  int NewtonRank() const override { return newton_rank_; }
  int Project(double t, double* y) override { return rt::ProjectOntoConstraints(program_, ws_, t, y); }
  int ProjectAside(double t, double* y) override {
    // Closed loops on the reduced form only: the multiplier form's projection moves every
    // coordinate, and its state was not seen to drift (docs/constraints.md "A drifted state").
    if (bridge_ == nullptr || !CanProject()) return -1;
    if (!aside_) aside_ = rt::MakeWorkspace(program_);
    return rt::ProjectOntoConstraints(program_, *aside_, t, y);
  }
  bool HasEnergy() const override { return energy_plan_ != nullptr; }
  int Energy(double t, const double* y, double* T, double* V) override {
    if (!energy_ws_) energy_ws_ = rt::MakeWorkspace(program_);
    double v[2];
    const int s = rt::EvalSignals(program_, *energy_plan_, *energy_ws_, t, y, v);
    *T = v[0];
    *V = v[1];
    return s;
  }
  // Closed loops or rolling contacts on the multiplier form (CanProject: the reduced form).
  // Contacts without loops have no branch monitor, and CVODE-BDF's projection
  // (integrator_cvode.cpp ProjectStep) is needed there as much: without it the rolling
  // disk's lean grew from t = 1.8 at rtol 1e-5 (energy off by 6.1e-2) and the disk fell
  // flat at 1e-4.
  int ProjectAsideMultiplierForm(double t, double* y) override {
    if (CanProject()) return -1;
    if (multiplier_rows_ < 0) {
      const rt::ProgramSummary s = rt::Summarize(program_);
      multiplier_rows_ = s.solver == rt::SolverPath::Sparse && s.dof < s.nu ? 1 : 0;
    }
    if (multiplier_rows_ == 0) return -1;
    if (!aside_) aside_ = rt::MakeWorkspace(program_);
    return rt::ProjectOntoConstraints(program_, *aside_, t, y);
  }

 private:
  const rt::Program& program_;
  rt::Workspace& ws_;
  std::unique_ptr<ChangePointBridge> bridge_;  // closed loops: the branch monitor and the bridge
  EndStopEvents* stops_ = nullptr;             // end stops and plane contacts (null: none)
  LiftOffGuard* lift_ = nullptr;               // rolling contacts' normal forces (null: none)
  StickSlipEvents* stick_ = nullptr;           // exact stick-slip friction (null: none)
  std::string event_cause_;                    // why an event stopped the run ("" : none did)
  WhenEvents* whens_ = nullptr;                // when clauses (null: none)
  std::vector<std::string> state_names_;       // y's entries (rt::StateNames), for the events' changes
  std::vector<EventRecord> events_;            // every event, in time order
  bool from_monitor_ = false;  // the last failure was the bridge's or the branch monitor's
  int newton_rank_ = -1;       // OdeSystem::NewtonRank
  int multiplier_rows_ = -1;   // the multiplier form with constraint rows: 1, 0; -1 not known yet
  bool hold_rows_ = true;      // TestHooks::hold_zone_rows
  std::function<void(double, const double*, double*)> fault_;  // TestHooks::rhs_fault
  std::unique_ptr<rt::Workspace, void (*)(rt::Workspace*)> aside_{nullptr, [](rt::Workspace*) {}};  // ProjectAside's
  std::shared_ptr<const rt::SignalPlan> energy_plan_;  // T and V (null: rows not checked)
  std::unique_ptr<rt::Workspace, void (*)(rt::Workspace*)> energy_ws_{nullptr, [](rt::Workspace*) {}};  // Energy's
};

// An output row whose projection moved the integrator's speeds by more than this many units
// of the tolerance (rt::SpeedMove) is not trusted near a change point. Measured: 925 on the
// row of the chain of 40 (CVODE, rtol 1e-6) that the partition's projection spoilt (its
// rods' speeds 1e-2 apart), 3e6 on one of DOP853's rows of the chain of ten at 1e-12; at
// most ~4 on the other rows of the first run.
constexpr double kRowTrust = 100.0;
// ... and replaced only by a projection that moved them this many times less. Measured:
// on that row 925 against 3.5e-5 (the integrator's speeds were right); ARKODE on the
// single parallelogram (a = 0.5, rtol 1e-4) at t = 5.04, 2e-3 rad from a crossing: the
// integrator's dependent speeds drifted by 0.2 rad/s, both projections move them alike,
// and the kinetic metric's spreads the correction onto the crank (0.2 rad/s off the
// motion) where the partition's keeps the crank's integrated speed: 440 against 279.
constexpr double kRowGain = 10.0;

SimResult UsageError(std::string message) {
  SimResult r;
  r.status = SimResult::Status::kUsageError;
  r.message = std::move(message);
  return r;
}

}  // namespace

std::string CheckRun(const OutputGrid& grid, double rtol, double atol) {
  if (std::string why = grid.Check(); !why.empty()) return why;
  for (auto [name, tol] : {std::pair{"rtol", rtol}, {"atol", atol}})
    if (!(tol > 0.0) || !std::isfinite(tol))
      return std::string("the tolerance ") + name + " (" + FormatShortest(tol) + ") must be a positive finite number";
  return "";
}

std::string ToleranceWarning(double rtol) {
  if (rtol > kMaxSensibleRtol)
    return "rtol = " + FormatShortest(rtol) + " allows errors larger than " + FormatShortest(100 * kMaxSensibleRtol) +
           "% of the solution (rtol is relative: 1e-6 asks for about six digits)";
  if (rtol > 0.0 && rtol < kMinSensibleRtol)
    return "rtol = " + FormatShortest(rtol) + " is below what double precision delivers (" +
           FormatShortest(kMinSensibleRtol) + "); the integrator may fail with too much work";
  return "";
}

OutputGrid ResolveGrid(const rt::Program& program, const SimOptions& options) {
  OutputGrid grid;
  grid.start = std::isnan(options.start_time) ? rt::StartTime(program) : options.start_time;
  grid.stop = options.stop_time;
  grid.interval = options.interval > 0.0 ? options.interval : (grid.stop - grid.start) / kDefaultIntervals;
  return grid;
}

SimResult Simulate(const rt::Program& program, const SimOptions& options, SignalSink& sink) {
  return Simulate(program, options, sink, TestHooks{});
}

SimResult Simulate(const rt::Program& program, const SimOptions& options, SignalSink& sink, const TestHooks& hooks) {
  // 1. Times, tolerances, integrator.
  const OutputGrid grid = ResolveGrid(program, options);
  if (std::string why = CheckRun(grid, options.rtol, options.atol); !why.empty()) return UsageError(why);
  IntegratorOptions iopt;
  iopt.method = options.integrator;
  if (iopt.method == rt::Integrator::Auto) iopt.method = rt::Summarize(program).integrator;
  iopt.rtol = options.rtol;
  iopt.atol = options.atol;
  iopt.max_steps = options.max_steps;
  iopt.ida_linear_solver = options.ida_linear_solver;
  iopt.project_steps = options.project_steps;
  iopt.bridge = hooks.bridge;
  iopt.dense_check = hooks.dense_check;
  iopt.row_energy_check = hooks.row_energy_check;
  if (iopt.method == rt::Integrator::IDA || iopt.method == rt::Integrator::CvodeBdf) iopt.coupling = rt::StateCouplingGroups(program);

  // 2. Signals.
  std::vector<std::string> names = options.signals.empty() ? rt::DefaultSignals(program) : options.signals;
  std::string plan_error;
  std::shared_ptr<const rt::SignalPlan> plan = rt::PlanSignals(program, names, &plan_error);
  if (!plan) return UsageError(plan_error.empty() ? "cannot compute the requested outputs" : plan_error);
  // The energy guard's T and V ride along after the written signals (not written).
  EnergyGuard energy(program, options.energy_check, options.rtol, options.atol);
  const size_t n_written = names.size();
  if (energy.Active()) {
    std::vector<std::string> all = names;
    for (const std::string& e : EnergyGuard::Signals()) all.push_back(e);
    plan = rt::PlanSignals(program, all, &plan_error);
    if (!plan) return UsageError(plan_error.empty() ? "cannot compute the requested outputs" : plan_error);
  }

  // Diagonal speeds: the checks, the order and their columns (written after the signals).
  std::vector<int> speed_order;
  if (options.speeds == Speeds::kDiagonal) {
    if (std::string why = DiagonalSpeedsRefusal(program); !why.empty()) return UsageError(why);
    std::string error;
    speed_order = SpeedOrder(program, options.speed_order, &error);
    if (speed_order.empty()) return UsageError(error);
  }
  const size_t n_diag = 3 * speed_order.size();
  std::vector<std::string> header = names;
  for (const char* prefix : {"w[", "d[", "T_w["})
    for (size_t i = 1; i <= speed_order.size(); ++i) header.push_back(prefix + std::to_string(i) + "]");

  // 3. Integrate. The right-hand side and the outputs use separate workspaces so that
  // evaluating an output never disturbs the solver's state of the engine.
  auto ws_rhs = rt::MakeWorkspace(program);
  auto ws_out = rt::MakeWorkspace(program);
  decltype(rt::MakeWorkspace(program)) ws_zone(nullptr, nullptr);  // made at the first row that needs it
  std::vector<double> y0(static_cast<size_t>(rt::StateSize(program)));
  rt::InitialState(program, y0.data());
  // End stops and plane contacts: events in every integrator (sim/end_stops.h); a start on
  // a closed contact is its first event.
  EndStopEvents stops(program, options.rtol, options.atol);
  if (stops.Active()) {
    const double t0 = grid.start;
    if (std::string why = stops.CheckStart(*ws_rhs, t0, y0.data()); !why.empty()) return UsageError(why);
    if (stops.Start(*ws_rhs, t0, y0.data()) != 0) return UsageError("contacts at the start: " + rt::ErrorMessage(*ws_rhs));
  }
  // Rolling contacts: a normal force turning tensile stops the run (sim/lift_off.h).
  LiftOffGuard lift(program);
  if (lift.Active()) {
    if (std::string why = lift.Cause(grid.start, y0.data(), -1); !why.empty()) {
      SimResult r;
      r.status = SimResult::Status::kNumericalFailure;
      r.fail_time = grid.start;
      r.message = why;
      return r;
    }
  }
  // Exact stick-slip friction: the start decides sliding or stuck (sim/stick_slip.h).
  StickSlipEvents stick(program);
  if (stick.Active() && stick.Start(*ws_rhs, grid.start, y0.data()) != 0)
    return UsageError("friction at the start: " + rt::ErrorMessage(*ws_rhs));
  std::vector<double> values(n_written + (energy.Active() ? EnergyGuard::Signals().size() : 0)), zone_values(values.size());
  const bool multiplier_form = rt::Summarize(program).solver == rt::SolverPath::Sparse;

  SimResult result;
  result.stats.method = iopt.method;
  if (!sink.Begin(header)) {
    result.status = SimResult::Status::kOutputError;
    result.message = "cannot write the output";
    return result;
  }
  bool sink_failed = false;
  Clock::duration output_time{};
  std::unique_ptr<DiagonalOde> diagonal;  // --speeds diagonal: the integrator's state is [q; w]
  std::vector<double> y_row(y0.size()), row_values(n_written + n_diag);
  RowCallback row = [&](double t, const double* y_in, std::string* cause) -> int {
    Clock::time_point t0 = Clock::now();
    if (stick.Active()) stick.Sync(*ws_out);  // the outputs see the friction laws of the run
    const double* y = y_in;
    int status = 0;
    bool converted = true;  // z = [q; w] -> y = [q; u] (diagonal speeds)
    if (diagonal) {
      status = diagonal->ToSpeeds(t, y_in, y_row.data());
      converted = status == 0;
      y = y_row.data();
    }
    if (status == 0) status = rt::EvalSignals(program, *plan, *ws_out, t, y, values.data());
    // A row near a change point whose projection moved the speeds too far: projected in the
    // kinetic metric instead, in a workspace of its own (docs/constraints.md "Rows near a
    // change point"); ws_out has gone through the row as before, so the rows after it are
    // unchanged. (A row the projection failed on, at the singular configuration itself,
    // still stops the run.)
    double move = 0.0;
    if (hooks.zone_rows && status == 0 && (move = rt::SpeedMove(program, *ws_out, y, options.rtol, options.atol)) > kRowTrust) {
      if (!ws_zone) ws_zone = rt::MakeWorkspace(program);
      // On the reduced form taken only where it moved the speeds far less: where the
      // integrator's own speeds are off the constraints (ARKODE's drift at loose
      // tolerances), the partition's projection, which keeps the independent speeds the
      // integrator integrates, stays. The multiplier form's projection is already the
      // kinetic metric's, without the truncation.
      if (rt::RowNearChangePoint(program, *ws_zone, t, y) &&
          rt::EvalSignalsNearChangePoint(program, *plan, *ws_zone, t, y, zone_values.data()) == 0 &&
          (multiplier_form || rt::SpeedMove(program, *ws_zone, y, options.rtol, options.atol) * kRowGain < move)) {
        values.swap(zone_values);
      }
    }
    std::string past_stop;
    if (!converted) {
      *cause = diagonal->FailureCause();
    } else if (status != 0) {
      const std::string& m = rt::ErrorMessage(*ws_out);
      *cause = m.empty() ? "an output signal could not be evaluated" : m;
    } else if (stops.Active() && !(past_stop = stops.CheckRow(*ws_out, t, y)).empty()) {
      *cause = past_stop;
      status = -1;  // the row is not written: the rows before it are on disk
    } else if (energy.Active() && energy.Row(t, values[n_written], values[n_written + 1], cause) != 0) {
      status = -1;  // the row is not written: the rows before it are on disk
    } else if (diagonal) {
      std::copy(values.begin(), values.begin() + static_cast<long>(n_written), row_values.begin());
      diagonal->Columns(y_in, row_values.data() + n_written);
      if (!sink.Row(t, row_values.data(), n_written + n_diag)) {
        sink_failed = true;
        *cause = "cannot write the output";
        status = -1;
      }
    } else if (!sink.Row(t, values.data(), n_written)) {
      sink_failed = true;
      *cause = "cannot write the output";
      status = -1;
    }
    if (status == 0 && options.progress) options.progress(t);
    output_time += Clock::now() - t0;
    return status;
  };
  EngineOde ode(program, *ws_rhs, hooks.row_energy_check);
  if (stops.Active()) ode.SetStops(&stops);
  if (lift.Active()) ode.SetLiftOff(&lift);
  if (stick.Active()) ode.SetStickSlip(&stick);
  WhenEvents whens(program);
  if (whens.Active()) ode.SetWhens(&whens);
  if (hooks.rhs_fault) ode.SetFault(hooks.rhs_fault);
  ode.SetHoldRows(hooks.hold_zone_rows);
  if (iopt.bridge) ode.EnableEarlyBridge(iopt.rtol, iopt.atol, hooks.bridge_switches);
  const size_t logged_at_start = stops.Log().size();  // a start on a contact (EndStopEvents::Start)
  OdeSystem* system = &ode;
  if (!speed_order.empty()) {
    if (whens.Active()) return UsageError("--speeds diagonal does not handle when clauses yet (docs/events.md)");
    diagonal = std::make_unique<DiagonalOde>(program, ode, speed_order);
    std::vector<double> z0(y0.size());
    if (diagonal->ToW(grid.start, y0.data(), z0.data()) != 0) return UsageError("--speeds diagonal: " + diagonal->FailureCause());
    y0.swap(z0);
    system = diagonal.get();
  }
  Clock::time_point start = Clock::now();
  IntegrateResult ir = Integrate(*system, y0.data(), grid, iopt, row);
  Clock::duration total = Clock::now() - start;
  bool end_ok = sink.End();

  result.stats.integrator = ir.stats;
  result.stats.rows = ir.rows;
  result.stats.bridges = ir.bridges;
  result.stats.events.assign(stops.Log().begin(), stops.Log().begin() + static_cast<long>(logged_at_start));
  result.stats.events.insert(result.stats.events.end(), ode.Events().begin(), ode.Events().end());
  result.stats.events.insert(result.stats.events.end(), stick.Log().begin(), stick.Log().end());
  result.stats.terminated = ir.terminated;
  result.stats.terminate_time = ir.terminate_time;
  result.stats.terminate_message = ir.terminate_message;
  ode.PassageCounts(&result.stats.passages_checked, &result.stats.passages_unchecked);
  result.stats.energy_guard = energy.Description();
  result.stats.energy_error = energy.WorstError();
  result.stats.energy_tolerance = energy.Tolerance();
  result.stats.times.output = Seconds(output_time);
  result.stats.times.integrate = Seconds(total - output_time);
  if (sink_failed || (ir.ok && !end_ok)) {
    result.status = SimResult::Status::kOutputError;
    result.message = "cannot write the output";
  } else if (!ir.ok) {
    result.status = SimResult::Status::kNumericalFailure;
    result.fail_time = ir.fail_time;
    result.message = ir.cause;
  }
  return result;
}

std::string FormatStats(const SimStats& s) {
  const IntegratorStats& i = s.integrator;
  const PhaseTimes& t = s.times;
  char nnz[64] = "";
  if (i.jac_nonzeros > 0) std::snprintf(nnz, sizeof nnz, ", %ld structural non-zeros", i.jac_nonzeros);
  char buf[1536];
  std::snprintf(buf, sizeof buf,
                "integrator                 %s\n"
                "  method                   %s\n"
                "  steps                    %ld (last step %.3g, last order %d)\n"
                "  right-hand sides         %ld (+ %ld for difference-quotient Jacobians)\n"
                "  Jacobian evaluations     %ld\n"
                "  linear setups            %ld (%s%s)\n"
                "  error-test failures      %ld\n"
                "  nonlinear iterations     %ld (%ld convergence failures)\n"
                "  output rows              %ld\n"
                "wall time (s)\n"
                "  load + elaborate         %.6f\n"
                "  compile                  %.6f\n"
                "  integrate                %.6f\n"
                "  output                   %.6f\n"
                "  total                    %.6f\n",
                MethodName(s.method), MethodDescription(s.method), i.steps, i.last_step, i.last_order, i.rhs_evals,
                i.rhs_evals_jac, i.jac_evals, i.lin_setups, i.linear_solver, nnz, i.err_test_fails, i.nonlin_iters, i.nonlin_conv_fails,
                s.rows, t.load, t.compile, t.integrate, t.output, t.load + t.compile + t.integrate + t.output);
  std::string out = buf;
  if (i.lin_iters > 0) {  // matrix-free Newton (sim/newton_krylov.h)
    std::snprintf(buf, sizeof buf, "  Krylov iterations        %ld (%ld convergence failures)\n", i.lin_iters,
                  i.lin_conv_fails);
    out.insert(out.find("wall time (s)"), buf);
  }
  if (i.dense_rejects > 0) {  // DOP853 (sim/integrator_dop853.cpp kDenseLimit; only where there were any)
    std::snprintf(buf, sizeof buf, "  dense output rejected    %ld (steps taken again onto an output instant)\n",
                  i.dense_rejects);
    out.insert(out.find("wall time (s)"), buf);
  }
  if (i.energy_rejects > 0) {  // docs/constraints.md "Rows checked against the energy"
    if (i.energy_reject_rhs > 0)
      std::snprintf(buf, sizeof buf,
                    "  rows' energy off         %ld (interpolated output instants integrated again, by DOP853: "
                    "%ld right-hand sides)\n",
                    i.energy_rejects, i.energy_reject_rhs);
    else
      std::snprintf(buf, sizeof buf, "  rows' energy off         %ld (interpolated output instants integrated again)\n",
                    i.energy_rejects);
    out.insert(out.find("wall time (s)"), buf);
  }
  if (s.bridges + s.passages_checked + s.passages_unchecked > 0) {
    // Closed loops through change points (only where there were any).
    std::snprintf(buf, sizeof buf,
                  "change points\n"
                  "  bridged                  %ld\n"
                  "  passed, checked          %ld\n"
                  "  passed, not checked      %ld\n",
                  s.bridges, s.passages_checked, s.passages_unchecked);
    out += buf;
  }
  if (!s.energy_guard.empty()) {
    out += "energy guard               " + s.energy_guard + "\n";
    if (s.energy_guard == "on" || s.energy_guard == "report") {
      std::snprintf(buf, sizeof buf, "  largest relative error   %.3g (of the motion's energy; bound %.3g)\n", s.energy_error,
                    s.energy_tolerance);
      out += buf;
    }
  }
  if (!s.events.empty()) {  // end stops and when clauses (only where there were events): time, element, kind
    std::snprintf(buf, sizeof buf, "events                     %zu\n", s.events.size());
    out += buf;
    for (const EventRecord& e : s.events) {
      std::snprintf(buf, sizeof buf, "  t = %-22.17g %s: %s\n", e.time, e.element.c_str(), e.kind.c_str());
      out += buf;
    }
  }
  if (s.terminated) out += "terminated                 at t = " + FormatShortest(s.terminate_time) + ": " + s.terminate_message + "\n";
  return out;
}

namespace {
// A CSV field: quoted when it holds a comma, a quote or a line break.
std::string CsvField(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}
}  // namespace

std::string FormatEventsCsv(const std::vector<EventRecord>& events) {
  std::string out = "time,element,kind,signal,before,after\n";
  for (const EventRecord& e : events) {
    const std::string head = FormatShortest(e.time) + "," + CsvField(e.element) + "," + CsvField(e.kind) + ",";
    if (e.changes.empty()) out += head + ",,\n";
    for (const EventChange& c : e.changes)
      out += head + CsvField(c.name) + "," + FormatShortest(c.before) + "," + FormatShortest(c.after) + "\n";
  }
  return out;
}

}  // namespace kanesim::sim
