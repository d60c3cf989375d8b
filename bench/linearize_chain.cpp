// kanesim linearize (linearize) on examples/chain.mech with N links (N
// coordinates and N speeds: 2N states), and on the four-bar ladder (loops, the dependent
// coordinates solved by Newton at every evaluation). Issue 23 asks for a 100-body chain
// in under 50 ms. Each linearization evaluates the right-hand side 6 times per state
// (Richardson over three steps) plus 4 times per state for the steadiness check when the
// operating point moves (the chain starts at rest, bent: it does). docs/linearize.md.
//
//   build/bench/linearize_chain --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "compiler/compiler.h"
#include "linearize/linearize.h"
#include "tests/support/model_loader.h"

namespace {

using namespace kanesim;

void Linearize(benchmark::State& state, const std::string& file, const std::string& size_param, bool modes) {
  auto m = test::LoadMech(std::string(KANESIM_SOURCE_DIR) + file, {{size_param, std::to_string(state.range(0))}});
  if (!m) {
    state.SkipWithError("cannot load the model");
    return;
  }
  auto r = rt::Compile(m->mech, {});
  if (!r.program) {
    state.SkipWithError("cannot compile the model");
    return;
  }
  const lin::OperatingPoint op = lin::StartPoint(*r.program);
  lin::LinearModel model;
  for (auto _ : state) {
    const lin::Status s = lin::Linearize(*r.program, op, {}, &model);
    if (!s.ok()) {
      state.SkipWithError(s.message.c_str());
      return;
    }
    if (modes) lin::ComputeModes(&model);
    benchmark::DoNotOptimize(model.A.data());
  }
  state.counters["states"] = static_cast<double>(model.states.size());
  state.counters["error_A"] = model.error_A;
}

// One right-hand side of the same chain, for scale: a linearization costs about 6 per state.
void ChainRhs(benchmark::State& state) {
  auto m = test::LoadMech(std::string(KANESIM_SOURCE_DIR) + "/examples/chain.mech", {{"N", std::to_string(state.range(0))}});
  auto r = m ? rt::Compile(m->mech, {}) : rt::CompileResult{};
  if (!r.program) {
    state.SkipWithError("cannot compile the model");
    return;
  }
  auto ws = rt::MakeWorkspace(*r.program);
  std::vector<double> y(static_cast<size_t>(rt::StateSize(*r.program))), ydot(y.size());
  rt::InitialState(*r.program, y.data());
  for (auto _ : state) {
    rt::Derivative(*r.program, *ws, 0.0, y.data(), ydot.data());
    benchmark::DoNotOptimize(ydot.data());
  }
}

// A, B, C, D only; and with the eigenvalues and modes (Eigen's EigenSolver, O(n^3)).
void Chain(benchmark::State& state) { Linearize(state, "/examples/chain.mech", "N", false); }
void ChainModes(benchmark::State& state) { Linearize(state, "/examples/chain.mech", "N", true); }
void Ladder(benchmark::State& state) { Linearize(state, "/bench/models/fourbar_ladder.mech", "N", false); }

BENCHMARK(ChainRhs)->Arg(100)->Unit(benchmark::kMicrosecond);
BENCHMARK(Chain)->Arg(10)->Arg(30)->Arg(100)->Unit(benchmark::kMillisecond);
BENCHMARK(ChainModes)->Arg(10)->Arg(30)->Arg(100)->Unit(benchmark::kMillisecond);
BENCHMARK(Ladder)->Arg(1)->Arg(4)->Arg(16)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
