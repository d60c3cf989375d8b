// Sweep throughput on 1 thread against 2 (issue #5: at least 1.8x on 2 cores).
//
// The workload: examples/chain.mech (N links, default 10) swept over the start angle q0
// (numeric: one compiled program, rt::Rebind per scenario) with two metrics, each
// scenario simulating `stop` seconds. Runs the same sweep with -j1 and -j2 through
// batch::RunSweep (summary written and fsynced as in `kanesim sweep`), best of
// `repeats`, and prints scenarios per second and the ratio.
//   build/bench/sweep_throughput [scenarios=32] [stop=4] [repeats=3] [N=10]
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <string>
#include <thread>

#include "lang/diagnostics.h"
#include "lang/elaborate.h"
#include "runtime/batch/sweep.h"
#include "runtime/engine.h"
#include "stdlib/stdlib.h"

namespace {

using namespace kanesim;

std::shared_ptr<const rt::Program> LoadChain(const std::string& path, int n) {
  lang::Program program;
  lang::Diagnostics diags(&program.sources);
  lang::ElaborateOptions eo;
  eo.overrides.push_back({"N", std::to_string(n)});
  flat::Mechanism mech;
  if (!lang::LoadProgram(path, stdlib::Files(), &program, diags) || !lang::Elaborate(program, eo, &mech, diags)) {
    std::cerr << diags.RenderAll();
    return nullptr;
  }
  rt::CompileResult r = rt::Compile(mech, rt::CompileOptions{});
  return r.program;
}

double SweepSeconds(std::shared_ptr<const rt::Program> program, batch::SweepConfig config, int threads) {
  config.threads = threads;
  config.out_dir = (std::filesystem::temp_directory_path() / ("kanesim_bench_j" + std::to_string(threads))).string();
  batch::SweepReport report;
  std::string err;
  auto t0 = std::chrono::steady_clock::now();
  if (!batch::RunSweep(program, nullptr, config, &report, &err) || report.progress.failed > 0) {
    std::cerr << "sweep failed: " << err << "\n";
    std::exit(1);
  }
  double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::filesystem::remove_all(config.out_dir);
  return s;
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

  double best1 = 1e300, best2 = 1e300;
  for (int r = 0; r < repeats; ++r) {
    best1 = std::min(best1, SweepSeconds(program, config, 1));
    best2 = std::min(best2, SweepSeconds(program, config, 2));
  }
  std::printf("sweep_throughput: chain N=%d, %d scenarios x %.3g s simulated, best of %d, %u hardware threads\n",
              links, scenarios, stop, repeats, std::thread::hardware_concurrency());
  std::printf("  -j1  %8.3f s  %8.1f scenarios/s\n", best1, scenarios / best1);
  std::printf("  -j2  %8.3f s  %8.1f scenarios/s\n", best2, scenarios / best2);
  std::printf("  speedup 2 threads / 1 thread: %.2fx (goal >= 1.8x)\n", best1 / best2);
  return 0;
}
