// `kanesim run file.mech`: load, compile, simulate, write CSV (DESIGN.md "The command
// line"), through the pipeline (pipeline/pipeline.h): the options fill one
// pipeline::RunSpec; times and tolerances not given come from the model's experiment
// annotation (pipeline::RunSpec says which and the defaults).
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <fmt/core.h>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "cli/common.h"
#include "cli/number_options.h"
#include "cli/scene.h"
#include "cli/signal_units.h"
#include "batch/file_guard.h"
#include "runtime/runtime.h"
#include "sim/csv.h"
#include "sim/signal_select.h"
#include "sim/simulate.h"

namespace kanesim::cli {
namespace {

using Clock = std::chrono::steady_clock;

struct RunArgs {
  LoadOptions load;
  std::string out_path;  // "" or "-": stdout
  pipeline::RunSpec spec;  // times, tolerances (NaN: not given) and outputs; the names below
  std::string solver = "auto";
  std::string integrator = "auto";
  std::string linear_solver = "auto";
  std::string projection = "eval";
  std::string reactions = "nan";
  std::string energy_check = "on";  // --energy-check on|off|report (sim/energy_guard.h)
  std::string speeds;               // --speeds joint|diagonal ("": the model's annotation)
  bool stats = false;
  std::string events_path;  // --events FILE.csv
  bool units_in_header = false;  // --units-in-header (cli/signal_units.h)
  std::string animation;  // --animation out.glb|out.gltf ("" = none; cli/animation.cpp)
  bool show_frames = false;  // --show-frames: the joints' frames as small axes in the animation
};

// A one-line bar on stderr, drawn only when stderr is a terminal and the run has taken
// more than a second; erased at the end.
class ProgressBar {
 public:
  ProgressBar(double start, double stop, bool enabled) : start_(start), stop_(stop), enabled_(enabled) {}
  ~ProgressBar() {
    if (drawn_) std::fputs("\r\033[K", stderr);
  }
  void Update(double t) {
    if (!enabled_) return;
    Clock::time_point now = Clock::now();
    if (now - begin_ < std::chrono::seconds(1)) return;
    if (drawn_ && now - last_draw_ < std::chrono::milliseconds(100)) return;
    last_draw_ = now;
    drawn_ = true;
    double frac = stop_ > start_ ? (t - start_) / (stop_ - start_) : 1.0;
    constexpr int kWidth = 30;
    int filled = static_cast<int>(frac * kWidth);
    std::string bar(static_cast<size_t>(filled), '=');
    bar.resize(kWidth, ' ');
    double elapsed = std::chrono::duration<double>(now - begin_).count();
    fmt::print(stderr, "\r[{}] {:3.0f}%  t = {:.6g} / {:.6g}  ({:.1f} s)", bar, 100.0 * frac, t, stop_, elapsed);
    std::fflush(stderr);
  }

 private:
  double start_, stop_;
  bool enabled_;
  bool drawn_ = false;
  Clock::time_point begin_ = Clock::now();
  Clock::time_point last_draw_{};
};

// The option names into the spec (CLI11 has checked them against the same tables).
pipeline::RunSpec SpecFor(const RunArgs& a) {
  pipeline::RunSpec spec = a.spec;
  pipeline::SolverFromName(a.solver, &spec.solver);
  pipeline::IntegratorFromName(a.integrator, &spec.integrator);
  pipeline::ReactionsFromName(a.reactions, &spec.reactions);
  pipeline::LinearSolverFromName(a.linear_solver, &spec.linear_solver);
  spec.project_steps = a.projection == "step";
  pipeline::EnergyCheckFromName(a.energy_check, &spec.energy_check);
  if (!a.speeds.empty()) spec.speeds = a.speeds == "diagonal" ? sim::Speeds::kDiagonal : sim::Speeds::kJoint;
  return spec;
}

int RunCommand(const RunArgs& a) {
  // Stages 1-3: parse, elaborate, compile.
  const pipeline::RunSpec spec = SpecFor(a);
  std::unique_ptr<pipeline::Model> loaded = LoadAndCompile(a.load, spec);
  if (!loaded) return kExitModelError;
  // Every output below is flushed and closed (errors checked) before a return; the model
  // is freed by the process's exit.
  const pipeline::Model* model = &LeaveToExit(std::move(loaded));
  const rt::Program& program = *model->program;
  if (spec.solver != rt::SolverPath::Auto && rt::Summarize(program).solver != spec.solver)
    fmt::print(stderr, "kanesim: note: solver {}\n", rt::Summarize(program).solver_reason);

  // Stage 4: the run's options, resolved once.
  pipeline::ResolvedRun run;
  pipeline::RunProblem problem = pipeline::RunProblem::kNone;
  std::string why = pipeline::ResolveRun(*model, spec, &run, &problem);
  if (problem == pipeline::RunProblem::kNone || problem == pipeline::RunProblem::kGrid)
    std::cerr << pipeline::RunWarnings(*model, run.sim.rtol, run.sim.signals);
  if (!why.empty()) {
    fmt::print(stderr, "kanesim: error: {}{}\n", problem == pipeline::RunProblem::kValue ? "--" : "", why);
    return kExitModelError;
  }
  sim::SimOptions& so = run.sim;
  // The model's inputs: --input-file tables; an input without a value is an error at its declaration.
  std::vector<std::string> input_names;
  for (int i = 0; i < rt::NumInputs(program); ++i) input_names.push_back(rt::InputName(program, i));
  sim::InputTable inputs(input_names);
  if (!LoadInputTables(*model, a.load.input_files, run.grid.start, run.grid.stop, &inputs)) return kExitModelError;
  if (!input_names.empty()) so.inputs = &inputs;
  AnimationRun animation(a.animation, a.show_frames);  // the bodies' poses ride along with the CSV's signals
  if (!animation.Prepare(*model->mech, program, &so.signals)) return kExitModelError;

  // The output: never the model itself, and one writer at a time (a lock beside it). A
  // regular file (or a new one) is written through a temporary beside it and renamed over
  // it at the end (docs/sweeps.md "Output files"), so a kill,
  // a crash or a full disk leaves the previous file whole and the rows so far in the
  // recognizable temporary <out>.tmp.<host>.<pid>; rows computed before a numerical
  // failure (exit 2) are correct and are kept: renamed like a complete run's. A FIFO or a
  // device (/dev/null, /dev/stdout) is streamed to directly, unlocked.
  bool to_stdout = a.out_path.empty() || a.out_path == "-";
  batch::FileLock out_lock;
  batch::AtomicFile atomic;
  std::FILE* out = stdout;
  if (!a.events_path.empty()) {
    if (std::string in = batch::OverwrittenInput(a.events_path, {a.load.path}); !in.empty()) {
      fmt::print(stderr, "kanesim: error: --events '{}' is the model '{}'; writing there would destroy it\n",
                 a.events_path, in);
      return kExitModelError;
    }
    if (!to_stdout && !batch::OverwrittenInput(a.events_path, {a.out_path}).empty()) {
      fmt::print(stderr, "kanesim: error: --events '{}' is the output -o\n", a.events_path);
      return kExitModelError;
    }
  }
  if (!to_stdout) {
    std::vector<std::string> protected_files{a.load.path};
    protected_files.insert(protected_files.end(), a.load.input_files.begin(), a.load.input_files.end());
    if (std::string in = batch::OverwrittenInput(a.out_path, protected_files); !in.empty()) {
      fmt::print(stderr, "kanesim: error: -o '{}' is the model '{}'; writing the CSV there would destroy it\n",
                 a.out_path, in);
      return kExitModelError;
    }
    std::string open_error;
    if (batch::NotRegularFile(a.out_path).empty()) {
      const std::filesystem::path target(batch::ReplacedFile(a.out_path));
      const std::string lock_path =
          (target.parent_path() / ("." + target.filename().string() + ".lock")).string();
      if (!out_lock.Acquire(lock_path, "'" + a.out_path + "'", &open_error, /*remove_at_end=*/true) ||
          (batch::RemoveStaleTemps(target.string()), !atomic.Open(a.out_path, &open_error))) {
        fmt::print(stderr, "kanesim: error: {}\n", open_error);
        return kExitModelError;
      }
      out = atomic.file();
    } else if (!(out = std::fopen(a.out_path.c_str(), "w"))) {
      fmt::print(stderr, "kanesim: error: cannot open '{}' for writing: {}\n", a.out_path, std::strerror(errno));
      return kExitModelError;
    }
  }
  bool bar_enabled = isatty(STDERR_FILENO) && !(to_stdout && isatty(STDOUT_FILENO));
  sim::SimResult result;
  {
    ProgressBar bar(run.grid.start, run.grid.stop, bar_enabled);
    so.progress = [&bar](double t) { bar.Update(t); };
    sim::CsvWriter csv(out);
    UnitsInHeader with_units(*model->mech, csv);
    sim::SignalSink& writer = a.units_in_header ? static_cast<sim::SignalSink&>(with_units) : csv;
    result = pipeline::Run(*model, run, animation.Wrap(writer));  // stages 5-6
  }
  const bool rows_correct = result.status == sim::SimResult::Status::kOk ||
                            result.status == sim::SimResult::Status::kNumericalFailure;
  std::string write_error;
  bool close_ok = true;
  if (atomic.file()) {
    if (rows_correct) close_ok = atomic.Commit(&write_error);
    else atomic.Abandon();  // a usage or output error: the previous file stays
  } else {
    close_ok = to_stdout ? std::fflush(stdout) == 0 : std::fclose(out) == 0;
  }
  // The animation follows the CSV: written for a complete run and for the rows before a
  // numerical failure; a usage or output error (say, the CSV's disk is full) leaves the
  // previous animation as it was, like the previous CSV, rather than replacing it with the
  // part of the motion computed before the error.
  const bool animation_ok = rows_correct && close_ok ? animation.Finish() : true;

  // The events (end stops, when clauses) as CSV, for a complete run and the rows before a
  // numerical failure alike.
  if (!a.events_path.empty() && rows_correct) {
    std::ofstream ev(a.events_path, std::ios::binary | std::ios::trunc);
    if (!(ev << sim::FormatEventsCsv(result.stats.events)) || !(ev.close(), ev)) {
      fmt::print(stderr, "kanesim: error: cannot write the events to '{}'\n", a.events_path);
      return kExitModelError;
    }
  }
  if (result.stats.terminated)
    fmt::print(stderr, "kanesim: terminated at t = {}: {}\n", sim::FormatShortest(result.stats.terminate_time),
               result.stats.terminate_message);
  if (a.stats) {
    result.stats.times.load = model->load_seconds;
    result.stats.times.compile = model->compile_seconds;
    fmt::print(stderr, "{}", sim::FormatStats(result.stats));
  }
  switch (result.status) {
    case sim::SimResult::Status::kOk: break;
    case sim::SimResult::Status::kUsageError:
      fmt::print(stderr, "kanesim: error: {}\n", result.message);
      return kExitModelError;
    case sim::SimResult::Status::kOutputError:
      fmt::print(stderr, "kanesim: error: {} ({})\n", result.message, to_stdout ? "stdout" : a.out_path);
      if (!to_stdout && out_lock.fd() >= 0)
        fmt::print(stderr, "kanesim: note: '{}' was left as it was before this run\n", a.out_path);
      return kExitModelError;
    case sim::SimResult::Status::kNumericalFailure:
      fmt::print(stderr, "kanesim: numerical failure at t = {}: {}\n", result.fail_time, result.message);
      if (!close_ok) break;
      return kExitNumerical;
  }
  if (!close_ok) {
    fmt::print(stderr, "kanesim: error: {}\n",
               write_error.empty() ? "cannot write the output (" + std::string(to_stdout ? "stdout" : a.out_path) + ")"
                                   : write_error);
    return kExitModelError;
  }
  if (!animation_ok) return kExitModelError;
  return kExitOk;
}

}  // namespace

void AddRunCommand(CLI::App& app, int* exit_code, bool options) {
  auto a = std::make_shared<RunArgs>();
  a->load.leave_to_exit = true;  // one model, then the process ends
  CLI::App* run = app.add_subcommand("run", "Simulate a model and write its motion as CSV");
  if (!options) return;  // only its name and description (main.cpp)
  run->add_option("file", a->load.path, "The .mech file")->required();
  run->add_option("-o,--out", a->out_path, "Write the CSV to this file (default: stdout)");
  run->add_option("--model", a->load.model, "Model to simulate (default: the last one in the file)");
  AddUrdfOptions(*run, &a->load.floating, &a->load.stops, &a->load.package_paths);
  run->add_option("--set", a->load.sets, "Set a parameter or an input, name=value (repeatable)")->allow_extra_args(false);
  AddInputFileOption(*run, &a->load.input_files);
  AddNumberOption(run, "--start-time", &a->spec.start_time, "Start time (default: experiment StartTime)");
  AddNumberOption(run, "--stop-time", &a->spec.stop_time, "Stop time (default: experiment StopTime)");
  AddNumberOption(run, "--interval", &a->spec.interval,
                  "Output interval (default: experiment Interval, else (stop - start) / 500)");
  AddNumberOption(run, "--rtol", &a->spec.rtol, "Relative tolerance (default: experiment Tolerance)");
  AddNumberOption(run, "--atol", &a->spec.atol, "Absolute tolerance (default: = rtol)");
  run->add_option("--output", a->spec.outputs,
                  "Signals to write: a glob over dotted names, * any run, ? one character (repeatable)")
      ->allow_extra_args(false);
  run->add_option("--solver", a->solver, "Solution path")->check(CLI::IsMember(pipeline::SolverNames()));
  run->add_option("--integrator", a->integrator, "Time integrator")
      ->check(CLI::IsMember(pipeline::IntegratorNames()));
  run->add_option("--linear-solver", a->linear_solver,
                  "The Newton iteration's linear solver (IDA, CVODE-BDF): auto (matrix-free GMRES on the multiplier "
                  "form: CVODE-BDF always, IDA with few degrees of freedom; else KLU when the block pattern is sparse), "
                  "dense, klu (IDA) or krylov")
      ->check(CLI::IsMember(pipeline::LinearSolverNames()));
  run->add_option("--projection", a->projection, kProjectionHelp)->check(CLI::IsMember({"eval", "step"}));
  run->add_option("--reactions", a->reactions,
                  "Statically indeterminate constraint-force components: nan, or their min-norm share")
      ->check(CLI::IsMember(pipeline::ReactionsNames()));
  run->add_option("--energy-check", a->energy_check, kEnergyCheckHelp)
      ->check(CLI::IsMember(pipeline::EnergyCheckNames()));
  run->add_option("--speeds", a->speeds, kSpeedsHelp)->check(CLI::IsMember({"joint", "diagonal"}));
  run->add_option("--speed-order", a->spec.speed_order, kSpeedOrderHelp)->delimiter(',')->allow_extra_args(false);
  run->add_flag("--units-in-header", a->units_in_header, "Write each column's unit into the CSV header: 'hinge.q [rad]'");
  run->add_flag("--stats", a->stats, "Print solver statistics and wall time per phase to stderr");
  run->add_option("--events", a->events_path,
                  "Write the events (end stops, when clauses) to this CSV file: time, element, kind, and each "
                  "changed state entry before and after");
  CLI::Option* animation =
      run->add_option("--animation", a->animation,
                      "Also write the motion as an animated glTF 2.0 file: out.glb, or out.gltf (with out.bin)");
  run->add_flag("--show-frames", a->show_frames, "With --animation: draw every joint's frames as small x/y/z axes")
      ->needs(animation);
  run->add_option("--sensitivity", a->spec.sensitivity,
                  "Also write d(y)/d(p) for every output y and each of these Real parameters (comma-separated; start "
                  "values too, e.g. j.q.start)")
      ->delimiter(',')
      ->excludes(animation);
  run->callback([a, exit_code] { *exit_code = RunCommand(*a); });
}

}  // namespace kanesim::cli
