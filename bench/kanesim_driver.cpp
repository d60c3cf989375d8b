// The work-precision benchmark's in-process kanesim runner, the counterpart of
// bench/pin/pin_driver.cpp: loads and compiles a .mech file once, then integrates it REPS
// times in the same process (fewer when the runs so far took over 1 s in all) and prints the
// median wall time of the integration (the "integrate" phase `kanesim run --stats`
// reports), so that kanesim and the Pinocchio driver are timed the same way: warm,
// repeated, process start-up and first-touch costs excluded.
// `kanesim run` (cold, one integration per process) is what bench/wp/run.py used before;
// docs/benchmarks.md compares the two.
//
//   kanesim_driver FILE.mech T RTOL INTEGRATOR SOLVER PROJECTION REPS [NAME=VALUE ...]
//     INTEGRATOR ida|cvode|cvode-bdf|arkode|dop853, SOLVER dense|sparse|recursive|auto,
//     PROJECTION eval|step; atol = rtol, one output row at T.
// Prints: wall=<median s> rhs=<evaluations> steps=<steps> names=<a,b,..> last=<v,v,..>
// Exit 1 on a usage or model error, 2 when the integration fails.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "compiler/compiler.h"
#include "sim/csv.h"
#include "sim/simulate.h"
#include "tests/support/model_loader.h"

namespace {

using namespace kanesim;

int Usage() {
  std::fprintf(stderr,
               "usage: kanesim_driver FILE.mech T RTOL ida|cvode|cvode-bdf|arkode|dop853 "
               "dense|sparse|recursive|auto eval|step REPS [NAME=VALUE ...]\n");
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 8) return Usage();
  std::vector<lang::ParamOverride> sets;
  for (int i = 8; i < argc; ++i) {
    const std::string a = argv[i];
    const auto eq = a.find('=');
    if (eq == std::string::npos) return Usage();
    sets.push_back({a.substr(0, eq), a.substr(eq + 1)});
  }
  std::string error;
  auto m = test::LoadMech(argv[1], sets, &error);
  if (!m) {
    std::fprintf(stderr, "%s\n", error.c_str());
    return 1;
  }
  sim::SimOptions o;
  o.stop_time = std::atof(argv[2]);
  o.interval = o.stop_time;
  o.rtol = o.atol = std::atof(argv[3]);
  const std::string integ = argv[4], solver = argv[5], proj = argv[6];
  const int reps = std::max(1, std::atoi(argv[7]));
  if (integ == "ida") o.integrator = rt::Integrator::IDA;
  else if (integ == "cvode") o.integrator = rt::Integrator::CvodeAdams;
  else if (integ == "cvode-bdf") o.integrator = rt::Integrator::CvodeBdf;
  else if (integ == "arkode") o.integrator = rt::Integrator::ArkodeErk;
  else if (integ == "dop853") o.integrator = rt::Integrator::Dop853;
  else return Usage();
  if (proj != "eval" && proj != "step") return Usage();
  o.project_steps = proj == "step";
  rt::CompileOptions co;
  if (solver == "dense") co.solver = rt::SolverPath::Dense;
  else if (solver == "sparse") co.solver = rt::SolverPath::Sparse;
  else if (solver == "recursive") co.solver = rt::SolverPath::Recursive;
  else if (solver != "auto") return Usage();
  auto c = rt::Compile(m->mech, co);
  if (!c.program) {
    std::fprintf(stderr, "cannot compile %s\n", argv[1]);
    return 1;
  }
  std::vector<double> walls;
  sim::MemorySink last_sink;
  sim::SimResult last;
  // Up to REPS runs; no further one once the runs so far took kRepeatBudget in all (as
  // pin_driver and run.py's Sweep for the Python peers).
  constexpr double kRepeatBudget = 1.0;  // s
  double total = 0.0;
  for (int k = 0; k < reps && (k == 0 || total < kRepeatBudget); ++k) {
    sim::MemorySink sink;
    last = sim::Simulate(*c.program, o, sink);
    if (last.status != sim::SimResult::Status::kOk) {
      std::fprintf(stderr, "%s\n", last.message.c_str());
      return last.status == sim::SimResult::Status::kNumericalFailure ? 2 : 1;
    }
    walls.push_back(last.stats.times.integrate);
    total += walls.back();
    last_sink = std::move(sink);
  }
  std::nth_element(walls.begin(), walls.begin() + static_cast<long>(walls.size() / 2), walls.end());
  std::printf("wall=%.9g rhs=%ld steps=%ld names=", walls[walls.size() / 2], last.stats.integrator.rhs_evals,
              last.stats.integrator.steps);
  for (size_t i = 0; i < last_sink.names.size(); ++i) std::printf("%s%s", i ? "," : "", last_sink.names[i].c_str());
  std::printf(" last=");
  const std::vector<double>& row = last_sink.rows.back();
  for (size_t i = 0; i < row.size(); ++i) std::printf("%s%.17g", i ? "," : "", row[i]);
  std::printf("\n");
  return 0;
}
