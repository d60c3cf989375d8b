// Scenarios in worker processes (SweepConfig::Isolation::kProcess, the default of
// `kanesim sweep`, of `kanesim test` and of Python's kanesim.sweep): one scenario's
// failure, of any kind, never takes the sweep down. ProcessPool is the machinery, for any
// PoolTasks; WorkerPool runs a sweep's scenarios with it.
//
// The sweep process forks workers that share its compiled programs (copy-on-write) and run
// one scenario at a time through the same ScenarioRunner as the threads do, so a worker's
// row is byte for byte a thread's row. The sweep process itself runs no scenario: it hands
// out scenarios, collects rows and watches the workers. A worker that dies (a signal:
// SIGSEGV, SIGABRT, the out-of-memory killer's SIGKILL; or an exit) or runs past the time
// limit (then killed) costs only the scenario it was running: that row is written with
// status "crashed" or "timeout" and a message saying why, and a fresh worker takes the
// next scenario. An exception that escapes a scenario (std::bad_alloc under the worker's
// memory limit) is a "failed" row, and the worker goes on.
//
// Workers are made more likely than the sweep process to be chosen by the kernel's
// out-of-memory killer (oom_score_adj), die with it (PR_SET_PDEATHSIG), ignore SIGINT (the
// sweep process decides what an interruption stops) and may get an address-space limit
// (SweepConfig::worker_memory_mib, on top of what they inherit at the fork).
//
// Protocol, two pipes per worker:
//   sweep -> worker   the scenario's index in SweepConfig::scenarios, an int32; the end
//                     of the pipe tells the worker to exit
//   worker -> sweep   a uint32 byte count, then 'O' (ok) or 'F' (failed), 'V' (a structural
//                     variant was compiled for it) or '-', and the row
// A worker that dies mid-message is a crash like any other.
//
// The sweep process must be single-threaded when it forks (the fork copies only the
// calling thread): WorkerPool's owner polls, it never starts threads. Forking from a
// process with other threads (Python's) is safe only as far as the child stays off their
// state: a worker runs C++ tasks only, resets every signal handler the owner installed,
// and leaves with _exit (no atexit handlers, no flushing of the owner's buffers).
#pragma once

#include <signal.h>

#include <atomic>
#include <string>
#include <vector>

#include "batch/sweep.h"

namespace kanesim::batch {

// Tasks a ProcessPool runs by index (0..Count()-1): the scenarios of a sweep, the golden
// tests of `kanesim test`, the scenarios of Python's kanesim.sweep.
class PoolTasks {
 public:
  virtual ~PoolTasks() = default;
  virtual size_t Count() const = 0;
  // In a worker process: task `index`'s result; *failed and *flag mean what the owner
  // says (a sweep: the row's status is "failed"; a structural variant was compiled).
  // Runs C++ only: a worker never touches state of the owner's language runtime.
  virtual std::string Run(size_t index, bool* failed, bool* flag) = 0;
  // The result of a task whose run was lost: `status` "crashed" (its worker died),
  // "timeout" (stopped) or "failed" (an exception escaped Run), and why.
  virtual std::string Lost(size_t index, const std::string& status, const std::string& message, double wall) const = 0;
  // The id the test fault hook ($KANESIM_TEST_SWEEP_FAULT) matches for this task.
  virtual int FaultId(size_t index) const = 0;
};

struct PoolLimits {
  double timeout = 0.0;      // seconds of wall time per task; 0: none
  double memory_mib = 0.0;   // address space a worker may add, MiB; 0: no limit
  std::string task = "scenario";                      // in messages: "the worker process running this <task>"
  std::string timeout_option = "--scenario-timeout";  // in messages: where the limits come from
  std::string memory_option = "--worker-memory";
};

// Runs tasks in at most `workers` forked processes (started on demand), one task at a
// time each, and reports every task's end: its result, or a lost result when its worker
// died or ran past the time limit.
class ProcessPool {
 public:
  enum class Outcome { kOk, kFailed, kCrashed, kTimedOut };
  struct Done {
    size_t index = 0;
    std::string line;  // the task's result
    Outcome outcome = Outcome::kOk;
    bool flag = false;
  };

  ProcessPool(PoolTasks& tasks, PoolLimits limits, int workers);
  ~ProcessPool();  // ends the idle workers, kills running ones, reaps all
  ProcessPool(const ProcessPool&) = delete;
  ProcessPool& operator=(const ProcessPool&) = delete;

  bool HasIdle() const;
  int Running() const;
  // Hands task `index` to an idle worker, forking one if needed. False with *error when
  // no process can be made (the owner cannot go on with processes).
  bool Start(size_t index, std::string* error);
  // Blocks until a running task ends (its result, or its crash or timeout result), or
  // until `max_wait` seconds passed (then false, so that the owner can look for an
  // interruption; < 0: no limit); false at once when none is running.
  bool Wait(Done* out, double max_wait = -1.0);

 private:
  struct Worker {
    int pid = -1;
    int command_fd = -1;  // write end: task indices
    int result_fd = -1;   // read end: results
    bool busy = false;
    size_t index = 0;     // the task it runs, when busy
    double started = 0.0; // monotonic seconds
    std::string buffer;   // bytes of the result read so far
  };
  bool Spawn(Worker* w, std::string* error);
  [[noreturn]] void WorkerMain(int command_fd, int result_fd);
  void Close(Worker* w);
  bool Collect(Worker* w, Done* out);
  void Lost(Worker* w, Done* out, const std::string& status, const std::string& message, Outcome outcome);

  PoolTasks& tasks_;
  PoolLimits limits_;
  std::vector<Worker> workers_;
  struct sigaction old_sigpipe_ {};  // restored at the end
};

// The sweep's pool: scenarios of a SweepConfig, rows made by a ScenarioRunner.
class WorkerPool {
 public:
  using Outcome = ProcessPool::Outcome;
  struct Done {
    const Scenario* scenario = nullptr;
    std::string line;  // the summary row
    Outcome outcome = Outcome::kOk;
    bool new_variant = false;  // the worker compiled a structural variant for it
  };

  // `timeout_option`, `memory_option`: how the caller names SweepConfig's limits, in messages.
  WorkerPool(ScenarioRunner& runner, const SweepConfig& config, int workers,
             const std::string& timeout_option = "--scenario-timeout", const std::string& memory_option = "--worker-memory");

  bool HasIdle() const { return pool_.HasIdle(); }
  int Running() const { return pool_.Running(); }
  // `s` must be an element of config.scenarios.
  bool Start(const Scenario& s, std::string* error);
  bool Wait(Done* out, double max_wait = -1.0);

 private:
  class Tasks : public PoolTasks {
   public:
    Tasks(ScenarioRunner& runner, const SweepConfig& config) : runner_(runner), config_(config) {}
    size_t Count() const override { return config_.scenarios.size(); }
    std::string Run(size_t index, bool* failed, bool* flag) override;
    std::string Lost(size_t index, const std::string& status, const std::string& message, double wall) const override;
    int FaultId(size_t index) const override { return config_.scenarios[index].id; }

   private:
    ScenarioRunner& runner_;
    const SweepConfig& config_;
  };
  const SweepConfig& config_;
  Tasks tasks_;
  ProcessPool pool_;
};

// Task ids in `spec` ("segv@3,hang@5,oom@7,abort@1,exit@2,throw@4") at which a worker
// injects that fault: a test hook read from $KANESIM_TEST_SWEEP_FAULT by worker processes
// (tests/batch/sweep_isolation_test.cpp, tests/batch/golden_isolation_test.cpp,
// python/tests/test_sweep_isolation.py); the ids are PoolTasks::FaultId (a sweep's scenario
// id, a golden test's position in the run). "nofork" in it makes the pool's fork fail, as
// under a process limit. Unknown entries are ignored.
void InjectTestFault(const std::string& spec, int id);

}  // namespace kanesim::batch
