// The two forms of the constrained equations against the number of loops: the reduced
// form (dependent speeds eliminated, Lesser eqs. 48-51: runtime/constraints/constraints.cpp) and the
// multiplier form (a multiplier per independent constraint row in the sparse K-vector
// system, KLU: runtime/kane/kane_sparse.cpp), on bench/models/fourbar_ladder.mech, N four-bar
// loops stacked between two hanging rails (3 N bodies, 3 N speeds, 2 N independent rows).
// The crossover sets kSparseLoopMinSpeeds (compiler/compile_internal.h);
// docs/constraints.md "Reduced or multiplier form" has the numbers. Also the cost of one
// right-hand side of the examples with constraints (the four-bar against Pinocchio's
// constraintDynamics: docs/benchmarks.md).
//
//   build/bench/loop_solvers --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "compiler/compiler.h"
#include "sim/simulate.h"
#include "tests/support/model_loader.h"

namespace {

using namespace kanesim;

const std::string kLadder = std::string(KANESIM_SOURCE_DIR) + "/bench/models/fourbar_ladder.mech";

std::shared_ptr<const rt::Program> Ladder(benchmark::State& state, rt::SolverPath path) {
  auto m = test::LoadMech(kLadder, {{"N", std::to_string(state.range(0))}});
  if (!m) return nullptr;
  rt::CompileOptions o;
  o.solver = path;
  auto r = rt::Compile(m->mech, o);
  if (!r.program || rt::Summarize(*r.program).solver != path) return nullptr;
  return r.program;
}

// One right-hand side at the assembled start with every speed 0.3 (projected onto the
// velocity constraints inside the call, as the integrator's states are).
void Rhs(benchmark::State& state, rt::SolverPath path) {
  auto p = Ladder(state, path);
  if (!p) {
    state.SkipWithError("cannot compile the ladder on this path");
    return;
  }
  auto ws = rt::MakeWorkspace(*p);
  std::vector<double> y(static_cast<size_t>(rt::StateSize(*p))), ydot(y.size());
  rt::InitialState(*p, y.data());
  for (size_t i = static_cast<size_t>(rt::NumQ(*p)); i < y.size(); ++i) y[i] = 0.3;
  for (auto _ : state) {
    if (rt::Derivative(*p, *ws, 0.0, y.data(), ydot.data()) != 0) {
      state.SkipWithError(rt::ErrorMessage(*ws).c_str());
      break;
    }
    benchmark::DoNotOptimize(ydot.data());
  }
  state.counters["speeds"] = rt::NumU(*p);
}

// A whole run: 1 s at rtol 1e-8 (CVODE, the automatic choice for loops), 10 rows.
void Run(benchmark::State& state, rt::SolverPath path) {
  auto p = Ladder(state, path);
  if (!p) {
    state.SkipWithError("cannot compile the ladder on this path");
    return;
  }
  sim::SimOptions o;
  o.stop_time = 1.0;
  o.interval = 0.1;
  o.rtol = o.atol = 1e-8;
  long rhs = 0;
  for (auto _ : state) {
    sim::MemorySink sink;
    sim::SimResult r = sim::Simulate(*p, o, sink);
    if (r.status != sim::SimResult::Status::kOk) {
      state.SkipWithError(r.message.c_str());
      return;
    }
    rhs = r.stats.integrator.rhs_evals;
  }
  state.counters["speeds"] = rt::NumU(*p);
  state.counters["rhs"] = static_cast<double>(rhs);
}

// One right-hand side of an example with constraints on its automatic path, at the
// assembled start with the coordinates moved 1e-9 off the manifold (as an integrator's
// states are: the projection takes its Newton step) and every speed 0.3.
// step = true: the right-hand side of --projection step (dependent speeds only).
void ExampleRhs(benchmark::State& state, const char* example, bool step = false) {
  auto m = test::LoadMech(std::string(KANESIM_SOURCE_DIR) + "/examples/" + example);
  auto r = m ? rt::Compile(m->mech, {}) : rt::CompileResult{};
  if (!r.program) {
    state.SkipWithError("cannot compile the example");
    return;
  }
  const rt::Program& p = *r.program;
  auto ws = rt::MakeWorkspace(p);
  rt::SetStepProjection(*ws, step);
  std::vector<double> y(static_cast<size_t>(rt::StateSize(p))), ydot(y.size());
  rt::InitialState(p, y.data());
  for (size_t i = 0; i < y.size(); ++i) y[i] += i < static_cast<size_t>(rt::NumQ(p)) ? 1e-9 : 0.3;
  for (auto _ : state) {
    if (rt::Derivative(p, *ws, 0.0, y.data(), ydot.data()) != 0) {
      state.SkipWithError(rt::ErrorMessage(*ws).c_str());
      break;
    }
    benchmark::DoNotOptimize(ydot.data());
  }
}

void BM_FourBarRhs(benchmark::State& s) { ExampleRhs(s, "fourbar.mech"); }
void BM_FourBarRhsStep(benchmark::State& s) { ExampleRhs(s, "fourbar.mech", true); }
void BM_SliderCrankRhs(benchmark::State& s) { ExampleRhs(s, "slider_crank.mech"); }
void BM_RollingDiskRhs(benchmark::State& s) { ExampleRhs(s, "rolling_disk.mech"); }
BENCHMARK(BM_FourBarRhs);
BENCHMARK(BM_FourBarRhsStep);
BENCHMARK(BM_SliderCrankRhs);
BENCHMARK(BM_RollingDiskRhs);

void BM_LadderRhsReduced(benchmark::State& s) { Rhs(s, rt::SolverPath::Dense); }
void BM_LadderRhsMultiplier(benchmark::State& s) { Rhs(s, rt::SolverPath::Sparse); }
void BM_LadderRunReduced(benchmark::State& s) { Run(s, rt::SolverPath::Dense); }
void BM_LadderRunMultiplier(benchmark::State& s) { Run(s, rt::SolverPath::Sparse); }

BENCHMARK(BM_LadderRhsReduced)->Arg(1)->Arg(2)->Arg(4)->Arg(8)->Arg(16)->Arg(20)->Arg(24)->Arg(32)->Arg(64);
BENCHMARK(BM_LadderRhsMultiplier)->Arg(1)->Arg(2)->Arg(4)->Arg(8)->Arg(16)->Arg(20)->Arg(24)->Arg(32)->Arg(64)->Arg(128);
BENCHMARK(BM_LadderRunReduced)->Arg(1)->Arg(4)->Arg(8)->Arg(16)->Arg(20)->Arg(24)->Arg(32)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LadderRunMultiplier)->Arg(1)->Arg(4)->Arg(8)->Arg(16)->Arg(20)->Arg(24)->Arg(32)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
