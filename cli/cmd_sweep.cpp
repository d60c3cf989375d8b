// `kanesim sweep`: many scenarios of one model, in parallel, one summary row each
// (docs/sweeps.md). The model is loaded and compiled here; runtime/batch does the rest.
//   kanesim sweep FILE.mech|SWEEP.toml [scenario sources] [--metric M]... [-o DIR] ...
//   kanesim sweep merge INPUT... [-o OUT.csv]
// Exit codes: 0 every scenario ok; 1 usage/model error or interrupted; 2 the sweep
// completed but some scenarios failed (their rows say why).
#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fmt/core.h>
#include <memory>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "cli/batch_cli.h"
#include "cli/common.h"
#include "runtime/batch/summary.h"
#include "runtime/batch/sweep.h"
#include "runtime/batch/sweep_toml.h"
#include "runtime/program.h"
#include "runtime/sim/csv.h"
#include "runtime/sim/signal_select.h"

namespace kanesim::cli {
namespace {

constexpr double kNaN = batch::kUnset;

struct SweepArgs {
  std::string file;
  LoadOptions load;
  std::vector<std::string> grids, uniforms, normals, metrics, patterns;
  std::string list;
  int sample = 0;
  long long seed = 1;
  bool lhs = false;
  std::string out_dir;
  bool trajectories = false;
  int threads = 0;
  bool resume = false;
  std::string shard;
  bool mpi = false;
  bool no_progress = false;
  double start_time = kNaN, stop_time = kNaN, interval = kNaN, rtol = kNaN, atol = kNaN;
  std::string solver = "auto", integrator = "auto", linear_solver = "auto";
  std::string reactions = "nan";
  std::string projection = "eval";
};

struct MergeArgs {
  std::vector<std::string> inputs;
  std::string out = "sweep-out/summary.csv";
};

std::atomic<bool> g_interrupted{false};
extern "C" void OnSigint(int) { g_interrupted.store(true); }

bool Fail(const std::string& msg) {
  fmt::print(stderr, "kanesim: error: {}\n", msg);
  return false;
}

int FailExit(const std::string& msg) {
  Fail(msg);
  return kExitModelError;
}

// "K/N" (no std::regex: GCC 12 reports false maybe-uninitialized warnings in it under
// the sanitizers).
bool ParseShard(const std::string& text, int* k, int* n) {
  int used = 0;
  if (std::sscanf(text.c_str(), "%d/%d%n", k, n, &used) != 2 || used != static_cast<int>(text.size())) return false;
  return *n >= 1 && *k >= 1 && *k <= *n;
}

// K and N of ".../summary.shard-K-of-N.csv"; false for other names.
bool ShardOfFile(const std::string& path, int* k, int* n) {
  std::string name = std::filesystem::path(path).filename().string();
  int used = 0;
  return std::sscanf(name.c_str(), "summary.shard-%d-of-%d.csv%n", k, n, &used) == 2 &&
         used == static_cast<int>(name.size());
}

// Builds the scenario sources and the run settings from the TOML file (if any) and the
// command line; the command line adds sources and overrides settings.
bool BuildConfig(SweepArgs& a, batch::SweepConfig* c, std::vector<batch::Block>* blocks, std::string* model_name) {
  std::string err;
  batch::SweepFileSpec file;
  if (a.file.size() > 5 && a.file.ends_with(".toml")) {
    if (!batch::ReadSweepToml(a.file, &file, &err)) return Fail(err);
    if (file.model.empty()) return Fail(a.file + ": the sweep file needs model = \"file.mech\"");
    a.load.path = file.model;
    if (a.load.model.empty()) a.load.model = file.model_name;
    a.load.sets.insert(a.load.sets.begin(), file.sets.begin(), file.sets.end());
    *blocks = file.blocks;
    a.metrics.insert(a.metrics.begin(), file.metrics.begin(), file.metrics.end());
    a.patterns.insert(a.patterns.begin(), file.signals.begin(), file.signals.end());
    for (auto [from, to] : {std::pair{file.start_time, &a.start_time}, {file.stop_time, &a.stop_time},
                            {file.interval, &a.interval}, {file.rtol, &a.rtol}, {file.atol, &a.atol}})
      if (std::isnan(*to)) *to = from;
    if (a.integrator == "auto" && !file.integrator.empty()) a.integrator = file.integrator;
    if (!IsIntegratorName(a.integrator))
      return Fail(a.file + ": integrator = \"" + a.integrator + "\": unknown (" + kIntegratorNames + ")");
    if (a.solver == "auto" && !file.solver.empty()) a.solver = file.solver;
    if (a.out_dir.empty()) a.out_dir = file.output_dir;
    a.trajectories = a.trajectories || file.trajectories;
  } else {
    a.load.path = a.file;
  }
  *model_name = a.load.model;
  for (const std::string& g : a.grids) {
    batch::Block b;
    if (!batch::ParseGrid(g, &b, &err)) return Fail("--grid " + err);
    blocks->push_back(std::move(b));
  }
  if (!a.list.empty()) {
    batch::Block b;
    if (!batch::ReadListCsv(a.list, &b, &err)) return Fail("--list: " + err);
    blocks->push_back(std::move(b));
  }
  if (a.sample > 0 || !a.uniforms.empty() || !a.normals.empty()) {
    batch::SampleSpec spec;
    spec.n = a.sample;
    spec.seed = static_cast<std::uint64_t>(a.seed);
    spec.latin_hypercube = a.lhs;
    if (spec.n <= 0) return Fail("--uniform/--normal need --sample N (N > 0)");
    for (const std::string& u : a.uniforms) {
      batch::Distribution d;
      if (!batch::ParseDistribution(u, batch::Distribution::Kind::Uniform, &d, &err)) return Fail(err);
      spec.dists.push_back(d);
    }
    for (const std::string& nrm : a.normals) {
      batch::Distribution d;
      if (!batch::ParseDistribution(nrm, batch::Distribution::Kind::Normal, &d, &err)) return Fail(err);
      spec.dists.push_back(d);
    }
    if (spec.dists.empty()) return Fail("--sample needs at least one --uniform or --normal");
    blocks->push_back(batch::SampleBlock(spec));
  }
  if (blocks->empty()) return Fail("no scenarios: give --grid, --list, --sample or a sweep.toml");
  if (!batch::CombineBlocks(*blocks, &c->param_names, &c->scenarios, &err)) return Fail(err);
  for (const std::string& m : a.metrics) {
    batch::Metric metric;
    if (!batch::ParseMetric(m, &metric, &err)) return Fail(err);
    c->metrics.push_back(metric);
  }
  c->out_dir = a.out_dir.empty() ? "sweep-out" : a.out_dir;
  c->trajectories = a.trajectories;
  c->threads = a.threads;
  c->resume = a.resume;
  if (!a.shard.empty()) {
    int k = 0, n = 0;
    if (!ParseShard(a.shard, &k, &n)) return Fail("--shard needs K/N with 1 <= K <= N, got '" + a.shard + "'");
    c->shard_index = k - 1;
    c->shard_count = n;
  }
  for (double v : {a.interval, a.rtol, a.atol})
    if (!std::isnan(v) && !(v > 0.0 && std::isfinite(v))) return Fail("intervals and tolerances must be positive");
  return true;
}

int SweepCommand(SweepArgs a) {
  batch::SweepConfig config;
  std::vector<batch::Block> blocks;
  std::string model_name;
  if (!BuildConfig(a, &config, &blocks, &model_name)) return kExitModelError;

  // The base program: the model with the fixed --set values.
  flat::Mechanism mech;
  if (!LoadModel(a.load, &mech)) return kExitModelError;
  rt::CompileOptions copts;
  copts.solver = SolverFromName(a.solver);
  copts.integrator = IntegratorFromName(a.integrator);
  copts.start_time = a.start_time;  // NaN when not given: the experiment's
  copts.stop_time = a.stop_time;
  copts.rtol = a.rtol;
  ReactionsFromName(a.reactions, &copts);
  rt::CompileResult compiled;
  if (!CompileModel(mech, copts, &compiled)) return kExitModelError;
  std::shared_ptr<const rt::Program> base = compiled.program;
  config.sim = ResolveSimOptions(mech.experiment, a.start_time, a.stop_time, a.interval, a.rtol, a.atol, a.integrator);
  config.sim.ida_linear_solver = IdaLinearSolverFromName(a.linear_solver);
  config.sim.project_steps = a.projection == "step";
  if (!a.patterns.empty()) {
    std::string err;
    if (!sim::SelectSignals(rt::AvailableSignals(*base), a.patterns, &config.trajectory_signals, &err))
      return FailExit(err);
    config.trajectories = true;
  }
  std::vector<std::string> used = config.trajectory_signals;
  for (const batch::Metric& m : config.metrics) used.push_back(m.signal);
  WarnIndeterminate(*base, used);
  if (config.metrics.empty() && !config.trajectories)
    fmt::print(stderr, "kanesim: note: no --metric given; the summary has status and statistics only\n");

  // Structural variants: the model elaborated again with the structural values.
  LoadOptions load = a.load;
  std::shared_ptr<const flat::Mechanism> base_mech = base->mech;
  batch::VariantBuilder build = [load, copts, base_mech](const std::vector<std::pair<std::string, double>>& structural,
                                                         std::string* error) -> std::shared_ptr<const rt::Program> {
    LoadOptions lo = load;
    for (const auto& [name, v] : structural) {
      int i = base_mech->FindParam(name);
      bool boolean = i >= 0 && base_mech->params[static_cast<size_t>(i)].type == flat::ParamType::Boolean;
      lo.sets.push_back(name + "=" + (boolean ? (v != 0.0 ? "true" : "false") : sim::FormatNumber(v)));
    }
    flat::Mechanism m;
    rt::CompileResult r;
    std::string what;
    for (const auto& [name, v] : structural) what += " " + name + "=" + sim::FormatNumber(v);
    if (!LoadModel(lo, &m) || !CompileModel(m, copts, &r)) {
      *error = "the model does not elaborate or compile with" + what + " (diagnostics on stderr)";
      return nullptr;
    }
    return r.program;
  };

  CountProgress bar(!a.no_progress);
  config.progress = [&bar](const batch::SweepProgress& p) {
    bar.Update(p.done + p.skipped, p.failed, p.total, p.elapsed);
  };
  g_interrupted.store(false);
  config.cancel = &g_interrupted;
  auto old_handler = std::signal(SIGINT, OnSigint);
  batch::SweepReport report;
  std::string err;
  auto t0 = std::chrono::steady_clock::now();
  bool ok = a.mpi ? batch::RunSweepMpi(base, build, config, &report, &err)
                  : batch::RunSweep(base, build, config, &report, &err);
  std::signal(SIGINT, old_handler);
  bar.Finish();
  if (!ok) return FailExit(err);
  if (!report.is_root) return kExitOk;
  const batch::SweepProgress& p = report.progress;
  double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  unsigned hw = std::max(1u, std::thread::hardware_concurrency());
  fmt::print(stderr,
             "sweep: {} scenario{} ({} run, {} failed, {} skipped as done) in {:.2f} s {}; {} program{} "
             "compiled (the base model and one per structural variant); summary: {}\n",
             p.total, p.total == 1 ? "" : "s", p.done, p.failed, p.skipped, secs,
             a.mpi ? std::string("over MPI ranks")
                   : fmt::format("on {} thread{}", a.threads > 0 ? a.threads : static_cast<int>(hw),
                                 (a.threads == 1 || (a.threads <= 0 && hw == 1)) ? "" : "s"),
             report.variants, report.variants == 1 ? "" : "s", report.summary_path);
  if (report.interrupted) {
    fmt::print(stderr, "kanesim: interrupted: {} of {} scenarios done; run again with --resume to finish\n",
               p.done + p.skipped, p.total);
    return kExitModelError;
  }
  return p.failed > 0 ? kExitNumerical : kExitOk;
}

int MergeCommand(const MergeArgs& a) {
  std::vector<std::string> files;
  for (const std::string& in : a.inputs) {
    if (std::filesystem::is_directory(in)) {
      std::vector<std::string> found;
      for (const auto& e : std::filesystem::directory_iterator(in)) {
        std::string name = e.path().filename().string();
        if (name.starts_with("summary.shard-") && name.ends_with(".csv")) found.push_back(e.path().string());
      }
      std::sort(found.begin(), found.end());
      if (found.empty()) return FailExit("'" + in + "' holds no summary.shard-*.csv");
      files.insert(files.end(), found.begin(), found.end());
    } else {
      files.push_back(in);
    }
  }
  // Shard names say K-of-N: report shards that are missing.
  std::set<int> seen;
  int count = 0;
  for (const std::string& f : files) {
    int k = 0, n = 0;
    if (ShardOfFile(f, &k, &n)) seen.insert(k), count = n;
  }
  batch::SummaryTable table;
  std::string err;
  if (!batch::MergeSummaries(files, &table, &err)) return FailExit(err);
  std::filesystem::path out(a.out);
  if (out.has_parent_path()) std::filesystem::create_directories(out.parent_path());
  if (!batch::WriteFileAtomic(a.out, batch::FormatSummary(table), &err)) return FailExit(err);
  fmt::print(stderr, "merge: {} file{}, {} scenarios -> {}\n", files.size(), files.size() == 1 ? "" : "s",
             table.rows.size(), a.out);
  if (count > 0 && static_cast<int>(seen.size()) < count) {
    std::string missing;
    for (int k = 1; k <= count; ++k)
      if (!seen.count(k)) missing += (missing.empty() ? "" : ", ") + std::to_string(k);
    fmt::print(stderr, "kanesim: warning: shard{} {} of {} missing\n", missing.find(',') == std::string::npos ? "" : "s",
               missing, count);
  }
  return kExitOk;
}

}  // namespace

void AddSweepCommand(CLI::App& app, int* exit_code) {
  auto a = std::make_shared<SweepArgs>();
  CLI::App* sw = app.add_subcommand("sweep", "Run many scenarios of a model; one summary row per scenario");
  sw->add_option("file", a->file, "The .mech file, or a sweep .toml file");
  sw->add_option("--model", a->load.model, "Model to simulate (default: the last one in the file)");
  sw->add_option("--set", a->load.sets, "Fix a parameter for every scenario, name=value (repeatable)")
      ->allow_extra_args(false);
  sw->add_option("--grid", a->grids, "name=a:step:b or name=v1,v2,... (repeatable; Cartesian product)")
      ->allow_extra_args(false);
  sw->add_option("--list", a->list, "CSV of scenarios: a header of parameter names (and stop_time, rtol, atol)");
  sw->add_option("--sample", a->sample, "Number of random scenarios (with --uniform / --normal)");
  sw->add_option("--uniform", a->uniforms, "name=low:high (repeatable)")->allow_extra_args(false);
  sw->add_option("--normal", a->normals, "name=mean,sd (repeatable)")->allow_extra_args(false);
  sw->add_option("--seed", a->seed, "Random seed (default 1)");
  sw->add_flag("--lhs,--latin-hypercube", a->lhs, "Latin hypercube instead of independent draws");
  sw->add_option("--metric", a->metrics,
                 "final|min|max|mean|rms:SIGNAL or cross:SIGNAL=LEVEL (repeatable)")
      ->allow_extra_args(false);
  sw->add_option("-o,--out", a->out_dir, "Output directory (default sweep-out)");
  sw->add_flag("--trajectories", a->trajectories, "Write one CSV per scenario into DIR/trajectories");
  sw->add_option("--output", a->patterns, "Trajectory signals, globs like `kanesim run --output` (implies "
                                          "--trajectories)")
      ->allow_extra_args(false);
  sw->add_option("-j,--jobs", a->threads, "Threads (default: all cores)");
  sw->add_flag("--resume", a->resume, "Keep the scenarios already in the summary and run the rest");
  sw->add_option("--shard", a->shard, "K/N: run the K-th of N disjoint slices (id mod N == K-1)");
  sw->add_flag("--mpi", a->mpi, "Spread scenarios over MPI ranks (mpirun -n R kanesim sweep --mpi ...)");
  sw->add_flag("--no-progress", a->no_progress, "No progress bar");
  sw->add_option("--start-time", a->start_time, "Start time (default: experiment StartTime)");
  sw->add_option("--stop-time", a->stop_time, "Stop time (default: experiment StopTime)");
  sw->add_option("--interval", a->interval, "Output interval (default: experiment Interval)");
  sw->add_option("--rtol", a->rtol, "Relative tolerance (default: experiment Tolerance)");
  sw->add_option("--atol", a->atol, "Absolute tolerance (default: = rtol)");
  sw->add_option("--solver", a->solver, "Solution path")->check(CLI::IsMember({"auto", "dense", "sparse", "recursive"}));
  sw->add_option("--integrator", a->integrator, "Time integrator")
      ->check(CLI::IsMember({"auto", "ida", "cvode", "cvode-bdf", "arkode", "dop853"}));
  sw->add_option("--linear-solver", a->linear_solver,
                 "IDA's Newton matrix: auto (KLU when its block pattern is sparse), dense or klu")
      ->check(CLI::IsMember({"auto", "dense", "klu"}));
  sw->add_option("--projection", a->projection, kProjectionHelp)->check(CLI::IsMember({"eval", "step"}));
  sw->add_option("--reactions", a->reactions,
                 "Statically indeterminate constraint-force components: nan, or their min-norm share")
      ->check(CLI::IsMember({"nan", "min-norm"}));

  auto m = std::make_shared<MergeArgs>();
  CLI::App* merge = sw->add_subcommand("merge", "Join shard summaries into one");
  merge->add_option("inputs", m->inputs, "Shard summary files, or folders holding summary.shard-*.csv")->required();
  merge->add_option("-o,--out", m->out, "Merged summary (default sweep-out/summary.csv)");
  merge->callback([m, exit_code] { *exit_code = MergeCommand(*m); });

  sw->callback([a, sw, merge, exit_code] {
    if (merge->parsed()) return;
    if (a->file.empty()) {
      fmt::print(stderr, "kanesim: error: sweep needs a .mech or sweep .toml file\n{}", sw->help());
      *exit_code = kExitModelError;
      return;
    }
    *exit_code = SweepCommand(*a);
  });
}

}  // namespace kanesim::cli
