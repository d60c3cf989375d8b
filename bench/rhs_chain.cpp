// Cost of one right-hand-side evaluation (rt::Derivative) against N for the chain of
// examples/chain.mech (N thin rods on alternating z/y revolute joints), on the three
// solution paths (dense, sparse, recursive). The measured crossovers set the automatic
// choice (ChooseSolver in compiler/forces.cpp); Pinocchio's aba at the same state
// is `bench/pin/pin_driver rhs N REPS` (docs/benchmarks.md runs both side by side).
// BM_RhsPlanarChain, BM_SolvePlanar, BM_SolveSpatial: the planar chain (every axis z) and
// the recursion alone on it in its 3x3 planar and 6x6 spatial forms.
//
//   build-t/bench/rhs_chain --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "compiler/compiler.h"
#include "runtime/kane/kane_tree.h"
#include "runtime/program/program.h"
#include "tests/support/builders.h"
#include "tests/support/random_state.h"

namespace {

using kanesim::rt::SolverPath;

// One Derivative call at y0 (chains: the start, q = 0.1) with every speed 0.3, or at a
// random valid state (fixed seed) when `random_state`.
void Rhs(benchmark::State& state, const kanesim::flat::Mechanism& m, SolverPath path, bool random_state = false) {
  const int N = static_cast<int>(state.range(0));
  kanesim::rt::CompileOptions o;
  o.solver = path;
  auto r = kanesim::rt::Compile(m, o);
  if (!r.program) {
    state.SkipWithError("compile failed");
    return;
  }
  auto ws = kanesim::rt::MakeWorkspace(*r.program);
  const int nq = kanesim::rt::NumQ(*r.program);
  std::vector<double> y(static_cast<size_t>(kanesim::rt::StateSize(*r.program))), ydot(y.size());
  kanesim::rt::InitialState(*r.program, y.data());
  if (random_state) {
    std::mt19937 rng(2);
    const Eigen::VectorXd yr = kanesim::test::RandomState(*r.program, rng);
    for (size_t i = 0; i < y.size(); ++i) y[i] = yr[static_cast<Eigen::Index>(i)];
  }
  for (size_t i = static_cast<size_t>(nq); i < y.size(); ++i) y[i] = 0.3;  // non-zero speeds: full bias terms
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

void RhsChain(benchmark::State& state, SolverPath path) {
  Rhs(state, kanesim::test::Chain(static_cast<int>(state.range(0))), path);
}

// A random tree of N bodies whose joints cycle through revolute, prismatic, cylindrical,
// universal, spherical, planar and free (1, 1, 2, 2, 3, 3, 6 speeds), fixed seed, at a
// random state (Euler angles at their start value 0 would be in gimbal lock).
void RhsMixedTree(benchmark::State& state, SolverPath path) {
  std::mt19937 rng(1);
  Rhs(state, kanesim::test::RandomTree(rng, {static_cast<int>(state.range(0)), true, false, false}), path, true);
}

// The recursion alone on the planar chain (every axis z), after one Derivative: the
// 3x3 planar form against the 6x6 spatial form of the same tree (runtime/kane/kane_tree.cpp).
void SolvePlanarChain(benchmark::State& state, bool planar) {
  const int N = static_cast<int>(state.range(0));
  kanesim::rt::CompileOptions o;
  o.solver = SolverPath::Recursive;
  auto r = kanesim::rt::Compile(kanesim::test::Chain(N, 1.0, 0.5, true), o);
  if (!r.program || !r.program->tree->planar) {
    state.SkipWithError("not compiled as a planar tree");
    return;
  }
  const kanesim::rt::Program& p = *r.program;
  auto ws = kanesim::rt::MakeWorkspace(p);
  std::vector<double> y(static_cast<size_t>(kanesim::rt::StateSize(p))), ydot(y.size());
  kanesim::rt::InitialState(p, y.data());
  for (size_t i = static_cast<size_t>(kanesim::rt::NumQ(p)); i < y.size(); ++i) y[i] = 0.3;
  if (kanesim::rt::Derivative(p, *ws, 0.0, y.data(), ydot.data()) != 0) {
    state.SkipWithError("Derivative failed");
    return;
  }
  for (auto _ : state) {
    const int s = planar ? kanesim::rt::SolveTreePlanar(p, *ws) : kanesim::rt::SolveTreeSpatial(p, *ws);
    benchmark::DoNotOptimize(s);
    benchmark::DoNotOptimize(ws->udot.data());
  }
  state.counters["N"] = N;
}

void BM_RhsDense(benchmark::State& state) { RhsChain(state, SolverPath::Dense); }
void BM_RhsSparse(benchmark::State& state) { RhsChain(state, SolverPath::Sparse); }
void BM_RhsRecursive(benchmark::State& state) { RhsChain(state, SolverPath::Recursive); }
void BM_RhsPlanarChain(benchmark::State& state) {
  Rhs(state, kanesim::test::Chain(static_cast<int>(state.range(0)), 1.0, 0.5, true), SolverPath::Recursive);
}
void BM_SolvePlanar(benchmark::State& state) { SolvePlanarChain(state, true); }
void BM_SolveSpatial(benchmark::State& state) { SolvePlanarChain(state, false); }
void BM_TreeDense(benchmark::State& state) { RhsMixedTree(state, SolverPath::Dense); }
void BM_TreeSparse(benchmark::State& state) { RhsMixedTree(state, SolverPath::Sparse); }
void BM_TreeRecursive(benchmark::State& state) { RhsMixedTree(state, SolverPath::Recursive); }

// Dense costs O(N^2) assembly (composite inertias) plus an O(N^3) Cholesky: stop at 500.
BENCHMARK(BM_RhsDense)->Arg(1)->Arg(2)->Arg(3)->Arg(5)->Arg(10)->Arg(20)->Arg(30)->Arg(40)->Arg(50)->Arg(60)
    ->Arg(80)->Arg(100)->Arg(120)->Arg(150)->Arg(200)->Arg(500)->Complexity(benchmark::oNCubed);
BENCHMARK(BM_RhsSparse)->Arg(5)->Arg(10)->Arg(20)->Arg(30)->Arg(40)->Arg(50)->Arg(60)->Arg(80)->Arg(100)->Arg(120)
    ->Arg(150)->Arg(200)->Arg(500)->Arg(1000)->Complexity(benchmark::oN);
BENCHMARK(BM_RhsRecursive)->Arg(1)->Arg(2)->Arg(3)->Arg(5)->Arg(10)->Arg(20)->Arg(30)->Arg(40)->Arg(50)->Arg(60)
    ->Arg(80)->Arg(100)->Arg(120)->Arg(150)->Arg(200)->Arg(500)->Arg(1000)->Complexity(benchmark::oN);
BENCHMARK(BM_RhsPlanarChain)->Arg(2)->Arg(5)->Arg(20)->Arg(100);
BENCHMARK(BM_SolvePlanar)->Arg(2)->Arg(5)->Arg(20)->Arg(100);
BENCHMARK(BM_SolveSpatial)->Arg(2)->Arg(5)->Arg(20)->Arg(100);
BENCHMARK(BM_TreeDense)->Arg(1)->Arg(2)->Arg(4)->Arg(7)->Arg(14)->Arg(28)->Arg(70);
BENCHMARK(BM_TreeSparse)->Arg(1)->Arg(2)->Arg(4)->Arg(7)->Arg(14)->Arg(28)->Arg(70);
BENCHMARK(BM_TreeRecursive)->Arg(1)->Arg(2)->Arg(4)->Arg(7)->Arg(14)->Arg(28)->Arg(70);

}  // namespace

BENCHMARK_MAIN();
