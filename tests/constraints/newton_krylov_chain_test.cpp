// Matrix-free Newton-Krylov (sim/newton_krylov.h) on the chains of equal-link
// parallelograms, multiplier form, with IDA and CVODE-BDF (issue 20's cost goal). There
// df/dy = -k I + (g' + k I) P' with rank(P') = 2 dof = 2, so the Newton matrices are an
// identity multiple plus rank 2; main formed them by dense difference quotients (n = 162
// evaluations for the chain of 40) and an LU. Measured over 20 s at rtol 1e-10 (chain of
// 40): CVODE-BDF 64 s -> 13 s CPU, IDA 87 s -> 12 s (docs/benchmarks.md).
//
// Checked against the independent lumped crank (tests/support/lumped_crank.h: the whole
// chain turns as one crank of lumped inertia): every row's energy (1/2) J w^2 + G sin(theta)
// within max(1e3 rtol, 1e-6) of the first row's (bench/change_point_chains.py's bound),
// every rod at rod 0's angle and speed (the branch), the run to its stop time; and the
// evaluations of f per step, Newton's included, bounded (deterministic counts).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "sim/simulate.h"
#include "tests/support/load_util.h"
#include "tests/support/lumped_crank.h"

namespace kanesim::test {
namespace {

struct Outcome {
  sim::SimResult r;
  double evals_per_step = 0.0;  // (rhs_evals + rhs_evals_jac) / steps
};

Outcome RunChain(int n, rt::Integrator method, sim::IdaLinearSolver ls, double rtol, double stop) {
  Outcome o;
  rt::CompileOptions co;
  co.solver = rt::SolverPath::Sparse;  // the multiplier form
  auto l = LoadModel(kRoot + "/tests/stress/models/parallelogram_chain.mech", {{"N", std::to_string(n)}}, co);
  EXPECT_TRUE(l && l->prog);
  if (!l || !l->prog) return o;
  sim::SimOptions so;
  so.stop_time = stop;
  so.interval = 0.01;
  so.rtol = so.atol = rtol;
  so.integrator = method;
  so.ida_linear_solver = ls;
  so.signals = lumped_crank::ChainSignals(n, {"q", "u"});
  sim::MemorySink sink;
  o.r = sim::Simulate(*l->prog, so, sink);
  EXPECT_FALSE(sink.rows.empty());
  if (sink.rows.empty()) return o;
  const double last_t = sink.times.back();
  EXPECT_EQ(o.r.status, sim::SimResult::Status::kOk) << o.r.message;
  EXPECT_NEAR(last_t, stop, 1e-9) << o.r.message;

  const lumped_crank::ChainRowErrors err = lumped_crank::ChainErrors(n, sink.rows);
  const double de = err.energy, off = err.off, apart = err.apart;
  EXPECT_LT(de, std::max(1e3 * rtol, 1e-6));
  EXPECT_LT(off, 1e-6);
  EXPECT_LT(apart, 1e-4);
  const sim::IntegratorStats& s = o.r.stats.integrator;
  o.evals_per_step = static_cast<double>(s.rhs_evals + s.rhs_evals_jac) / static_cast<double>(std::max(s.steps, 1L));
  std::printf("chain of %d, multiplier form, %s, %s, rtol %.0e: to t = %.2f, energy %.2g, rods %.2g rad and %.2g rad/s "
              "apart, %ld steps, %ld + %ld evaluations (%.2f per step), %ld Newton, %ld GMRES iterations\n",
              n, sim::MethodName(method), s.linear_solver, rtol, last_t, de, off, apart, s.steps, s.rhs_evals,
              s.rhs_evals_jac, o.evals_per_step, s.nonlin_iters, s.lin_iters);
  return o;
}

class BdfChain : public ::testing::TestWithParam<rt::Integrator> {};
INSTANTIATE_TEST_SUITE_P(Chain, BdfChain, ::testing::Values(rt::Integrator::IDA, rt::Integrator::CvodeBdf),
                         [](const ::testing::TestParamInfo<rt::Integrator>& p) {
                           return p.param == rt::Integrator::IDA ? std::string("IDA") : std::string("CVODE_BDF");
                         });

// The chain of 40 (n = 162) to t = 2.1, five change points, rtol 1e-8: auto goes
// matrix-free. Measured: CVODE-BDF 2.88 evaluations per step (564 + 341 in 314 steps), IDA
// 3.11 (380 + 789 in 376); main's dense difference quotients 4.39 (359 + 972 in 303) and
// 4.59 (506 + 1296 in 393), and over 20 s 7.5 and 12.3 (the matrix-free 3.0 and 3.1).
TEST_P(BdfChain, ChainOfFortyAutoGoesMatrixFreeOnTheBranch) {
#if defined(__SANITIZE_ADDRESS__) || defined(KANESIM_STRESS_SHORT)
  GTEST_SKIP() << "about a second in Release";
#endif
  const Outcome o = RunChain(40, GetParam(), sim::IdaLinearSolver::Auto, 1e-8, 2.1);
  EXPECT_STREQ(o.r.stats.integrator.linear_solver, "GMRES, matrix-free");
  EXPECT_LT(o.evals_per_step, 3.5);
  EXPECT_EQ(o.r.stats.integrator.jac_evals, 0);
}

// The chain of ten (n = 42: auto stays dense there, where the matrix-free iteration is not
// cheaper) with the matrix-free iteration forced, 20 s through its crossings at rtol
// 1e-8: on the branch, and at most r + 1 = 3 GMRES iterations per Newton iteration.
TEST_P(BdfChain, ChainOfTenKrylovOnTheBranchFor20s) {
#if defined(__SANITIZE_ADDRESS__) || defined(KANESIM_STRESS_SHORT)
  GTEST_SKIP() << "about a second in Release";
#endif
  const Outcome o = RunChain(10, GetParam(), sim::IdaLinearSolver::Krylov, 1e-8, 20.0);
  EXPECT_STREQ(o.r.stats.integrator.linear_solver, "GMRES, matrix-free");
  EXPECT_LE(o.r.stats.integrator.lin_iters, 3 * o.r.stats.integrator.nonlin_iters);
  EXPECT_LT(o.evals_per_step, 4.0);
}

}  // namespace
}  // namespace kanesim::test
