// Cost of one right-hand-side evaluation (rt::Derivative) against N for the chain of
// examples/chain.mech (N thin rods on alternating z/y revolute joints), on the three
// solution paths (dense, sparse, recursive). The measured crossovers set the automatic
// choice (ChooseSolver in runtime/compile/forces.cpp); Pinocchio's aba at the same state
// is `bench/pin/pin_driver rhs N REPS` (docs/benchmarks.md runs both side by side).
//
//   build-t/bench/rhs_chain --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include <vector>

#include "runtime/engine.h"
#include "tests/runtime/builders.h"

namespace {

using kanesim::rt::SolverPath;

void RhsChain(benchmark::State& state, SolverPath path) {
  const int N = static_cast<int>(state.range(0));
  kanesim::rt::CompileOptions o;
  o.solver = path;
  auto r = kanesim::rt::Compile(kanesim::test::Chain(N), o);
  if (!r.program) {
    state.SkipWithError("compile failed");
    return;
  }
  auto ws = kanesim::rt::MakeWorkspace(*r.program);
  std::vector<double> y(static_cast<size_t>(kanesim::rt::StateSize(*r.program))), ydot(y.size());
  kanesim::rt::InitialState(*r.program, y.data());
  for (size_t i = y.size() / 2; i < y.size(); ++i) y[i] = 0.3;  // non-zero speeds: full bias terms
  for (auto _ : state) {
    if (kanesim::rt::Derivative(*r.program, *ws, 0.0, y.data(), ydot.data()) != 0) {
      state.SkipWithError("Derivative failed");
      break;
    }
    benchmark::DoNotOptimize(ydot.data());
  }
  state.SetComplexityN(N);
  state.counters["N"] = N;
}

void BM_RhsDense(benchmark::State& state) { RhsChain(state, SolverPath::Dense); }
void BM_RhsSparse(benchmark::State& state) { RhsChain(state, SolverPath::Sparse); }
void BM_RhsRecursive(benchmark::State& state) { RhsChain(state, SolverPath::Recursive); }

// Dense costs O(N^2) assembly (composite inertias) plus an O(N^3) Cholesky: stop at 500.
BENCHMARK(BM_RhsDense)->Arg(5)->Arg(10)->Arg(20)->Arg(30)->Arg(40)->Arg(50)->Arg(60)->Arg(80)->Arg(100)->Arg(120)
    ->Arg(150)->Arg(200)->Arg(500)->Complexity(benchmark::oNCubed);
BENCHMARK(BM_RhsSparse)->Arg(5)->Arg(10)->Arg(20)->Arg(30)->Arg(40)->Arg(50)->Arg(60)->Arg(80)->Arg(100)->Arg(120)
    ->Arg(150)->Arg(200)->Arg(500)->Arg(1000)->Complexity(benchmark::oN);
BENCHMARK(BM_RhsRecursive)->Arg(5)->Arg(10)->Arg(20)->Arg(30)->Arg(40)->Arg(50)->Arg(60)->Arg(80)->Arg(100)
    ->Arg(120)->Arg(150)->Arg(200)->Arg(500)->Arg(1000)->Complexity(benchmark::oN);

}  // namespace

BENCHMARK_MAIN();
