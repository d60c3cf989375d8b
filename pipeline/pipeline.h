// The pipeline: from .mech text to output rows, in named stages. Every front end (the
// `kanesim` commands, the benchmark drivers, the tests, the viewer, linearization
// and Python) goes through these functions; docs/architecture.md draws them.
//
//   LoadModel                                                    (pipeline.cpp)
//     0. import     a URDF file -> .mech text (robot.urdf only)   import::UrdfToMech
//     1. parse      text -> AST: the main file and the stdlib     lang::LoadProgram
//     2. elaborate  AST -> flat mechanism, --set values applied    lang::Elaborate
//     3. compile    flat mechanism -> immutable rt::Program       rt::Compile
//   Run                                                          (pipeline.cpp)
//     4. resolve    RunSpec + the model's experiment -> options   ResolveRun
//     5. integrate  from the start to the stop time               sim::Simulate
//     6. output     selected signals at every output instant      sim::SignalSink
//
// A user mistake is never thrown: LoadModel returns the rendered diagnostics, ResolveRun
// the reason, Run a SimResult with a status. Only `main` chooses exit codes.
//
// Example (what `kanesim run model.mech --set N=3 --rtol 1e-8` does):
//   pipeline::RunSpec spec;
//   spec.rtol = 1e-8;
//   pipeline::LoadResult r = pipeline::LoadModel(pipeline::Source::File("model.mech"), {"", {"N=3"}}, spec);
//   std::cerr << r.diagnostics;
//   if (!r.model) return 1;
//   sim::CsvWriter csv(stdout);
//   sim::SimResult result = pipeline::Run(*r.model, spec, csv);
#pragma once

#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "lang/elaborate.h"
#include "compiler/compiler.h"
#include "flat/mechanism.h"
#include "import/import.h"
#include "sim/energy_guard.h"
#include "sim/integrator.h"
#include "sim/sensitivity.h"
#include "sim/simulate.h"

namespace kanesim::pipeline {

inline constexpr double kUnset = std::numeric_limits<double>::quiet_NaN();

// ---------------------------------------------------------------------------------------
// The run specification: everything a user chooses about one run, resolved once.
// ---------------------------------------------------------------------------------------

// A number left kUnset (NaN) comes from the model's experiment annotation, else the
// default (DESIGN.md "The command line"):
//   start_time  experiment StartTime, else 0
//   stop_time   experiment StopTime, else 1
//   interval    experiment Interval, else (stop - start) / sim::kDefaultIntervals
//   rtol        experiment Tolerance, else 1e-6
//   atol        = rtol (states are angles, lengths and their rates, of order one)
struct RunSpec {
  // Compiled into the program (read by LoadModel, stage 3).
  rt::SolverPath solver = rt::SolverPath::Auto;  // Kane's equations: dense, sparse, recursive
  // The time integrator; Auto: the compiler's choice (rt::Summarize(program).integrator).
  rt::Integrator integrator = rt::Integrator::Auto;
  rt::IndeterminateReactions reactions = rt::IndeterminateReactions::NaN;

  // Times and tolerances (stage 4); given values must be positive and finite (times: finite).
  double start_time = kUnset;
  double stop_time = kUnset;
  double interval = kUnset;
  double rtol = kUnset;
  double atol = kUnset;
  sim::IdaLinearSolver linear_solver = sim::IdaLinearSolver::Auto;  // IDA's Newton matrix
  bool project_steps = false;  // --projection step: project once per accepted step (DOP853)
  // --energy-check: the energy guard of conservative models (docs/integrators.md).
  sim::EnergyCheck energy_check = sim::EnergyCheck::kOn;
  // --speeds joint|diagonal [--speed-order j1,j2]: Lesser's diagonal speeds
  // (sim/diagonal_speeds.h). Not given: the model's annotation(speeds(kind =, order =)).
  std::optional<sim::Speeds> speeds;
  std::vector<std::string> speed_order;

  // Outputs: glob patterns over dotted signal names (sim/signal_select.h); empty: the
  // default signals (rt::DefaultSignals: joints' q and u, declared outputs).
  std::vector<std::string> outputs;
  // --sensitivity: real, non-structural parameters (start values too, e.g. "j.q.start")
  // whose derivatives d(y)/d(p) are written beside every output (sim/sensitivity.h).
  std::vector<std::string> sensitivity;
};

// The one place option names meet the enums (run, sweep, test, check, sweep and golden
// files). Each returns false for an unknown name and leaves *out unchanged.
//   solver       auto | dense | sparse | recursive
//   integrator   auto | ida | cvode | cvode-bdf | arkode | dop853   ("cvode" is Adams)
//   reactions    nan | min-norm
//   linear solver  auto | dense | klu
//   energy check   on | off | report
bool SolverFromName(std::string_view name, rt::SolverPath* out);
bool IntegratorFromName(std::string_view name, rt::Integrator* out);
bool ReactionsFromName(std::string_view name, rt::IndeterminateReactions* out);
bool LinearSolverFromName(std::string_view name, sim::IdaLinearSolver* out);
bool EnergyCheckFromName(std::string_view name, sim::EnergyCheck* out);
// The names above, in the order listed (for CLI11's IsMember and error messages).
const std::vector<std::string>& SolverNames();
const std::vector<std::string>& IntegratorNames();
const std::vector<std::string>& ReactionsNames();
const std::vector<std::string>& LinearSolverNames();
const std::vector<std::string>& EnergyCheckNames();
// The name of a choice: the inverse of the *FromName functions.
std::string IntegratorOptionName(rt::Integrator integrator);
// "auto, ida, cvode, ..." for messages.
std::string JoinNames(const std::vector<std::string>& names);
// The compiler's choices as `kanesim check` prints them ("dense", "IDA", ...).
const char* SolverName(rt::SolverPath solver);
const char* IntegratorName(rt::Integrator integrator);

// What rt::Compile takes from the spec (the solver path, the integrator kind, reactions).
rt::CompileOptions CompileOptionsFor(const RunSpec& spec);

// ---------------------------------------------------------------------------------------
// Stages 1-3: load a model.
// ---------------------------------------------------------------------------------------

// Where the main file's text comes from.
struct Source {
  std::string path;        // the .mech file; with from_text, the name diagnostics give it
  std::string text;        // the main file's text when from_text
  bool from_text = false;
  static Source File(std::string path) { return Source{std::move(path), {}, false}; }
  static Source Text(std::string name, std::string text) { return Source{std::move(name), std::move(text), true}; }
};

struct LoadOptions {
  std::string model;               // class to elaborate; "" = the last model of the main file
  std::vector<std::string> sets;   // "name=value" as given to --set, applied in order
  bool compile = true;             // false: stop after stage 2 (program stays null)
  // A main file named *.urdf is translated to .mech text first (import/import.h) with these
  // options; the text is then named PATH.mech in diagnostics (what `kanesim import` writes).
  import::Options urdf;
  // The data files (meshes) read from elsewhere (lang::ElaborateOptions::data_files): an
  // FMU's resources. Null: as the model names them.
  const std::map<std::string, std::string>* data_files = nullptr;
  // The process ends after this model's command: lang::ElaborateOptions::leave_to_exit.
  bool leave_to_exit = false;
};

// A loaded model. Immutable once loaded; the program may be shared across threads.
struct Model {
  lang::Program source;     // stage 1: parsed files; owns the text diagnostics point into
  // Stage 2: the flat mechanism (mech->experiment: the run defaults); the program shares it.
  std::shared_ptr<const flat::Mechanism> mech;
  std::shared_ptr<const rt::Program> program;  // stage 3; null when LoadOptions::compile is false
  double load_seconds = 0.0;     // wall time of stages 1-2
  double compile_seconds = 0.0;  // wall time of stage 3
};

struct LoadResult {
  std::unique_ptr<Model> model;  // null when a stage failed
  // Rendered diagnostics: errors that stopped a stage, and warnings (also on success),
  // "file:line:col: error[CODE]: message", the source line with a caret, notes, hint.
  std::string diagnostics;
};

LoadResult LoadModel(const Source& source, const LoadOptions& options, const RunSpec& spec);

// A compiler message (K3xx, W31x) as a language diagnostic in `diags` (its caps apply):
// the location and the notes' become spans in diags.Sources() (no span when the file is
// not among them), the code, message and hint are kept.
void AddCompileMessage(const rt::CompileMessage& message, lang::Severity severity, lang::Diagnostics& diags);
// The same, rendered alone with the source lines of `model`'s files.
std::string RenderCompileMessage(const Model& model, const rt::CompileMessage& message, lang::Severity severity);

// E239 at the declaration of each of the model's inputs named in `missing` (rt::InputName:
// "tau", "f[2]"): nothing gives its value (no --input-file column, no --set).
void AddUnconnectedInputs(const flat::Mechanism& mech, const std::vector<std::string>& missing, lang::Diagnostics& diags);
// The same, rendered with the source lines of `model`'s files ("" when `missing` is empty).
std::string RenderUnconnectedInputs(const Model& model, const std::vector<std::string>& missing);

// ---------------------------------------------------------------------------------------
// Stages 4-6: run it.
// ---------------------------------------------------------------------------------------

struct ResolvedRun {
  sim::SimOptions sim;    // what sim::Simulate takes; sim.signals empty: the default signals
  sim::OutputGrid grid;   // start, stop, interval of the output rows
  std::vector<std::string> sensitivity;  // RunSpec::sensitivity, checked against the model
};

// What ResolveRun found wrong, so each command can classify it.
enum class RunProblem {
  kNone,
  kValue,    // a given interval or tolerance is not a positive finite number
  kSignals,  // an output pattern matches no signal
  kGrid,     // the output grid cannot be run (sim::CheckRun: stop before start, too many rows)
  kSensitivity,  // a --sensitivity name is not a real, non-structural parameter
};

// Stage 4: fills *out from the spec and the model's experiment; returns "" or why the run
// cannot start (and *problem, when given). On kGrid, *out is complete: a sweep whose
// scenarios override the times checks each scenario's grid itself.
std::string ResolveRun(const Model& model, const RunSpec& spec, ResolvedRun* out, RunProblem* problem = nullptr);

// Warnings for a run that writes or measures `signals` (exact names; empty = the
// defaults) at tolerance `rtol`, rendered: W314 (friction on an indeterminate normal
// force), W315 (start speeds projected onto the velocity constraints), W313
// (indeterminate reaction components among the signals), and a relative
// tolerance that is almost certainly a mistake. "" when there is nothing to say.
std::string RunWarnings(const Model& model, double rtol, const std::vector<std::string>& signals);

// The model at p +/- delta for each of `names` (--sensitivity: Real, non-structural, not
// constant), rebound from model's program: "" or why not.
std::string SensitivityParams(const Model& model, const std::vector<std::string>& names,
                              std::vector<sim::SensitivityParam>* out);

// Stages 5-6 with resolved options.
sim::SimResult Run(const Model& model, const ResolvedRun& run, sim::SignalSink& sink);
// Stages 4-6: a ResolveRun problem is returned as Status::kUsageError with its reason.
sim::SimResult Run(const Model& model, const RunSpec& spec, sim::SignalSink& sink);

}  // namespace kanesim::pipeline
