// Scenarios in worker processes (SweepConfig::Isolation::kProcess, the default of
// `kanesim sweep`): one scenario's failure, of any kind, never takes the sweep down.
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
// calling thread): WorkerPool's owner polls, it never starts threads.
#pragma once

#include <signal.h>

#include <atomic>
#include <string>
#include <vector>

#include "runtime/batch/sweep.h"

namespace kanesim::batch {

class WorkerPool {
 public:
  enum class Outcome { kOk, kFailed, kCrashed, kTimedOut };
  struct Done {
    const Scenario* scenario = nullptr;
    std::string line;  // the summary row
    Outcome outcome = Outcome::kOk;
    bool new_variant = false;  // the worker compiled a structural variant for it
  };

  // At most `workers` processes, started on demand.
  WorkerPool(ScenarioRunner& runner, const SweepConfig& config, int workers);
  ~WorkerPool();  // ends the idle workers, kills running ones, reaps all
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  bool HasIdle() const;
  int Running() const;
  // Hands `s` (an element of config.scenarios) to an idle worker, forking one if needed.
  // False with *error when no process can be made (the sweep cannot go on).
  bool Start(const Scenario& s, std::string* error);
  // Blocks until a running scenario ends (its row, or its crash or timeout row); false
  // when none is running.
  bool Wait(Done* out);

 private:
  struct Worker {
    int pid = -1;
    int command_fd = -1;  // write end: scenario indices
    int result_fd = -1;   // read end: rows
    const Scenario* scenario = nullptr;  // running, or null when idle
    double started = 0.0;                // monotonic seconds
    std::string buffer;                  // bytes of the row read so far
  };
  bool Spawn(Worker* w, std::string* error);
  [[noreturn]] void WorkerMain(int command_fd, int result_fd);
  void Close(Worker* w);
  // Reads what is available; true when the row is complete (in *out) or the worker died.
  bool Collect(Worker* w, Done* out);
  void Lost(Worker* w, Done* out, const std::string& status, const std::string& message, Outcome outcome);

  ScenarioRunner& runner_;
  const SweepConfig& config_;
  std::vector<Worker> workers_;
  struct sigaction old_sigpipe_ {};  // restored at the end
};

// Scenario ids in `spec` ("segv@3,hang@5,oom@7,abort@1,exit@2,throw@4") at which a worker
// injects that fault: a test hook read from $KANESIM_TEST_SWEEP_FAULT by worker processes
// (tests/batch/sweep_isolation_test.cpp); "nofork" in it makes the pool's fork fail, as
// under a process limit. Unknown entries are ignored.
void InjectTestFault(const std::string& spec, int id);

}  // namespace kanesim::batch
