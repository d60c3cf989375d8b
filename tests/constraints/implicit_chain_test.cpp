// IDA on the multiplier form keeps df/dy across linear setups (sim/integrator_ida.cpp,
// kReuseMinEvals / kMaxReuseSteps; docs/constraints.md "Singular configurations", issue 20).
// IDA asks for a Newton matrix cj I - df/dy at every linear setup (a new step size, a
// Newton failure); on the multiplier form f reads every state (the projection in the mass
// metric), so each fresh df/dy costs one evaluation per state, 2 (2N + 1) for the chain of
// N loops: 96 % of IDA's evaluations on the chain of 40 at rtol 1e-10. Now the last df/dy is
// taken with the new cj, as CVODE does, unless a step failed since or it is 20 steps old.
// Checked against the independent lumped crank (tests/support/lumped_crank.h), through the
// chain's change points over 20 s:
//  - multiplier form: on the branch, within 2e-5 rad of the lumped crank, its lumped energy
//    kept, and fewer evaluations for Jacobians than states x Jacobian setups (on main, where
//    every setup perturbed every state, exactly equal);
//  - reduced form (2 evaluations per Jacobian, ProjectedStates): every setup still a fresh
//    df/dy (reuse only where one costs at least 16 evaluations).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "runtime/runtime.h"
#include "runtime/program/program.h"
#include "sim/simulate.h"
#include "tests/support/load_util.h"
#include "tests/support/lumped_crank.h"

namespace kanesim::test {
namespace {

#if defined(__SANITIZE_ADDRESS__) || defined(KANESIM_STRESS_SHORT)
constexpr int kLoops = 4;  // sanitizers: ~30x slower; 18 states, still above the reuse threshold
#else
constexpr int kLoops = 10;
#endif

struct ChainRun {
  sim::SimResult r;
  int states = 0;
  double branch = 0.0, angle = 0.0, energy = 0.0;  // max over rows: rods apart, |theta - lumped|, |E - E0| / E0
};

ChainRun RunChain(rt::SolverPath solver, double rtol) {
  ChainRun out;
  rt::CompileOptions co;
  co.solver = solver;
  auto l = LoadModel(kRoot + lumped_crank::kChainPath, {{"N", std::to_string(kLoops)}}, co);
  EXPECT_TRUE(l && l->prog);
  if (!l || !l->prog) return out;
  sim::SimOptions so;
  so.stop_time = 20.0;
  so.interval = 0.01;
  so.rtol = so.atol = rtol;
  so.integrator = rt::Integrator::IDA;
  so.signals = lumped_crank::ChainSignals(kLoops, {"q"});
  sim::MemorySink sink;
  out.r = sim::Simulate(*l->prog, so, sink);
  out.states = rt::StateSize(*l->prog);
  EXPECT_EQ(out.r.status, sim::SimResult::Status::kOk) << out.r.message;
  if (sink.rows.empty()) return out;
  EXPECT_NEAR(sink.times.back(), 20.0, 1e-12);
  const lumped_crank::Crank c = lumped_crank::ParallelogramChain(kLoops);
  std::vector<double> th, w;
  const double e0 = 0.5 * c.J * sink.rows[0][1] * sink.rows[0][1] + c.G * std::sin(sink.rows[0][0]);
  for (const auto& row : sink.rows) {
    th.push_back(row[0]);
    w.push_back(row[1]);
    for (size_t k = 2; k < row.size(); ++k)
      out.branch = std::max(out.branch, std::fabs(std::remainder(row[k] - row[0], 2 * M_PI)));
    out.energy = std::max(out.energy, std::fabs(0.5 * c.J * row[1] * row[1] + c.G * std::sin(row[0]) - e0) / std::fabs(e0));
  }
  out.angle = lumped_crank::MaxAngleError(c, sink.times, th, w, 1e-5);
  return out;
}

TEST(ImplicitChain, IdaMultiplierFormKeepsItsJacobianAcrossSetups) {
  const ChainRun run = RunChain(rt::SolverPath::Sparse, 1e-10);
  const auto& st = run.r.stats.integrator;
  ASSERT_GT(st.jac_evals, 0);
  EXPECT_LT(run.branch, 1e-8);
  EXPECT_LT(run.angle, 2e-5);   // main: 4.9e-6 (N = 10)
  EXPECT_LT(run.energy, 1e-6);  // main: 7.5e-7 (N = 10)
  // A fresh df/dy perturbs every state (one group: f reads them all); some setups reused one.
  EXPECT_LT(static_cast<double>(st.rhs_evals_jac), 0.5 * run.states * static_cast<double>(st.jac_evals));
  EXPECT_EQ(st.rhs_evals_jac % run.states, 0);
  std::printf("IDA multiplier N = %d: %ld setups, %ld fresh Jacobians (%d states), %.2g rad, energy %.2g\n", kLoops,
              st.jac_evals, st.rhs_evals_jac / run.states, run.states, run.angle, run.energy);
}

TEST(ImplicitChain, IdaReducedFormTakesAFreshJacobianAtEverySetup) {
  const ChainRun run = RunChain(rt::SolverPath::Dense, 1e-10);
  const auto& st = run.r.stats.integrator;
  ASSERT_GT(st.jac_evals, 0);
  EXPECT_LT(run.branch, 1e-8);
  EXPECT_LT(run.angle, 2e-5);
  // Outside zones 2 evaluations per Jacobian (the independent angle and speed); at least 1
  // per setup means none was skipped.
  EXPECT_GE(st.rhs_evals_jac, st.jac_evals);
  EXPECT_LT(st.rhs_evals_jac, 16 * st.jac_evals);
}

}  // namespace
}  // namespace kanesim::test
