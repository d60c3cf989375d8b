// The states a difference-quotient Jacobian need not perturb (rt::ProjectedStates,
// OdeSystem::ProjectedStates; docs/constraints.md "Singular configurations"; issue 20).
// On the reduced form with closed loops, f reads the dependent speeds and the coordinates
// of joints whose every speed is dependent only through the projection, which recomputes
// them from the independent ones (plus the pull to the manifold, -k_drift on the diagonal).
// IDA's Jacobian sets those columns to that instead of perturbing them: on the chain of N
// loops, 2 evaluations of f per Jacobian instead of 2 (2N + 1) outside the change-point
// zones. Checked:
//  - at a state of the chain away from its change points, held, every listed state perturbed
//    changes f only by -k_drift times the perturbation on its own row, and the states not
//    listed (the independent ones) do change it: the list is exactly what f does not read;
//  - IDA and CVODE-BDF on the chain (reduced form) at rtol 1e-10 through its change points:
//    far fewer Jacobian evaluations of f than states per Jacobian, on the branch to 20 s
//    and within 2e-5 rad of the independent lumped crank (tests/support/lumped_crank.h).
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

TEST(ProjectedStates, FDoesNotReadThem) {
  rt::CompileOptions co;
  co.solver = rt::SolverPath::Dense;
  const int loops = 4;
  auto l = LoadModel(kRoot + lumped_crank::kChainPath, {{"N", std::to_string(loops)}, {"theta0", "0.7"}}, co);
  ASSERT_TRUE(l && l->prog);
  const rt::Program& p = *l->prog;
  auto ws = rt::MakeWorkspace(p);
  const int n = rt::StateSize(p);
  std::vector<double> y(static_cast<size_t>(n)), f0(y.size()), f1(y.size());
  rt::InitialState(p, y.data());
  ASSERT_EQ(rt::Derivative(p, *ws, 0.0, y.data(), f0.data()), 0) << rt::ErrorMessage(*ws);
  rt::HoldPartition(*ws, true);
  std::vector<int> states;
  double diag = 0.0;
  ASSERT_TRUE(rt::ProjectedStates(p, *ws, &states, &diag));
  // Every loop: two dependent speeds and the angles of their joints.
  EXPECT_EQ(static_cast<int>(states.size()), 4 * loops);
  EXPECT_EQ(static_cast<int>(states.size()), n - 2);
  const double d = 1e-6;
  for (int j = 0; j < n; ++j) {
    std::vector<double> y1 = y;
    y1[static_cast<size_t>(j)] += d;
    ASSERT_EQ(rt::Derivative(p, *ws, 0.0, y1.data(), f1.data()), 0) << rt::ErrorMessage(*ws);
    const bool listed = std::count(states.begin(), states.end(), j) > 0;
    double off = 0.0;  // max over rows of |df_i/dy_j - (listed: diag on its row, else 0)|
    for (int i = 0; i < n; ++i) {
      const double dq = (f1[static_cast<size_t>(i)] - f0[static_cast<size_t>(i)]) / d;
      off = std::max(off, std::fabs(dq - (i == j ? diag : 0.0)));
    }
    if (listed)
      EXPECT_LT(off, 1e-5) << "state " << j << " is listed but f reads it";
    else
      EXPECT_GT(off, 1e-2) << "state " << j << " is not listed yet f does not read it";
  }
  rt::HoldPartition(*ws, false);
}

#if defined(__SANITIZE_ADDRESS__) || defined(KANESIM_STRESS_SHORT)
constexpr int kLoops = 2;  // sanitizers: ~30x slower
constexpr int kCvodeLoops = 2;
#else
constexpr int kLoops = 4;
constexpr int kCvodeLoops = 10;
#endif

// The chain of `loops` on the reduced form at rtol 1e-10 through its change points with
// `integrator`: on the branch to 20 s, within 2e-5 rad of the lumped crank, and its
// Jacobians' evaluations of f, which are checked against the number of states.
void ChainJacobians(rt::Integrator integrator, const char* name, int loops, double max_evals_per_jacobian) {
  rt::CompileOptions co;
  co.solver = rt::SolverPath::Dense;
  auto l = LoadModel(kRoot + lumped_crank::kChainPath, {{"N", std::to_string(loops)}}, co);
  ASSERT_TRUE(l && l->prog);
  sim::SimOptions so;
  so.stop_time = 20.0;
  so.interval = 0.01;
  so.rtol = so.atol = 1e-10;
  so.integrator = integrator;
  so.signals = lumped_crank::ChainSignals(loops, {"q"});
  sim::MemorySink sink;
  const sim::SimResult r = sim::Simulate(*l->prog, so, sink);
  EXPECT_EQ(r.status, sim::SimResult::Status::kOk) << r.message;
  ASSERT_FALSE(sink.rows.empty());
  EXPECT_NEAR(sink.times.back(), 20.0, 1e-12);
  std::vector<double> th, w;
  double branch = 0.0;
  for (const auto& row : sink.rows) {
    th.push_back(row[0]);
    w.push_back(row[1]);
    for (size_t k = 2; k < row.size(); ++k) branch = std::max(branch, std::fabs(std::remainder(row[k] - row[0], 2 * M_PI)));
  }
  EXPECT_LT(branch, 1e-8);
  const double err = lumped_crank::MaxAngleError(lumped_crank::ParallelogramChain(loops), sink.times, th, w, 1e-5);
  EXPECT_LT(err, 2e-5);
  const auto& st = r.stats.integrator;
  const int n = rt::StateSize(*l->prog);
  ASSERT_GT(st.jac_evals, 0);
  EXPECT_LE(static_cast<double>(st.rhs_evals_jac), max_evals_per_jacobian * static_cast<double>(st.jac_evals))
      << st.rhs_evals_jac << " evaluations for " << st.jac_evals << " Jacobians of " << n << " states";
  std::printf("%s N = %d: %ld Jacobians, %ld evaluations for them (%d states), %ld steps, %ld evaluations, %.2g rad\n",
              name, loops, st.jac_evals, st.rhs_evals_jac, n, st.steps, st.rhs_evals, err);
}

// Without the projected states every Jacobian takes n evaluations (one group).
TEST(ProjectedStates, IdaJacobiansPerturbOnlyTheIndependentStates) {
  ChainJacobians(rt::Integrator::IDA, "IDA", kLoops, 0.5 * (2 * (2 * kLoops + 1)));
}

// CVODE-BDF's df/dy by the same grouped difference quotients (sim/dq_jacobian.h):
// 2 evaluations per Jacobian (the angle and the speed of the independent joint) on the
// chain of ten, 42 states (measured: 424 for 212 Jacobians, 8.1e-6 rad). CVODE's own dense
// difference quotients (main, b2c5e4c) took one per state: 8022 for 191, 1.4e-5 rad.
TEST(ProjectedStates, CvodeBdfJacobiansPerturbOnlyTheIndependentStates) {
  ChainJacobians(rt::Integrator::CvodeBdf, "CVODE-BDF", kCvodeLoops, 2.0);
}

}  // namespace
}  // namespace kanesim::test
