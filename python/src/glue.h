// The Python module's only contact with loading and running: parse + elaborate + compile
// a model (Load), resolve a run's options and simulate it into memory (Run), summarize it
// (Check) and sweep it (Sweep). Everything here is plain C++ (no Python types), so that
// the bindings (module.cpp) stay thin. Loading and run settings go through the library
// pipeline (pipeline/pipeline.h), as the command line's.
#pragma once

#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "runtime/runtime.h"
#include "flat/mechanism.h"
#include "linearize/linearize.h"
#include "pipeline/pipeline.h"
#include "sim/simulate.h"

namespace kanesim::py {

inline constexpr double kUnset = std::numeric_limits<double>::quiet_NaN();

// A model error: the first error's code and place, and every diagnostic rendered as
// `kanesim check` prints it (file:line:col, source line, caret, notes, hint).
struct ModelErrorInfo {
  std::string code;  // "E203", "K308"; "" for errors without a code
  std::string file;  // "" when there is no location
  int line = 0, column = 0;
  std::string rendered;
};

struct LoadRequest {
  std::string path;       // the .mech file, or a display name for `text`
  std::string text;       // the model's text when from_text
  bool from_text = false;
  std::string model;      // the model to elaborate ("" = the last in the file)
  std::vector<std::string> sets;  // "name=value", as --set
  std::string solver = "auto";     // auto|dense|sparse|recursive
  std::string integrator = "auto"; // auto|ida|cvode|cvode-bdf|arkode|dop853 (compile-time choice)
  std::string reactions = "nan";   // nan|min-norm
  bool floating = false;                   // a .urdf file: a free base (docs/import.md)
  bool stops = true;                       // a .urdf file: <limit>s as end stops (limits="stops")
  std::vector<std::string> package_paths;  // a .urdf file: where package:// meshes are looked up
};

struct LoadedModel {
  LoadRequest request;  // kept to load variants (run(set=...), structural sweeps)
  std::shared_ptr<const pipeline::Model> model;  // the pipeline's stages 1-3
  std::shared_ptr<const rt::Program> program;    // model->program
  std::vector<std::string> warnings;  // rendered
  // rt::AvailableSignals, made on first use (output globs select among them).
  const std::vector<std::string>& Signals() const;

 private:
  mutable std::once_flag signals_once_;
  mutable std::vector<std::string> signals_;
};

// Parse, elaborate and compile. False with *error filled on a model error.
bool Load(const LoadRequest& request, LoadedModel* out, ModelErrorInfo* error);

// A run's settings; NaN / empty = the model's experiment annotation, as `kanesim run`.
struct RunRequest {
  double start_time = kUnset, stop_time = kUnset, interval = kUnset, rtol = kUnset, atol = kUnset;
  std::vector<std::string> outputs;  // --output patterns; empty: the default signals
  std::string integrator = "auto";
  std::string linear_solver = "auto";
  std::string projection = "eval";
  std::string energy_check = "on";  // --energy-check (docs/integrators.md "The energy guard")
  std::vector<std::string> sensitivity;  // --sensitivity: d(y)/d(p) columns (sim/sensitivity.h)
};

// Run settings resolved against a loaded model: the SimOptions `kanesim run` would use.
// False with a usage message (bad tolerance, unknown signal, too many rows).
bool ResolveRun(const LoadedModel& model, const RunRequest& request, sim::SimOptions* out,
                std::vector<std::string>* warnings, std::string* error);

struct RunOutput {
  std::vector<std::string> columns;
  std::vector<double> time;
  std::vector<double> values;  // row-major: time.size() x columns.size()
  bool failed = false;         // numerical failure: the rows before fail_time are kept
  double fail_time = 0.0;
  std::string message;         // the cause of the failure
  sim::SimStats stats;
  double simulate_seconds = 0.0;  // wall time of sim::Simulate (the C++ run, setup included)
  bool interrupted = false;       // `interrupted` said stop (Ctrl-C): the rows so far are kept
};

// Simulates; thread-safe for one model from many threads (the program is immutable,
// every run owns its workspace). False with a usage message; a numerical failure
// returns true with out->failed set. `interrupted`, when given, is asked at an output row at
// most every 0.1 s whether to stop (the bindings check Python's signals there); a stop
// returns true with out->interrupted set.
// `sensitivity`: parameters whose d(y)/d(p) columns follow the signals' (RunRequest).
bool Simulate(const LoadedModel& model, const sim::SimOptions& options, RunOutput* out, std::string* error,
              const std::function<bool()>& interrupted = {}, const std::vector<std::string>& sensitivity = {});

// The facts of `kanesim check`, as (key, value) trees for a Python dict.
struct Value;
using Dict = std::vector<std::pair<std::string, Value>>;
using List = std::vector<Value>;
struct Value {
  std::variant<std::monostate, bool, long, double, std::string, std::shared_ptr<Dict>, std::shared_ptr<List>> v;
};
Dict Check(const LoadedModel& model);
std::vector<std::string> AvailableSignals(const LoadedModel& model);

// A sweep: a product of grids (and zipped sample columns), metrics per scenario, threads.
struct SweepRequest {
  std::vector<std::pair<std::string, std::vector<double>>> grid;     // each a factor of the product
  std::vector<std::pair<std::string, std::vector<double>>> samples;  // zipped rows (one block)
  std::vector<std::string> metrics;  // "final:j.q", "cross:x.q=0", ...
  RunRequest run;
  int threads = 0;  // 0: all cores (workers or threads)
  // Scenarios in worker processes forked from this one (batch/worker_pool.h), so a
  // scenario that crashes or hangs costs its own row ("crashed", "timeout"), not the
  // interpreter; or on threads of this process (a crash ends the interpreter).
  bool processes = true;
  double scenario_timeout = 0.0;  // seconds of wall time per scenario (processes); 0: none
  // Asked by the calling thread between its scenarios (with processes: also every 0.25 s)
  // whether to stop (Ctrl-C); threads finish the scenarios running then, workers are
  // killed; no new one starts, and Sweep sets out->interrupted.
  std::function<bool()> interrupted;
};
struct SweepTable {
  std::string header;              // the summary.csv header of `kanesim sweep`
  std::vector<std::string> lines;  // one per scenario, by id
  int failed = 0;   // rows whose status is not "ok", these two included:
  int crashed = 0;  //   the worker process died running it
  int timed_out = 0;
  bool interrupted = false;
  std::string warning;  // e.g. no worker process could be made (the rest ran on threads)
};
bool Sweep(const LoadedModel& model, const SweepRequest& request, SweepTable* out, std::string* error);

// A linear model about an operating point, as `kanesim linearize` (linearize,
// docs/linearize.md): the start values, the motion at `at`, or an equilibrium found from
// either.
struct LinearizeRequest {
  bool has_at = false;
  double at = 0.0;
  bool equilibrium = false;
  std::vector<std::string> inputs, outputs;
  // The model's own inputs (`input Real u;`) at the operating point, by name: held there,
  // each a column of B and D (as `kanesim linearize --set u=...`); every one needs a value.
  std::vector<std::pair<std::string, double>> input_values;
  double step = 1e-3;
};
struct LinearizeOutput {
  lin::LinearModel model;       // with its modes (lin::ComputeModes)
  lin::OperatingPoint point;    // where it was linearized
  bool has_equilibrium = false;
  lin::EquilibriumResult equilibrium;
  lin::Status status;           // code 1: bad input (a model error), 2: numerical failure
  double seconds = 0.0;         // wall time
};
// False with a usage message (a step outside (0, 0.1], a non-finite time). Otherwise
// true; out->status says whether the linearization succeeded. Thread-safe like Simulate.
bool Linearize(const LoadedModel& model, const LinearizeRequest& request, LinearizeOutput* out, std::string* error);

}  // namespace kanesim::py
