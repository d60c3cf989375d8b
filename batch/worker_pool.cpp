#include "batch/worker_pool.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <new>
#include <stdexcept>
#include <thread>
#include <utility>
#include <vector>

#include "sim/csv.h"

namespace kanesim::batch {
namespace {

double Now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

bool WriteAll(int fd, const void* data, size_t n) {
  const char* p = static_cast<const char*>(data);
  while (n > 0) {
    ssize_t k = ::write(fd, p, n);
    if (k < 0 && errno == EINTR) continue;
    if (k <= 0) return false;
    p += k;
    n -= static_cast<size_t>(k);
  }
  return true;
}

// Exactly n bytes, or false at the end of the pipe.
bool ReadAll(int fd, void* data, size_t n) {
  char* p = static_cast<char*>(data);
  while (n > 0) {
    ssize_t k = ::read(fd, p, n);
    if (k < 0 && errno == EINTR) continue;
    if (k <= 0) return false;
    p += k;
    n -= static_cast<size_t>(k);
  }
  return true;
}

std::string SignalText(int sig) {
  const char* abbrev = sigabbrev_np(sig);
  const char* what = strsignal(sig);
  std::string s = "signal " + std::to_string(sig);
  if (abbrev) s += std::string(" (SIG") + abbrev + (what ? std::string(", ") + what : std::string()) + ")";
  if (sig == SIGKILL) s += "; the kernel's out-of-memory killer sends it when memory runs out";
  return s;
}

// Address space in use now (bytes), from /proc/self/statm; 0 when unknown.
double AddressSpaceBytes() {
  std::FILE* f = std::fopen("/proc/self/statm", "r");
  if (!f) return 0.0;
  unsigned long pages = 0;
  const int n = std::fscanf(f, "%lu", &pages);
  std::fclose(f);
  return n == 1 ? static_cast<double>(pages) * static_cast<double>(::sysconf(_SC_PAGESIZE)) : 0.0;
}

// A worker's first steps after the fork.
void PrepareWorkerProcess(double memory_mib) {
  ::prctl(PR_SET_PDEATHSIG, SIGKILL);  // never outlive the sweep (a hung worker would hold its lock)
  // The owner's handlers (an interpreter's, which would touch its state) are not the
  // worker's: a signal does what it does by default.
  for (int sig = 1; sig < SIGRTMIN; ++sig)
    if (sig != SIGKILL && sig != SIGSTOP) std::signal(sig, SIG_DFL);
  std::signal(SIGINT, SIG_IGN);  // the terminal's ^C reaches the whole group; the sweep decides
  if (std::FILE* f = std::fopen("/proc/self/oom_score_adj", "w")) {  // best effort
    std::fputs("1000", f);  // the first the out-of-memory killer chooses: never the sweep process
    std::fclose(f);
  }
  if (memory_mib > 0.0) {
    const double limit = AddressSpaceBytes() + memory_mib * 1024.0 * 1024.0;
    struct rlimit rl;
    rl.rlim_cur = rl.rlim_max = static_cast<rlim_t>(std::min(limit, 9.0e18));
    ::setrlimit(RLIMIT_AS, &rl);
  }
}

}  // namespace

void InjectTestFault(const std::string& spec, int id) {
  size_t pos = 0;
  while (pos < spec.size()) {
    size_t end = spec.find(',', pos);
    if (end == std::string::npos) end = spec.size();
    const std::string item = spec.substr(pos, end - pos);
    pos = end + 1;
    const size_t at = item.find('@');
    if (at == std::string::npos || std::atoi(item.c_str() + at + 1) != id) continue;
    const std::string kind = item.substr(0, at);
    if (kind == "segv") {
      // A real invalid access, as a bug would make; not the null pointer, which
      // UndefinedBehaviorSanitizer would report (and end with exit 1) before the signal.
      volatile std::uintptr_t unmapped = 64;  // volatile: no constant address for -Warray-bounds
      *reinterpret_cast<volatile int*>(unmapped) = 1;
    } else if (kind == "abort") {
      std::abort();
    } else if (kind == "exit") {
      std::_Exit(3);
    } else if (kind == "throw") {
      throw std::runtime_error("injected test fault");
    } else if (kind == "hang") {
      while (true) std::this_thread::sleep_for(std::chrono::seconds(1));
    } else if (kind == "oom") {
      // Touch memory until an allocation fails (std::bad_alloc under the worker's limit)
      // or the kernel kills the process.
      std::vector<std::unique_ptr<char[]>> hog;
      while (true) {
        constexpr size_t kChunk = 64u << 20;
        hog.emplace_back(new char[kChunk]);
        std::memset(hog.back().get(), 1, kChunk);
      }
    }
  }
}

ProcessPool::ProcessPool(PoolTasks& tasks, PoolLimits limits, int workers)
    : tasks_(tasks), limits_(std::move(limits)), workers_(static_cast<size_t>(std::max(1, workers))) {
  // A worker killed while idle (the out-of-memory killer prefers workers) has closed its
  // command pipe: writing to it must fail with EPIPE (Start then forks a fresh worker),
  // not raise SIGPIPE, which would end the sweep.
  struct sigaction ignore {};
  ignore.sa_handler = SIG_IGN;
  ::sigaction(SIGPIPE, &ignore, &old_sigpipe_);
}

ProcessPool::~ProcessPool() {
  for (Worker& w : workers_) {
    if (w.pid > 0 && w.busy) ::kill(w.pid, SIGKILL);  // only when the sweep stops early
    Close(&w);
  }
  ::sigaction(SIGPIPE, &old_sigpipe_, nullptr);
}

bool ProcessPool::HasIdle() const {
  for (const Worker& w : workers_)
    if (!w.busy) return true;
  return false;
}

int ProcessPool::Running() const {
  int n = 0;
  for (const Worker& w : workers_) n += w.busy ? 1 : 0;
  return n;
}

void ProcessPool::Close(Worker* w) {
  if (w->command_fd >= 0) ::close(w->command_fd);
  if (w->result_fd >= 0) ::close(w->result_fd);
  if (w->pid > 0) {
    // An idle worker would exit at the end of its command pipe, but another pool's workers,
    // forked meanwhile by another thread (two Python sweeps at once), hold copies of that
    // pipe: waiting for the end could wait for them, and they for us. An idle worker holds
    // nothing unfinished (its last result was sent whole), so it is killed.
    ::kill(w->pid, SIGKILL);
    int status = 0;
    while (::waitpid(w->pid, &status, 0) < 0 && errno == EINTR) {
    }
  }
  *w = Worker{};
}

bool ProcessPool::Spawn(Worker* w, std::string* error) {
  int command[2], result[2];
  if (::pipe2(command, O_CLOEXEC) != 0) {
    *error = std::string("cannot make a pipe for a worker process: ") + std::strerror(errno);
    return false;
  }
  if (::pipe2(result, O_CLOEXEC) != 0) {
    *error = std::string("cannot make a pipe for a worker process: ") + std::strerror(errno);
    ::close(command[0]), ::close(command[1]);
    return false;
  }
  std::fflush(nullptr);  // nothing buffered is written twice
  // Test hook (tests/batch/sweep_isolation_test.cpp): fork fails as under a process limit.
  const char* fault = std::getenv("KANESIM_TEST_SWEEP_FAULT");
  const bool no_fork = fault && std::string(fault).find("nofork") != std::string::npos;
  const pid_t pid = no_fork ? (errno = EAGAIN, -1) : ::fork();
  if (pid < 0) {
    *error = std::string("cannot start a worker process: ") + std::strerror(errno);
    for (int fd : {command[0], command[1], result[0], result[1]}) ::close(fd);
    return false;
  }
  if (pid == 0) {
    // The other workers' pipe ends: held here, they would keep those workers from seeing
    // the end of their command pipe.
    for (Worker& other : workers_)
      for (int fd : {other.command_fd, other.result_fd})
        if (fd >= 0) ::close(fd);
    ::close(command[1]);
    ::close(result[0]);
    WorkerMain(command[0], result[1]);
  }
  ::close(command[0]);
  ::close(result[1]);
  w->pid = pid;
  w->command_fd = command[1];
  w->result_fd = result[0];
  return true;
}

void ProcessPool::WorkerMain(int command_fd, int result_fd) {
  PrepareWorkerProcess(limits_.memory_mib);
  const char* fault = std::getenv("KANESIM_TEST_SWEEP_FAULT");
  while (true) {
    std::int32_t index = -1;
    if (!ReadAll(command_fd, &index, sizeof index) || index < 0 || static_cast<size_t>(index) >= tasks_.Count())
      std::_Exit(0);  // the owner is done with this worker: no destructors of the owner's state
    const auto k = static_cast<size_t>(index);
    const double t0 = Now();
    bool failed = false, flag = false;
    std::string line;
    try {
      if (fault) InjectTestFault(fault, tasks_.FaultId(k));
      line = tasks_.Run(k, &failed, &flag);
    } catch (const std::bad_alloc&) {
      failed = true;
      line = tasks_.Lost(k, "failed",
                         limits_.memory_mib > 0 ? "out of memory (the worker's limit, " + limits_.memory_option +
                                                      ", is " + sim::FormatNumber(limits_.memory_mib) + " MiB)"
                                                : "out of memory",
                         Now() - t0);
    } catch (const std::exception& e) {
      failed = true;
      line = tasks_.Lost(k, "failed", e.what(), Now() - t0);
    }
    std::string message(1, failed ? 'F' : 'O');
    message += flag ? 'V' : '-';
    message += line;
    const std::uint32_t size = static_cast<std::uint32_t>(message.size());
    if (!WriteAll(result_fd, &size, sizeof size) || !WriteAll(result_fd, message.data(), message.size()))
      std::_Exit(0);  // the owner is gone
  }
}

bool ProcessPool::Start(size_t task, std::string* error) {
  for (Worker& w : workers_) {
    if (w.busy) continue;
    if (w.pid <= 0 && !Spawn(&w, error)) return false;
    const auto index = static_cast<std::int32_t>(task);
    if (!WriteAll(w.command_fd, &index, sizeof index)) {
      // The idle worker died (killed from outside): a fresh one takes the task.
      Close(&w);
      if (!Spawn(&w, error) || !WriteAll(w.command_fd, &index, sizeof index)) {
        if (error->empty()) *error = "cannot hand a task to a worker process";
        return false;
      }
    }
    w.busy = true;
    w.index = task;
    w.started = Now();
    w.buffer.clear();
    return true;
  }
  *error = "no idle worker";
  return false;
}

void ProcessPool::Lost(Worker* w, Done* out, const std::string& status, const std::string& message, Outcome outcome) {
  out->index = w->index;
  out->outcome = outcome;
  out->flag = false;
  out->line = tasks_.Lost(w->index, status, message, Now() - w->started);
  w->busy = false;
}

bool ProcessPool::Collect(Worker* w, Done* out) {
  char chunk[65536];
  ssize_t n = ::read(w->result_fd, chunk, sizeof chunk);
  if (n < 0 && (errno == EINTR || errno == EAGAIN)) return false;
  if (n > 0) {
    w->buffer.append(chunk, static_cast<size_t>(n));
    std::uint32_t size = 0;
    if (w->buffer.size() < sizeof size) return false;
    std::memcpy(&size, w->buffer.data(), sizeof size);
    if (w->buffer.size() < sizeof size + size) return false;
    const std::string message = w->buffer.substr(sizeof size, size);
    w->buffer.erase(0, sizeof size + size);
    out->index = w->index;
    out->outcome = !message.empty() && message[0] == 'O' ? Outcome::kOk : Outcome::kFailed;
    out->flag = message.size() > 1 && message[1] == 'V';
    out->line = message.size() > 2 ? message.substr(2) : std::string();
    w->busy = false;
    return true;
  }
  // The end of the pipe: the worker is gone. Why: its exit status.
  ::close(w->command_fd);
  w->command_fd = -1;
  int status = 0;
  while (::waitpid(w->pid, &status, 0) < 0 && errno == EINTR) {
  }
  w->pid = -1;
  std::string why = WIFSIGNALED(status) ? "was killed by " + SignalText(WTERMSIG(status))
                                         : "exited with status " + std::to_string(WEXITSTATUS(status));
  Lost(w, out, "crashed", "the worker process running this " + limits_.task + " " + why, Outcome::kCrashed);
  Close(w);
  return true;
}

bool ProcessPool::Wait(Done* out, double max_wait) {
  const double give_up = max_wait < 0.0 ? HUGE_VAL : Now() + max_wait;
  while (Running() > 0) {
    // Time limits: the nearest deadline bounds the wait.
    const double now = Now();
    double wait = 0.25;  // also how often an interruption is noticed
    for (Worker& w : workers_) {
      if (!w.busy || limits_.timeout <= 0.0) continue;
      const double left = w.started + limits_.timeout - now;
      if (left <= 0.0) {
        ::kill(w.pid, SIGKILL);
        Lost(&w, out, "timeout",
             "stopped after " + sim::FormatNumber(limits_.timeout) + " s of wall time (" +
                 limits_.timeout_option + "); the worker process was killed",
             Outcome::kTimedOut);
        Close(&w);
        return true;
      }
      wait = std::min(wait, left);
    }
    if (now >= give_up) return false;
    wait = std::min(wait, give_up - now);
    std::vector<pollfd> fds;
    std::vector<Worker*> who;
    for (Worker& w : workers_)
      if (w.busy) {
        fds.push_back(pollfd{w.result_fd, POLLIN, 0});
        who.push_back(&w);
      }
    const int ready = ::poll(fds.data(), fds.size(), static_cast<int>(std::ceil(std::max(wait, 0.0) * 1000.0)));
    if (ready <= 0) continue;  // a time-out, or a signal (SIGINT): look again
    for (size_t k = 0; k < fds.size(); ++k)
      if (fds[k].revents != 0 && Collect(who[k], out)) return true;
  }
  return false;
}

WorkerPool::WorkerPool(ScenarioRunner& runner, const SweepConfig& config, int workers,
                       const std::string& timeout_option, const std::string& memory_option)
    : config_(config),
      tasks_(runner, config),
      pool_(tasks_, PoolLimits{config.scenario_timeout, config.worker_memory_mib, "scenario", timeout_option, memory_option},
            workers) {}

std::string WorkerPool::Tasks::Run(size_t index, bool* failed, bool* flag) {
  const int variants_before = runner_.NumVariants();
  std::string line = runner_.Run(config_.scenarios[index], failed);
  *flag = runner_.NumVariants() > variants_before;
  return line;
}

std::string WorkerPool::Tasks::Lost(size_t index, const std::string& status, const std::string& message,
                                    double wall) const {
  return runner_.LostRow(config_.scenarios[index], status, message, wall);
}

bool WorkerPool::Start(const Scenario& s, std::string* error) {
  return pool_.Start(static_cast<size_t>(&s - config_.scenarios.data()), error);
}

bool WorkerPool::Wait(Done* out, double max_wait) {
  ProcessPool::Done d;
  if (!pool_.Wait(&d, max_wait)) return false;
  out->scenario = &config_.scenarios[d.index];
  out->line = std::move(d.line);
  out->outcome = d.outcome;
  out->new_variant = d.flag;
  return true;
}

}  // namespace kanesim::batch
