// The unit check's cost (issue 43: at most 5 % of load + elaborate): each model loaded and
// elaborated `repeats` times with the check and as many without it (ElaborateOptions::
// check_units), alternating, in one process after a first load that parses the standard
// library; the best CPU time of each, and their ratio.
//   build/bench/units_cost MODEL.mech [NAME=VALUE ...]   (e.g. examples/chain.mech N=1000)
//   KANESIM_UNITS_REPEATS=21                             (default 21)
// Output: `with ms, without ms, +percent`. docs/benchmarks/2026-11-29_units.md has results.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <string>
#include <vector>

#include "lang/diagnostics.h"
#include "lang/elaborate.h"
#include "stdlib/stdlib.h"

namespace {

using namespace kanesim;

double CpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// One load + elaborate; its CPU seconds, or a negative number after an error.
double LoadAndElaborate(const std::string& path, const std::vector<lang::ParamOverride>& sets, bool check) {
  const double t0 = CpuSeconds();
  lang::Program program;
  lang::Diagnostics diags(&program.sources);
  lang::ElaborateOptions o;
  o.overrides = sets;
  o.check_units = check;
  flat::Mechanism mech;
  if (!lang::LoadProgram(path, stdlib::Files(), &program, diags) || !lang::Elaborate(program, o, &mech, diags)) {
    std::fprintf(stderr, "%s", diags.RenderAll().c_str());
    return -1;
  }
  return CpuSeconds() - t0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: units_cost MODEL.mech [NAME=VALUE ...]\n");
    return 2;
  }
  std::vector<lang::ParamOverride> sets;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    const size_t eq = a.find('=');
    sets.push_back({a.substr(0, eq), eq == std::string::npos ? "" : a.substr(eq + 1)});
  }
  const char* env = std::getenv("KANESIM_UNITS_REPEATS");
  const int repeats = env ? std::max(1, std::atoi(env)) : 21;
  if (LoadAndElaborate(argv[1], sets, true) < 0) return 1;  // parses the library once
  double with = 1e300, without = 1e300;
  for (int r = 0; r < repeats; ++r) {
    with = std::min(with, LoadAndElaborate(argv[1], sets, true));
    without = std::min(without, LoadAndElaborate(argv[1], sets, false));
  }
  std::printf("%s: with the unit check %.3f ms, without %.3f ms, %+.2f %%\n", argv[1], 1e3 * with, 1e3 * without,
              100 * (with / without - 1));
  return 0;
}
