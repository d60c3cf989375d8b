// Loading and running for the Python module (glue.h), through the library pipeline
// (pipeline/pipeline.h) as the `kanesim` commands: pipeline::LoadModel loads,
// pipeline::ResolveRun resolves a run's settings, sim::Simulate (pipeline::Run's stage
// 5-6) runs into memory, batch::ScenarioRunner sweeps.
#include "python/src/glue.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <mutex>
#include <pthread.h>
#include <thread>

#include "lang/diagnostics.h"
#include "batch/metrics.h"
#include "batch/scenario.h"
#include "batch/sweep.h"
#include "batch/worker_pool.h"
#include "runtime/program/program.h"
#include "sim/sim.h"  // ConstantInputs
#include "sim/signal_select.h"
#include "pipeline/pipeline.h"
#include "compiler/compiler.h"
#include "lang/lang.h"  // lang::NodePoolsLock / NodePoolsUnlock (lang/node_pool.h)

namespace kanesim::py {
namespace {

// One front-end load at a time: loads are short, and the front end shares the parsed
// standard library between programs.
std::mutex g_load_mutex;

bool Fail(std::string* error, std::string message) {
  *error = std::move(message);
  return false;
}

// The code and place of the first error in rendered diagnostics: its line reads
// "FILE:LINE:COL: error[CODE]: ..." or "kanesim: error[CODE]: ..." (lang/diagnostics.h).
void FirstError(const std::string& rendered, ModelErrorInfo* error) {
  size_t line_start = 0;
  while (line_start < rendered.size()) {
    size_t line_end = rendered.find('\n', line_start);
    if (line_end == std::string::npos) line_end = rendered.size();
    const std::string line = rendered.substr(line_start, line_end - line_start);
    line_start = line_end + 1;
    const size_t at = line.find(": error");
    if (at == std::string::npos) continue;
    const size_t open = at + 7;
    if (open < line.size() && line[open] == '[') {
      const size_t close = line.find(']', open);
      if (close != std::string::npos) error->code = line.substr(open + 1, close - open - 1);
    }
    // FILE:LINE:COL: the last two colon-separated fields are numbers.
    const std::string where = line.substr(0, at);
    const size_t c2 = where.rfind(':');
    const size_t c1 = c2 == std::string::npos || c2 == 0 ? std::string::npos : where.rfind(':', c2 - 1);
    if (c1 != std::string::npos) {
      const std::string l = where.substr(c1 + 1, c2 - c1 - 1), c = where.substr(c2 + 1);
      const auto digits = [](const std::string& x) {
        return !x.empty() && x.size() < 10 && std::all_of(x.begin(), x.end(), [](char ch) { return ch >= '0' && ch <= '9'; });
      };
      if (digits(l) && digits(c)) {
        error->file = where.substr(0, c1);
        error->line = std::stoi(l);
        error->column = std::stoi(c);
      }
    }
    return;
  }
}

}  // namespace

bool Load(const LoadRequest& req, LoadedModel* out, ModelErrorInfo* error) {
  pipeline::RunSpec spec;
  if (!pipeline::SolverFromName(req.solver, &spec.solver) ||
      !pipeline::IntegratorFromName(req.integrator, &spec.integrator) ||
      !pipeline::ReactionsFromName(req.reactions, &spec.reactions)) {
    error->rendered = "kanesim: error: unknown solver, integrator or reactions choice\n";
    return false;
  }
  pipeline::LoadResult r;
  {
    std::lock_guard<std::mutex> lock(g_load_mutex);
    const pipeline::Source source = req.from_text ? pipeline::Source::Text(req.path, req.text)
                                                  : pipeline::Source::File(req.path);
    pipeline::LoadOptions lo;
    lo.model = req.model;
    lo.sets = req.sets;
    lo.urdf.floating = req.floating;
    lo.urdf.stops = req.stops;
    lo.urdf.package_paths = req.package_paths;
    r = pipeline::LoadModel(source, lo, spec);
  }
  if (!r.model) {
    error->rendered = r.diagnostics.empty() ? "kanesim: error: the model could not be loaded\n" : r.diagnostics;
    FirstError(error->rendered, error);
    return false;
  }
  // Warnings: the diagnostics' (also on success) and W314 (friction on an indeterminate
  // normal force), which `kanesim run` prints for every run (pipeline::RunWarnings).
  if (!r.diagnostics.empty()) out->warnings.push_back(r.diagnostics);
  if (rt::CompileMessage f = rt::FrictionIndeterminateWarning(*r.model->program); !f.message.empty())
    out->warnings.push_back(pipeline::RenderCompileMessage(*r.model, f, lang::Severity::Warning));
  out->request = req;
  out->program = r.model->program;
  out->model = std::shared_ptr<const pipeline::Model>(std::move(r.model));
  return true;
}

const std::vector<std::string>& LoadedModel::Signals() const {
  std::call_once(signals_once_, [this] { signals_ = rt::AvailableSignals(*program); });
  return signals_;
}

bool ResolveRun(const LoadedModel& model, const RunRequest& r, sim::SimOptions* so, std::vector<std::string>* warnings,
                std::string* error) {
  const rt::Program& program = *model.program;
  pipeline::RunSpec spec;
  if (!pipeline::IntegratorFromName(r.integrator, &spec.integrator))
    return Fail(error, "integrator '" + r.integrator + "': unknown (" + pipeline::JoinNames(pipeline::IntegratorNames()) + ")");
  if (!pipeline::LinearSolverFromName(r.linear_solver, &spec.linear_solver))
    return Fail(error, "linear_solver '" + r.linear_solver + "': unknown (" +
                           pipeline::JoinNames(pipeline::LinearSolverNames()) + ")");
  if (r.projection != "eval" && r.projection != "step")
    return Fail(error, "projection '" + r.projection + "': unknown (eval, step)");
  spec.project_steps = r.projection == "step";
  if (!pipeline::EnergyCheckFromName(r.energy_check, &spec.energy_check))
    return Fail(error, "energy_check '" + r.energy_check + "': unknown (" + pipeline::JoinNames(pipeline::EnergyCheckNames()) + ")");
  for (auto [name, value] : {std::pair{"start_time", r.start_time}, {"stop_time", r.stop_time}})
    if (!std::isnan(value) && !std::isfinite(value))
      return Fail(error, std::string(name) + " must be finite, got " + sim::FormatShortest(value));
  spec.start_time = r.start_time;
  spec.stop_time = r.stop_time;
  spec.interval = r.interval;
  spec.rtol = r.rtol;
  spec.atol = r.atol;
  spec.outputs = r.outputs;
  pipeline::ResolvedRun resolved;
  if (std::string why = pipeline::ResolveRun(*model.model, spec, &resolved); !why.empty()) return Fail(error, why);
  *so = resolved.sim;
  // W313 and a suspicious rtol (W314 came with the load).
  if (program.options.indeterminate == rt::IndeterminateReactions::NaN) {
    const std::vector<std::string> which = rt::IndeterminateSignals(program, so->signals);
    if (!which.empty())
      warnings->push_back(pipeline::RenderCompileMessage(*model.model, rt::IndeterminateWarning(program, which),
                                                         lang::Severity::Warning));
  }
  if (std::string w = sim::ToleranceWarning(so->rtol); !w.empty()) warnings->push_back("kanesim: warning: " + w);
  return true;
}

namespace {
// Rows into one contiguous buffer.
class BufferSink final : public sim::SignalSink {
 public:
  BufferSink(RunOutput* out, const std::function<bool()>& interrupted) : out_(out), interrupted_(interrupted) {}
  bool Begin(const std::vector<std::string>& names) override {
    out_->columns = names;
    return true;
  }
  bool Row(double t, const double* values, size_t count) override {
    out_->time.push_back(t);
    out_->values.insert(out_->values.end(), values, values + count);
    if (interrupted_) {
      const auto now = std::chrono::steady_clock::now();
      if (now - last_poll_ >= std::chrono::milliseconds(100)) {
        last_poll_ = now;
        if (interrupted_()) {
          out_->interrupted = true;
          return false;  // Simulate stops: "cannot write the output", read as the interruption
        }
      }
    }
    return true;
  }

 private:
  RunOutput* out_;
  const std::function<bool()>& interrupted_;
  std::chrono::steady_clock::time_point last_poll_ = std::chrono::steady_clock::now();
};
}  // namespace

bool Simulate(const LoadedModel& model, const sim::SimOptions& options, RunOutput* out, std::string* error,
              const std::function<bool()>& interrupted, const std::vector<std::string>& sensitivity) {
  std::vector<sim::SensitivityParam> params;
  if (!sensitivity.empty())
    if (std::string why = pipeline::SensitivityParams(*model.model, sensitivity, &params); !why.empty())
      return Fail(error, "sensitivity" + why.substr(why.find(' ')));
  const sim::OutputGrid grid = sim::ResolveGrid(*model.program, options);
  const long rows = grid.Count();
  out->time.reserve(static_cast<size_t>(rows));
  if (!options.signals.empty()) out->values.reserve(static_cast<size_t>(rows) * options.signals.size());
  BufferSink sink(out, interrupted);
  const auto t0 = std::chrono::steady_clock::now();
  const sim::SimResult result = params.empty() ? sim::Simulate(*model.program, options, sink)
                                               : sim::SimulateSensitivities(*model.program, params, options, sink);
  out->simulate_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  out->stats = result.stats;
  if (out->interrupted) return true;
  switch (result.status) {
    case sim::SimResult::Status::kOk: return true;
    case sim::SimResult::Status::kUsageError:
    case sim::SimResult::Status::kOutputError: return Fail(error, result.message);
    case sim::SimResult::Status::kNumericalFailure:
      out->failed = true;
      out->fail_time = result.fail_time;
      out->message = result.message;
      return true;
  }
  return true;
}

namespace {
Value V(std::string s) { return Value{std::move(s)}; }
Value V(const char* s) { return Value{std::string(s)}; }
Value V(double d) { return Value{d}; }
Value V(int i) { return Value{static_cast<long>(i)}; }
Value V(bool b) { return Value{b}; }
Value V(Dict d) { return Value{std::make_shared<Dict>(std::move(d))}; }
Value V(List l) { return Value{std::make_shared<List>(std::move(l))}; }
}  // namespace

Dict Check(const LoadedModel& model) {
  const rt::Program& program = *model.program;
  const flat::Mechanism& mech = *program.mech;
  const rt::ProgramSummary s = rt::Summarize(program);
  Dict d;
  d.emplace_back("model", V(mech.model_name));
  d.emplace_back("description", V(mech.description));
  d.emplace_back("bodies", V(s.num_bodies));
  List joints;
  for (const auto& j : mech.joints) {
    bool prescribed = false;
    for (auto p : j.prescribed) prescribed = prescribed || p != flat::kNoExpr;
    joints.push_back(V(Dict{{"name", V(j.name)},
                            {"type", V(flat::JointTypeName(j.type))},
                            {"prescribed", V(prescribed)},
                            {"cut", V(j.cut)}}));
  }
  d.emplace_back("joints", V(std::move(joints)));
  d.emplace_back("nq", V(s.nq));
  d.emplace_back("nu", V(s.nu));
  d.emplace_back("dof", V(s.dof));
  d.emplace_back("grubler_dof", V(s.grubler_dof));
  d.emplace_back("solver", V(pipeline::SolverName(s.solver)));
  d.emplace_back("solver_reason", V(s.solver_reason));
  d.emplace_back("integrator", V(pipeline::IntegratorName(s.integrator)));
  d.emplace_back("integrator_reason", V(s.integrator_reason));
  List cuts;
  for (const auto& c : s.cut_joints) cuts.push_back(V(c));
  d.emplace_back("cut_joints", V(std::move(cuts)));
  List notes;
  for (const auto& n : s.notes) notes.push_back(V(n));
  d.emplace_back("notes", V(std::move(notes)));
  const flat::Experiment& x = mech.experiment;
  Dict ex{{"start_time", V(x.start_time)}, {"stop_time", V(x.stop_time)}, {"tolerance", V(x.tolerance)}};
  if (x.has_interval) ex.emplace_back("interval", V(x.interval));
  d.emplace_back("experiment", V(std::move(ex)));
  // The model's own parameters (declared in its file), as `kanesim check` lists them.
  Dict params;
  for (size_t i = 0; i < mech.params.size(); ++i) {
    const flat::Param& p = mech.params[i];
    if (p.loc.file != model.request.path) continue;
    Dict one;
    if (p.type == flat::ParamType::String) one.emplace_back("value", V(p.string_value));
    else if (p.type == flat::ParamType::Boolean) one.emplace_back("value", V(p.value != 0.0));
    else if (p.type == flat::ParamType::Integer) one.emplace_back("value", Value{static_cast<long>(p.value)});
    else one.emplace_back("value", V(p.value));
    one.emplace_back("unit", V(p.unit));
    one.emplace_back("structural", V(p.structural));
    params.emplace_back(std::string(mech.ParamName(i)), V(std::move(one)));
  }
  d.emplace_back("parameters", V(std::move(params)));
  List outputs;
  for (const auto& o : mech.outputs) outputs.push_back(V(o.name));
  d.emplace_back("outputs", V(std::move(outputs)));
  return d;
}

std::vector<std::string> AvailableSignals(const LoadedModel& model) { return model.Signals(); }

namespace {

// Forking from the interpreter's process: the worker runs C++ only (the scenario, and the
// front end for a structural variant) and leaves with _exit; the calling thread holds no
// GIL (released by module.cpp). A lock another thread holds at the fork stays locked in the
// worker forever. Two are taken around every fork (pthread_atfork), so the worker starts
// with them free: the front end's (g_load_mutex, the one way into it here), then the
// syntax-tree nodes' (lang/node_pool.h), which a thread dropping a model takes outside
// the front end (the worker then spun on it until the scenario's timeout). That order is
// the front end's own, so no thread holds the second while waiting for the first.
void ForkGuards() {
  static std::once_flag once;
  std::call_once(once, [] {
    const auto unlock = [] {
      lang::NodePoolsUnlock();
      g_load_mutex.unlock();
    };
    ::pthread_atfork(
        [] {
          g_load_mutex.lock();
          lang::NodePoolsLock();
        },
        unlock, unlock);
  });
}

// The sweep's scenarios in worker processes (batch/worker_pool.h). False when no
// process could be made: *first is where the threads take over (scenarios before it have
// their rows); true when every scenario has its row or the sweep was interrupted.
bool SweepInWorkers(batch::ScenarioRunner& runner, const batch::SweepConfig& config, const SweepRequest& request,
                    unsigned workers, SweepTable* out, size_t* first, std::string* why) {
  ForkGuards();
  batch::WorkerPool pool(runner, config, static_cast<int>(workers), "scenario_timeout");
  size_t next = 0;
  while (true) {
    bool can_start = true;
    while (can_start && next < config.scenarios.size() && pool.HasIdle()) {
      can_start = pool.Start(config.scenarios[next], why);
      if (can_start) ++next;
    }
    if (pool.Running() == 0) {
      *first = next;
      return next >= config.scenarios.size();
    }
    batch::WorkerPool::Done done;
    const bool ended = pool.Wait(&done, 0.25);  // a quarter second: how often Ctrl-C is noticed
    if (ended) {
      out->lines[static_cast<size_t>(done.scenario - config.scenarios.data())] = done.line;
      out->failed += done.outcome != batch::WorkerPool::Outcome::kOk ? 1 : 0;
      out->crashed += done.outcome == batch::WorkerPool::Outcome::kCrashed ? 1 : 0;
      out->timed_out += done.outcome == batch::WorkerPool::Outcome::kTimedOut ? 1 : 0;
    }
    if (request.interrupted && request.interrupted()) {
      out->interrupted = true;
      return true;  // the pool's end kills the running workers
    }
  }
}

}  // namespace

bool Sweep(const LoadedModel& model, const SweepRequest& request, SweepTable* out, std::string* error) {
  batch::SweepConfig config;
  std::vector<batch::Block> blocks;
  for (const auto& [name, values] : request.grid) {
    batch::Block b;
    b.names = {name};
    for (double v : values) b.rows.push_back({v});
    blocks.push_back(std::move(b));
  }
  if (!request.samples.empty()) {
    batch::Block b;
    const size_t n = request.samples.front().second.size();
    for (const auto& [name, values] : request.samples) {
      if (values.size() != n) return Fail(error, "samples: every column needs the same length ('" + name + "' has " +
                                                     std::to_string(values.size()) + ", not " + std::to_string(n) + ")");
      b.names.push_back(name);
    }
    for (size_t i = 0; i < n; ++i) {
      std::vector<double> row;
      for (const auto& col : request.samples) row.push_back(col.second[i]);
      b.rows.push_back(std::move(row));
    }
    blocks.push_back(std::move(b));
  }
  if (blocks.empty()) return Fail(error, "no scenarios: give grid= or samples=");
  if (!batch::CombineBlocks(blocks, &config.param_names, &config.scenarios, error)) return false;
  for (const std::string& m : request.metrics) {
    batch::Metric metric;
    if (!batch::ParseMetric(m, &metric, error)) return false;
    config.metrics.push_back(metric);
  }
  std::vector<std::string> warnings;
  if (!ResolveRun(model, request.run, &config.sim, &warnings, error)) return false;
  config.sim.signals.clear();
  if (!batch::ValidateSweep(*model.program, config, error)) return false;

  // Structural variants: the model loaded again with the structural values set.
  const std::shared_ptr<const rt::Program> base = model.program;
  const LoadRequest base_request = model.request;
  batch::VariantBuilder build = [base, base_request](const std::vector<std::pair<std::string, double>>& structural,
                                                     std::string* err) -> std::shared_ptr<const rt::Program> {
    LoadRequest lr = base_request;
    std::string what;
    for (const auto& [name, v] : structural) {
      const int i = base->mech->FindParam(name);
      const bool boolean = i >= 0 && base->mech->params[static_cast<size_t>(i)].type == flat::ParamType::Boolean;
      lr.sets.push_back(name + "=" + (boolean ? (v != 0.0 ? "true" : "false") : sim::FormatNumber(v)));
      what += " " + name + "=" + sim::FormatNumber(v);
    }
    LoadedModel variant;
    ModelErrorInfo info;
    if (!Load(lr, &variant, &info)) {
      *err = "the model does not elaborate or compile with" + what + ": " + info.rendered;
      return nullptr;
    }
    return variant.program;
  };
  batch::ScenarioRunner runner(base, build, config);
  out->header = runner.Header();
  out->lines.assign(config.scenarios.size(), std::string());
  unsigned threads = request.threads > 0 ? static_cast<unsigned>(request.threads)
                                         : std::max(1u, std::thread::hardware_concurrency());
  threads = std::min<unsigned>(threads, static_cast<unsigned>(std::max<size_t>(1, config.scenarios.size())));
  config.scenario_timeout = request.scenario_timeout;
  size_t first = 0;  // the first scenario for the threads
  if (request.processes) {
    std::string why;
    if (SweepInWorkers(runner, config, request, threads, out, &first, &why)) return true;  // all done, or interrupted
    out->warning = why + "; the remaining " + std::to_string(config.scenarios.size() - first) +
                   " scenarios ran on threads of this process, where a crash ends the interpreter";
  }
  std::atomic<size_t> next{first};
  std::atomic<int> failed{0};
  std::atomic<bool> stop{false};
  auto work = [&](bool poll) {
    for (size_t i = next++; i < config.scenarios.size() && !stop; i = next++) {
      bool f = false;
      out->lines[i] = runner.Run(config.scenarios[i], &f);
      if (f) ++failed;
      if (poll && request.interrupted && request.interrupted()) stop = true;
    }
  };
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < threads; ++t) pool.emplace_back(work, false);
  work(true);
  for (std::thread& t : pool) t.join();
  out->failed += failed.load();
  out->interrupted = stop.load();
  return true;
}

namespace {
// The model's inputs' values from `given` (name, value) into *values (rt::InputName order):
// status 1 for a name that is not one of them and for one left without a value (at its
// declaration, as the CLI's E239).
lin::Status HeldInputs(const rt::Program& p, const std::vector<std::pair<std::string, double>>& given,
                       std::vector<double>* values) {
  std::vector<char> set(values->size(), 0);
  for (const auto& [name, v] : given) {
    int k = 0;
    while (k < rt::NumInputs(p) && rt::InputName(p, k) != name) ++k;
    if (k == rt::NumInputs(p))
      return {1, "'" + name + "' is not one of the model's inputs (input Real ...;)",
              "a joint force or a parameter as a column of B: inputs=[...] or inputs={name: None}"};
    if (!std::isfinite(v)) return {1, "input '" + name + "': " + sim::FormatShortest(v) + " is not a finite number"};
    (*values)[size_t(k)] = v;
    set[size_t(k)] = 1;
  }
  for (int k = 0; k < rt::NumInputs(p); ++k)
    if (!set[size_t(k)])
      return {1, "input '" + rt::InputName(p, k) + "' has no value",
              "give its value at the operating point: inputs={'" + rt::InputName(p, k) + "': value}",
              p.mech->inputs[size_t(k)].loc};
  return {};
}
}  // namespace

bool Linearize(const LoadedModel& model, const LinearizeRequest& r, LinearizeOutput* out, std::string* error) {
  if (!(r.step > 0.0) || r.step > 0.1) return Fail(error, "step must be in (0, 0.1], got " + sim::FormatShortest(r.step));
  if (r.has_at && !std::isfinite(r.at)) return Fail(error, "at must be finite, got " + sim::FormatShortest(r.at));
  const auto t0 = std::chrono::steady_clock::now();
  const rt::Program& program = *model.program;
  sim::ConstantInputs held(rt::NumInputs(program));
  lin::Status s = HeldInputs(program, r.input_values, &held.values);
  // The operating point as `kanesim linearize` takes it (cli/cmd_linearize.cpp).
  lin::OperatingPoint op = lin::StartPoint(program);
  if (s.ok() && r.has_at) s = lin::PointAtTime(program, r.at, &op, held.values.empty() ? nullptr : &held);
  if (s.ok() && r.equilibrium) {
    out->has_equilibrium = true;
    s = lin::FindEquilibrium(program, op, &out->equilibrium, held.values);
    if (s.ok()) op = out->equilibrium.point;
  }
  out->point = op;
  if (s.ok()) {
    lin::LinearizeOptions o;
    o.step = r.step;
    o.input_values = held.values;
    o.inputs = r.inputs;
    o.outputs = r.outputs;
    s = lin::Linearize(program, op, o, &out->model);
    if (s.ok()) lin::ComputeModes(&out->model);
  }
  out->status = std::move(s);
  out->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return true;
}

}  // namespace kanesim::py
