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
#include "sim/held_outputs.h"
#include "sim/when_events.h"
#include "sim/engine_ode.h"
#include "runtime/program/program.h"  // Program::nq, rows
#include "sim/lift_off.h"
#include "sim/stick_slip.h"
#include "sim/test_hooks.h"

namespace kanesim::sim {
namespace {
// A joint sliding one way (exact friction, its law +1 or -1) whose speed is the other way
// beyond the tolerance's reach: its reversal's crossing was missed, and its friction now
// pushes along its motion (energy from nowhere). The row is refused (exit 2).
std::string SlidingAgainstItsLaw(const StickSlipEvents& stick, const rt::Program& program, double t, const double* y,
                                 const SimOptions& options) {
  for (int i = 0; i < stick.Count(); ++i) {
    const int mode = stick.ModeOf(i);
    if (mode == 0 || !stick.Watched(i)) continue;
    const double u = y[program.nq + stick.SpeedOf(i)];
    if (mode * u < -1e3 * (options.atol + options.rtol)) {
      char buf[300];
      std::snprintf(buf, sizeof buf,
                    "a joint sliding %s (exact friction, speed %d) moves the other way at %.3g at time %.9g: its "
                    "reversal was missed",
                    mode > 0 ? "forwards" : "backwards", stick.SpeedOf(i), u, t);
      return buf;
    }
  }
  return "";
}

using detail::EngineOde;
using Clock = std::chrono::steady_clock;

double Seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

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

}  // namespace

SimResult UsageResult(std::string message) {
  SimResult r;
  r.status = SimResult::Status::kUsageError;
  r.message = std::move(message);
  return r;
}

void FinishRun(const IntegrateResult& ir, bool sink_failed, bool end_ok, double integrate_seconds,
               double output_seconds, SimResult* result) {
  result->stats.integrator = ir.stats;
  result->stats.rows = ir.rows;
  result->stats.bridges = ir.bridges;
  result->stats.times.output = output_seconds;
  result->stats.times.integrate = integrate_seconds;
  if (sink_failed || (ir.ok && !end_ok)) {
    result->status = SimResult::Status::kOutputError;
    result->message = "cannot write the output";
  } else if (!ir.ok) {
    result->status = SimResult::Status::kNumericalFailure;
    result->fail_time = ir.fail_time;
    result->message = ir.cause;
  }
}

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

void ResolveMethod(const rt::Program& program, rt::Integrator requested, IntegratorOptions* io) {
  io->method = requested;
  if (requested == rt::Integrator::Auto) {
    io->method = rt::Summarize(program).integrator;
    io->switch_when_stiff = io->method == rt::Integrator::Dop853;
  }
  if (io->method == rt::Integrator::IDA || io->method == rt::Integrator::CvodeBdf || io->switch_when_stiff)
    io->coupling = rt::StateCouplingGroups(program);
}

SimResult Simulate(const rt::Program& program, const SimOptions& options, SignalSink& sink) {
  return Simulate(program, options, sink, TestHooks{});
}

SimResult Simulate(const rt::Program& program, const SimOptions& options, SignalSink& sink, const TestHooks& hooks) {
  // 1. Times, tolerances, integrator.
  const OutputGrid grid = ResolveGrid(program, options);
  if (std::string why = CheckRun(grid, options.rtol, options.atol); !why.empty()) return UsageResult(why);
  IntegratorOptions iopt;
  ResolveMethod(program, options.integrator, &iopt);
  iopt.rtol = options.rtol;
  iopt.atol = options.atol;
  iopt.max_steps = options.max_steps;
  iopt.ida_linear_solver = options.ida_linear_solver;
  iopt.project_steps = options.project_steps;
  iopt.bridge = hooks.bridge;
  iopt.dense_check = hooks.dense_check;
  iopt.row_energy_check = hooks.row_energy_check;

  // 2. Signals.
  std::vector<std::string> names = options.signals.empty() ? rt::DefaultSignals(program) : options.signals;
  std::string plan_error;
  std::shared_ptr<const rt::SignalPlan> plan = rt::PlanSignals(program, names, &plan_error);
  if (!plan) return UsageResult(plan_error.empty() ? "cannot compute the requested outputs" : plan_error);
  // The energy guard's T and V ride along after the written signals (not written).
  EnergyGuard energy(program, options.energy_check, options.rtol, options.atol);
  const size_t n_written = names.size();
  if (energy.Active()) {
    std::vector<std::string> all = names;
    for (const std::string& e : EnergyGuard::Signals()) all.push_back(e);
    plan = rt::PlanSignals(program, all, &plan_error);
    if (!plan) return UsageResult(plan_error.empty() ? "cannot compute the requested outputs" : plan_error);
  }

  // Diagonal speeds: the checks, the order and their columns (written after the signals).
  std::vector<int> speed_order;
  if (options.speeds == Speeds::kDiagonal) {
    if (std::string why = DiagonalSpeedsRefusal(program); !why.empty()) return UsageResult(why);
    std::string error;
    speed_order = SpeedOrder(program, options.speed_order, &error);
    if (speed_order.empty()) return UsageResult(error);
  }
  const size_t n_w = speed_order.empty() ? 0 : static_cast<size_t>(DiagonalSpeedCount(program));
  const size_t n_diag = 3 * n_w;
  std::vector<std::string> header = names;
  for (const char* prefix : {"w[", "d[", "T_w["})
    for (size_t i = 1; i <= n_w; ++i) header.push_back(prefix + std::to_string(i) + "]");

  // 3. Integrate. The right-hand side and the outputs use separate workspaces so that
  // evaluating an output never disturbs the solver's state of the engine.
  if (rt::NumInputs(program) > 0 && !options.inputs)
    return UsageResult("input '" + rt::InputName(program, 0) + "' has no value (give it with --input-file or --set)");
  auto ws_rhs = rt::MakeWorkspace(program);
  auto ws_out = rt::MakeWorkspace(program);
  rt::SetInputSource(*ws_rhs, options.inputs);
  rt::SetInputSource(*ws_out, options.inputs);
  decltype(rt::MakeWorkspace(program)) ws_zone(nullptr, nullptr);  // made at the first row that needs it
  std::vector<double> y0(static_cast<size_t>(rt::StateSize(program)));
  rt::InitialState(program, y0.data());
  // End stops and plane contacts: events in every integrator (sim/end_stops.h); a start on
  // a closed contact is its first event.
  EndStopEvents stops(program, options.rtol, options.atol);
  std::vector<double> y_given;  // the state before the start's events, for their changes
  if (stops.Active()) {
    y_given = y0;
    const double t0 = grid.start;
    if (std::string why = stops.CheckStart(*ws_rhs, t0, y0.data()); !why.empty()) return UsageResult(why);
    if (stops.Start(*ws_rhs, t0, y0.data()) != 0)
      return UsageResult("contacts at the start: " + (stops.Error().empty() ? rt::ErrorMessage(*ws_rhs) : stops.Error()));
  }
  // Rolling contacts: a normal force turning tensile stops the run (sim/lift_off.h).
  LiftOffGuard lift(program);
  lift.SetInputs(options.inputs);
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
  if (stick.Active() && stops.Active()) stick.SetStops(&stops);  // a joint resting on its stop is the stop's
  if (stick.Active() && y_given.empty()) y_given = y0;
  // Its failure is the start state's physics found by evaluating it (no consistent friction
  // force, a joint the rows fix), not the input's form: exit 2 at t0, as a failure later on.
  if (stick.Active() && stick.Start(*ws_rhs, grid.start, y0.data()) != 0) {
    SimResult r;
    r.status = SimResult::Status::kNumericalFailure;
    r.fail_time = grid.start;
    r.message = "friction at the start: " + (stick.Error().empty() ? rt::ErrorMessage(*ws_rhs) : stick.Error());
    return r;
  }
  // The output rows' view of the held rows (resting contacts, stuck joints), on copies of their events.
  std::unique_ptr<HeldOutputs> held;
  if (stops.Active() || stick.Active()) held = std::make_unique<HeldOutputs>(program, options.rtol, options.atol);
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
    const double* y = y_in;
    int status = 0;
    bool converted = true;  // z = [q; w] -> y = [q; u] (diagonal speeds)
    if (diagonal) {
      status = diagonal->ToSpeeds(t, y_in, y_row.data());
      converted = status == 0;
      y = y_row.data();
    }
    if (status == 0 && stops.AnyResting()) {  // exactly on their stops (an interpolant's round-off aside)
      if (y != y_row.data()) std::copy(y, y + y_row.size(), y_row.begin());
      stops.SnapResting(y_row.data());
      y = y_row.data();
    }
    // The friction laws of the run, and the held rows' motion at this row (sim/held_outputs.h).
    if (status == 0 && held) status = held->Prepare(&stops, &stick, *ws_out, t, y);
    if (status == 0) status = rt::EvalSignals(program, *plan, *ws_out, t, y, values.data());
    // A row near a change point whose projection moved the speeds too far: projected in the
    // kinetic metric instead, in a workspace of its own (docs/constraints.md "Rows near a
    // change point"); ws_out has gone through the row as before, so the rows after it are
    // unchanged. (A row the projection failed on, at the singular configuration itself,
    // still stops the run.)
    double move = 0.0;
    if (hooks.zone_rows && status == 0 && (move = rt::SpeedMove(program, *ws_out, y, options.rtol, options.atol)) > kRowTrust) {
      if (!ws_zone) {
        ws_zone = rt::MakeWorkspace(program);
        rt::SetInputSource(*ws_zone, options.inputs);
      }
      // On the reduced form taken only where it moved the speeds far less: where the
      // integrator's own speeds are off the constraints (ARKODE's drift at loose
      // tolerances), the partition's projection, which keeps the independent speeds the
      // integrator integrates, stays. The multiplier form's projection is already the
      // kinetic metric's, without the truncation.
      if (rt::RowNearChangePoint(program, *ws_zone, t, y) && (!held || held->Prepare(&stops, &stick, *ws_zone, t, y) == 0) &&
          rt::EvalSignalsNearChangePoint(program, *plan, *ws_zone, t, y, zone_values.data()) == 0 &&
          (multiplier_form || rt::SpeedMove(program, *ws_zone, y, options.rtol, options.atol) * kRowGain < move)) {
        values.swap(zone_values);
      }
    }
    std::string past_stop;
    if (!converted) {
      *cause = diagonal->FailureCause();
    } else if (status != 0) {
      const std::string& m = held && !held->Error().empty() ? held->Error() : rt::ErrorMessage(*ws_out);
      *cause = m.empty() ? "an output signal could not be evaluated" : m;
    } else if (stops.Active() && !(past_stop = stops.CheckRow(*ws_out, t, y)).empty()) {
      *cause = past_stop;
      status = -1;  // the row is not written: the rows before it are on disk
    } else if (stick.Active() && program.rows.empty() && !(past_stop = SlidingAgainstItsLaw(stick, program, t, y, options)).empty()) {
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
  ode.SetInputs(options.inputs);
  if (stops.Active()) ode.SetStops(&stops);
  if (lift.Active()) ode.SetLiftOff(&lift);
  if (stick.Active()) ode.SetStickSlip(&stick);
  WhenEvents whens(program);  // when clauses (sim/when_events.h)
  whens.SetTolerance(iopt.rtol);
  if (whens.Active()) ode.SetWhens(&whens);
  if (hooks.rhs_fault) ode.SetFault(hooks.rhs_fault);
  ode.SetHoldRows(hooks.hold_zone_rows);
  if (iopt.bridge) ode.EnableEarlyBridge(iopt.rtol, iopt.atol, hooks.bridge_switches);
  // The start's events (on a contact: EndStopEvents::Start; stuck or sliding: StickSlipEvents::Start).
  std::vector<EventRecord> at_start(stops.Log().begin(), stops.Log().end());
  at_start.insert(at_start.end(), stick.Log().begin(), stick.Log().end());
  if (!at_start.empty()) AddChanges(rt::StateNames(program), y_given.data(), y0.data(), &at_start.front(), &at_start.back());
  OdeSystem* system = &ode;
  if (!speed_order.empty()) {
    if (whens.Active()) return UsageResult("--speeds diagonal does not handle when clauses yet (docs/events.md)");
    diagonal = std::make_unique<DiagonalOde>(program, ode, speed_order);
    if (diagonal->Init(grid.start, y0.data()) != 0) return UsageResult("--speeds diagonal: " + diagonal->FailureCause());
    std::vector<double> z0(static_cast<size_t>(diagonal->Size()));
    if (diagonal->ToW(grid.start, y0.data(), z0.data()) != 0) return UsageResult("--speeds diagonal: " + diagonal->FailureCause());
    y0.swap(z0);
    system = diagonal.get();
  }
  Clock::time_point start = Clock::now();
  IntegrateResult ir = Integrate(*system, y0.data(), grid, iopt, row);
  Clock::duration total = Clock::now() - start;
  bool end_ok = sink.End();

  FinishRun(ir, sink_failed, end_ok, Seconds(total - output_time), Seconds(output_time), &result);
  result.stats.events = std::move(at_start);
  result.stats.events.insert(result.stats.events.end(), ode.Events().begin(), ode.Events().end());
  result.stats.terminated = ir.terminated;
  result.stats.terminate_time = ir.terminate_time;
  result.stats.terminate_message = ir.terminate_message;
  ode.PassageCounts(&result.stats.passages_checked, &result.stats.passages_unchecked);
  result.stats.energy_guard = energy.Description();
  result.stats.energy_error = energy.WorstError();
  result.stats.energy_tolerance = energy.Tolerance();
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
  if (!std::isnan(i.stiff_time)) {  // DOP853's stiffness detection (sim/dop853_stiffness.h)
    char at[32];
    std::snprintf(at, sizeof at, "%.6g", i.stiff_time);
    std::snprintf(buf, sizeof buf, "  stiffness                found at t = %s: h|lambda| %.3g, past DOP853's stability boundary 6.1%s\n",
                  at, i.stiff_h_lambda, i.switched         ? ""
                  : i.switch_allowed ? " (not switched: fewer than 100 of its steps were left)"
                                     : " (not switched: DOP853 was chosen explicitly)");
    std::string lines = buf;
    if (i.switched) {  // what ran: DOP853 to the hand-over, CVODE-BDF from there
      const std::string head = std::string("integrator                 ") + MethodName(s.method);
      out.replace(0, head.size(), head + " \u2192 " + MethodName(rt::Integrator::CvodeBdf) + " at t = " + at + ", stiffness detected");
      lines = std::string("  then                     ") + MethodDescription(rt::Integrator::CvodeBdf) + "\n" + lines;
    }
    out.insert(out.find("  steps "), lines);
  }
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
  if (!s.sensitivity.empty()) {  // --sensitivity: the differences' estimated errors (docs/integrators.md)
    out += "sensitivity differences    estimated error (largest over the rows) / largest value\n";
    for (const SensitivityErrors& e : s.sensitivity) {
      std::snprintf(buf, sizeof buf, "  %-24s df/dp %.2g / %.2g, (df/dy) s %.2g / %.2g, start %.2g / %.2g\n",
                    e.param.c_str(), e.dfdp_error, e.dfdp_scale, e.dfdy_error, e.dfdy_scale, e.start_error,
                    e.start_scale);
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

void AddChanges(const std::vector<std::string>& names, const double* before, const double* y, EventRecord* first,
                EventRecord* last) {
  for (size_t k = 0; k < names.size(); ++k)
    if (y[k] != before[k]) first->changes.push_back({names[k], before[k], y[k]});
  for (EventRecord* r = first; r <= last; ++r) {
    if (!r->changes.empty()) continue;
    const auto it = std::find(names.begin(), names.end(), r->element + ".u");
    if (it != names.end()) {
      const size_t k = static_cast<size_t>(it - names.begin());
      r->changes.push_back({*it, before[k], y[k]});
    }
  }
}

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
