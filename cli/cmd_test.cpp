// `kanesim test DIR|SPEC.toml...`: golden-output regression tests (docs/golden_tests.md).
// For each spec: load and compile the model, simulate, compare with the stored output and
// check the spec's invariants. Each test runs whole in a worker process of its own
// (batch/worker_pool.h, -j of them at once), so a test that crashes kanesim
// (a signal, out of memory) or runs past --timeout is reported as CRASH or TIMEOUT and
// the others still run. When no process can be made, the rest run on threads (the front
// end, not re-entrant, one at a time). Prints one report per test in the order given.
// Exit codes: 0 all pass; 3 a regression (a comparison or invariant failed, the model no
// longer loads or runs, or its test crashed or timed out); 1 a usage error (bad spec,
// missing golden without --update). --update rewrites the stored outputs and prints what
// changed.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fmt/core.h>
#include <fstream>
#include <memory>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "cli/batch_cli.h"
#include "cli/common.h"
#include "cli/number_options.h"
#include "batch/csv_util.h"
#include "batch/file_guard.h"
#include "batch/golden.h"
#include "batch/summary.h"
#include "batch/worker_pool.h"
#include "sim/csv.h"
#include "sim/signal_select.h"
#include "stdlib/stdlib.h"

namespace kanesim::cli {
namespace {

struct TestArgs {
  std::vector<std::string> paths;
  bool update = false;
  int threads = 0;
  std::vector<std::string> sets;
  bool verbose = false;
  double timeout = 0.0;  // seconds of wall time per test; 0: none
  double worker_memory = 0.0;  // MiB a test's worker process may allocate; 0: no limit
};

// kCrashed: the worker process running the test died or ran past --timeout (a failure).
enum class Outcome { kPass, kFail, kError, kUpdated, kCrashed };

struct TestResult {
  Outcome outcome = Outcome::kPass;
  std::string report;  // lines printed for this test
};

// A TestResult through a worker's pipe: the outcome as one letter, then the report.
constexpr char kOutcomeCodes[] = {'P', 'F', 'E', 'U', 'C'};
std::string EncodeResult(const TestResult& r) { return kOutcomeCodes[static_cast<int>(r.outcome)] + r.report; }
TestResult DecodeResult(const std::string& s) {
  TestResult r;
  r.outcome = Outcome::kCrashed;
  for (int k = 0; k < 5; ++k)
    if (!s.empty() && s[0] == kOutcomeCodes[k]) r.outcome = static_cast<Outcome>(k);
  r.report = s.empty() ? std::string() : s.substr(1);
  return r;
}


std::string G(double x) { return fmt::format("{:.3g}", x); }

// What changed between an old golden and a new one, one line per signal that moved.
std::string DescribeChanges(const batch::GoldenSpec& spec, const batch::Trajectory& old_golden,
                            const batch::Trajectory& fresh) {
  std::string out;
  batch::CompareResult c = batch::Compare(spec, old_golden, fresh);
  for (const std::string& p : c.problems) out += "    " + p + "\n";
  int unchanged = 0;
  for (const batch::SignalDeviation& d : c.signals) {
    if (d.max_dev == 0.0) {
      ++unchanged;
      continue;
    }
    out += fmt::format("    {}: changed by at most {} at t = {} ({} of its tolerance){}\n", d.signal, G(d.max_dev),
                       G(d.t_max), G(d.worst_ratio), d.failed() ? "  <- beyond tolerance" : "");
  }
  if (unchanged > 0) out += fmt::format("    {} signal{} unchanged\n", unchanged, unchanged == 1 ? "" : "s");
  for (const auto& [k, v] : fresh.provenance) {
    auto it = old_golden.provenance.find(k);
    if (k != "recorded" && k != "rows" && k != "data" && (it == old_golden.provenance.end() || it->second != v))
      out += fmt::format("    provenance {}: {} -> {}\n", k, it == old_golden.provenance.end() ? "(none)" : it->second, v);
  }
  return out;
}

TestResult RunOne(const std::string& spec_path, const TestArgs& args, std::mutex& load_mutex) {
  TestResult r;
  auto t0 = std::chrono::steady_clock::now();
  batch::GoldenSpec spec;
  std::string err;
  if (!batch::ReadGoldenSpec(spec_path, &spec, &err)) {
    r.outcome = Outcome::kError;
    r.report = "ERROR " + spec_path + "\n    " + err + "\n";
    return r;
  }
  pipeline::RunSpec run_spec;
  if (!SpecFromNames(spec.solver, spec.integrator, &run_spec, &err)) {
    r.outcome = Outcome::kError;
    r.report = "ERROR " + spec_path + "\n    run." + err + "\n";
    return r;
  }
  if (!pipeline::EnergyCheckFromName(spec.energy_check, &run_spec.energy_check)) {
    r.outcome = Outcome::kError;
    r.report = "ERROR " + spec_path + "\n    run.energy_check '" + spec.energy_check + "': unknown (" +
               pipeline::JoinNames(pipeline::EnergyCheckNames()) + ")\n";
    return r;
  }
  run_spec.start_time = spec.start_time;  // NaN when the spec leaves it to the experiment
  run_spec.stop_time = spec.stop_time;
  run_spec.interval = spec.interval;
  run_spec.rtol = spec.rtol;
  run_spec.atol = spec.atol;
  run_spec.outputs = spec.signals;
  const std::string label = spec.name;
  auto fail = [&](const std::string& why) {
    r.outcome = Outcome::kFail;
    r.report = "FAIL  " + label + "\n    " + why + "\n";
    return r;
  };
  auto error = [&](const std::string& why) {
    r.outcome = Outcome::kError;
    r.report = "ERROR " + label + "\n    " + why + "\n";
    return r;
  };

  // Stages 1-3, serialized.
  std::unique_ptr<pipeline::Model> model;
  {
    std::lock_guard<std::mutex> lock(load_mutex);
    LoadOptions lo;
    lo.path = spec.model;
    lo.model = spec.model_name;
    lo.sets = spec.sets;
    lo.input_files = spec.input_files;
    lo.sets.insert(lo.sets.end(), args.sets.begin(), args.sets.end());
    if (!std::filesystem::exists(spec.model)) {
      r.outcome = Outcome::kError;
      r.report = "ERROR " + label + "\n    the model '" + spec.model + "' does not exist\n";
      return r;
    }
    model = LoadAndCompile(lo, run_spec);
    if (!model) return fail("the model no longer loads or compiles (diagnostics above)");
  }
  const rt::Program& program = *model->program;

  // Stage 4. Signals: the stored ones, then what the invariants need. Settings a run
  // cannot take are the spec's mistake (exit 1), not a regression.
  pipeline::ResolvedRun run;
  pipeline::RunProblem problem = pipeline::RunProblem::kNone;
  if (std::string why = pipeline::ResolveRun(*model, run_spec, &run, &problem); !why.empty())
    return problem == pipeline::RunProblem::kSignals ? fail("signals: " + why) : error(spec_path + ": " + why);
  std::vector<std::string> available = rt::AvailableSignals(program);
  std::vector<std::string> stored = run.sim.signals.empty() ? rt::DefaultSignals(program) : run.sim.signals;
  std::vector<std::string> names = stored;
  for (const batch::Invariant& inv : spec.invariants)
    for (const std::string& n : batch::InvariantSignals(inv, available))
      if (std::find(names.begin(), names.end(), n) == names.end()) names.push_back(n);
  run.sim.signals = names;
  std::vector<std::string> input_names;
  for (int i = 0; i < rt::NumInputs(program); ++i) input_names.push_back(rt::InputName(program, i));
  sim::InputTable input_table(input_names);
  if (!LoadInputTables(*model, spec.input_files, run.grid.start, run.grid.stop, &input_table))
    return error(spec_path + ": the model's inputs (above)");
  if (!input_names.empty()) run.sim.inputs = &input_table;
  const sim::OutputGrid& grid = run.grid;
  const sim::SimOptions& so = run.sim;
  if (grid.Count() > batch::kMaxGoldenRows)
    return error(fmt::format("{}: the run would have {} instants; a golden stores at most {} (give a larger "
                             "run.interval)",
                             spec_path, grid.Count(), batch::kMaxGoldenRows));
  std::string notes;
  if (std::string w = sim::ToleranceWarning(so.rtol); !w.empty()) notes += "    warning: " + w + "\n";
  sim::MemorySink sink;
  sim::SimResult result = pipeline::Run(*model, run, sink);  // stages 5-6
  if (result.status == sim::SimResult::Status::kNumericalFailure)
    return fail(fmt::format("numerical failure at t = {}: {}", result.fail_time, result.message));
  if (result.status == sim::SimResult::Status::kUsageError) return error(spec_path + ": " + result.message);
  if (result.status != sim::SimResult::Status::kOk) return fail(result.message);

  batch::Trajectory actual;
  actual.names = sink.names;
  actual.t = sink.times;
  actual.rows = sink.rows;
  batch::Trajectory fresh;  // the stored columns only, with provenance
  fresh.names = stored;
  fresh.t = sink.times;
  for (const auto& row : sink.rows) fresh.rows.emplace_back(row.begin(), row.begin() + static_cast<long>(stored.size()));
  fresh.provenance["kanesim_version"] = KANESIM_VERSION;
  fresh.provenance["model"] = std::filesystem::path(spec.model).filename().string() + " fnv1a64:" +
                              batch::Fnv1a64Hex(ReadFileText(spec.model));
  fresh.provenance["stdlib"] = "fnv1a64:" + StdlibHash();
  fresh.provenance["settings"] = "fnv1a64:" + batch::Fnv1a64Hex(batch::SettingsText(spec));
  fresh.provenance["integrator"] = sim::MethodName(result.stats.method);

  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  batch::Trajectory golden;
  const bool golden_exists = std::filesystem::exists(spec.golden_path);
  std::string corrupt;  // why the stored output cannot be used, when it exists
  if (golden_exists && !batch::ReadTrajectoryCsv(spec.golden_path, &golden, &corrupt) && corrupt.empty())
    corrupt = "unreadable";
  const bool have_golden = golden_exists && corrupt.empty();

  if (args.update) {
    if (std::string in = batch::OverwrittenInput(spec.golden_path, {spec_path, spec.model}); !in.empty())
      return error("the stored output '" + spec.golden_path + "' is the input '" + in +
                   "'; give the spec another golden = \"...\"");
    // A FIFO or a device named as the golden would be replaced by a regular file (issue 38).
    if (std::string what = batch::NotRegularFile(spec.golden_path); !what.empty())
      return error("the stored output '" + spec.golden_path + "' is " + what +
                   ", not a regular file; --update replaces only regular files, so it was left as it is: give "
                   "the spec another golden = \"...\"");
    for (size_t k = 0; k < fresh.t.size(); ++k)
      for (size_t j = 0; j < fresh.names.size(); ++j)
        if (!std::isfinite(fresh.rows[k][j]))
          return error(fmt::format("signal '{}' is {} at t = {}; a golden stores finite values only (leave the "
                                   "signal out of `signals`)",
                                   fresh.names[j], fresh.rows[k][j], fresh.t[k]));
    std::string text = batch::FormatTrajectoryCsv(fresh);
    if (have_golden && ReadFileText(spec.golden_path) == text) {
      r.outcome = Outcome::kUpdated;
      r.report = fmt::format("SAME  {} (golden unchanged, {} signals x {} instants)\n{}", label, stored.size(),
                             fresh.t.size(), notes);
      return r;
    }
    batch::RemoveStaleTemps(spec.golden_path);  // left by an --update that was killed
    if (!batch::WriteFileAtomic(spec.golden_path, text, &err)) return error(err);
    r.outcome = Outcome::kUpdated;
    r.report = have_golden ? fmt::format("UPDATED {} -> {}\n{}{}", label, spec.golden_path, notes,
                                         DescribeChanges(spec, golden, fresh))
               : golden_exists
                   ? fmt::format("UPDATED {} -> {} ({} signals x {} instants; it replaces a corrupt file: {})\n",
                                 label, spec.golden_path, stored.size(), fresh.t.size(), corrupt)
                   : fmt::format("NEW   {} -> {} ({} signals x {} instants)\n", label, spec.golden_path,
                                 stored.size(), fresh.t.size());
    if (!have_golden) r.report += notes;
    return r;
  }
  if (!golden_exists)
    return error("no stored output '" + spec.golden_path + "'; record it with kanesim test --update " + spec_path);
  if (!have_golden)
    return error("the stored output is corrupt: " + corrupt +
                 "\n    it was neither compared nor changed; restore it (e.g. from version control)");

  // Compare, then the invariants.
  std::string lines = notes;
  bool pass = true;
  auto settings = golden.provenance.find("settings");
  if (settings != golden.provenance.end() && settings->second != fresh.provenance["settings"]) {
    pass = false;
    lines += "    the spec's run settings changed since the golden was recorded; run kanesim test --update\n";
  }
  if (std::string g = batch::CompareGrids(golden, fresh); !g.empty()) {
    pass = false;
    lines += "    " + g + "\n";
  }
  batch::CompareResult c = batch::Compare(spec, golden, fresh);
  pass = pass && c.pass;
  for (const std::string& p : c.problems) lines += "    " + p + "\n";
  const batch::SignalDeviation* worst = nullptr;
  for (const batch::SignalDeviation& d : c.signals) {
    if (!worst || d.worst_ratio > worst->worst_ratio) worst = &d;
    if (!d.failed()) continue;
    lines += fmt::format(
        "    {}: largest deviation {} at t = {} (tolerance there {}, {}x); first beyond tolerance at t = {}\n",
        d.signal, G(d.max_dev), fmt::format("{:.6g}", d.t_max), G(d.tol_at_max), G(d.worst_ratio),
        fmt::format("{:.6g}", d.first_exceed));
  }
  for (const batch::Invariant& inv : spec.invariants) {
    batch::InvariantResult ir = batch::CheckInvariant(inv, actual, available);
    if (ir.status == batch::InvariantResult::Status::kFail) pass = false;
    if (ir.status != batch::InvariantResult::Status::kPass || args.verbose)
      lines += std::string("    ") + (ir.status == batch::InvariantResult::Status::kFail ? "" : "note: ") + ir.text +
               "\n";
  }
  for (const char* key : {"model", "stdlib", "kanesim_version"}) {
    auto it = golden.provenance.find(key);
    if (it != golden.provenance.end() && it->second != fresh.provenance[key])
      lines += fmt::format("    note: {} changed since the golden was recorded ({} -> {})\n", key, it->second,
                           fresh.provenance[key]);
  }
  r.outcome = pass ? Outcome::kPass : Outcome::kFail;
  r.report = fmt::format("{} {} ({} signals x {} instants, {:.2f} s{})\n{}", pass ? "PASS " : "FAIL ", label,
                         golden.names.size(), golden.t.size(), secs,
                         worst ? fmt::format("; worst {} at {} of its tolerance", worst->signal, G(worst->worst_ratio))
                               : "",
                         lines);
  return r;
}

// The tests of one run, for worker processes: each runs RunOne whole in its worker.
class TestTasks : public batch::PoolTasks {
 public:
  TestTasks(const std::vector<std::string>& specs, const TestArgs& args) : specs_(specs), args_(args) {}
  size_t Count() const override { return specs_.size(); }
  std::string Run(size_t k, bool* failed, bool*) override {
    TestResult r = RunOne(specs_[k], args_, load_mutex_);
    *failed = r.outcome == Outcome::kFail || r.outcome == Outcome::kError;
    std::fflush(stderr);  // its diagnostics before its report is printed
    return EncodeResult(r);
  }
  // A crash, a timeout, or an exception that escaped the test (out of memory).
  std::string Lost(size_t k, const std::string& status, const std::string& message, double) const override {
    TestResult r;
    r.outcome = Outcome::kCrashed;
    const std::string label = std::filesystem::path(specs_[k]).stem().string();
    r.report = (status == "timeout" ? "TIMEOUT " : status == "crashed" ? "CRASH " : "FAIL  ") + label + "\n    " +
               message + "\n";
    return EncodeResult(r);
  }
  int FaultId(size_t k) const override { return static_cast<int>(k); }

 private:
  const std::vector<std::string>& specs_;
  const TestArgs& args_;
  std::mutex load_mutex_;  // unused in a worker (one test at a time), but RunOne takes it
};

// Every test in a worker process, at most n at once. False when no process can be made:
// *handed tests were run (their results are in *results), the rest were not.
bool RunInWorkers(const std::vector<std::string>& specs, const TestArgs& a, size_t n,
                  std::vector<TestResult>* results, size_t* handed, std::string* error) {
  TestTasks tasks(specs, a);
  batch::PoolLimits limits;
  limits.timeout = a.timeout;
  limits.memory_mib = a.worker_memory;
  limits.task = "test";
  limits.timeout_option = "--timeout";
  batch::ProcessPool pool(tasks, limits, static_cast<int>(n));
  size_t next = 0;
  while (true) {
    bool ok = true;
    while (ok && next < specs.size() && pool.HasIdle()) {
      ok = pool.Start(next, error);
      if (ok) ++next;
    }
    batch::ProcessPool::Done done;
    if (!pool.Wait(&done)) {  // none running
      *handed = next;
      return next >= specs.size();
    }
    (*results)[done.index] = DecodeResult(done.line);
  }
}

// Tests from `first` on, on n threads of this process (fork failed).
void RunOnThreads(const std::vector<std::string>& specs, const TestArgs& a, size_t n, size_t first,
                  std::vector<TestResult>* results) {
  std::mutex load_mutex;
  std::atomic<size_t> next{first};
  auto work = [&] {
    for (size_t k = next.fetch_add(1); k < specs.size(); k = next.fetch_add(1))
      (*results)[k] = RunOne(specs[k], a, load_mutex);
  };
  std::vector<std::jthread> pool;
  for (size_t i = 1; i < n; ++i) pool.emplace_back(work);
  work();
}

int TestCommand(const TestArgs& a) {
  if (a.update && !a.sets.empty()) {
    fmt::print(stderr, "kanesim: error: --update with --set would record perturbed goldens; drop one\n");
    return kExitModelError;
  }
  if (!(a.timeout >= 0.0 && a.timeout <= 1e6)) {  // 1e6 s (11 days): what the pool's int milliseconds hold
    fmt::print(stderr, "kanesim: error: --timeout needs seconds from 0 (none) to 1e6, got {}\n",
               sim::FormatShortest(a.timeout));
    return kExitModelError;
  }
  if (!(a.worker_memory >= 0.0 && a.worker_memory <= 1e9)) {
    fmt::print(stderr, "kanesim: error: --worker-memory needs MiB from 0 (no limit) to 1e9, got {}\n",
               sim::FormatShortest(a.worker_memory));
    return kExitModelError;
  }
  std::vector<std::string> specs;
  for (const std::string& p : a.paths) {
    if (std::filesystem::is_directory(p)) {
      std::vector<std::string> found;
      for (const auto& e : std::filesystem::recursive_directory_iterator(p))
        if (e.is_regular_file() && e.path().extension() == ".toml") found.push_back(e.path().string());
      std::sort(found.begin(), found.end());
      if (found.empty()) fmt::print(stderr, "kanesim: warning: no golden specs (*.toml) in '{}'\n", p);
      specs.insert(specs.end(), found.begin(), found.end());
    } else if (std::filesystem::path(p).extension() == ".toml") {
      specs.push_back(p);
    } else {
      fmt::print(stderr, "kanesim: error: '{}' is not a folder or a golden spec (.toml)\n", p);
      return kExitModelError;
    }
  }
  std::vector<TestResult> results(specs.size());
  unsigned hw = std::max(1u, std::thread::hardware_concurrency());
  size_t n = std::max<size_t>(1, std::min<size_t>(a.threads > 0 ? static_cast<size_t>(a.threads) : hw, specs.size()));
  size_t handed = 0;
  std::string why;
  if (!RunInWorkers(specs, a, n, &results, &handed, &why)) {
    // Better tests on threads than none: say what protection is lost.
    fmt::print(stderr, "kanesim: warning: {}; the remaining {} tests run on threads of this process, where a crash "
               "ends the run\n", why, specs.size() - handed);
    RunOnThreads(specs, a, n, handed, &results);
  }
  int pass = 0, fail = 0, error = 0, updated = 0, crashed = 0;
  for (const TestResult& r : results) {
    fmt::print("{}", r.report);
    switch (r.outcome) {
      case Outcome::kPass: ++pass; break;
      case Outcome::kFail: ++fail; break;
      case Outcome::kError: ++error; break;
      case Outcome::kUpdated: ++updated; break;
      case Outcome::kCrashed: ++fail, ++crashed; break;
    }
  }
  const std::string crashes = crashed > 0 ? fmt::format(" ({} crashed or timed out)", crashed) : std::string();
  if (a.update)
    fmt::print("{} golden{} recorded, {}{} error{}\n", updated, updated == 1 ? "" : "s",
               fail > 0 ? fmt::format("{} failed{}, ", fail, crashes) : std::string(), error, error == 1 ? "" : "s");
  else
    fmt::print("{} passed, {} failed{}, {} error{}\n", pass, fail, crashes, error, error == 1 ? "" : "s");
  std::fflush(stdout);
  if (fail > 0) return kExitRegression;
  return error > 0 ? kExitModelError : kExitOk;
}

}  // namespace

void AddTestCommand(CLI::App& app, int* exit_code, bool options) {
  auto a = std::make_shared<TestArgs>();
  CLI::App* t = app.add_subcommand("test", "Golden-output regression tests: run, compare, report deviations");
  if (!options) return;  // only its name and description (main.cpp)
  t->add_option("paths", a->paths, "Golden specs (.toml) or folders holding them")->required();
  t->add_flag("--update", a->update, "Rewrite the stored outputs and print what changed");
  AddIntegerOption(t, "-j,--jobs", &a->threads, 0, kMaxJobs, "Tests run in parallel (default 0: all cores)");
  t->add_option("--set", a->sets, "Override a parameter in every test, name=value (what-if checks)")
      ->allow_extra_args(false);
  t->add_flag("-v,--verbose", a->verbose, "Also print invariants that passed");
  AddNumberOption(t, "--timeout", &a->timeout,
                  "Seconds of wall time a test may take before its process is killed (TIMEOUT, a failure); 0: none");
  AddNumberOption(t, "--worker-memory", &a->worker_memory,
                  "MiB of memory a test's worker process may allocate; a test that needs more fails with 'out of "
                  "memory' (default 0: no limit)");
  t->callback([a, exit_code] { *exit_code = TestCommand(*a); });
}

}  // namespace kanesim::cli
