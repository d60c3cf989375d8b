// The chain of 40 equal-link parallelograms on the multiplier form with CVODE (Adams) at rtol
// 1e-12 is bridged over its change point at t = 4.309 (issue 20; runtime/engine/
// branch_monitor.cpp, kApproachStartRho). The bridge's approach is meant to start at the last
// accepted step with rho >= 3.5e-2, but only the last 8 accepted steps before a zone were
// kept, and at this tolerance they began at rho 0.0134: the approach started there, its fit
// nodes closer to the crossing where the equations are inaccurate, its error estimate 1.85e7
// and its projection's move 2.2e-5 (above the limit 2e-5), so main refused the bridge and
// CVODE crept until the monitor stopped it with exit 2 at t = 4.3091 (1001 steps in the zone
// of cut[18]). The step with rho >= 3.5e-2 is now kept.
//
// Checked against the independent lumped crank (tests/stress/lumped_crank.h): every row's
// energy (1/2) J w^2 + G sin(theta) within max(1e3 rtol, 1e-6) of the first row's
// (bench/change_point_chains.py's bound), every rod at rod 0's angle and speed (the branch),
// and the run to its stop time just past the crossing where main stopped.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "runtime/sim/simulate.h"
#include "tests/constraints/load_util.h"
#include "tests/stress/lumped_crank.h"

namespace kanesim::test {
namespace {

void RunChainOf40(bool bdf, double rtol, double stop) {
  const int n = 40;
  rt::CompileOptions co;
  co.solver = rt::SolverPath::Sparse;  // the multiplier form
  auto l = LoadModel(kRoot + "/tests/stress/models/parallelogram_chain.mech", {{"N", std::to_string(n)}}, co);
  ASSERT_TRUE(l && l->prog);
  sim::SimOptions so;
  so.stop_time = stop;
  so.interval = 0.01;
  so.rtol = so.atol = rtol;
  so.integrator = rt::IntegratorKind::CVODE;
  so.cvode_bdf = bdf;
  so.signals = {"rj0.q", "rj0.u"};
  for (int i = 1; i <= n; ++i) so.signals.push_back("rj[" + std::to_string(i) + "].q");
  for (int i = 1; i <= n; ++i) so.signals.push_back("rj[" + std::to_string(i) + "].u");
  sim::MemorySink sink;
  const sim::SimResult r = sim::Simulate(*l->prog, so, sink);
  ASSERT_FALSE(sink.rows.empty());
  const double last_t = sink.times.back();
  EXPECT_EQ(r.status, sim::SimResult::Status::kOk) << r.message;
  EXPECT_NEAR(last_t, stop, 1e-9) << r.message;

  const lumped_crank::Crank c = lumped_crank::ParallelogramChain(n);
  auto energy = [&](const std::vector<double>& row) { return 0.5 * c.J * row[1] * row[1] + c.G * std::sin(row[0]); };
  const double e0 = energy(sink.rows.front());
  double de = 0.0, off = 0.0, apart = 0.0;
  for (const auto& row : sink.rows) {
    de = std::max(de, std::fabs(energy(row) - e0) / std::fabs(e0));
    for (int i = 0; i < n; ++i) {
      off = std::max(off, std::fabs(std::remainder(row[2 + static_cast<size_t>(i)] - row[0], 2 * M_PI)));
      apart = std::max(apart, std::fabs(row[2 + static_cast<size_t>(n + i)] - row[1]));
    }
  }
  EXPECT_LT(de, std::max(1e3 * rtol, 1e-6));
  EXPECT_LT(off, 1e-6);
  EXPECT_LT(apart, 1e-4);
  std::printf("chain of 40, multiplier form, %s, rtol %.0e: to t = %.2f, energy %.2g, rods %.2g rad and %.2g rad/s "
              "apart, %ld bridges\n",
              bdf ? "CVODE-BDF" : "CVODE", rtol, last_t, de, off, apart, r.stats.bridges);
}

// Main: exit 2 at t = 4.3091 (1001 steps in the zone of cut[18]).
TEST(ChainBridgeApproach, CvodeAdamsAtRtol1e12PassesTheCrossingAtT4p309) {
#if defined(__SANITIZE_ADDRESS__)
  // 5 s in Release, ~30x that under the sanitizers; the approach's code runs there in
  // ChangePointBridge's cells.
  GTEST_SKIP() << "5 s in Release";
#endif
  RunChainOf40(false, 1e-12, 4.35);
}

}  // namespace
}  // namespace kanesim::test
