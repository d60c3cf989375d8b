// `kanesim sweep`: run many scenarios of one model and write one summary row each.
//
// Stages (RunSweep):
//   1. validate: every swept parameter exists and is not a constant, every metric names
//      an available signal                                        (ValidateSweep)
//   2. lock the output, check the settings record, open the summary, keeping finished
//      rows with --resume                                          (OpenSweepOutput)
//   3. hand out this shard's remaining scenarios to worker processes (or threads:
//      SweepConfig::isolation; worker_pool.h supervises the processes); each scenario is
//        a. its structural variant's program: built once per distinct set of structural
//           values (re-elaboration through the caller's VariantBuilder), cached
//        b. its numeric values bound with rt::Rebind (patterns and KLU's symbolic
//           analysis reused), or the variant's program itself when nothing numeric changes
//        c. simulated with sim::Simulate into a MetricSink (and a trajectory file)
//        d. formatted as one line and appended durably              (ScenarioRunner::Run)
//   4. rewrite the summary sorted by id                             (SummaryFile::Finish)
// Every scenario starts from the shared immutable programs and owns its workspaces, so
// its row does not depend on the thread count, the order, shards or MPI ranks (only the
// wall_time column does).
#pragma once

#include <atomic>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "batch/file_guard.h"
#include "batch/metrics.h"
#include "batch/scenario.h"
#include "batch/settings_record.h"
#include "batch/summary.h"
#include "runtime/runtime.h"
#include "sim/simulate.h"

namespace kanesim::batch {

struct SweepProgress {
  int total = 0;    // scenarios of this shard
  int skipped = 0;  // already done (--resume)
  int done = 0;     // finished in this run, failed included
  int failed = 0;    // every row whose status is not "ok", these two included:
  int crashed = 0;   //   the worker process died running it (a signal, out of memory)
  int timed_out = 0; //   stopped after SweepConfig::scenario_timeout
  double elapsed = 0.0;  // seconds since the first scenario started
};

struct SweepConfig {
  std::vector<std::string> param_names;  // columns of Scenario::values
  std::vector<Scenario> scenarios;       // the whole sweep, ids 0..n-1
  std::vector<Block> blocks;             // their sources: written beside the summary (ScenariosPathFor)
  std::vector<Metric> metrics;
  sim::SimOptions sim;                   // defaults for every scenario (signals ignored)
  bool trajectories = false;             // write <out_dir>/trajectories/scenario_<id>.csv
  std::vector<std::string> trajectory_signals;  // exact names; empty: rt::DefaultSignals
  std::string out_dir = "sweep-out";
  int threads = 0;                       // 0: all cores
  // How scenarios are kept apart (worker_pool.h): in worker processes supervised by the
  // sweep, so that a scenario that crashes, exhausts memory or hangs costs its own row
  // only; or on threads of this process (a crash ends the sweep).
  enum class Isolation { kProcess, kThread };
  Isolation isolation = Isolation::kProcess;
  double scenario_timeout = 0.0;         // seconds of wall time per scenario; 0: none (processes only)
  double worker_memory_mib = 0.0;        // address space a worker may add, MiB; 0: no limit (processes only)
  bool resume = false;
  int shard_index = 0, shard_count = 1;  // run scenarios with id % count == index
  const std::atomic<bool>* cancel = nullptr;  // set (e.g. by SIGINT): stop handing out work
  std::function<void(const SweepProgress&)> progress;  // called under a lock
  // What the summary is made with (settings_record.h); written beside it, and compared
  // with the record of the summary that --resume continues. Empty: no record.
  SettingsRecord settings;
  std::vector<std::string> inputs;       // files the sweep reads: never overwritten
};

struct SweepReport {
  std::string summary_path;
  SweepProgress progress;
  int variants = 0;          // programs compiled: the base, and every structural variant once per
                             // thread pool or once per worker process that needed it
  bool interrupted = false;
  bool is_root = true;       // false on MPI worker ranks (they write nothing)
  std::vector<std::string> warnings;  // e.g. worker processes could not be made (threads ran instead)
};

// Builds the program of a structural variant: the model elaborated again with these
// structural parameter values (on top of the sweep's fixed --set values). Called at most
// once per variant and never concurrently.
using VariantBuilder = std::function<std::shared_ptr<const rt::Program>(
    const std::vector<std::pair<std::string, double>>& structural, std::string* error)>;

// The summary's file name: summary.csv, or summary.shard-K-of-N.csv for a shard.
std::string SummaryFileName(const SweepConfig& config);

// Stage 2, the output of this process: the directory made; locked against a second
// sweep writing the same summary at once (a shard locks its own summary, so shards may
// share a directory); no input overwritten; temporaries of killed sweeps removed; with
// --resume the settings record compared with the one beside the old summary; the summary
// opened (finished rows kept with --resume, in `done`); the settings record written.
struct SweepOutput {
  std::string summary_path;
  FileLock lock;
  SummaryFile summary;
  std::map<int, std::string> done;  // id -> line already in the summary (--resume)
};
bool OpenSweepOutput(const SweepConfig& config, const std::string& header, SweepOutput* out, std::string* error);

bool ValidateSweep(const rt::Program& base, const SweepConfig& config, std::string* error);

// Runs one scenario into its summary line; thread-safe.
class ScenarioRunner {
 public:
  ScenarioRunner(std::shared_ptr<const rt::Program> base, VariantBuilder build, const SweepConfig& config);
  std::string Header() const;
  // The line for scenario `s` (its id first); *failed when its status is "failed".
  std::string Run(const Scenario& s, bool* failed);
  // The line of a scenario whose run was lost (its worker crashed or was stopped): the
  // scenario's settings, `status` and `message`, no metrics or statistics.
  std::string LostRow(const Scenario& s, const std::string& status, const std::string& message, double wall) const;
  int NumVariants() const;

 private:
  sim::SimOptions OptionsFor(const Scenario& s) const;
  std::string Row(const Scenario& s, const sim::SimOptions& so, const std::string& status, const std::string& message,
                  double fail_time, const std::vector<double>& metric_values, const sim::SimStats* stats,
                  double wall) const;
  struct Variant {
    std::shared_ptr<const rt::Program> program;
    std::string error;
  };
  const Variant& GetVariant(const std::vector<std::pair<std::string, double>>& structural);

  std::shared_ptr<const rt::Program> base_;
  std::vector<double> base_values_;
  VariantBuilder build_;
  const SweepConfig& config_;
  std::mutex variants_mutex_;
  std::mutex build_mutex_;
  std::map<std::string, std::unique_ptr<Variant>> variants_;
};

// Stages 2-4 with threads. False on a usage or I/O error (failed scenarios are rows).
bool RunSweep(std::shared_ptr<const rt::Program> base, const VariantBuilder& build, const SweepConfig& config,
              SweepReport* report, std::string* error);

// The same over MPI ranks (rank 0 hands out scenario ids on request and writes the
// summary; the others simulate). False with a message when the MPI module cannot be loaded
// (a build without MPI has none).
bool RunSweepMpi(std::shared_ptr<const rt::Program> base, const VariantBuilder& build, const SweepConfig& config,
                 SweepReport* report, std::string* error);

// Resume support: true when a summary line's status is "crashed" or "timeout" (what became
// of the worker, not of the model: --resume runs the scenario again).
bool RerunOnResume(const std::string& line, size_t num_params);
// Resume support: false when the line's parameter fields differ from the scenario's.
bool RowMatchesScenario(const std::string& line, const Scenario& s);

}  // namespace kanesim::batch
