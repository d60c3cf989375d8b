// IDA with dense LU against IDA with KLU on the same scene and tolerance (issue 3): where
// does KLU pay, and what does the grouped difference-quotient Jacobian save?
//
// Scene: tests/sim/models/forest.mech, M independent stiff double pendulums (4 states
// each, n = 4 M; the Newton matrix has M blocks of 4 x 4), 0.5 s at rtol = atol = 1e-6,
// the stiff case the compiler hands to IDA. Both runs take the same steps (the Newton
// matrices agree to round-off), so the ratio is the linear algebra alone plus the shared
// right-hand sides.
//   build/bench/ida_linear_solver --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
// Also a chain (examples/chain.mech, one coupling group) to show that KLU gains nothing
// when df/dy is dense: the automatic choice keeps dense LU there.
#include <benchmark/benchmark.h>

#include <memory>
#include <string>

#include "compiler/compiler.h"
#include "sim/simulate.h"
#include "tests/support/model_loader.h"

namespace {

using namespace kanesim;

// The mechanism and its compiled program (test::LoadMech keeps the sources alive).
struct Model {
  std::unique_ptr<test::LoadedMech> loaded;
  std::shared_ptr<const rt::Program> prog;
};

std::unique_ptr<Model> Load(const std::string& path, std::vector<lang::ParamOverride> sets) {
  auto m = std::make_unique<Model>();
  m->loaded = test::LoadMech(path, std::move(sets));
  if (!m->loaded) return nullptr;
  m->prog = rt::Compile(m->loaded->mech, {}).program;
  return m->prog ? std::move(m) : nullptr;
}

void Simulate(benchmark::State& state, const std::string& path, std::vector<lang::ParamOverride> sets, double stop,
              sim::IdaLinearSolver ls) {
  auto m = Load(path, std::move(sets));
  if (!m) {
    state.SkipWithError("cannot load the model");
    return;
  }
  sim::SimOptions o;
  o.stop_time = stop;
  o.interval = stop / 10;
  o.rtol = o.atol = 1e-6;
  o.integrator = rt::Integrator::IDA;
  o.ida_linear_solver = ls;
  sim::SimStats stats;
  for (auto _ : state) {
    sim::MemorySink sink;
    sim::SimResult r = sim::Simulate(*m->prog, o, sink);
    if (r.status != sim::SimResult::Status::kOk) {
      state.SkipWithError(r.message.c_str());
      return;
    }
    stats = r.stats;
  }
  state.counters["n"] = rt::StateSize(*m->prog);
  state.counters["steps"] = static_cast<double>(stats.integrator.steps);
  state.counters["jacobians"] = static_cast<double>(stats.integrator.jac_evals);
  state.counters["f_for_jac"] = static_cast<double>(stats.integrator.rhs_evals_jac);
  state.counters["f"] = static_cast<double>(stats.integrator.rhs_evals);
}

const std::string kForest = std::string(KANESIM_SOURCE_DIR) + "/tests/sim/models/forest.mech";
const std::string kChain = std::string(KANESIM_SOURCE_DIR) + "/examples/chain.mech";

void BM_ForestDense(benchmark::State& s) {
  Simulate(s, kForest, {{"M", std::to_string(s.range(0))}}, 0.5, sim::IdaLinearSolver::Dense);
}
void BM_ForestKlu(benchmark::State& s) {
  Simulate(s, kForest, {{"M", std::to_string(s.range(0))}}, 0.5, sim::IdaLinearSolver::Klu);
}
void BM_ChainDense(benchmark::State& s) {
  Simulate(s, kChain, {{"N", std::to_string(s.range(0))}}, 0.2, sim::IdaLinearSolver::Dense);
}
void BM_ChainKlu(benchmark::State& s) {
  Simulate(s, kChain, {{"N", std::to_string(s.range(0))}}, 0.2, sim::IdaLinearSolver::Klu);
}

BENCHMARK(BM_ForestDense)->Arg(5)->Arg(10)->Arg(25)->Arg(50)->Arg(100)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ForestKlu)->Arg(5)->Arg(10)->Arg(25)->Arg(50)->Arg(100)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ChainDense)->Arg(10)->Arg(40)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ChainKlu)->Arg(10)->Arg(40)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
