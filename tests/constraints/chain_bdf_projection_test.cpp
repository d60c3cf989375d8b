// The chain of ten equal-link parallelograms on the multiplier form with CVODE-BDF (issue 20)
// at rtol 1e-12 goes on through its change points on the branch
// (sim/integrator_cvode.cpp, ProjectStep). Main restarted CVODE (CVodeReInit, order
// 1) from the projection y* whenever a step's drift from it grew past 10 error weights;
// inside the change-point zones, where the projection is ill-conditioned, that happened
// 234 times by t = 7.705, each restart shrinking the step, until the branch monitor stopped
// the run with exit 2 at t = 7.705 ("the integrator took 1001 steps since 7.704 without
// passing the change point", loop cut[3]). CVODE-BDF now projects each step through
// CVODE's own projection (the Nordsieck history corrected with y, no restart).
//
// Checked against the independent lumped crank (tests/support/lumped_crank.h: the whole
// chain turns as one crank of lumped inertia): every row's energy (1/2) J w^2 + G sin(theta)
// within max(1e3 rtol, 1e-6) of the first row's (bench/change_point_chains.py's bound),
// every rod at rod 0's angle and speed (the branch), and the run to its stop time past the
// crossing where main stopped.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "sim/simulate.h"
#include "tests/support/load_util.h"
#include "tests/support/lumped_crank.h"
#include "tests/support/sanitizer_cases.h"

namespace kanesim::test {
namespace {

void RunChain(int n, bool bdf, double rtol, double stop) {
  rt::CompileOptions co;
  co.solver = rt::SolverPath::Sparse;  // the multiplier form
  auto l = LoadModel(kRoot + "/tests/stress/models/parallelogram_chain.mech", {{"N", std::to_string(n)}}, co);
  ASSERT_TRUE(l && l->prog);
  sim::SimOptions so;
  so.stop_time = stop;
  so.interval = 0.01;
  so.rtol = so.atol = rtol;
  so.integrator = bdf ? rt::Integrator::CvodeBdf : rt::Integrator::CvodeAdams;
  // The dense Newton matrix these were measured with (auto takes the matrix-free iteration
  // on the chain of 40's multiplier form: tests/constraints/newton_krylov_chain_test.cpp),
  // so that the t = 2.04 crossing below still exercises the bridge's projected start.
  so.ida_linear_solver = sim::IdaLinearSolver::Dense;
  so.signals = lumped_crank::ChainSignals(n, {"q", "u"});
  sim::MemorySink sink;
  const sim::SimResult r = sim::Simulate(*l->prog, so, sink);
  ASSERT_FALSE(sink.rows.empty());
  const double last_t = sink.times.back();
  EXPECT_EQ(r.status, sim::SimResult::Status::kOk) << r.message;
  EXPECT_NEAR(last_t, stop, 1e-9) << r.message;

  const lumped_crank::ChainRowErrors err = lumped_crank::ChainErrors(n, sink.rows);
  const double de = err.energy, off = err.off, apart = err.apart;
  EXPECT_LT(de, std::max(1e3 * rtol, 1e-6));
  EXPECT_LT(off, 1e-6);
  EXPECT_LT(apart, 1e-4);
  std::printf("chain of %d, multiplier form, %s, rtol %.0e: to t = %.2f, energy %.2g, rods %.2g rad and %.2g rad/s "
              "apart, %ld steps, %ld bridges\n",
              n, bdf ? "CVODE-BDF" : "CVODE", rtol, last_t, de, off, apart, r.stats.integrator.steps, r.stats.bridges);
}

// Measured with the projection: 4.5e-8 of E, rods 1.5e-10 rad and 6.4e-7 rad/s apart over
// 20 s (bench/change_point_chains.py).
// Under the sanitizers (~30x slower) to t = 2.5: CVODE's projection at every step and the
// first crossing's change points (8 bridged by then, kanesim run --stats); the one at 7.7 in
// Release only.
TEST(ChainBdfProjection, ChainOfTenAtRtol1e12PassesTheChangePointOfT7p7OnTheBranch) {
  RunChain(10, true, 1e-12, test::kUnderSanitizers ? 2.5 : 8.0);
}

// The chain of 40 with CVODE-BDF at rtol 1e-10 (sim/change_point_bridge.cpp,
// ProjectStart): main refused the bridge at t = 2.04 (the projection moved the bridged
// state by 2.53e-5 of |u|, limit 2e-5: the rods' speeds 5.7e-4 apart in the extrapolation)
// and stopped with exit 2 at t = 2.047 by the turn check. With the approach started from
// the state projected to round-off the bridge's estimate there is 37, its move 7e-9.
TEST(ChainBdfProjection, ChainOfFortyBdfAtRtol1e10BridgesTheCrossingOfT2p04) {
#if defined(__SANITIZE_ADDRESS__) || defined(KANESIM_STRESS_SHORT)
  GTEST_SKIP() << "a few seconds in Release";
#endif
  RunChain(40, true, 1e-10, 2.1);
}

}  // namespace
}  // namespace kanesim::test
