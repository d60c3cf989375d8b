// The multiplier form of the constrained equations (runtime/kane/kane_sparse.cpp eqs. 3-4:
// a multiplier per independent constraint row in the sparse K-vector system, KLU; the
// projection in the kinetic metric, runtime/kane/kane_sparse.cpp ProjectStateSparse) against
// the reduced form (dependent speeds eliminated, Lesser eqs. 48-51), which the other
// constraint tests hold against closed forms. Two different algorithms: the same
// accelerations on the manifold, the same trajectories and constraint forces to the
// integration tolerance; and the multiplier form's own invariants on a ladder of loops
// large enough for the automatic choice to take it.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "runtime/program/program.h"
#include "tests/support/load_util.h"
#include "tests/support/lumped_crank.h"
#include "compiler/compiler.h"

namespace kanesim::test {
namespace {

std::shared_ptr<const rt::Program> CompileOn(const flat::Mechanism& m, rt::SolverPath path) {
  rt::CompileOptions o;
  o.solver = path;
  rt::CompileResult r = rt::Compile(m, o);
  EXPECT_TRUE(r.program) << (r.errors.empty() ? "" : r.errors[0].message);
  return r.program;
}

// Every signal but the integrator-path ones (the drift before projection).
std::vector<std::string> Compared(const rt::Program& p) {
  std::vector<std::string> out;
  for (const std::string& s : rt::AvailableSignals(p))
    if (s.find("constraint_drift") == std::string::npos) out.push_back(s);
  return out;
}

void AgreeWithReducedForm(const std::string& path) {
  SCOPED_TRACE(path);
  auto l = LoadModel(kRoot + "/" + path);
  ASSERT_TRUE(l && l->prog);
  auto reduced = CompileOn(l->mech, rt::SolverPath::Dense);
  auto multiplier = CompileOn(l->mech, rt::SolverPath::Sparse);
  ASSERT_TRUE(reduced && multiplier);
  ASSERT_EQ(rt::Summarize(*multiplier).solver, rt::SolverPath::Sparse) << rt::Summarize(*multiplier).solver_reason;
  ASSERT_EQ(rt::Summarize(*reduced).solver, rt::SolverPath::Dense);
  // The assembled start lies on the manifold, where both projections are the identity:
  // the accelerations agree to round-off.
  const size_t n = static_cast<size_t>(rt::StateSize(*reduced));
  std::vector<double> y(n), a(n), b(n);
  rt::InitialState(*reduced, y.data());
  auto wr = rt::MakeWorkspace(*reduced);
  auto wm = rt::MakeWorkspace(*multiplier);
  ASSERT_EQ(rt::Derivative(*reduced, *wr, 0.0, y.data(), a.data()), 0) << rt::ErrorMessage(*wr);
  ASSERT_EQ(rt::Derivative(*multiplier, *wm, 0.0, y.data(), b.data()), 0) << rt::ErrorMessage(*wm);
  for (size_t i = 0; i < n; ++i) EXPECT_NEAR(a[i], b[i], 1e-10 * (1.0 + std::fabs(a[i]))) << "ydot[" << i << "]";
  // Whole runs at a tight tolerance: coordinates, speeds, energies, reactions, contact
  // forces, drive forces, constraint residuals and power.
  const std::vector<std::string> names = Compared(*reduced);
  sim::MemorySink sr = RunModel(*reduced, 1.0, 0.1, 1e-10, names);
  sim::MemorySink sm = RunModel(*multiplier, 1.0, 0.1, 1e-10, names);
  ASSERT_EQ(sr.rows.size(), sm.rows.size());
  for (size_t k = 0; k < sr.rows.size(); ++k)
    for (size_t c = 0; c < names.size(); ++c) {
      const double x = sr.rows[k][c], z = sm.rows[k][c];
      if (std::isnan(x)) {  // indeterminate components: nan on both paths
        EXPECT_TRUE(std::isnan(z)) << names[c] << " at t = " << sr.times[k];
        continue;
      }
      EXPECT_NEAR(x, z, 2e-6 * (1.0 + std::fabs(x))) << names[c] << " at t = " << sr.times[k];
    }
}

TEST(MultiplierForm, FourBarAgreesWithReducedForm) { AgreeWithReducedForm("examples/fourbar.mech"); }
TEST(MultiplierForm, SliderCrankDriveAgreesWithReducedForm) { AgreeWithReducedForm("examples/slider_crank.mech"); }
TEST(MultiplierForm, RollingDiskAgreesWithReducedForm) { AgreeWithReducedForm("examples/rolling_disk.mech"); }
TEST(MultiplierForm, SphereOnInclineAgreesWithReducedForm) { AgreeWithReducedForm("examples/sphere_incline.mech"); }
TEST(MultiplierForm, SleighAgreesWithReducedForm) { AgreeWithReducedForm("examples/sleigh.mech"); }
TEST(MultiplierForm, FourBarWithJointTorquesAgreesWithReducedForm) {
  AgreeWithReducedForm("tests/constraints/models/fourbar_torques.mech");
}
TEST(MultiplierForm, SpatialFourBarAgreesWithReducedForm) {
  AgreeWithReducedForm("tests/constraints/models/rusr_fourbar.mech");
}

const std::string kLadder = "bench/models/fourbar_ladder.mech";

TEST(MultiplierForm, AutomaticChoiceFollowsTheLadderBenchmark) {
  // bench/loop_solvers: the reduced form is cheaper up to about 20 loops (60 speeds), the
  // multiplier form from there on. If this fails, the threshold or the reason changed.
  auto small = LoadModel(kRoot + "/" + kLadder, {{"N", "16"}});
  auto large = LoadModel(kRoot + "/" + kLadder, {{"N", "20"}});
  ASSERT_TRUE(small && small->prog && large && large->prog);
  EXPECT_EQ(rt::Summarize(*small->prog).solver, rt::SolverPath::Dense);
  const rt::ProgramSummary s = rt::Summarize(*large->prog);
  EXPECT_EQ(s.solver, rt::SolverPath::Sparse);
  EXPECT_NE(s.solver_reason.find("measured cheaper than the reduced form from 60 free speeds"), std::string::npos)
      << s.solver_reason;
  EXPECT_EQ(s.dof, 20);
}

rt::CompileOptions Multiplier() {
  rt::CompileOptions o;
  o.solver = rt::SolverPath::Sparse;
  return o;
}

TEST(MultiplierForm, LadderKeepsEnergyAndConstraintsAndMatchesReducedForm) {
  // 16 loops, 48 bodies: conservative, so kinetic + potential energy is constant; every
  // loop's position and velocity residual stays at round-off (the projection) and the
  // trajectory is the reduced form's to the tolerance.
  auto l = LoadModel(kRoot + "/" + kLadder, {{"N", "16"}}, Multiplier());
  ASSERT_TRUE(l && l->prog);
  ASSERT_EQ(rt::Summarize(*l->prog).solver, rt::SolverPath::Sparse);
  std::vector<std::string> names = {"kinetic_energy", "potential_energy"};
  for (int i = 1; i <= 16; i += 5) {
    names.push_back("jr[" + std::to_string(i) + "].q");
    names.push_back("c[" + std::to_string(i) + "].constraint_residual");
    names.push_back("c[" + std::to_string(i) + "].constraint_residual_velocity");
  }
  const double rtol = 1e-8;
  sim::MemorySink m = RunModel(*l->prog, 2.0, 0.05, rtol, names);
  double e_max = 0.0, t_max = 0.0, res = 0.0;
  const double e0 = m.rows[0][0] + m.rows[0][1];
  for (const auto& row : m.rows) {
    e_max = std::max(e_max, std::fabs(row[0] + row[1] - e0));
    t_max = std::max(t_max, row[0]);
    for (size_t c = 2; c < names.size(); ++c)
      if (names[c].find("constraint_residual") != std::string::npos) res = std::max(res, std::fabs(row[c]));
  }
  ASSERT_GT(t_max, 1.0);  // it moves (J)
  EXPECT_LT(e_max, 100 * rtol * t_max) << "energy drift";
  EXPECT_LT(res, 1e-11) << "constraint residuals";
  auto reduced = CompileOn(l->mech, rt::SolverPath::Dense);
  ASSERT_TRUE(reduced);
  sim::MemorySink r = RunModel(*reduced, 2.0, 0.05, rtol, names);
  ASSERT_EQ(r.rows.size(), m.rows.size());
  for (size_t c = 2; c < names.size(); ++c) {
    if (names[c].find(".q") == std::string::npos) continue;
    EXPECT_NEAR(r.rows.back()[c], m.rows.back()[c], 1e-5) << names[c];
  }
}

TEST(MultiplierForm, RebindKeepsTheSparsePattern) {
  // A sweep re-binds parameters: the symbolic analysis is reused and the run still closes
  // its loops (a wider start swing).
  auto l = LoadModel(kRoot + "/" + kLadder, {{"N", "16"}}, Multiplier());
  ASSERT_TRUE(l && l->prog && l->prog->sparse_symbolic);
  std::vector<double> values = l->prog->param_values;
  for (size_t i = 0; i < l->mech.params.size(); ++i)
    if (l->mech.ParamName(i) == "swing") values[i] = 0.5;
  rt::CompileResult r = rt::Rebind(*l->prog, values);
  ASSERT_TRUE(r.program);
  EXPECT_EQ(r.program->sparse_symbolic, l->prog->sparse_symbolic);
  sim::MemorySink m = RunModel(*r.program, 0.5, 0.25, 1e-8, {"jl[1].q", "c[16].constraint_residual"});
  EXPECT_NEAR(m.rows[0][0], -M_PI / 2 + 0.5, 1e-9);  // held at assembly; projected in the kinetic metric
  EXPECT_LT(std::fabs(m.rows.back()[1]), 1e-11);
}

// The reduced form's two ways to Kane's equations on the constrained basis
// (runtime/constraints/constraints.cpp (10)-(12)): the composite mass matrix reduced by beta, and the
// bodies' partial twists from one velocity pass per degree of freedom. Same scene, same
// state (off the manifold, so the projection works too), both projection modes: the
// accelerations agree to round-off. With the multiplier-form comparisons above (which see
// whichever way the compiler chose), each way is held against an independent algorithm.
void PassesAgreeWithMassMatrix(const std::string& path, std::vector<lang::ParamOverride> sets = {}) {
  SCOPED_TRACE(path);
  auto l = LoadModel(kRoot + "/" + path, sets, [] {
    rt::CompileOptions o;
    o.solver = rt::SolverPath::Dense;
    return o;
  }());
  ASSERT_TRUE(l && l->prog);
  ASSERT_EQ(rt::Summarize(*l->prog).solver, rt::SolverPath::Dense);
  rt::Program by_m = *l->prog, by_passes = *l->prog;
  by_m.reduce_by_passes = false;
  by_passes.reduce_by_passes = true;
  const size_t n = static_cast<size_t>(rt::StateSize(by_m));
  const size_t nq = static_cast<size_t>(rt::NumQ(by_m));
  std::vector<double> y(n), a(n), b(n);
  rt::InitialState(by_m, y.data());
  for (size_t i = 0; i < n; ++i) y[i] += (i < nq ? 1e-7 : 0.2) * std::cos(1.0 + static_cast<double>(i));
  for (bool step : {false, true}) {
    auto wm = rt::MakeWorkspace(by_m);
    auto wp = rt::MakeWorkspace(by_passes);
    rt::SetStepProjection(*wm, step);
    rt::SetStepProjection(*wp, step);
    ASSERT_EQ(rt::Derivative(by_m, *wm, 0.0, y.data(), a.data()), 0) << rt::ErrorMessage(*wm);
    ASSERT_EQ(rt::Derivative(by_passes, *wp, 0.0, y.data(), b.data()), 0) << rt::ErrorMessage(*wp);
    double scale = 0.0;
    for (size_t i = nq; i < n; ++i) scale = std::max(scale, std::fabs(a[i]));
    ASSERT_GT(scale, 0.1);  // it accelerates
    for (size_t i = 0; i < n; ++i)
      EXPECT_NEAR(a[i], b[i], 1e-12 * (1.0 + scale)) << "ydot[" << i << "], step projection " << step;
  }
}

TEST(ReducedForm, PassesAgreeWithMassMatrix) {
  PassesAgreeWithMassMatrix("examples/fourbar.mech");
  PassesAgreeWithMassMatrix("examples/slider_crank.mech");
  PassesAgreeWithMassMatrix("examples/rolling_disk.mech");
  PassesAgreeWithMassMatrix("examples/sphere_incline.mech");
  PassesAgreeWithMassMatrix("examples/sleigh.mech");
  PassesAgreeWithMassMatrix("tests/constraints/models/rusr_fourbar.mech");
  PassesAgreeWithMassMatrix("tests/constraints/models/fourbar_torques.mech");
  PassesAgreeWithMassMatrix(kLadder, {{"N", "5"}});
}

TEST(ReducedForm, CompilerChoosesPassesForFewDegreesOfFreedom) {
  // bench/loop_solvers: by passes up to 16 degrees of freedom (the ladder of 16 loops,
  // 0.96x the mass matrix route), through M from the ladder of 20 (1.06x) on.
  rt::CompileOptions dense;
  dense.solver = rt::SolverPath::Dense;
  auto fourbar = LoadModel(kRoot + "/examples/fourbar.mech");
  auto l16 = LoadModel(kRoot + "/" + kLadder, {{"N", "16"}}, dense);
  auto l17 = LoadModel(kRoot + "/" + kLadder, {{"N", "17"}}, dense);
  ASSERT_TRUE(fourbar && fourbar->prog && l16 && l16->prog && l17 && l17->prog);
  EXPECT_TRUE(fourbar->prog->reduce_by_passes);
  EXPECT_TRUE(l16->prog->reduce_by_passes);
  EXPECT_FALSE(l17->prog->reduce_by_passes);
  EXPECT_EQ(l17->prog->dof, 17);
}

TEST(MultiplierForm, FrictionOnRedundantConstraintsKeepsTheReducedForm) {
  // The cart on two rails: its friction reads the minimum-norm share of an indeterminate
  // normal force, which only the reduced form computes; a forced --solver sparse says so.
  auto l = LoadModel(kRoot + "/tests/constraints/models/double_rail.mech");
  ASSERT_TRUE(l && l->prog);
  auto p = CompileOn(l->mech, rt::SolverPath::Sparse);
  ASSERT_TRUE(p);
  const rt::ProgramSummary s = rt::Summarize(*p);
  EXPECT_EQ(s.solver, rt::SolverPath::Dense);
  EXPECT_NE(s.solver_reason.find("--solver sparse is ignored here: Coulomb friction"), std::string::npos)
      << s.solver_reason;
}

}  // namespace
}  // namespace kanesim::test

namespace kanesim::test {
namespace {

// The automatic choice between the forms: from 60 free speeds on the multiplier form, as
// measured on the ladder of four-bars (its dependent block fills in: the reduced form is
// O(nu^3)) — except when the dependent block is banded (a chain of loops, each coupled to
// its neighbours), where the reduced form factors it in linear time and stays cheaper
// (docs/constraints.md "Reduced or multiplier form"). Wrong if the ladder leaves the
// multiplier form or the chain of 40 parallelograms (81 free speeds) takes it; and the
// reduced form the chain gets must follow its independent one-degree-of-freedom model
// (tests/support/lumped_crank.h).
TEST(AutoForm, BandedChainOfLoopsKeepsTheReducedFormLadderTakesTheMultiplierForm) {
  auto ladder = LoadModel(kRoot + "/bench/models/fourbar_ladder.mech", {{"N", "30"}});
  ASSERT_TRUE(ladder && ladder->prog);
  EXPECT_EQ(ladder->prog->nu, 90);
  EXPECT_EQ(ladder->prog->solver, rt::SolverPath::Sparse) << ladder->prog->solver_reason;

  const double a = 0.6, m_rod = 0.5, m_coupler = 1.0, g = 9.81;
  for (int n : {29, 40}) {
    SCOPED_TRACE(n);
    auto chain = LoadModel(kRoot + "/tests/stress/models/parallelogram_chain.mech", {{"N", std::to_string(n)}});
    ASSERT_TRUE(chain && chain->prog);
    const rt::Program& p = *chain->prog;
    EXPECT_EQ(p.nu, 2 * n + 1);
    EXPECT_EQ(p.solver, rt::SolverPath::Dense) << p.solver_reason;
    if (n == 40) {
      EXPECT_NE(p.solver_reason.find("banded"), std::string::npos) << p.solver_reason;
    }
    // 0.2 s from theta0 = -0.5 at 12 rad/s: rod 0 turns through the change point at 0
    // (all links collinear) to about 1.7 rad.
    sim::MemorySink rows = RunModel(p, 0.2, 0.01, 1e-10, {"rj0.q", "rj0.u"});
    ASSERT_EQ(rows.times.size(), 21u);
    std::vector<double> th, w;
    for (const auto& r : rows.rows) {
      th.push_back(r[0]);
      w.push_back(r[1]);
    }
    lumped_crank::Crank c;
    c.J = (n + 1) * m_rod * a * a / 3 + n * m_coupler * a * a;
    c.G = g * ((n + 1) * m_rod * a / 2 + n * m_coupler * a);
    EXPECT_LT(lumped_crank::MaxAngleError(c, rows.times, th, w, 1e-4), 1e-7);
  }
}

}  // namespace
}  // namespace kanesim::test
