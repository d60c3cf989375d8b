// `kanesim sweep`: many scenarios of one model, in parallel, one summary row each
// (docs/sweeps.md). The model is loaded and compiled here; batch does the rest.
//   kanesim sweep FILE.mech|SWEEP.toml [scenario sources] [--metric M]... [-o DIR] ...
//   kanesim sweep merge INPUT... [-o OUT.csv]
// Exit codes: 0 every scenario ok; 1 usage/model error or interrupted; 2 the sweep
// completed but some scenarios failed, crashed or timed out (their rows say why).
#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <climits>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fmt/core.h>
#include <iostream>
#include <memory>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "cli/batch_cli.h"
#include "cli/common.h"
#include "import/import.h"
#include "cli/number_options.h"
#include "batch/csv_util.h"
#include "batch/file_guard.h"
#include "batch/settings_record.h"
#include "batch/summary.h"
#include "batch/sweep.h"
#include "batch/sweep_toml.h"
#include "runtime/program/program.h"
#include "sim/csv.h"
#include "sim/signal_select.h"

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
  std::string isolation = "process";  // --isolation (SweepConfig::Isolation)
  double scenario_timeout = 0.0;      // --scenario-timeout, seconds; 0: none
  double worker_memory = 0.0;         // --worker-memory, MiB; 0: no limit
  double start_time = kNaN, stop_time = kNaN, interval = kNaN, rtol = kNaN, atol = kNaN;
  std::string solver = "auto", integrator = "auto", linear_solver = "auto";
  std::string reactions = "nan";
  std::string projection = "eval";
  std::string energy_check = "on";  // --energy-check (RunSpec::energy_check)
};

struct MergeArgs {
  std::vector<std::string> inputs;
  std::string out = "sweep-out/summary.csv";
};

std::atomic<bool> g_interrupted{false};
// The first ^C stops handing out scenarios and lets the running ones finish; the second
// ends the sweep at once (a scenario may hang): every row written so far is on disk, the
// workers die with the sweep process, and --resume continues.
extern "C" void OnSigint(int) {
  g_interrupted.store(true);
  std::signal(SIGINT, SIG_DFL);
}

bool Fail(const std::string& msg) {
  fmt::print(stderr, "kanesim: error: {}\n", msg);
  return false;
}

int FailExit(const std::string& msg) {
  Fail(msg);
  return kExitModelError;
}

// "K/N", two integers (no std::regex: GCC 12 reports false maybe-uninitialized warnings
// in it under the sanitizers).
bool ParseShard(const std::string& text, int* k, int* n) {
  const size_t slash = text.find('/');
  long long kk = 0, nn = 0;
  std::string unused;
  if (slash == std::string::npos || !flat::ParseInteger(text.substr(0, slash), 1, INT_MAX, &kk, &unused) ||
      !flat::ParseInteger(text.substr(slash + 1), 1, INT_MAX, &nn, &unused) || kk > nn)
    return false;
  *k = static_cast<int>(kk);
  *n = static_cast<int>(nn);
  return true;
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
    if (a.solver == "auto" && !file.solver.empty()) a.solver = file.solver;
    pipeline::RunSpec names_only;
    if (!SpecFromNames(a.solver, a.integrator, &names_only, &err)) return Fail(a.file + ": " + err);
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
  c->blocks = *blocks;
  for (const std::string& m : a.metrics) {
    batch::Metric metric;
    if (!batch::ParseMetric(m, &metric, &err)) return Fail(err);
    c->metrics.push_back(metric);
  }
  c->out_dir = a.out_dir.empty() ? "sweep-out" : a.out_dir;
  c->trajectories = a.trajectories;
  c->threads = a.threads;
  c->isolation = a.isolation == "thread" ? batch::SweepConfig::Isolation::kThread : batch::SweepConfig::Isolation::kProcess;
  // 1e6 s (11 days) and 1e9 MiB (1 PB) bound what an int timeout and an rlimit can hold.
  if (!(a.scenario_timeout >= 0.0 && a.scenario_timeout <= 1e6))
    return Fail("--scenario-timeout needs seconds from 0 (none) to 1e6, got " + sim::FormatShortest(a.scenario_timeout));
  if (!(a.worker_memory >= 0.0 && a.worker_memory <= 1e9))
    return Fail("--worker-memory needs MiB from 0 (no limit) to 1e9, got " + sim::FormatShortest(a.worker_memory));
  if (c->isolation == batch::SweepConfig::Isolation::kThread && (a.scenario_timeout > 0.0 || a.worker_memory > 0.0))
    return Fail("--scenario-timeout and --worker-memory need worker processes (--isolation process)");
  c->scenario_timeout = a.scenario_timeout;
  c->worker_memory_mib = a.worker_memory;
  c->resume = a.resume;
  if (!a.shard.empty()) {
    int k = 0, n = 0;
    if (!ParseShard(a.shard, &k, &n)) return Fail("--shard needs K/N with 1 <= K <= N, got '" + a.shard + "'");
    c->shard_index = k - 1;
    c->shard_count = n;
  }
  return true;
}

std::string Join(const std::vector<std::string>& items) {
  std::string out;
  for (const std::string& x : items) out.append(out.empty() ? "" : "; ").append(x);
  return out;
}

// What the summary is made with (batch/settings_record.h): everything that
// decides a scenario's row, resolved (the experiment's defaults filled in).
batch::SettingsRecord SweepSettings(const SweepArgs& a, const batch::SweepConfig& c, const rt::Program& base) {
  batch::SettingsRecord r;
  r.Set("kanesim_version", KANESIM_VERSION);
  r.Set("model", a.load.path);
  r.Set("model_text", "fnv1a64:" + batch::Fnv1a64Hex(ReadFileText(a.load.path)));
  r.Set("stdlib", "fnv1a64:" + StdlibHash());
  // Every other file the model read: its other source files and its data files (meshes;
  // tables later), one key each, named relative to the model's folder; the rows depend on
  // their contents as much as on the model's (issue 38: a resume mixed two meshes).
  const std::filesystem::path model_dir = std::filesystem::absolute(a.load.path).parent_path();
  std::vector<std::string> inputs;
  // A URDF's model is its translation in memory, named PATH.mech (docs/import.md): no file.
  const bool urdf = import::IsUrdfPath(a.load.path);
  for (const std::string& f : base.mech->source_files)
    if (!f.empty() && f[0] != '<' && !batch::SameFile(f, a.load.path) && !(urdf && f == a.load.path + ".mech"))
      inputs.push_back(f);
  inputs.insert(inputs.end(), base.mech->data_files.begin(), base.mech->data_files.end());
  inputs.insert(inputs.end(), a.load.input_files.begin(), a.load.input_files.end());  // --input-file tables
  for (const std::string& f : inputs) {
    std::string text, why;
    const std::string hash = batch::ReadTextFile(f, batch::kMaxDataBytes, &text, &why)
                                 ? "fnv1a64:" + batch::Fnv1a64Hex(text)
                                 : "unreadable";
    r.Set("input_file:" + std::filesystem::absolute(f).lexically_normal().lexically_relative(model_dir).string(), hash);
  }
  if (urdf) r.Set("urdf_floating", a.load.floating ? "true" : "false");  // --floating changes the model
  r.Set("model_name", a.load.model);
  r.Set("set", Join(a.load.sets));
  const sim::OutputGrid grid = sim::ResolveGrid(base, c.sim);
  r.Set("start_time", sim::FormatNumber(grid.start));
  r.Set("stop_time", sim::FormatNumber(grid.stop));
  r.Set("interval", sim::FormatNumber(grid.interval));
  r.Set("rtol", sim::FormatNumber(c.sim.rtol));
  r.Set("atol", sim::FormatNumber(c.sim.atol));
  r.Set("integrator", a.integrator);
  r.Set("solver", a.solver);
  r.Set("linear_solver", a.linear_solver);
  r.Set("projection", a.projection);
  r.Set("energy_check", a.energy_check);
  r.Set("reactions", a.reactions);
  std::vector<std::string> metrics;
  for (const batch::Metric& m : c.metrics) metrics.push_back(m.Column());
  r.Set("metrics", Join(metrics));
  r.Set("trajectories", c.trajectories ? "true" : "false");
  r.Set("signals", Join(c.trajectory_signals));
  r.Set("scenarios", batch::ScenarioDefinitionsDigest(c.param_names, c.scenarios));
  r.Set("shard", std::to_string(c.shard_index + 1) + "/" + std::to_string(c.shard_count));
  return r;
}

int SweepCommand(SweepArgs a) {
  batch::SweepConfig config;
  std::vector<batch::Block> blocks;
  std::string model_name;
  if (!BuildConfig(a, &config, &blocks, &model_name)) return kExitModelError;

  // The run settings, resolved once: the options over the sweep file over the experiment.
  pipeline::RunSpec spec;
  std::string err;
  if (!SpecFromNames(a.solver, a.integrator, &spec, &err)) return FailExit(err);
  pipeline::ReactionsFromName(a.reactions, &spec.reactions);
  pipeline::LinearSolverFromName(a.linear_solver, &spec.linear_solver);
  spec.project_steps = a.projection == "step";
  pipeline::EnergyCheckFromName(a.energy_check, &spec.energy_check);
  spec.start_time = a.start_time;
  spec.stop_time = a.stop_time;
  spec.interval = a.interval;
  spec.rtol = a.rtol;
  spec.atol = a.atol;
  spec.outputs = a.patterns;

  // The base program: the model with the fixed --set values.
  std::shared_ptr<const pipeline::Model> model = LoadAndCompile(a.load, spec);
  if (!model) return kExitModelError;
  std::shared_ptr<const rt::Program> base = model->program;
  // A scenario may override the stop time and tolerances: each scenario's grid is checked
  // by the sweep itself (kGrid is not an error here).
  pipeline::ResolvedRun run;
  pipeline::RunProblem problem = pipeline::RunProblem::kNone;
  if (std::string why = pipeline::ResolveRun(*model, spec, &run, &problem);
      !why.empty() && problem != pipeline::RunProblem::kGrid)
    return FailExit(why);
  config.sim = run.sim;
  // The model's inputs (--input-file): one table, read only, shared by every scenario.
  std::vector<std::string> input_names;
  for (int i = 0; i < rt::NumInputs(*base); ++i) input_names.push_back(rt::InputName(*base, i));
  sim::InputTable input_table(input_names);
  if (!LoadInputTables(*model, a.load.input_files, run.grid.start, run.grid.stop, &input_table))
    return kExitModelError;
  if (!input_names.empty()) config.sim.inputs = &input_table;
  if (!a.patterns.empty()) {
    config.trajectory_signals = run.sim.signals;
    config.trajectories = true;
  }
  config.sim.signals.clear();  // the sweep's signals are trajectory_signals and the metrics'
  config.settings = SweepSettings(a, config, *base);
  config.inputs = {a.load.path};
  if (a.file != a.load.path) config.inputs.push_back(a.file);
  if (!a.list.empty()) config.inputs.push_back(a.list);
  config.inputs.insert(config.inputs.end(), a.load.input_files.begin(), a.load.input_files.end());
  std::vector<std::string> used = config.trajectory_signals;
  for (const batch::Metric& m : config.metrics) used.push_back(m.signal);
  std::cerr << pipeline::RunWarnings(*model, config.sim.rtol, used);
  if (config.metrics.empty() && !config.trajectories)
    fmt::print(stderr, "kanesim: note: no --metric given; the summary has status and statistics only\n");

  // Structural variants: the model elaborated again with the structural values.
  LoadOptions load = a.load;
  std::shared_ptr<const flat::Mechanism> base_mech = base->mech;
  batch::VariantBuilder build = [load, spec, base_mech](const std::vector<std::pair<std::string, double>>& structural,
                                                        std::string* error) -> std::shared_ptr<const rt::Program> {
    LoadOptions lo = load;
    for (const auto& [name, v] : structural) {
      int i = base_mech->FindParam(name);
      bool boolean = i >= 0 && base_mech->params[static_cast<size_t>(i)].type == flat::ParamType::Boolean;
      lo.sets.push_back(name + "=" + (boolean ? (v != 0.0 ? "true" : "false") : sim::FormatNumber(v)));
    }
    std::string what;
    for (const auto& [name, v] : structural) what += " " + name + "=" + sim::FormatNumber(v);
    std::unique_ptr<pipeline::Model> variant = LoadAndCompile(lo, spec);
    if (!variant) {
      *error = "the model does not elaborate or compile with" + what + " (diagnostics on stderr)";
      return nullptr;
    }
    return variant->program;
  };

  CountProgress bar(!a.no_progress);
  config.progress = [&bar](const batch::SweepProgress& p) {
    bar.Update(p.done + p.skipped, p.failed, p.total, p.elapsed);
  };
  g_interrupted.store(false);
  config.cancel = &g_interrupted;
  auto old_handler = std::signal(SIGINT, OnSigint);
  batch::SweepReport report;
  auto t0 = std::chrono::steady_clock::now();
  bool ok = a.mpi ? batch::RunSweepMpi(base, build, config, &report, &err)
                  : batch::RunSweep(base, build, config, &report, &err);
  std::signal(SIGINT, old_handler);
  bar.Finish();
  if (!ok) return FailExit(err);
  if (!report.is_root) return kExitOk;
  for (const std::string& w : report.warnings) fmt::print(stderr, "kanesim: warning: {}\n", w);
  const batch::SweepProgress& p = report.progress;
  double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  unsigned hw = std::max(1u, std::thread::hardware_concurrency());
  const int workers = a.threads > 0 ? a.threads : static_cast<int>(hw);
  const bool processes = config.isolation == batch::SweepConfig::Isolation::kProcess;
  std::string lost;
  if (p.crashed > 0) lost += fmt::format("{} crashed", p.crashed);
  if (p.timed_out > 0) lost += fmt::format("{}{} timed out", lost.empty() ? "" : ", ", p.timed_out);
  fmt::print(stderr,
             "sweep: {} scenario{} ({} run, {} failed{}, {} skipped as done) in {:.2f} s {}; {} program{} "
             "compiled (the base model and the structural variants{}); summary: {}\n",
             p.total, p.total == 1 ? "" : "s", p.done, p.failed, lost.empty() ? "" : " (" + lost + ")", p.skipped, secs,
             a.mpi ? std::string("over MPI ranks")
                   : fmt::format("on {} {}", workers,
                                 processes ? (workers == 1 ? "worker process" : "worker processes")
                                           : (workers == 1 ? "thread" : "threads")),
             report.variants, report.variants == 1 ? "" : "s", processes ? ", once per worker that needed one" : "",
             report.summary_path);
  if (p.crashed + p.timed_out > 0)
    fmt::print(stderr,
               "kanesim: {} scenario{} lost {} worker process (status crashed or timeout in the summary); "
               "--resume runs them again\n",
               p.crashed + p.timed_out, p.crashed + p.timed_out == 1 ? "" : "s",
               p.crashed + p.timed_out == 1 ? "its" : "their");
  if (report.interrupted) {
    fmt::print(stderr, "kanesim: interrupted: {} of {} scenarios done; run again with --resume to finish\n",
               p.done + p.skipped, p.total);
    return kExitModelError;
  }
  return p.failed > 0 ? kExitNumerical : kExitOk;
}

// The sweep's scenarios rebuilt from the sources recorded beside the first input that has
// them (summary.scenarios), checked against the settings record's digest; every row of
// every input must then carry its scenario's parameter values, as `--resume` checks.
bool CheckRowsAgainstScenarios(const std::vector<std::string>& files, const batch::SettingsRecord& settings,
                               std::string* sources_text) {
  std::string source;
  for (const std::string& f : files)
    if (std::filesystem::exists(batch::ScenariosPathFor(f))) {
      source = batch::ScenariosPathFor(f);
      break;
    }
  if (source.empty())
    return Fail("'" + batch::ScenariosPathFor(files[0]) + "' is missing (a sweep writes its scenario sources " +
                "beside its summary), so the rows cannot be checked against their scenario ids");
  std::vector<batch::Block> blocks;
  std::vector<std::string> names;
  std::vector<batch::Scenario> scenarios;
  std::string err;
  if (!batch::ReadTextFile(source, batch::kMaxDataBytes, sources_text, &err)) return Fail(err);
  if (!batch::ParseBlocks(*sources_text, &blocks, &err)) return Fail("'" + source + "', " + err);
  if (!batch::CombineBlocks(blocks, &names, &scenarios, &err)) return Fail("'" + source + "': " + err);
  const std::string* digest = settings.Find("scenarios");
  if (!digest || *digest != batch::ScenarioDefinitionsDigest(names, scenarios))
    return Fail("'" + source + "' does not hold the scenarios its settings record names (edited or from another "
                "sweep)");
  for (const std::string& f : files) {
    batch::SummaryTable t;
    if (!batch::ReadSummary(f, &t, &err)) return Fail(err);
    for (const auto& [id, line] : t.rows)
      if (static_cast<size_t>(id) >= scenarios.size() || !batch::RowMatchesScenario(line, scenarios[static_cast<size_t>(id)]))
        return Fail("'" + f + "': the row of scenario " + std::to_string(id) +
                    (static_cast<size_t>(id) >= scenarios.size()
                         ? " is not a scenario of the sweep (it has " + std::to_string(scenarios.size()) + ")"
                         : " has other parameter values than scenario " + std::to_string(id) + " of the sweep") +
                    "; the file was edited or mixed with another sweep's rows");
  }
  return true;
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
  // Every input must come from the same sweep: same settings record (shard aside).
  batch::SettingsRecord merged_settings;
  for (size_t i = 0; i < files.size(); ++i) {
    const std::string sp = batch::SettingsPathFor(files[i]);
    batch::SettingsRecord rec;
    std::string err;
    if (!std::filesystem::exists(sp))
      return FailExit("'" + files[i] + "' has no settings record ('" + sp +
                      "'), so it cannot be checked to come from the same sweep as the other inputs");
    if (!batch::ReadSettings(sp, &rec, &err)) return FailExit(err);
    if (i == 0) {
      merged_settings = rec;
      continue;
    }
    std::vector<std::string> diff = batch::SettingsDifferences(merged_settings, rec, files[0], files[i]);
    if (!diff.empty()) {
      std::string msg = "'" + files[i] + "' was made with other settings than '" + files[0] + "':";
      for (const std::string& d : diff) msg += "\n    " + d;
      return FailExit(msg);
    }
  }
  std::string sources_text;
  if (!CheckRowsAgainstScenarios(files, merged_settings, &sources_text)) return kExitModelError;
  merged_settings.Set("shard", "merged from " + std::to_string(files.size()) + " file" + (files.size() == 1 ? "" : "s"));
  for (const std::string& path : {a.out, batch::SettingsPathFor(a.out), batch::ScenariosPathFor(a.out)})
    if (std::string in = batch::OverwrittenInput(path, files); !in.empty())
      return FailExit("the merged summary '" + path + "' would overwrite the input '" + in + "'; choose another -o");
  batch::SummaryTable table;
  std::string err;
  if (!batch::MergeSummaries(files, &table, &err)) return FailExit(err);
  std::filesystem::path out(a.out);
  if (out.has_parent_path()) std::filesystem::create_directories(out.parent_path());
  if (!batch::WriteFileAtomic(a.out, batch::FormatSummary(table), &err) ||
      !batch::WriteFileAtomic(batch::ScenariosPathFor(a.out), sources_text, &err) ||
      !batch::WriteFileAtomic(batch::SettingsPathFor(a.out), batch::FormatSettings(merged_settings), &err))
    return FailExit(err);
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

void AddSweepCommand(CLI::App& app, int* exit_code, bool options) {
  auto a = std::make_shared<SweepArgs>();
  CLI::App* sw = app.add_subcommand("sweep", "Run many scenarios of a model; one summary row per scenario");
  if (!options) return;  // only its name and description (main.cpp)
  sw->add_option("file", a->file, "The .mech file, or a sweep .toml file");
  sw->add_option("--model", a->load.model, "Model to simulate (default: the last one in the file)");
  AddUrdfOptions(*sw, &a->load.floating, &a->load.package_paths);
  AddInputFileOption(*sw, &a->load.input_files);
  sw->add_option("--set", a->load.sets, "Fix a parameter for every scenario, name=value (repeatable)")
      ->allow_extra_args(false);
  sw->add_option("--grid", a->grids, "name=a:step:b or name=v1,v2,... (repeatable; Cartesian product)")
      ->allow_extra_args(false);
  sw->add_option("--list", a->list, "CSV of scenarios: a header of parameter names (and stop_time, rtol, atol)");
  AddIntegerOption(sw, "--sample", &a->sample, 1, batch::kMaxScenarios,
                   "Number of random scenarios (with --uniform / --normal)");
  sw->add_option("--uniform", a->uniforms, "name=low:high (repeatable)")->allow_extra_args(false);
  sw->add_option("--normal", a->normals, "name=mean,sd (repeatable)")->allow_extra_args(false);
  AddIntegerOption(sw, "--seed", &a->seed, LLONG_MIN, LLONG_MAX, "Random seed (default 1; taken modulo 2^64)");
  sw->add_flag("--lhs,--latin-hypercube", a->lhs, "Latin hypercube instead of independent draws");
  sw->add_option("--metric", a->metrics,
                 "final|min|max|mean|rms:SIGNAL or cross:SIGNAL=LEVEL (repeatable)")
      ->allow_extra_args(false);
  sw->add_option("-o,--out", a->out_dir, "Output directory (default sweep-out)");
  sw->add_flag("--trajectories", a->trajectories, "Write one CSV per scenario into DIR/trajectories");
  sw->add_option("--output", a->patterns, "Trajectory signals, globs like `kanesim run --output` (implies "
                                          "--trajectories)")
      ->allow_extra_args(false);
  AddIntegerOption(sw, "-j,--jobs", &a->threads, 0, kMaxJobs, "Threads (default 0: all cores)");
  sw->add_flag("--resume", a->resume, "Keep the scenarios already in the summary and run the rest");
  sw->add_option("--shard", a->shard, "K/N: run the K-th of N disjoint slices (id mod N == K-1)");
  sw->add_flag("--mpi", a->mpi, "Spread scenarios over MPI ranks (mpirun -n R kanesim sweep --mpi ...)");
  sw->add_flag("--no-progress", a->no_progress, "No progress bar");
  sw->add_option("--isolation", a->isolation,
                 "process (default): scenarios run in worker processes, so one that crashes, runs out of memory or "
                 "hangs costs its own row only; thread: on threads of one process (a crash ends the sweep)")
      ->check(CLI::IsMember({"process", "thread"}));
  AddNumberOption(sw, "--scenario-timeout", &a->scenario_timeout,
                  "Seconds of wall time a scenario may take; its worker is then killed and the row says timeout "
                  "(default 0: no limit)");
  AddNumberOption(sw, "--worker-memory", &a->worker_memory,
                  "MiB of memory a worker process may allocate; a scenario that needs more fails with 'out of "
                  "memory' (default 0: no limit)");
  AddNumberOption(sw, "--start-time", &a->start_time, "Start time (default: experiment StartTime)");
  AddNumberOption(sw, "--stop-time", &a->stop_time, "Stop time (default: experiment StopTime)");
  AddNumberOption(sw, "--interval", &a->interval, "Output interval (default: experiment Interval)");
  AddNumberOption(sw, "--rtol", &a->rtol, "Relative tolerance (default: experiment Tolerance)");
  AddNumberOption(sw, "--atol", &a->atol, "Absolute tolerance (default: = rtol)");
  sw->add_option("--solver", a->solver, "Solution path")->check(CLI::IsMember(pipeline::SolverNames()));
  sw->add_option("--integrator", a->integrator, "Time integrator")->check(CLI::IsMember(pipeline::IntegratorNames()));
  sw->add_option("--linear-solver", a->linear_solver,
                 "The Newton iteration's linear solver (IDA, CVODE-BDF): auto (matrix-free GMRES on closed loops on the "
                  "multiplier form with few degrees of freedom, else KLU when the block pattern is sparse), dense, klu "
                  "(IDA) or krylov")
      ->check(CLI::IsMember(pipeline::LinearSolverNames()));
  sw->add_option("--projection", a->projection, kProjectionHelp)->check(CLI::IsMember({"eval", "step"}));
  sw->add_option("--energy-check", a->energy_check, kEnergyCheckHelp)
      ->check(CLI::IsMember(pipeline::EnergyCheckNames()));
  sw->add_option("--reactions", a->reactions,
                 "Statically indeterminate constraint-force components: nan, or their min-norm share")
      ->check(CLI::IsMember(pipeline::ReactionsNames()));

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
