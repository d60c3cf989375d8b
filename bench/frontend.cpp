// Front-end cost: load (parse) + elaborate + compile of the N-chain (examples/chain.mech
// --set N=...) and of the double pendulum, with the peak memory of each size; and of flat
// models of n scalar declarations (`parameter Real p17 = 17;`, `output Real y17 = 17;`,
// n = 10 000, 40 000, 100 000), whose cost per declaration must stay flat (issue 38: it grew
// as n^2.5 when the elaborator matched every element name against all the others).
//
// Each model runs in a child process of its own, so that its peak RSS is its own. In
// the child, the first load includes parsing the standard library (once per process);
// the steady cost is the best of `repeats` further loads.
//   build/bench/frontend [N ...] [MODEL.mech ...]   (default: 10 100 1000 10000)
//   KANESIM_FRONTEND_REPEATS=5              (default: 5; 1 above N = 2000)
//   KANESIM_FRONTEND_NOFORK=1               (in this process: for profilers; RSS is then shared)
// Output: one row per model: ms for load+elaborate, compile, their sum (first load and
// best steady load), microseconds per link, peak RSS in MB, and the minor page faults of
// the first load (fresh memory the process touches for the first time). Times are the process's CPU
// time (CLOCK_PROCESS_CPUTIME_ID; single-threaded work), steadier than wall time on a
// shared machine.
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <ctime>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <memory>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "lang/diagnostics.h"
#include "lang/elaborate.h"
#include "compiler/compiler.h"
#include "runtime/program/program.h"
#include "stdlib/stdlib.h"

namespace {

using namespace kanesim;
// CPU seconds of this process.
double CpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

struct Cost {
  double elaborate = 0;  // load + elaborate, seconds
  double compile = 0;
  long faults = 0;       // minor page faults during the load
};

long MinorFaults() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  return ru.ru_minflt;
}

// One load + elaborate + compile of `path` with `sets`; false on an error.
bool LoadOnce(const std::string& path, const std::vector<lang::ParamOverride>& sets, Cost* cost) {
  const long f0 = MinorFaults();
  const double t0 = CpuSeconds();
  lang::Program program;
  lang::Diagnostics diags(&program.sources);
  lang::ElaborateOptions eo;
  eo.overrides = sets;
  auto mech = std::make_shared<flat::Mechanism>();  // shared with the program, as pipeline::LoadModel does
  if (!lang::LoadProgram(path, stdlib::Files(), &program, diags, stdlib::Image()) || !lang::Elaborate(program, eo, mech.get(), diags)) {
    std::cerr << diags.RenderAll().substr(0, 4000);
    return false;
  }
  const double t1 = CpuSeconds();
  rt::CompileResult r = rt::Compile(std::shared_ptr<const flat::Mechanism>(std::move(mech)), rt::CompileOptions{});
  const double t2 = CpuSeconds();
  if (!r.program) {
    std::cerr << "compile failed\n";
    return false;
  }
  cost->elaborate = t1 - t0;
  cost->compile = t2 - t1;
  cost->faults = MinorFaults() - f0;
  return true;
}

// Runs in the child: prints one row.
int Measure(const std::string& label, const std::string& path, const std::vector<lang::ParamOverride>& sets, int links,
            int repeats) {
  Cost first, best{1e30, 1e30};
  if (!LoadOnce(path, sets, &first)) return 1;
  double best_total = 1e30;
  for (int r = 0; r < repeats; ++r) {
    Cost c;
    if (!LoadOnce(path, sets, &c)) return 1;
    if (c.elaborate + c.compile < best_total) best_total = c.elaborate + c.compile, best = c;
  }
  if (repeats == 0) best = first, best_total = first.elaborate + first.compile;
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  std::printf("%-16s %7d %12.3f %10.3f %12.3f %12.3f %10.2f %10.1f %10ld\n", label.c_str(), links,
              1e3 * best.elaborate, 1e3 * best.compile, 1e3 * best_total, 1e3 * (first.elaborate + first.compile),
              1e6 * best_total / links, static_cast<double>(ru.ru_maxrss) / 1024.0, first.faults);
  std::fflush(stdout);
  return 0;
}

int InChild(const std::string& label, const std::string& path, const std::vector<lang::ParamOverride>& sets, int links,
            int repeats) {
  std::fflush(stdout);
  if (std::getenv("KANESIM_FRONTEND_NOFORK")) return Measure(label, path, sets, links, repeats);
  pid_t pid = fork();
  if (pid == 0) std::_Exit(Measure(label, path, sets, links, repeats));
  int status = 0;
  waitpid(pid, &status, 0);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) std::printf("%-16s %7d failed\n", label.c_str(), links);
  return 0;
}

// A model of n scalar declarations `<decl> Real <name>i = i;` in a temporary file.
std::string WriteDeclarations(const std::string& decl, const std::string& name, int n) {
  const std::string path = "/tmp/kanesim_frontend_" + name + std::to_string(n) + "_" + std::to_string(getpid()) + ".mech";
  std::ofstream o(path);
  o << "model M\n  World world;\n";
  for (int i = 0; i < n; ++i) o << "  " << decl << " Real " << name << i << " = " << i << ";\n";
  o << "end M;\n";
  return path;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<int> sizes;
  std::vector<std::string> files;  // arguments ending in .mech: those models only, one row each
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a.size() > 5 && a.compare(a.size() - 5, 5, ".mech") == 0)
      files.push_back(a);
    else
      sizes.push_back(std::atoi(argv[i]));
  }
  if (sizes.empty() && files.empty()) sizes = {10, 100, 1000, 10000};
  const char* rep = std::getenv("KANESIM_FRONTEND_REPEATS");
  const int repeats = rep ? std::atoi(rep) : 5;
  const std::string root = KANESIM_SOURCE_DIR;
  std::printf("%-16s %7s %12s %10s %12s %12s %10s %10s %10s\n", "model", "links", "elab_ms", "compile_ms", "total_ms",
              "first_ms", "us/link", "peak_MB", "first_flt");
  for (const std::string& f : files) InChild(f.substr(f.find_last_of('/') + 1), f, {}, 1, repeats);
  if (!files.empty()) return 0;
  InChild("double_pendulum", root + "/examples/double_pendulum.mech", {}, 2, repeats);
  for (int n : sizes)
    InChild("chain", root + "/examples/chain.mech", {{"N", std::to_string(n)}}, n, n > 2000 ? 1 : repeats);
  for (auto [decl, name, label] : {std::tuple{"parameter", "p", "parameters"}, {"output", "y", "outputs"}})
    for (int n : {10000, 40000, 100000}) {
      const std::string path = WriteDeclarations(decl, name, n);
      InChild(label, path, {}, n, repeats);
      std::remove(path.c_str());
    }
  return 0;
}
