#include "batch/sweep.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <stdexcept>
#include <filesystem>
#include <map>
#include <set>
#include <thread>

#include "batch/csv_util.h"
#include "batch/summary.h"
#include "batch/worker_pool.h"
#include "flat/mechanism.h"
#include "runtime/program/program.h"
#include "compiler/compiler.h"
#include "sim/sensitivity.h"

namespace kanesim::batch {
namespace {

using Clock = std::chrono::steady_clock;

std::string Num(double x) { return std::isnan(x) ? std::string() : sim::FormatNumber(x); }

// `j.q.start` / `j.u.start` of a joint j: a start value, not a parameter. A sweep over it
// elaborates the model again with --set (as a structural value), so that the start is
// exactly the one written in the file would be (same assembly of closed loops).
bool IsStartName(const flat::Mechanism& mech, const std::string& name) {
  for (const char* tail : {".q.start", ".u.start"}) {
    const size_t n = std::char_traits<char>::length(tail);
    if (name.size() <= n || name.compare(name.size() - n, n, tail) != 0) continue;
    const std::string joint = name.substr(0, name.size() - n);
    for (const flat::Joint& j : mech.joints)
      if (j.name == joint) return true;
  }
  return false;
}

// The signal a metric reads: y of a sensitivity "d(y)/d(p)", else its own.
std::string MetricSignal(const Metric& m) {
  std::string y, p;
  return sim::SplitSensitivityColumn(m.signal, &y, &p) ? y : m.signal;
}

// The parameters of the metrics' sensitivities, in first-use order.
std::vector<std::string> SensitivityNames(const SweepConfig& c) {
  std::vector<std::string> names;
  std::string y, p;
  for (const Metric& m : c.metrics)
    if (sim::SplitSensitivityColumn(m.signal, &y, &p) && std::find(names.begin(), names.end(), p) == names.end())
      names.push_back(p);
  return names;
}

// The scenario's program at p +/- delta for each sensitivity of the metrics (parameters only;
// `overrides` are the scenario's numeric values, so that bound parameters follow).
std::vector<sim::SensitivityParam> SensitivityPrograms(const rt::Program& program, std::map<size_t, double> overrides,
                                                       const SweepConfig& c) {
  std::vector<sim::SensitivityParam> out;
  const flat::Mechanism& mech = *program.mech;
  for (const std::string& name : SensitivityNames(c)) {
    const int found = mech.FindParam(name);
    if (found < 0) throw std::runtime_error("the sensitivity's parameter '" + name + "' does not exist in this variant");
    const auto i = static_cast<size_t>(found);
    const double p = program.param_values[i];
    sim::SensitivityParam sp;
    sp.name = name;
    sp.delta = sim::SensitivityStep(p);
    for (int sign : {1, -1}) {
      overrides[i] = p + sign * sp.delta;
      rt::CompileResult r = rt::Rebind(program, flat::EvaluateParams(mech, overrides));
      if (!r.program) throw std::runtime_error("the model does not compile at " + name + " = " + Num(overrides[i]));
      (sign > 0 ? sp.plus : sp.minus) = r.program;
    }
    overrides[i] = p;
    out.push_back(std::move(sp));
  }
  return out;
}

std::vector<std::string> SignalsFor(const rt::Program& program, const SweepConfig& c) {
  std::vector<std::string> names;
  for (const Metric& m : c.metrics)
    if (std::find(names.begin(), names.end(), MetricSignal(m)) == names.end()) names.push_back(MetricSignal(m));
  if (c.trajectories) {
    std::vector<std::string> t = c.trajectory_signals.empty() ? rt::DefaultSignals(program) : c.trajectory_signals;
    for (const std::string& n : t)
      if (std::find(names.begin(), names.end(), n) == names.end()) names.push_back(n);
  }
  return names;
}

}  // namespace

std::string SummaryFileName(const SweepConfig& config) {
  if (config.shard_count <= 1) return "summary.csv";
  return "summary.shard-" + std::to_string(config.shard_index + 1) + "-of-" + std::to_string(config.shard_count) +
         ".csv";
}

bool OpenSweepOutput(const SweepConfig& config, const std::string& header, SweepOutput* out, std::string* error) {
  namespace fs = std::filesystem;
  const std::string traj_dir = config.out_dir + "/trajectories";
  std::error_code ec;
  fs::create_directories(config.trajectories ? traj_dir : config.out_dir, ec);
  if (ec) {
    *error = "cannot create '" + config.out_dir + "': " + ec.message();
    return false;
  }
  const std::string name = SummaryFileName(config);
  out->summary_path = config.out_dir + "/" + name;
  const std::string settings_path = SettingsPathFor(out->summary_path);
  const std::string lock_path = config.out_dir + "/." + name + ".lock";
  for (const std::string& path : {out->summary_path, settings_path, ScenariosPathFor(out->summary_path), lock_path}) {
    if (std::string in = OverwrittenInput(path, config.inputs); !in.empty()) {
      *error = "the sweep would overwrite its input '" + in + "' (as '" + path + "'); choose another -o";
      return false;
    }
  }
  if (config.trajectories)
    for (const std::string& in : config.inputs)
      if (SameFile(fs::path(in).parent_path().empty() ? "." : fs::path(in).parent_path().string(), traj_dir)) {
        *error = "the input '" + in + "' is in '" + traj_dir + "', where the sweep writes its trajectories";
        return false;
      }
  if (!out->lock.Acquire(lock_path, "'" + out->summary_path + "'", error, /*remove_at_end=*/true)) return false;
  RemoveStaleTemps(out->summary_path);
  RemoveStaleTemps(settings_path);
  RemoveStaleTemps(ScenariosPathFor(out->summary_path));
  if (config.trajectories) RemoveStaleTempsIn(traj_dir);
  // A summary without one complete row (a sweep killed between creating it and writing
  // its settings record, or before its first scenario finished) has nothing to keep: a
  // resume starts it over, whatever record lies beside it.
  bool resuming = config.resume && fs::exists(out->summary_path);
  if (resuming) {
    SummaryTable kept;
    std::string err;
    resuming = ReadSummary(out->summary_path, &kept, &err) ? !kept.rows.empty() : !kept.header.empty();
  }
  if (resuming && !config.settings.empty()) {
    SettingsRecord old;
    std::string err;
    if (!fs::exists(settings_path)) {
      *error = "cannot resume: '" + out->summary_path + "' has no settings record ('" + settings_path +
               "'), so it cannot be checked to come from this sweep; run without --resume to start over";
      return false;
    }
    if (!ReadSettings(settings_path, &old, &err)) {
      *error = "cannot resume: " + err;
      return false;
    }
    std::vector<std::string> diff = SettingsDifferences(old, config.settings, "recorded", "this run");
    if (!diff.empty()) {
      *error = "cannot resume: '" + out->summary_path + "' was made with other settings:";
      for (const std::string& d : diff) *error += "\n    " + d;
      *error += "\n  resume with the same settings, or run without --resume (or with another -o) to start over";
      return false;
    }
  }
  if (!out->summary.Open(out->summary_path, header, resuming, &out->done, error)) return false;
  // After the summary: a sweep killed in between leaves an empty summary beside the old
  // record (or none), which a resume starts over, never old rows beside a new record.
  if (!config.blocks.empty() &&
      !WriteFileAtomic(ScenariosPathFor(out->summary_path), FormatBlocks(config.blocks), error))
    return false;
  if (!config.settings.empty() && !WriteFileAtomic(settings_path, FormatSettings(config.settings), error))
    return false;
  return true;
}

bool ValidateSweep(const rt::Program& base, const SweepConfig& config, std::string* error) {
  const flat::Mechanism& mech = *base.mech;
  for (const std::string& name : config.param_names) {
    int i = mech.FindParam(name);
    if (i < 0 && IsStartName(mech, name)) continue;
    if (i < 0) {
      *error = "the model has no parameter '" + name + "' (kanesim check lists them)";
      return false;
    }
    const flat::Param& p = mech.params[static_cast<size_t>(i)];
    if (p.is_constant) {
      *error = "'" + name + "' is a constant; a sweep cannot change it";
      return false;
    }
    if (p.type == flat::ParamType::String) {
      *error = "'" + name + "' is a String parameter; a sweep varies numbers only";
      return false;
    }
  }
  std::vector<std::string> available = rt::AvailableSignals(base);
  for (const Metric& m : config.metrics) {
    if (std::find(available.begin(), available.end(), MetricSignal(m)) == available.end()) {
      *error = "metric '" + m.Column() + "': the model has no signal '" + MetricSignal(m) + "'";
      return false;
    }
  }
  // Sensitivities (d(y)/d(p)): of Real parameters that are neither structural nor swept
  // structurally (docs/sweeps.md "Metrics").
  for (const std::string& name : SensitivityNames(config)) {
    const int i = mech.FindParam(name);
    const flat::Param* p = i < 0 ? nullptr : &mech.params[static_cast<size_t>(i)];
    if (!p || p->type != flat::ParamType::Real || p->structural || p->is_constant) {
      *error = "a sensitivity metric d(..)/d(" + name + "): '" + name +
               "' is not a Real, non-structural parameter (start values: `kanesim run --sensitivity`)";
      return false;
    }
  }
  for (const std::string& s : config.trajectory_signals) {
    if (std::find(available.begin(), available.end(), s) == available.end()) {
      *error = "the model has no signal '" + s + "'";
      return false;
    }
  }
  // Every scenario's times and tolerances, before anything runs (a scenario's own
  // stop_time, rtol, atol override the sweep's).
  if (std::string why = sim::CheckRun(sim::ResolveGrid(base, config.sim), config.sim.rtol, config.sim.atol);
      !why.empty()) {
    *error = why;
    return false;
  }
  for (const Scenario& s : config.scenarios) {
    if (std::isnan(s.run.stop_time) && std::isnan(s.run.rtol) && std::isnan(s.run.atol)) continue;
    sim::SimOptions so = config.sim;
    if (!std::isnan(s.run.stop_time)) so.stop_time = s.run.stop_time;
    if (!std::isnan(s.run.rtol)) so.rtol = s.run.rtol;
    if (!std::isnan(s.run.atol)) so.atol = s.run.atol;
    if (std::string why = sim::CheckRun(sim::ResolveGrid(base, so), so.rtol, so.atol); !why.empty()) {
      *error = "scenario " + std::to_string(s.id) + ": " + why;
      return false;
    }
  }
  if (config.shard_count < 1 || config.shard_index < 0 || config.shard_index >= config.shard_count) {
    *error = "bad shard " + std::to_string(config.shard_index + 1) + "/" + std::to_string(config.shard_count);
    return false;
  }
  return true;
}

bool RerunOnResume(const std::string& line, size_t num_params) {
  const std::vector<std::string> f = SplitCsvLine(line);
  const size_t status = 1 + num_params + 3;  // id, the parameters, stop_time, rtol, atol
  return status < f.size() && (f[status] == "crashed" || f[status] == "timeout");
}

bool RowMatchesScenario(const std::string& line, const Scenario& s) {
  std::vector<std::string> f = SplitCsvLine(line);
  if (f.size() < s.values.size() + 1 || f[0] != std::to_string(s.id)) return false;
  for (size_t j = 0; j < s.values.size(); ++j)
    if (f[j + 1] != Num(s.values[j])) return false;
  return true;
}

ScenarioRunner::ScenarioRunner(std::shared_ptr<const rt::Program> base, VariantBuilder build, const SweepConfig& config)
    : base_(std::move(base)), build_(std::move(build)), config_(config) {
  base_values_ = base_->param_values;
  auto v = std::make_unique<Variant>();
  v->program = base_;
  variants_[""] = std::move(v);
}

int ScenarioRunner::NumVariants() const {
  int n = 0;
  for (const auto& [key, v] : variants_) n += v->program ? 1 : 0;
  return n;
}

std::string ScenarioRunner::Header() const {
  std::string h = "id";
  for (const std::string& n : config_.param_names) h.append(",").append(QuoteCsv(n));
  h.append(",stop_time,rtol,atol,status,message,fail_time");
  for (const Metric& m : config_.metrics) h.append(",").append(QuoteCsv(m.Column()));
  h.append(",method,steps,rhs_evals,jac_rhs_evals,err_test_fails,wall_time");
  return h;
}

const ScenarioRunner::Variant& ScenarioRunner::GetVariant(
    const std::vector<std::pair<std::string, double>>& structural) {
  std::string key;
  for (const auto& [name, value] : structural) key.append(name).append("=").append(Num(value)).append(";");
  Variant* v = nullptr;
  {
    std::lock_guard<std::mutex> lock(variants_mutex_);
    auto& slot = variants_[key];
    if (!slot) slot = std::make_unique<Variant>();
    v = slot.get();
  }
  // One build at a time (the front end is not re-entrant); a variant is built once.
  std::lock_guard<std::mutex> lock(build_mutex_);
  if (!v->program && v->error.empty()) {
    v->program = build_ ? build_(structural, &v->error) : nullptr;
    if (!v->program && v->error.empty()) v->error = "the structural variant could not be built";
  }
  return *v;
}

std::string ScenarioRunner::Run(const Scenario& s, bool* failed) {
  Clock::time_point t0 = Clock::now();
  sim::SimOptions so = OptionsFor(s);

  std::string message;
  double fail_time = kUnset;
  std::vector<double> metric_values(config_.metrics.size(), kUnset);
  sim::SimStats stats;
  bool ok = false, simulated = false;
  try {
    // a. Structural values that differ from the base program's select a variant.
    const flat::Mechanism& base_mech = *base_->mech;
    std::vector<std::pair<std::string, double>> structural;
    std::vector<std::pair<std::string, double>> numeric;
    for (size_t j = 0; j < config_.param_names.size(); ++j) {
      const double v = s.values[j];
      if (std::isnan(v)) continue;
      const std::string& name = config_.param_names[j];
      const int found = base_mech.FindParam(name);
      if (found < 0) {  // a start value (IsStartName): always elaborated again
        structural.emplace_back(name, v);
        continue;
      }
      const auto i = static_cast<size_t>(found);
      if (base_mech.params[i].structural) {
        if (v != base_values_[i]) structural.emplace_back(name, v);
      } else {
        numeric.emplace_back(name, v);
      }
    }
    const Variant& variant = GetVariant(structural);
    if (!variant.program) throw std::runtime_error(variant.error);
    std::shared_ptr<const rt::Program> program = variant.program;
    std::map<size_t, double> overrides;  // the numeric values, by parameter index

    // b. Numeric values: rebind (type checks first: a sweep must not truncate silently).
    if (!numeric.empty()) {
      const flat::Mechanism& mech = *program->mech;
      overrides.clear();
      for (const auto& [name, v] : numeric) {
        int i = mech.FindParam(name);
        if (i < 0) throw std::runtime_error("parameter '" + name + "' does not exist in this structural variant");
        const flat::Param& p = mech.params[static_cast<size_t>(i)];
        if ((p.type == flat::ParamType::Integer || p.type == flat::ParamType::Boolean) && v != std::round(v))
          throw std::runtime_error("'" + name + "' is an Integer/Boolean parameter, got " + Num(v));
        if (v < p.min || v > p.max)
          throw std::runtime_error("'" + name + "' = " + Num(v) + " is outside [" + Num(p.min) + ", " +
                                   Num(p.max) + "]");
        overrides[static_cast<size_t>(i)] = v;
      }
      rt::CompileResult rebound = rt::Rebind(*program, flat::EvaluateParams(mech, overrides));
      if (!rebound.program) {
        std::string msg = "the model does not compile with these parameter values";
        for (const rt::CompileMessage& e : rebound.errors) msg += std::string("; ") + flat::DiagCodeString(e.code) + ": " + e.message;
        throw std::runtime_error(msg);
      }
      program = rebound.program;
    }

    // c. Simulate into the metrics (and the trajectory file).
    so.signals = SignalsFor(*program, config_);
    AtomicFile traj;  // the old file stays until the new one is complete
    std::string io_error;
    if (config_.trajectories &&
        !traj.Open(config_.out_dir + "/trajectories/scenario_" + std::to_string(s.id) + ".csv", &io_error))
      throw std::runtime_error(io_error);
    sim::CsvWriter writer(traj.file());
    MetricSink sink(config_.metrics, traj.file() ? &writer : nullptr);
    const std::vector<sim::SensitivityParam> sens = SensitivityPrograms(*program, overrides, config_);
    sim::SimResult r = sens.empty() ? sim::Simulate(*program, so, sink) : sim::SimulateSensitivities(*program, sens, so, sink);
    if (traj.file() && !traj.Commit(&io_error)) throw std::runtime_error(io_error);
    stats = r.stats;
    simulated = true;
    if (r.status == sim::SimResult::Status::kOk) {
      ok = true;
      metric_values = sink.Values();
    } else {
      message = r.message.empty() ? sink.error() : r.message;
      if (r.status == sim::SimResult::Status::kNumericalFailure) fail_time = r.fail_time;
    }
  } catch (const std::exception& e) {
    message = e.what();
  }
  const double wall = std::chrono::duration<double>(Clock::now() - t0).count();
  *failed = !ok;
  // d. The line.
  return Row(s, so, ok ? "ok" : "failed", message, fail_time, metric_values, simulated ? &stats : nullptr, wall);
}

sim::SimOptions ScenarioRunner::OptionsFor(const Scenario& s) const {
  sim::SimOptions so = config_.sim;
  if (!std::isnan(s.run.stop_time)) so.stop_time = s.run.stop_time;
  if (!std::isnan(s.run.rtol)) so.rtol = s.run.rtol;
  if (!std::isnan(s.run.atol)) so.atol = s.run.atol;
  else if (!std::isnan(s.run.rtol)) so.atol = std::min(so.atol, s.run.rtol);
  return so;
}

std::string ScenarioRunner::Row(const Scenario& s, const sim::SimOptions& so, const std::string& status,
                                const std::string& message, double fail_time, const std::vector<double>& metric_values,
                                const sim::SimStats* stats, double wall) const {
  std::string line = std::to_string(s.id);
  for (double v : s.values) line.append(",").append(Num(v));
  line.append(",").append(Num(so.stop_time)).append(",").append(Num(so.rtol)).append(",").append(Num(so.atol));
  line.append(",").append(status).append(",").append(QuoteCsv(message)).append(",").append(Num(fail_time));
  for (size_t k = 0; k < config_.metrics.size(); ++k)
    line.append(",").append(Num(k < metric_values.size() ? metric_values[k] : kUnset));
  const sim::IntegratorStats is = stats ? stats->integrator : sim::IntegratorStats{};
  line.append(",").append(stats ? sim::MethodName(stats->method) : "");
  for (long c : {is.steps, is.rhs_evals, is.rhs_evals_jac, is.err_test_fails}) line.append(",").append(std::to_string(c));
  char wall_text[32];
  std::snprintf(wall_text, sizeof wall_text, "%.6f", wall);
  line.append(",").append(wall_text);
  return line;
}

std::string ScenarioRunner::LostRow(const Scenario& s, const std::string& status, const std::string& message,
                                    double wall) const {
  return Row(s, OptionsFor(s), status, message, kUnset, {}, nullptr, wall);
}

namespace {

// id, row, outcome, whether a structural variant was compiled for it
using RecordRow = std::function<void(int id, const std::string& line, WorkerPool::Outcome outcome, bool new_variant)>;

// Stage 3 on threads of this process: each takes the next pending scenario.
void RunOnThreads(ScenarioRunner& runner, const SweepConfig& config, const std::vector<const Scenario*>& pending,
                  size_t nthreads, const RecordRow& record) {
  std::atomic<size_t> next{0};
  std::mutex record_mutex;
  auto work = [&] {
    while (true) {
      if (config.cancel && config.cancel->load()) return;
      size_t k = next.fetch_add(1);
      if (k >= pending.size()) return;
      bool failed = false;
      std::string line = runner.Run(*pending[k], &failed);
      std::lock_guard<std::mutex> lock(record_mutex);
      record(pending[k]->id, line, failed ? WorkerPool::Outcome::kFailed : WorkerPool::Outcome::kOk, false);
    }
  };
  std::vector<std::jthread> pool;
  for (size_t i = 1; i < nthreads; ++i) pool.emplace_back(work);
  work();
}

// Stage 3 in worker processes (worker_pool.h): this process hands out the scenarios in
// order and records each row as it comes, whatever became of its worker. False when no
// worker process can be made at all (fork fails: a process limit, no memory to copy the
// page tables): *handed says how many scenarios were handed out (and recorded), so that the
// caller runs the rest another way.
bool RunInWorkers(ScenarioRunner& runner, const SweepConfig& config, const std::vector<const Scenario*>& pending,
                  int nworkers, const RecordRow& record, size_t* handed, std::string* error) {
  WorkerPool pool(runner, config, nworkers);
  size_t next = 0;
  auto refill = [&] {
    const bool cancelled = config.cancel && config.cancel->load();
    while (!cancelled && next < pending.size() && pool.HasIdle()) {
      if (!pool.Start(*pending[next], error)) return false;  // retried when a running one ends
      ++next;
    }
    return true;
  };
  while (true) {
    if (!refill() && pool.Running() == 0) {
      *handed = next;
      return false;
    }
    WorkerPool::Done done;
    if (!pool.Wait(&done)) {
      *handed = next;
      if ((config.cancel && config.cancel->load()) || next >= pending.size()) return true;
      continue;
    }
    // The freed worker gets its next scenario before this row's fsync, so it never waits on it.
    refill();
    record(done.scenario->id, done.line, done.outcome, done.new_variant);
    // A lost worker's half-written trajectory: its process is gone, so the temporary is stale.
    if (config.trajectories && done.outcome != WorkerPool::Outcome::kOk && done.outcome != WorkerPool::Outcome::kFailed)
      RemoveStaleTempsIn(config.out_dir + "/trajectories");
  }
}

}  // namespace

bool RunSweep(std::shared_ptr<const rt::Program> base, const VariantBuilder& build, const SweepConfig& config,
              SweepReport* report, std::string* error) {
  // 1. Validate.
  if (!ValidateSweep(*base, config, error)) return false;
  // 2. Output (and what is already done).
  ScenarioRunner runner(base, build, config);
  SweepOutput output;
  if (!OpenSweepOutput(config, runner.Header(), &output, error)) return false;
  report->summary_path = output.summary_path;
  SummaryFile& summary = output.summary;
  const std::map<int, std::string>& done = output.done;
  std::vector<const Scenario*> pending;
  SweepProgress& pr = report->progress;
  pr = SweepProgress{};
  for (const Scenario& s : config.scenarios) {
    if (s.id % config.shard_count != config.shard_index) continue;
    ++pr.total;
    auto it = done.find(s.id);
    if (it == done.end() || RerunOnResume(it->second, config.param_names.size())) {
      pending.push_back(&s);
      continue;
    }
    if (!RowMatchesScenario(it->second, s)) {
      *error = "cannot resume: scenario " + std::to_string(s.id) + " in '" + report->summary_path +
               "' has other parameter values (another sweep?)";
      return false;
    }
    ++pr.skipped;
  }

  // 3. Workers take the next pending scenario until none is left.
  unsigned hw = std::max(1u, std::thread::hardware_concurrency());
  size_t nworkers = config.threads > 0 ? static_cast<size_t>(config.threads) : hw;
  nworkers = std::max<size_t>(1, std::min(nworkers, pending.size()));
  std::string io_error;
  Clock::time_point start = Clock::now();
  // One finished row: into the summary and the counts (under the caller's lock, if any).
  report->variants = 0;
  auto record = [&](int id, const std::string& line, WorkerPool::Outcome outcome, bool new_variant) {
    std::string err;
    if (!summary.Append(id, line, &err) && io_error.empty()) io_error = err;
    ++pr.done;
    report->variants += new_variant ? 1 : 0;
    pr.failed += outcome != WorkerPool::Outcome::kOk ? 1 : 0;
    pr.crashed += outcome == WorkerPool::Outcome::kCrashed ? 1 : 0;
    pr.timed_out += outcome == WorkerPool::Outcome::kTimedOut ? 1 : 0;
    pr.elapsed = std::chrono::duration<double>(Clock::now() - start).count();
    if (config.progress) config.progress(pr);
  };
  if (config.isolation == SweepConfig::Isolation::kProcess) {
    size_t handed = 0;
    std::string why;
    if (!RunInWorkers(runner, config, pending, static_cast<int>(nworkers), record, &handed, &why)) {
      // Better a sweep on threads than none: say what protection is lost.
      report->warnings.push_back(why + "; the remaining " + std::to_string(pending.size() - handed) +
                                 " scenarios run on threads of this process, where a crash ends the sweep");
      RunOnThreads(runner, config, std::vector<const Scenario*>(pending.begin() + static_cast<long>(handed), pending.end()),
                   nworkers, record);
    }
  } else {
    RunOnThreads(runner, config, pending, nworkers, record);
  }
  report->interrupted = config.cancel && config.cancel->load() && pr.done + pr.skipped < pr.total;
  // Threads share one cache of variants; each worker process has its own.
  report->variants = config.isolation == SweepConfig::Isolation::kProcess ? 1 + report->variants : runner.NumVariants();
  // 4. Sorted, atomically.
  if (!summary.Finish(error)) return false;
  if (!io_error.empty()) {
    *error = io_error;
    return false;
  }
  return true;
}

}  // namespace kanesim::batch
