// Sweep throughput on 1 thread against 2 (issue #5: at least 1.8x on 2 cores), and the
// cost of running scenarios in worker processes (issue 38) against threads.
//
// The workload: examples/chain.mech (N links, default 10) swept over the start angle q0
// (numeric: one compiled program, rt::Rebind per scenario) with two metrics, each
// scenario simulating `stop` seconds. Runs the same sweep with -j1 and -j2 through
// batch::RunSweep (summary written and fsynced as in `kanesim sweep`), best of
// `repeats`, and prints scenarios per second and the ratio.
// Both isolations are measured: threads of one process, and worker processes (the default
// of `kanesim sweep`); CPU time counts the reaped workers too.
//   build/bench/sweep_throughput [scenarios=32] [stop=4] [repeats=3] [N=10]
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <string>
#include <thread>

#include "batch/sweep.h"
#include "pipeline/pipeline.h"

namespace {

using namespace kanesim;

std::shared_ptr<const rt::Program> LoadChain(const std::string& path, int n) {
  pipeline::LoadOptions options;
  options.sets = {"N=" + std::to_string(n)};
  pipeline::LoadResult r = pipeline::LoadModel(pipeline::Source::File(path), options, pipeline::RunSpec{});
  std::cerr << r.diagnostics;
  return r.model ? r.model->program : nullptr;
}

struct Timing {
  double wall = 0.0;  // seconds
  double cpu = 0.0;   // CPU seconds of this process (all threads) and of its reaped workers
};

double CpuSeconds() {
  double total = 0.0;
  for (int who : {RUSAGE_SELF, RUSAGE_CHILDREN}) {
    rusage u{};
    getrusage(who, &u);
    total += static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
             1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
  }
  return total;
}

Timing SweepSeconds(std::shared_ptr<const rt::Program> program, batch::SweepConfig config, int threads,
                    batch::SweepConfig::Isolation isolation) {
  config.threads = threads;
  config.isolation = isolation;
  config.out_dir = (std::filesystem::temp_directory_path() / ("kanesim_bench_j" + std::to_string(threads))).string();
  batch::SweepReport report;
  std::string err;
  auto t0 = std::chrono::steady_clock::now();
  const double c0 = CpuSeconds();
  if (!batch::RunSweep(program, nullptr, config, &report, &err) || report.progress.failed > 0) {
    std::cerr << "sweep failed: " << err << "\n";
    std::exit(1);
  }
  Timing t;
  t.wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  t.cpu = CpuSeconds() - c0;
  std::filesystem::remove_all(config.out_dir);
  return t;
}

}  // namespace

int main(int argc, char** argv) {
  const int scenarios = argc > 1 ? std::atoi(argv[1]) : 32;
  const double stop = argc > 2 ? std::atof(argv[2]) : 4.0;
  const int repeats = argc > 3 ? std::atoi(argv[3]) : 3;
  const int links = argc > 4 ? std::atoi(argv[4]) : 10;
  auto program = LoadChain(std::string(KANESIM_SOURCE_DIR) + "/examples/chain.mech", links);
  if (!program) return 1;

  batch::SweepConfig config;
  config.param_names = {"q0"};
  for (int i = 0; i < scenarios; ++i) {
    batch::Scenario s;
    s.id = i;
    s.values = {0.05 + 0.4 * i / scenarios};
    config.scenarios.push_back(s);
  }
  std::string err;
  for (const char* m : {"final:j[1].q", "max:kinetic_energy"}) {
    batch::Metric metric;
    batch::ParseMetric(m, &metric, &err);
    config.metrics.push_back(metric);
  }
  config.sim.stop_time = stop;
  config.sim.interval = 0.01;
  config.sim.rtol = config.sim.atol = 1e-8;

  using Iso = batch::SweepConfig::Isolation;
  // Interleaved, best of `repeats`: threads -j1, -j2, then processes -j1, -j2.
  Timing best[2][2] = {{{1e300, 0}, {1e300, 0}}, {{1e300, 0}, {1e300, 0}}};
  for (int r = 0; r < repeats; ++r)
    for (int iso = 0; iso < 2; ++iso)
      for (int j = 0; j < 2; ++j) {
        Timing t = SweepSeconds(program, config, j + 1, iso == 0 ? Iso::kThread : Iso::kProcess);
        if (t.wall < best[iso][j].wall) best[iso][j] = t;
      }
  std::printf("sweep_throughput: chain N=%d, %d scenarios x %.3g s simulated, best of %d, %u hardware threads\n",
              links, scenarios, stop, repeats, std::thread::hardware_concurrency());
  for (int iso = 0; iso < 2; ++iso) {
    const Timing& b1 = best[iso][0];
    const Timing& b2 = best[iso][1];
    const char* what = iso == 0 ? "threads" : "worker processes";
    std::printf("  %s\n", what);
    std::printf("    -j1  %8.3f s wall  %8.3f s CPU  %8.1f scenarios/s\n", b1.wall, b1.cpu, scenarios / b1.wall);
    std::printf("    -j2  %8.3f s wall  %8.3f s CPU  %8.1f scenarios/s\n", b2.wall, b2.cpu, scenarios / b2.wall);
    std::printf("    speedup 2 / 1: %.2fx (goal >= 1.8x); cores used by -j2 (CPU / wall): %.2f; CPU per scenario "
                "-j2 / -j1: %.2f\n",
                b1.wall / b2.wall, b2.cpu / b2.wall, b2.cpu / b1.cpu);
  }
  std::printf("  worker processes / threads, wall: -j1 %.3f, -j2 %.3f; CPU: -j1 %.3f, -j2 %.3f\n",
              best[1][0].wall / best[0][0].wall, best[1][1].wall / best[0][1].wall, best[1][0].cpu / best[0][0].cpu,
              best[1][1].cpu / best[0][1].cpu);
  return 0;
}
