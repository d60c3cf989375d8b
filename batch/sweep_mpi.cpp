// MPI mode of the sweep: `mpirun -n R kanesim sweep --mpi ...`.
//
// Dynamic load balancing by a manager/worker protocol: rank 0 owns the summary and the
// list of pending scenario ids; ranks 1..R-1 each ask for work (kTagReady), receive an
// id (kTagWork; -1 = no more work), simulate it and send back its summary line
// (kTagResult), which is also their next request. Fast ranks therefore take more
// scenarios, and no rank waits on a static partition. Rank 0 only coordinates (its
// waits are blocking receives), so R ranks give R - 1 simulating processes; with R = 1
// the sweep runs on threads as without MPI.
//
// The MPI calls are in the module libkanesim_batch_mpi.so (mpi_module.h), loaded here only
// when an MPI sweep starts: kanesim does not map libmpi at start.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <filesystem>
#include <string>

#include "batch/mpi_module.h"
#include "batch/summary.h"
#include "batch/sweep.h"
#include "batch/worker_pool.h"

namespace kanesim::batch {

namespace {

constexpr int kTagReady = 1, kTagWork = 2, kTagResult = 3;

bool Manager(const mpi::ModuleApi& mpi, ScenarioRunner& runner, const SweepConfig& config, int size,
             SweepReport* report, std::string* error) {
  SweepOutput output;
  bool ok = OpenSweepOutput(config, runner.Header(), &output, error);
  report->summary_path = output.summary_path;
  SummaryFile& summary = output.summary;
  const std::map<int, std::string>& done = output.done;
  std::vector<int> pending;
  SweepProgress& pr = report->progress;
  pr = SweepProgress{};
  for (const Scenario& s : config.scenarios) {
    if (!ok || s.id % config.shard_count != config.shard_index) continue;
    ++pr.total;
    auto it = done.find(s.id);
    if (it == done.end() || RerunOnResume(it->second, config.param_names.size())) {
      pending.push_back(s.id);
    } else if (!RowMatchesScenario(it->second, s)) {
      *error = "cannot resume: scenario " + std::to_string(s.id) + " has other parameter values (another sweep?)";
      ok = false;
    } else {
      ++pr.skipped;
    }
  }
  if (!ok) pending.clear();  // still release the workers
  auto start = std::chrono::steady_clock::now();
  size_t next = 0;
  int active = size - 1;
  std::string io_error;
  while (active > 0) {
    std::string msg;
    int source = 0, tag = 0;
    mpi.receive_any(&msg, &source, &tag);
    if (tag == kTagResult && msg.size() > 1) {
      // 'O' ok, 'F' failed, 'C' crashed, 'T' timed out; then the line.
      const char kind = msg[0];
      std::string line = msg.substr(1);
      int id = std::atoi(line.c_str());
      std::string err;
      if (!summary.Append(id, line, &err) && io_error.empty()) io_error = err;
      ++pr.done;
      pr.failed += kind != 'O' ? 1 : 0;
      pr.crashed += kind == 'C' ? 1 : 0;
      pr.timed_out += kind == 'T' ? 1 : 0;
      pr.elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      if (config.progress) config.progress(pr);
    }
    bool cancelled = config.cancel && config.cancel->load();
    int id = (!cancelled && next < pending.size()) ? pending[next++] : -1;
    const std::string work = std::to_string(id);  // the id as text; -1: no more work
    mpi.send(work.data(), static_cast<int>(work.size()), source, kTagWork);
    if (id < 0) --active;
  }
  report->interrupted = config.cancel && config.cancel->load() && next < pending.size();
  if (!ok) return false;
  if (!summary.Finish(error)) return false;
  if (!io_error.empty()) {
    *error = io_error;
    return false;
  }
  return true;
}

// A rank's scenarios run in one worker process of its own (worker_pool.h) unless the
// sweep runs on threads: a crash costs the scenario, not the rank (which would end the
// whole MPI job).
void Worker(const mpi::ModuleApi& mpi, ScenarioRunner& runner, const SweepConfig& config) {
  std::map<int, const Scenario*> by_id;
  for (const Scenario& s : config.scenarios) by_id[s.id] = &s;
  std::unique_ptr<WorkerPool> pool;
  if (config.isolation == SweepConfig::Isolation::kProcess) pool = std::make_unique<WorkerPool>(runner, config, 1);
  const char ready = 'R';
  mpi.send(&ready, 1, 0, kTagReady);
  while (true) {
    std::string work;
    mpi.receive(&work, 0, kTagWork);
    const int id = std::atoi(work.c_str());
    if (id < 0) return;
    std::string msg;
    WorkerPool::Done done;
    std::string error;
    if (pool && pool->Start(*by_id.at(id), &error) && pool->Wait(&done)) {
      const char kinds[] = {'O', 'F', 'C', 'T'};
      msg = kinds[static_cast<int>(done.outcome)] + done.line;
    } else {
      if (pool) std::fprintf(stderr, "kanesim: warning: %s; this rank runs the scenario itself\n", error.c_str());
      bool failed = false;
      msg = runner.Run(*by_id.at(id), &failed);
      msg.insert(msg.begin(), failed ? 'F' : 'O');
    }
    mpi.send(msg.data(), static_cast<int>(msg.size()), 0, kTagResult);
  }
}

}  // namespace

bool RunSweepMpi(std::shared_ptr<const rt::Program> base, const VariantBuilder& build, const SweepConfig& config,
                 SweepReport* report, std::string* error) {
  const mpi::ModuleApi* module = mpi::Module(error);
  if (!module) {
    if (error) *error += " (the module is built when CMake finds MPI: install libopenmpi-dev, configure again)";
    return false;
  }
  const mpi::ModuleApi& mpi = *module;
  int rank = 0, size = 1;
  mpi.init(&rank, &size);
  report->is_root = rank == 0;
  bool ok = true;
  if (size == 1) {
    ok = RunSweep(std::move(base), build, config, report, error);
  } else if (!ValidateSweep(*base, config, error)) {
    ok = false;  // every rank validates the same inputs, so all stop here
  } else {
    ScenarioRunner runner(base, build, config);
    if (rank == 0) {
      ok = Manager(mpi, runner, config, size, report, error);
    } else {
      Worker(mpi, runner, config);
    }
    report->variants = runner.NumVariants();
  }
  mpi.finalize();
  return ok;
}

}  // namespace kanesim::batch
