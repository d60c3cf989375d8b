// IDA's Newton matrix: the block pattern from rt::StateCouplingGroups, grouped
// difference quotients, dense LU against KLU (issue 3: "IDA ... dense or KLU linear
// solver as the size says").
//
// The scene, tests/sim/models/forest.mech: M independent stiff double pendulums (each tip
// tied to a world anchor by a 1e6 N/m spring-damper), optionally coupled by a spring
// between pendulums 1 and 2 (`coupled`) or by a force law on a[3] reading a[4]'s angle
// (`law`). The groups are checked against a second method: the full Jacobian by central
// differences of rt::Derivative, whose entries between groups must vanish and whose
// entries inside a merged group must not (the merge was needed).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>

#include "runtime/runtime.h"
#include "runtime/program/program.h"
#include "tests/support/load_util.h"

namespace kanesim::test {
namespace {

const std::string kForest = kRoot + "/tests/sim/models/forest.mech";

std::unique_ptr<Loaded> Forest(int m, bool coupled, bool law) {
  return LoadModel(kForest, {{"M", std::to_string(m)},
                             {"coupled", coupled ? "true" : "false"},
                             {"law", law ? "true" : "false"}});
}

// Full df/dy by central differences at a state away from the start.
std::vector<std::vector<double>> NumericalJacobian(const rt::Program& p, std::vector<double> y) {
  auto ws = rt::MakeWorkspace(p);
  const size_t n = y.size();
  std::vector<std::vector<double>> J(n, std::vector<double>(n, 0.0));
  std::vector<double> fp(n), fm(n);
  for (size_t j = 0; j < n; ++j) {
    const double h = 1e-6 * std::max(1.0, std::fabs(y[j]));
    const double keep = y[j];
    y[j] = keep + h;
    EXPECT_EQ(rt::Derivative(p, *ws, 0.3, y.data(), fp.data()), 0);
    y[j] = keep - h;
    EXPECT_EQ(rt::Derivative(p, *ws, 0.3, y.data(), fm.data()), 0);
    y[j] = keep;
    for (size_t i = 0; i < n; ++i) J[i][j] = (fp[i] - fm[i]) / (2 * h);
  }
  return J;
}

struct Structure {
  double max_outside = 0.0;  // largest |J_ij| with i, j in different groups
  double max_inside = 0.0;   // largest |J_ij| in a group
};

Structure Check(const rt::Program& p, const std::vector<int>& groups) {
  std::vector<double> y(static_cast<size_t>(rt::StateSize(p)));
  rt::InitialState(p, y.data());
  for (size_t i = 0; i < y.size(); ++i) y[i] += 0.1 * std::sin(1.7 * static_cast<double>(i) + 0.3);
  auto J = NumericalJacobian(p, y);
  Structure s;
  for (size_t i = 0; i < y.size(); ++i)
    for (size_t j = 0; j < y.size(); ++j)
      (groups[i] == groups[j] ? s.max_inside : s.max_outside) =
          std::max(groups[i] == groups[j] ? s.max_inside : s.max_outside, std::fabs(J[i][j]));
  return s;
}

int CountGroups(const std::vector<int>& g) { return static_cast<int>(std::set<int>(g.begin(), g.end()).size()); }

// The largest |df_i/dy_j| between states of pendulums pa and pb (their q and u).
double CrossCoupling(const rt::Program& p, int pa, int pb) {
  std::vector<double> y(static_cast<size_t>(rt::StateSize(p)));
  rt::InitialState(p, y.data());
  for (size_t i = 0; i < y.size(); ++i) y[i] += 0.1 * std::sin(1.7 * static_cast<double>(i) + 0.3);
  auto J = NumericalJacobian(p, y);
  auto owner = [&](size_t idx) {  // pendulum of state idx, from the joint names a[k], b[k]
    int nq = rt::NumQ(p);
    int joint = idx < static_cast<size_t>(nq) ? -1 : p.joint_of_speed[static_cast<size_t>(p.u_free[idx - static_cast<size_t>(nq)])];
    if (joint < 0)
      for (size_t j = 0; j < p.joints.size(); ++j)
        if (p.joints[j].q0 == p.q_free[idx]) joint = static_cast<int>(j);
    const std::string& name = p.joints[static_cast<size_t>(joint)].name;
    return std::stoi(name.substr(name.find('[') + 1));
  };
  double m = 0.0;
  for (size_t i = 0; i < y.size(); ++i)
    for (size_t j = 0; j < y.size(); ++j)
      if (owner(i) == pb && owner(j) == pa) m = std::max(m, std::fabs(J[i][j]));
  return m;
}

TEST(IdaCoupling, IndependentPendulumsAreSeparateGroupsAndTheJacobianAgrees) {
  auto l = Forest(4, false, false);
  ASSERT_TRUE(l && l->prog);
  std::vector<int> g = rt::StateCouplingGroups(*l->prog);
  ASSERT_EQ(g.size(), static_cast<size_t>(rt::StateSize(*l->prog)));
  EXPECT_EQ(CountGroups(g), 4);
  Structure s = Check(*l->prog, g);
  std::printf("[ coupling ] 4 free pendulums: max |J| inside groups %.3g, outside %.3g\n", s.max_inside, s.max_outside);
  EXPECT_GT(s.max_inside, 1.0);
  EXPECT_LT(s.max_outside, 1e-6 * s.max_inside);
}

TEST(IdaCoupling, ASpringBetweenPendulumsMergesTheirGroups) {
  auto l = Forest(4, true, false);
  ASSERT_TRUE(l && l->prog);
  std::vector<int> g = rt::StateCouplingGroups(*l->prog);
  EXPECT_EQ(CountGroups(g), 3);
  Structure s = Check(*l->prog, g);
  EXPECT_LT(s.max_outside, 1e-6 * s.max_inside);
  EXPECT_GT(CrossCoupling(*l->prog, 1, 2), 1e-3);  // the merge was needed
}

TEST(IdaCoupling, AForceLawReadingAnotherPendulumMergesTheirGroups) {
  auto l = Forest(4, false, true);
  ASSERT_TRUE(l && l->prog);
  std::vector<int> g = rt::StateCouplingGroups(*l->prog);
  EXPECT_EQ(CountGroups(g), 3);
  Structure s = Check(*l->prog, g);
  EXPECT_LT(s.max_outside, 1e-6 * s.max_inside);
  EXPECT_GT(CrossCoupling(*l->prog, 4, 3), 1e-3);
}

TEST(IdaCoupling, AChainIsOneGroup) {
  auto l = LoadModel(kRoot + "/examples/chain.mech", {{"N", "6"}});
  ASSERT_TRUE(l && l->prog);
  EXPECT_EQ(CountGroups(rt::StateCouplingGroups(*l->prog)), 1);
}

struct ForestRun {
  sim::MemorySink sink;
  sim::SimStats stats;
};

ForestRun RunForest(const rt::Program& p, sim::IdaLinearSolver ls, rt::Integrator kind, double tol) {
  sim::SimOptions o;
  o.stop_time = 0.5;
  o.interval = 0.01;
  o.rtol = o.atol = tol;
  o.integrator = kind;
  o.ida_linear_solver = ls;
  ForestRun r;
  sim::SimResult res = sim::Simulate(p, o, r.sink);
  EXPECT_EQ(res.status, sim::SimResult::Status::kOk) << res.message;
  r.stats = res.stats;
  return r;
}

double MaxDiff(const sim::MemorySink& a, const sim::MemorySink& b) {
  double m = 0.0;
  EXPECT_EQ(a.rows.size(), b.rows.size());
  for (size_t r = 0; r < std::min(a.rows.size(), b.rows.size()); ++r)
    for (size_t c = 0; c < a.rows[r].size(); ++c) m = std::max(m, std::fabs(a.rows[r][c] - b.rows[r][c]));
  return m;
}

TEST(IdaKlu, AgreesWithDenseLuAndWithATightReference) {
  auto l = Forest(20, false, false);
  ASSERT_TRUE(l && l->prog);
  ASSERT_EQ(rt::Summarize(*l->prog).integrator, rt::Integrator::IDA);  // the stiff springs
  const double tol = 1e-6;
  ForestRun automatic = RunForest(*l->prog, sim::IdaLinearSolver::Auto, rt::Integrator::Auto, tol);
  ForestRun dense = RunForest(*l->prog, sim::IdaLinearSolver::Dense, rt::Integrator::IDA, tol);
  ForestRun klu = RunForest(*l->prog, sim::IdaLinearSolver::Klu, rt::Integrator::IDA, tol);
  // An independent reference: CVODE's BDF with its own dense difference-quotient Jacobian.
  ForestRun ref = RunForest(*l->prog, sim::IdaLinearSolver::Auto, rt::Integrator::CvodeBdf, 1e-11);

  // 80 states in 20 blocks of 4: 5 % fill, so the automatic choice is KLU.
  EXPECT_STREQ(automatic.stats.integrator.linear_solver, "KLU");
  EXPECT_STREQ(dense.stats.integrator.linear_solver, "dense LU");
  EXPECT_EQ(klu.stats.integrator.jac_nonzeros, 20 * 16);
  // Grouped difference quotients: 4 evaluations of f per Jacobian, not 80.
  ASSERT_GT(klu.stats.integrator.jac_evals, 0);
  EXPECT_EQ(klu.stats.integrator.rhs_evals_jac, 4 * klu.stats.integrator.jac_evals);

  const double dk = MaxDiff(dense.sink, klu.sink), dr = MaxDiff(klu.sink, ref.sink);
  std::printf("[ ida-klu ] dense LU vs KLU %.3g; KLU vs CVODE-BDF at 1e-11: %.3g (rtol %.0e); steps %ld / %ld\n", dk,
              dr, tol, dense.stats.integrator.steps, klu.stats.integrator.steps);
  // The same Newton matrix up to round-off in its factorization: the runs may take
  // slightly different step sequences, each within the tolerance.
  EXPECT_LT(dk, 100 * tol);
  EXPECT_LT(dr, 1000 * tol);  // measured 8e-5
}

TEST(IdaKlu, AChainKeepsTheDenseSolver) {
  auto l = LoadModel(kRoot + "/examples/chain.mech", {{"N", "30"}});
  ASSERT_TRUE(l && l->prog);
  sim::SimOptions o;
  o.stop_time = 0.05;
  o.rtol = o.atol = 1e-6;
  o.integrator = rt::Integrator::IDA;
  sim::MemorySink sink;
  sim::SimResult res = sim::Simulate(*l->prog, o, sink);
  ASSERT_EQ(res.status, sim::SimResult::Status::kOk) << res.message;
  EXPECT_STREQ(res.stats.integrator.linear_solver, "dense LU");
  // One group: every column is its own colour, n evaluations per fresh Jacobian (IDA keeps
  // df/dy across some linear setups where it costs that many: sim/integrator_ida.cpp).
  EXPECT_GT(res.stats.integrator.rhs_evals_jac, 0);
  EXPECT_EQ(res.stats.integrator.rhs_evals_jac % 60, 0);
  EXPECT_LE(res.stats.integrator.rhs_evals_jac, 60 * res.stats.integrator.jac_evals);
}

}  // namespace
}  // namespace kanesim::test
