// The speed partition held across a difference-quotient Jacobian (rt::HoldPartition,
// OdeSystem::HoldForJacobian; docs/constraints.md "Singular configurations"; issue 20).
// Near a change point of a chain of equal-link parallelograms every partition's dependent
// block is degraded (pivot ratio below 1e-2), so an evaluation re-chooses it by pivoting;
// IDA's Jacobian takes one evaluation per column around the same state, and columns taken
// with different partitions differentiate different functions (the partition decides which
// coordinates the projection corrects). IDA holds it there; CVODE-BDF's Jacobian is CVODE's
// own (held, it stopped on the chain of 40 at rtol 1e-12, docs/benchmarks.md). Checked:
//  - at a state in the zone, unheld, each perturbed evaluation re-chooses (the zone is real,
//    so the next check can fail), and held none does, and the held evaluation at the base
//    state itself is the unheld one bit for bit;
//  - IDA (held) and CVODE-BDF (not) on the chain (reduced form) at rtol 1e-10 through its
//    change points:
//    on the branch to 20 s, within 2e-5 rad of the independent lumped crank
//    (tests/support/lumped_crank.h).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "runtime/runtime.h"
#include "runtime/program/program.h"
#include "sim/simulate.h"
#include "tests/support/load_util.h"
#include "tests/support/lumped_crank.h"

namespace kanesim::test {
namespace {

TEST(PartitionHold, PerturbedEvaluationsKeepThePartitionWhenHeld) {
  rt::CompileOptions co;
  co.solver = rt::SolverPath::Dense;
  // Rod angle 2e-3 rad from the collinear change point: every loop near singular.
  auto l = LoadModel(kRoot + lumped_crank::kChainPath, {{"N", "4"}, {"theta0", "0.002"}}, co);
  ASSERT_TRUE(l && l->prog);
  const rt::Program& p = *l->prog;
  auto ws = rt::MakeWorkspace(p);
  const int n = rt::StateSize(p);
  std::vector<double> y(static_cast<size_t>(n)), f0(y.size()), f1(y.size()), f_held(y.size());
  rt::InitialState(p, y.data());
  ASSERT_EQ(rt::Derivative(p, *ws, 0.0, y.data(), f0.data()), 0) << rt::ErrorMessage(*ws);
  const std::vector<int> dep = ws->dep;

  // Unheld: every evaluation in the zone re-chooses.
  long before = ws->partition_changes;
  for (int j = 0; j < n; ++j) {
    std::vector<double> y1 = y;
    y1[static_cast<size_t>(j)] += 1e-7;
    ASSERT_EQ(rt::Derivative(p, *ws, 0.0, y1.data(), f1.data()), 0) << rt::ErrorMessage(*ws);
  }
  EXPECT_GE(ws->partition_changes - before, n) << "the state is not in a degraded zone";

  // Held, after an evaluation at the base state: none does, and the base's partition stays.
  ASSERT_EQ(rt::Derivative(p, *ws, 0.0, y.data(), f1.data()), 0);
  EXPECT_EQ(ws->dep, dep);
  rt::HoldPartition(*ws, true);
  before = ws->partition_changes;
  ASSERT_EQ(rt::Derivative(p, *ws, 0.0, y.data(), f_held.data()), 0);
  for (int j = 0; j < n; ++j) {
    std::vector<double> y1 = y;
    y1[static_cast<size_t>(j)] += 1e-7;
    ASSERT_EQ(rt::Derivative(p, *ws, 0.0, y1.data(), f1.data()), 0) << rt::ErrorMessage(*ws);
  }
  EXPECT_EQ(ws->partition_changes, before);
  EXPECT_EQ(ws->dep, dep);
  rt::HoldPartition(*ws, false);
  for (int i = 0; i < n; ++i) EXPECT_EQ(f_held[static_cast<size_t>(i)], f0[static_cast<size_t>(i)]) << i;
}

struct ChainRun {
  sim::SimResult result;
  double branch = 0.0, theta_error = 0.0, last_t = 0.0;
};

ChainRun RunChain(int n, bool bdf, double rtol) {
  rt::CompileOptions co;
  co.solver = rt::SolverPath::Dense;
  auto l = LoadModel(kRoot + lumped_crank::kChainPath, {{"N", std::to_string(n)}}, co);
  ChainRun o;
  if (!l || !l->prog) {
    ADD_FAILURE() << "the model did not compile";
    return o;
  }
  sim::SimOptions so;
  so.stop_time = 20.0;
  so.interval = 0.01;
  so.rtol = so.atol = rtol;
  so.integrator = bdf ? rt::Integrator::CvodeBdf : rt::Integrator::IDA;
  so.signals = lumped_crank::ChainSignals(n, {"q"});
  sim::MemorySink sink;
  o.result = sim::Simulate(*l->prog, so, sink);
  if (sink.rows.empty()) return o;
  std::vector<double> th, w;
  for (const auto& r : sink.rows) {
    th.push_back(r[0]);
    w.push_back(r[1]);
    for (size_t k = 2; k < r.size(); ++k)
      o.branch = std::max(o.branch, std::fabs(std::remainder(r[k] - r[0], 2 * M_PI)));
  }
  o.last_t = sink.times.back();
  o.theta_error = lumped_crank::MaxAngleError(lumped_crank::ParallelogramChain(n), sink.times, th, w, 1e-5);
  return o;
}

#if defined(__SANITIZE_ADDRESS__) || defined(KANESIM_STRESS_SHORT)
constexpr int kLoops = 2;  // sanitizers: ~30x slower
#else
constexpr int kLoops = 4;
#endif

// Measured (N = 4, rtol 1e-10): IDA 2.4e-7 rad, CVODE-BDF 7.7e-6 rad off the lumped crank (main:
// 5.7e-7, 7.7e-6; the chain of ten on main 7.4e-6, 9.6e-6).
TEST(PartitionHold, ImplicitSolversPassTheChainsChangePoints) {
  for (bool bdf : {false, true}) {
    SCOPED_TRACE(bdf ? "CVODE-BDF" : "IDA");
    const ChainRun o = RunChain(kLoops, bdf, 1e-10);
    EXPECT_EQ(o.result.status, sim::SimResult::Status::kOk) << o.result.message;
    EXPECT_NEAR(o.last_t, 20.0, 1e-12);
    EXPECT_LT(o.branch, 1e-8);
    EXPECT_LT(o.theta_error, 2e-5);
    const auto& st = o.result.stats.integrator;
    std::printf("%s N = %d: %ld steps, %ld Jacobians, %ld convergence failures, %.2g rad\n", bdf ? "CVODE-BDF" : "IDA",
                kLoops, st.steps, st.jac_evals, st.nonlin_conv_fails, o.theta_error);
  }
}

}  // namespace
}  // namespace kanesim::test
