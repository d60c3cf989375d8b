// The bridge over a change point where several loops are near singular at once, on the
// reduced form: the bridged state's speeds projected in the kinetic metric
// (runtime/engine/change_point_bridge.cpp MetricSpeeds; docs/constraints.md "Singular
// configurations", issue 20). The partition's own solve for the dependent speeds is an
// oblique projection, ill-conditioned near the crossing: on the chain of 40 equal-link
// parallelograms with IDA at rtol 1e-12 it moved the lumped energy across a bridge by up to
// 2.1e-5 J where the extrapolation itself was within 7e-8 J, so the several-loop limit of
// the bridge's estimate was held at 3e4, and the run stopped at t = 2.04 (1001 steps in a
// zone, the bridge's estimate 3.53e4). With the metric projection the jump is the
// extrapolation's and the limit is 1e5. Checked against the independent lumped crank
// (tests/stress/lumped_crank.h) past that stop: exit 0, every rod on the parallelogram
// branch, the crank angle and the lumped energy kept.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "runtime/engine/engine.h"
#include "runtime/program/program.h"
#include "runtime/sim/simulate.h"
#include "tests/constraints/load_util.h"
#include "tests/stress/lumped_crank.h"

namespace kanesim::test {
namespace {

const char* const kChain = "/tests/stress/models/parallelogram_chain.mech";

TEST(ImplicitBridge, IdaReducedChainOfFortyPassesItsFirstChangePointsAtTightTolerance) {
#if defined(__SANITIZE_ADDRESS__) || defined(KANESIM_STRESS_SHORT)
  GTEST_SKIP() << "about 5 s in Release";
#endif
  constexpr int kLoops = 40;
  constexpr double kStop = 3.0;  // main stopped at t = 2.04
  rt::CompileOptions co;
  co.solver = rt::SolverPath::Dense;
  auto l = LoadModel(kRoot + kChain, {{"N", std::to_string(kLoops)}}, co);
  ASSERT_TRUE(l && l->prog);
  sim::SimOptions so;
  so.stop_time = kStop;
  so.interval = 0.01;
  so.rtol = so.atol = 1e-12;
  so.integrator = rt::IntegratorKind::IDA;
  so.signals = {"rj0.q", "rj0.u"};
  for (int i = 1; i <= kLoops; ++i) so.signals.push_back("rj[" + std::to_string(i) + "].q");
  sim::MemorySink sink;
  const sim::SimResult r = sim::Simulate(*l->prog, so, sink);
  ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << r.message;
  ASSERT_FALSE(sink.rows.empty());
  EXPECT_NEAR(sink.times.back(), kStop, 1e-12);
  const lumped_crank::Crank c = lumped_crank::ParallelogramChain(kLoops);
  std::vector<double> th, w;
  const double e0 = 0.5 * c.J * sink.rows[0][1] * sink.rows[0][1] + c.G * std::sin(sink.rows[0][0]);
  double branch = 0.0, energy = 0.0;
  for (const auto& row : sink.rows) {
    th.push_back(row[0]);
    w.push_back(row[1]);
    for (size_t k = 2; k < row.size(); ++k) branch = std::max(branch, std::fabs(std::remainder(row[k] - row[0], 2 * M_PI)));
    energy = std::max(energy, std::fabs(0.5 * c.J * row[1] * row[1] + c.G * std::sin(row[0]) - e0) / std::fabs(e0));
  }
  const double angle = lumped_crank::MaxAngleError(c, sink.times, th, w, 1e-5);
  std::printf("IDA reduced N = 40, rtol 1e-12, to t = %g: %.2g rad off the lumped crank, energy %.2g of E, rods %.2g apart\n",
              kStop, angle, energy, branch);
  EXPECT_LT(branch, 1e-8);
  EXPECT_LT(angle, 1e-5);
  EXPECT_LT(energy, 1e-8);
}

}  // namespace
}  // namespace kanesim::test
