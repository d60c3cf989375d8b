// `kanesim run file.mech`: load, compile, simulate, write CSV (DESIGN.md "The command
// line"). Defaults come from the model's experiment annotation:
//   start time  experiment StartTime, else 0         (--start-time)
//   stop time   experiment StopTime, else 1          (--stop-time)
//   interval    experiment Interval, else (stop - start) / 500   (--interval)
//   rtol        experiment Tolerance, else 1e-6      (--rtol)
//   atol        = rtol                               (--atol)
// atol = rtol because the states are angles (rad), lengths (m) and their rates, all of
// order one in the units mechanisms are written in; a scene with very small or very
// large states should set --atol.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fmt/core.h>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "cli/common.h"
#include "cli/number_options.h"
#include "cli/scene.h"
#include "runtime/batch/file_guard.h"
#include "runtime/engine.h"
#include "runtime/sim/csv.h"
#include "runtime/sim/signal_select.h"
#include "runtime/sim/simulate.h"

namespace kanesim::cli {
namespace {

using Clock = std::chrono::steady_clock;

struct RunArgs {
  LoadOptions load;
  std::string out_path;  // "" or "-": stdout
  double start_time = 0.0, stop_time = 0.0, interval = 0.0, rtol = 0.0, atol = 0.0;
  CLI::Option* start_opt = nullptr;
  CLI::Option* stop_opt = nullptr;
  CLI::Option* interval_opt = nullptr;
  CLI::Option* rtol_opt = nullptr;
  CLI::Option* atol_opt = nullptr;
  std::vector<std::string> patterns;
  std::string solver = "auto";
  std::string integrator = "auto";
  std::string linear_solver = "auto";
  std::string projection = "eval";
  std::string reactions = "nan";
  bool stats = false;
  std::string animation;  // --animation out.glb|out.gltf ("" = none; cli/animation.cpp)
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

double Since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

rt::SolverPath SolverFromName(const std::string& s) {
  if (s == "dense") return rt::SolverPath::Dense;
  if (s == "sparse") return rt::SolverPath::Sparse;
  if (s == "recursive") return rt::SolverPath::Recursive;
  return rt::SolverPath::Auto;
}

rt::IntegratorKind IntegratorFromName(const std::string& s) {
  if (s == "ida") return rt::IntegratorKind::IDA;
  if (s == "cvode" || s == "cvode-bdf") return rt::IntegratorKind::CVODE;
  if (s == "arkode") return rt::IntegratorKind::ARKODE;
  if (s == "dop853") return rt::IntegratorKind::DOP853;
  return rt::IntegratorKind::Auto;
}

int RunCommand(const RunArgs& a) {
  Clock::time_point t_load = Clock::now();
  flat::Mechanism mech;
  if (!LoadModel(a.load, &mech)) return kExitModelError;
  double load_seconds = Since(t_load);

  Clock::time_point t_compile = Clock::now();
  rt::CompileOptions copts;
  copts.solver = SolverFromName(a.solver);
  copts.integrator = IntegratorFromName(a.integrator);
  ReactionsFromName(a.reactions, &copts);
  if (a.start_opt->count() > 0) copts.start_time = a.start_time;  // the integrator choice
  if (a.stop_opt->count() > 0) copts.stop_time = a.stop_time;     // depends on the horizon
  if (a.rtol_opt->count() > 0) copts.rtol = a.rtol;               // and the tolerance
  rt::CompileResult compiled;
  if (!CompileModel(mech, copts, &compiled)) return kExitModelError;
  const rt::Program& program = *compiled.program;
  if (copts.solver != rt::SolverPath::Auto && rt::Summarize(program).solver != copts.solver)
    fmt::print(stderr, "kanesim: note: solver {}\n", rt::Summarize(program).solver_reason);
  double compile_seconds = Since(t_compile);

  const flat::Experiment& ex = mech.experiment;
  sim::SimOptions so;
  if (a.start_opt->count() > 0) so.start_time = a.start_time;
  so.stop_time = a.stop_opt->count() > 0 ? a.stop_time : ex.stop_time;
  for (auto [opt, value] : {std::pair{a.interval_opt, a.interval}, {a.rtol_opt, a.rtol}, {a.atol_opt, a.atol}}) {
    if (opt->count() > 0 && !(value > 0.0 && std::isfinite(value))) {
      fmt::print(stderr, "kanesim: error: {} must be a positive number, got {}\n", opt->get_name(), value);
      return kExitModelError;
    }
  }
  if (a.interval_opt->count() > 0)
    so.interval = a.interval;
  else if (ex.has_interval)
    so.interval = ex.interval;
  so.rtol = a.rtol_opt->count() > 0 ? a.rtol : ex.tolerance;
  so.atol = a.atol_opt->count() > 0 ? a.atol : so.rtol;
  so.integrator = copts.integrator;
  so.cvode_bdf = a.integrator == "cvode-bdf";
  so.ida_linear_solver = IdaLinearSolverFromName(a.linear_solver);
  so.project_steps = a.projection == "step";

  if (!a.patterns.empty()) {
    std::string error;
    if (!sim::SelectSignals(rt::AvailableSignals(program), a.patterns, &so.signals, &error)) {
      fmt::print(stderr, "kanesim: error: {}\n", error);
      return kExitModelError;
    }
  }
  WarnIndeterminate(program, so.signals);
  AnimationRun animation(a.animation);  // the bodies' poses ride along with the CSV's signals
  if (!animation.Prepare(mech, program, &so.signals)) return kExitModelError;

  if (std::string w = sim::ToleranceWarning(so.rtol); !w.empty()) fmt::print(stderr, "kanesim: warning: {}\n", w);
  const sim::OutputGrid grid = sim::ResolveGrid(program, so);
  if (std::string why = sim::CheckRun(grid, so.rtol, so.atol); !why.empty()) {
    fmt::print(stderr, "kanesim: error: {}\n", why);
    return kExitModelError;
  }

  // The output: never the model itself, and one writer at a time (locked while written;
  // only a regular file, not /dev/null or a pipe, which many may share).
  bool to_stdout = a.out_path.empty() || a.out_path == "-";
  batch::FileLock out_lock;
  if (!to_stdout) {
    if (std::string in = batch::OverwrittenInput(a.out_path, {a.load.path}); !in.empty()) {
      fmt::print(stderr, "kanesim: error: -o '{}' is the model '{}'; writing the CSV there would destroy it\n",
                 a.out_path, in);
      return kExitModelError;
    }
    std::error_code ec;
    const auto status = std::filesystem::status(a.out_path, ec);
    std::string lock_error;
    if ((ec || std::filesystem::is_regular_file(status) || !std::filesystem::exists(status)) &&
        !out_lock.Acquire(a.out_path, "'" + a.out_path + "'", &lock_error)) {
      fmt::print(stderr, "kanesim: error: {}\n", lock_error);
      return kExitModelError;
    }
  }
  std::FILE* out = to_stdout ? stdout : std::fopen(a.out_path.c_str(), "w");
  if (!out) {
    fmt::print(stderr, "kanesim: error: cannot open '{}' for writing: {}\n", a.out_path, std::strerror(errno));
    return kExitModelError;
  }
  double start_for_bar = std::isnan(so.start_time) ? rt::StartTime(program) : so.start_time;
  bool bar_enabled = isatty(STDERR_FILENO) && !(to_stdout && isatty(STDOUT_FILENO));
  sim::SimResult result;
  {
    ProgressBar bar(start_for_bar, so.stop_time, bar_enabled);
    so.progress = [&bar](double t) { bar.Update(t); };
    sim::CsvWriter writer(out);
    result = sim::Simulate(program, so, animation.Wrap(writer));
  }
  bool close_ok = to_stdout ? std::fflush(stdout) == 0 : std::fclose(out) == 0;
  const bool animation_ok = animation.Finish();  // also the rows before a numerical failure

  if (a.stats) {
    result.stats.times.load = load_seconds;
    result.stats.times.compile = compile_seconds;
    fmt::print(stderr, "{}", sim::FormatStats(result.stats));
  }
  switch (result.status) {
    case sim::SimResult::Status::kOk: break;
    case sim::SimResult::Status::kUsageError:
      fmt::print(stderr, "kanesim: error: {}\n", result.message);
      return kExitModelError;
    case sim::SimResult::Status::kOutputError:
      fmt::print(stderr, "kanesim: error: {} ({})\n", result.message, to_stdout ? "stdout" : a.out_path);
      return kExitModelError;
    case sim::SimResult::Status::kNumericalFailure:
      fmt::print(stderr, "kanesim: numerical failure at t = {}: {}\n", result.fail_time, result.message);
      return kExitNumerical;
  }
  if (!close_ok) {
    fmt::print(stderr, "kanesim: error: cannot write the output ({})\n", to_stdout ? "stdout" : a.out_path);
    return kExitModelError;
  }
  if (!animation_ok) return kExitModelError;
  return kExitOk;
}

}  // namespace

void AddRunCommand(CLI::App& app, int* exit_code) {
  auto a = std::make_shared<RunArgs>();
  CLI::App* run = app.add_subcommand("run", "Simulate a model and write its motion as CSV");
  run->add_option("file", a->load.path, "The .mech file")->required();
  run->add_option("-o,--out", a->out_path, "Write the CSV to this file (default: stdout)");
  run->add_option("--model", a->load.model, "Model to simulate (default: the last one in the file)");
  run->add_option("--set", a->load.sets, "Set a parameter, name=value (repeatable)")->allow_extra_args(false);
  a->start_opt = AddNumberOption(run, "--start-time", &a->start_time, "Start time (default: experiment StartTime)");
  a->stop_opt = AddNumberOption(run, "--stop-time", &a->stop_time, "Stop time (default: experiment StopTime)");
  a->interval_opt = AddNumberOption(run, "--interval", &a->interval,
                                    "Output interval (default: experiment Interval, else (stop - start) / 500)");
  a->rtol_opt = AddNumberOption(run, "--rtol", &a->rtol, "Relative tolerance (default: experiment Tolerance)");
  a->atol_opt = AddNumberOption(run, "--atol", &a->atol, "Absolute tolerance (default: = rtol)");
  run->add_option("--output", a->patterns,
                  "Signals to write: a glob over dotted names, * any run, ? one character (repeatable)")
      ->allow_extra_args(false);
  run->add_option("--solver", a->solver, "Solution path")->check(CLI::IsMember({"auto", "dense", "sparse", "recursive"}));
  run->add_option("--integrator", a->integrator, "Time integrator")
      ->check(CLI::IsMember({"auto", "ida", "cvode", "cvode-bdf", "arkode", "dop853"}));
  run->add_option("--linear-solver", a->linear_solver,
                  "IDA's Newton matrix: auto (KLU when its block pattern is sparse), dense or klu")
      ->check(CLI::IsMember({"auto", "dense", "klu"}));
  run->add_option("--projection", a->projection, kProjectionHelp)->check(CLI::IsMember({"eval", "step"}));
  run->add_option("--reactions", a->reactions,
                  "Statically indeterminate constraint-force components: nan, or their min-norm share")
      ->check(CLI::IsMember({"nan", "min-norm"}));
  run->add_flag("--stats", a->stats, "Print solver statistics and wall time per phase to stderr");
  run->add_option("--animation", a->animation,
                  "Also write the motion as an animated glTF 2.0 file: out.glb, or out.gltf (with out.bin)");
  run->callback([a, exit_code] { *exit_code = RunCommand(*a); });
}

}  // namespace kanesim::cli
