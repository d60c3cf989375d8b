// Simulate: one run of a compiled program from the start time to the stop time, the
// selected signals written to a sink at every output instant. The stages, in order:
//   1. resolve times, tolerances, integrator          (ResolveRun)
//   2. plan the signals                                (rt::PlanSignals)
//   3. integrate, evaluating signals at each instant   (sim::Integrate, rt::EvalSignals)
#pragma once

#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "runtime/runtime.h"
#include "sim/csv.h"
#include "sim/diagonal_speeds.h"
#include "sim/energy_guard.h"
#include "sim/integrator.h"

namespace kanesim::sim {

struct SimOptions {
  double start_time = std::numeric_limits<double>::quiet_NaN();  // NaN: rt::StartTime(program)
  double stop_time = 1.0;
  double interval = 0.0;  // output spacing; <= 0: (stop - start) / kDefaultIntervals
  double rtol = 1e-6;
  double atol = 1e-6;
  rt::Integrator integrator = rt::Integrator::Auto;  // Auto: rt::Summarize(program).integrator
  IdaLinearSolver ida_linear_solver = IdaLinearSolver::Auto;  // IDA and CVODE-BDF: dense LU, KLU or GMRES
  long max_steps = 100000;      // internal steps allowed between two output instants
  // Closed loops and contacts with DOP853: project once per accepted step instead of at every
  // evaluation (`--projection step`; runtime/runtime.h SetStepProjection, docs/constraints.md "Drift").
  bool project_steps = false;
  // Conservative models: stop with exit 2 where T + V leaves the tolerance's reach
  // (`--energy-check on|off|report`; sim/energy_guard.h, docs/integrators.md).
  EnergyCheck energy_check = EnergyCheck::kOn;
  std::vector<std::string> signals;  // exact names; empty: rt::DefaultSignals(program)
  // The model's inputs (rt::NumInputs > 0): a table (sim/input_table.h) or any source; not
  // owned. A model with inputs and no source is a usage error naming them.
  const rt::InputSource* inputs = nullptr;
  // `--speeds diagonal`: integrate in Lesser's speeds w = L^T u (sim/diagonal_speeds.h); the
  // rows add w[i], d[i] and T_w[i] = 1/2 d_i w_i^2. speed_order: joints whose speeds come first
  // (`--speed-order`), the rest root to leaf.
  Speeds speeds = Speeds::kJoint;
  std::vector<std::string> speed_order;
  std::function<void(double t)> progress;  // after each row; may be empty
};

inline constexpr int kDefaultIntervals = 500;

// Wall time of each phase in seconds; load and compile are filled by the caller.
struct PhaseTimes {
  double load = 0.0;       // parse + elaborate
  double compile = 0.0;
  double integrate = 0.0;  // solver and right-hand side, output excluded
  double output = 0.0;     // signal evaluation and writing
};

// A state entry an event changed: its name ("j.u"), its values at the left and right limits.
struct EventChange {
  std::string name;
  double before = 0.0, after = 0.0;
};

struct EventRecord;
// The records of one event (*first .. *last, the state before it and after): the entries of y
// that differ from before (names: rt::StateNames) on the first record; a record left without
// changes (a rest, a leave, a later record of the event) carries its joint's speed entry
// ("j.u") before and after, where its element is a joint.
void AddChanges(const std::vector<std::string>& names, const double* before, const double* y, EventRecord* first,
                EventRecord* last);

// One event of a run: its time, the element ("j1", "when (ball.mech:12)") and what happened
// ("impact at q_min", "rests on q_max", "leaves q_min", "fires", "terminate: why"), with the
// state entries it changed (on the event's first record).
struct EventRecord {
  EventRecord() = default;
  EventRecord(double t, std::string e, std::string k) : time(t), element(std::move(e)), kind(std::move(k)) {}
  double time = 0.0;
  std::string element, kind;
  std::vector<EventChange> changes;
};

// --sensitivity: the estimated error of one parameter's difference quotients (sim/sensitivity.h),
// the largest over the output rows, each beside the largest size of what it estimates.
struct SensitivityErrors {
  std::string param;
  double dfdp_error = 0.0, dfdp_scale = 0.0;    // df/dp between the programs at p +/- delta
  double dfdy_error = 0.0, dfdy_scale = 0.0;    // (df/dy) s along s
  double start_error = 0.0, start_scale = 0.0;  // dy0/dp from the starts at p +/- delta
};

struct SimStats {
  rt::Integrator method = rt::Integrator::IDA;
  IntegratorStats integrator;
  long rows = 0;
  // Closed loops through change points: bridged, and passed by the solver itself, checked
  // against the bridge's approach or not (docs/constraints.md "Singular configurations").
  long bridges = 0, passages_checked = 0, passages_unchecked = 0;
  // The energy guard: "on", "off", "report" or "not applied (...)"; on and report, the
  // largest relative energy error seen and the bound (EnergyGuard).
  std::string energy_guard;
  double energy_error = 0.0, energy_tolerance = 0.0;
  std::vector<EventRecord> events;  // in time order (--stats prints them, --events writes them)
  // terminate("why") in a when clause ended the run at terminate_time (rows up to it kept).
  bool terminated = false;
  double terminate_time = 0.0;
  std::string terminate_message;
  std::vector<SensitivityErrors> sensitivity;  // --sensitivity: one per parameter
  PhaseTimes times;
};

struct SimResult {
  enum class Status {
    kOk,
    kUsageError,        // bad options or signal names (exit 1)
    kOutputError,       // the sink could not write (exit 1)
    kNumericalFailure,  // exit 2; rows before fail_time were written
  };
  Status status = Status::kOk;
  double fail_time = 0.0;
  std::string message;  // the usage error, or the cause of the numerical failure
  SimStats stats;
};

// The output grid of a run: the start time (the options' or the program's), the stop
// time, the interval (the options', else (stop - start) / kDefaultIntervals).
OutputGrid ResolveGrid(const rt::Program& program, const SimOptions& options);

// Why a run with these settings cannot start, in words ("" when it can): the grid's limits
// (OutputGrid::Check) and positive finite tolerances. Simulate reports it as a usage
// error; sweeps and golden tests call it before they run anything.
std::string CheckRun(const OutputGrid& grid, double rtol, double atol);

// A relative tolerance that is legal but almost certainly a mistake: above
// kMaxSensibleRtol (errors as large as the solution) or below kMinSensibleRtol (beyond
// double precision). The warning's text, or "".
inline constexpr double kMaxSensibleRtol = 0.1;
inline constexpr double kMinSensibleRtol = 1e-14;
std::string ToleranceWarning(double rtol);

// The integrator of a run, a sensitivity run and the stepping core, set in *io: the
// requested method, Auto resolved to the compiler's choice (rt::Summarize), a DOP853 chosen
// so handing over to CVODE-BDF when it finds the problem stiff (docs/integrators.md "The
// automatic choice"), and the coupling groups of the implicit methods it may run.
void ResolveMethod(const rt::Program& program, rt::Integrator requested, IntegratorOptions* io);

// For the run drivers (Simulate, SimulateSensitivities): a usage error's result, and the end
// of a run: the integrator's counts and phase times into result->stats, and the status from
// how the integration and the sink ended (rows before a failure stay written).
SimResult UsageResult(std::string message);
void FinishRun(const IntegrateResult& ir, bool sink_failed, bool end_ok, double integrate_seconds,
               double output_seconds, SimResult* result);

// (Tests switch parts of a run off through sim/test_hooks.h's overload.)
SimResult Simulate(const rt::Program& program, const SimOptions& options, SignalSink& sink);

// The `--stats` report, one fact per line.
std::string FormatStats(const SimStats& stats);

// The events as CSV (`--events FILE.csv`; docs/cli.md): a header, then one row per state
// entry an event changed (time,element,kind,signal,before,after), or one row with the last
// three empty for an event that changed none.
std::string FormatEventsCsv(const std::vector<EventRecord>& events);

}  // namespace kanesim::sim
