// The unit check's cost (issue 43: at most 5 % of load + elaborate): each model loaded and
// elaborated `repeats` times with the check and as many without it (ElaborateOptions::
// check_units), alternating, in one process after a first load that parses the standard
// library; the median and the best CPU time of each, and the ratio of the medians.
//   build/bench/units_cost MODEL.mech [NAME=VALUE ...]   (e.g. examples/chain.mech N=1000)
//   KANESIM_UNITS_REPEATS=21                             (default 21)
//   KANESIM_UNITS_ONLY=with|without   every load (the first too) with the check, or without
//                                     it: for an instruction count (valgrind --tool=callgrind
//                                     --toggle-collect='*LoadAndElaborate*'), per load = the
//                                     count / (repeats + 1)
// Output: medians `with ms, without ms, +percent`, then the best times. Results:
// docs/benchmarks/2026-11-29_units.md, docs/benchmarks/2026-11-29_units_cost.md.
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
  const char* only = std::getenv("KANESIM_UNITS_ONLY");
  if (only) {
    const bool check = std::string(only) == "with";
    double total = 0;
    for (int r = 0; r <= repeats; ++r) {
      const double t = LoadAndElaborate(argv[1], sets, check);
      if (t < 0) return 1;
      total += t;
    }
    std::printf("%s: %d loads %s the unit check, mean %.3f ms\n", argv[1], repeats + 1, check ? "with" : "without",
                1e3 * total / (repeats + 1));
    return 0;
  }
  if (LoadAndElaborate(argv[1], sets, true) < 0) return 1;  // parses the library once
  std::vector<double> with, without;
  for (int r = 0; r < repeats; ++r) {
    with.push_back(LoadAndElaborate(argv[1], sets, true));
    without.push_back(LoadAndElaborate(argv[1], sets, false));
  }
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  };
  const double mw = median(with), mo = median(without);
  std::printf("%s: median with the unit check %.3f ms, without %.3f ms, %+.2f %% (best %.3f, %.3f ms)\n", argv[1],
              1e3 * mw, 1e3 * mo, 100 * (mw / mo - 1), 1e3 * *std::min_element(with.begin(), with.end()),
              1e3 * *std::min_element(without.begin(), without.end()));
  return 0;
}
