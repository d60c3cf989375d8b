// Sweep throughput on 1 thread against 2 (issue #5: at least 1.8x on 2 cores).
//
// The workload: examples/chain.mech (N links, default 10) swept over the start angle q0
// (numeric: one compiled program, rt::Rebind per scenario) with two metrics, each
// scenario simulating `stop` seconds. Runs the same sweep with -j1 and -j2 through
// batch::RunSweep (summary written and fsynced as in `kanesim sweep`), best of
// `repeats`, and prints scenarios per second and the ratio.
//   build/bench/sweep_throughput [scenarios=32] [stop=4] [repeats=3] [N=10]
#include <algorithm>
#include <chrono>
#include <ctime>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <string>
#include <thread>

#include "runtime/batch/sweep.h"
#include "runtime/pipeline/pipeline.h"

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
  double cpu = 0.0;   // process CPU seconds, all threads (std::clock)
};

Timing SweepSeconds(std::shared_ptr<const rt::Program> program, batch::SweepConfig config, int threads) {
  config.threads = threads;
  config.out_dir = (std::filesystem::temp_directory_path() / ("kanesim_bench_j" + std::to_string(threads))).string();
  batch::SweepReport report;
  std::string err;
  auto t0 = std::chrono::steady_clock::now();
  std::clock_t c0 = std::clock();
  if (!batch::RunSweep(program, nullptr, config, &report, &err) || report.progress.failed > 0) {
    std::cerr << "sweep failed: " << err << "\n";
    std::exit(1);
  }
  Timing t;
  t.wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  t.cpu = static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;
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

  Timing best1{1e300, 0}, best2{1e300, 0};
  for (int r = 0; r < repeats; ++r) {
    Timing t1 = SweepSeconds(program, config, 1), t2 = SweepSeconds(program, config, 2);
    if (t1.wall < best1.wall) best1 = t1;
    if (t2.wall < best2.wall) best2 = t2;
  }
  std::printf("sweep_throughput: chain N=%d, %d scenarios x %.3g s simulated, best of %d, %u hardware threads\n",
              links, scenarios, stop, repeats, std::thread::hardware_concurrency());
  std::printf("  -j1  %8.3f s wall  %8.3f s CPU  %8.1f scenarios/s\n", best1.wall, best1.cpu, scenarios / best1.wall);
  std::printf("  -j2  %8.3f s wall  %8.3f s CPU  %8.1f scenarios/s\n", best2.wall, best2.cpu, scenarios / best2.wall);
  std::printf("  speedup 2 threads / 1 thread: %.2fx (goal >= 1.8x)\n", best1.wall / best2.wall);
  // CPU / wall of the -j2 run: how many cores it actually got (2.0 = both, the whole
  // time). Below ~1.9 the machine was shared with other work and the speedup above is
  // bounded by that, not by the sweep.
  std::printf("  cores used by -j2 (CPU / wall): %.2f; CPU per scenario -j2 / -j1: %.2f\n", best2.cpu / best2.wall,
              best2.cpu / best1.cpu);
  return 0;
}
