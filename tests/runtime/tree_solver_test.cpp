// The recursive path (runtime/kane/kane_tree.cpp) against the dense path on random trees of
// every joint type, with prescribed coordinates and every force element; its planar form
// against the dense path and the spatial recursion on random planar trees; energy of a
// chain integrated on it; and its right-hand side allocates nothing. Its own binary,
// because it replaces the global operator new to count allocations.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <new>
#include <random>

#include "compiler/compiler.h"
#include "runtime/kane/kane.h"
#include "runtime/kane/kane_tree.h"
#include "runtime/program/program.h"
#include "sim/simulate.h"
#include "tests/support/alloc_counter.h"
#include "tests/support/alloc_free_check.h"
#include "tests/support/builders.h"
#include "tests/support/random_state.h"

namespace kanesim {
namespace {

using flat::Op;

// Both paths solve the same equations in double precision: Cholesky of M against the
// leaf-to-root Schur complements of the same M, cond(M) ~ 1e2..1e4 for these trees;
// normwise relative difference of udot observed <= 1e-14.
constexpr double kPathsAgreeTol = 1e-12;
// Backward error ||M udot - f|| / (||M|| ||udot||) of a stable solve: a few eps
// (observed 1.5e-17 .. 5e-17 on the 60-chain); a wrong term is O(1e-3) or more.
constexpr double kBackwardErrorTol = 1e-14;
// Energy drift of a conservative chain integrated at rtol = atol = 1e-10 over 2 s,
// relative to the largest kinetic energy: the integrator's global error (observed ~1e-9);
// a wrong acceleration (a sign, a missing term) gives O(1).
constexpr double kEnergyDriftTol = 1e-6;

rt::CompileResult CompileWith(const flat::Mechanism& m, rt::SolverPath path) {
  rt::CompileOptions o;
  o.solver = path;
  return rt::Compile(m, o);
}

// Normwise relative difference of the free udot of the two paths, at `trials` random states.
void ExpectRecursiveAgreesWithDense(const flat::Mechanism& m, std::mt19937& rng, int trials) {
  auto d = CompileWith(m, rt::SolverPath::Dense);
  auto r = CompileWith(m, rt::SolverPath::Recursive);
  ASSERT_TRUE(d.errors.empty()) << d.errors[0].message;
  ASSERT_TRUE(r.errors.empty()) << r.errors[0].message;
  ASSERT_EQ(rt::Summarize(*r.program).solver, rt::SolverPath::Recursive);
  auto wd = rt::MakeWorkspace(*d.program);
  auto wr = rt::MakeWorkspace(*r.program);
  const int nq = rt::NumQ(*d.program), nu = rt::NumU(*d.program);
  ASSERT_GT(nu, 0);
  for (int t = 0; t < trials; ++t) {
    Eigen::VectorXd y = test::RandomState(*d.program, rng), yd(nq + nu), yr(nq + nu);
    ASSERT_EQ(rt::Derivative(*d.program, *wd, 0.1 * t, y.data(), yd.data()), 0) << rt::ErrorMessage(*wd);
    ASSERT_EQ(rt::Derivative(*r.program, *wr, 0.1 * t, y.data(), yr.data()), 0) << rt::ErrorMessage(*wr);
    const double err = (yd.tail(nu) - yr.tail(nu)).norm() / yd.tail(nu).norm();
    EXPECT_LT(err, kPathsAgreeTol) << "trial " << t;
    EXPECT_TRUE(yd.head(nq) == yr.head(nq)) << "qdot does not depend on the path";
  }
}

// A scene with every force element and prescribed coordinates that leave a joint with
// none, some (not the first) or all of its speeds free. RandomTree's joint i + 1 has type
// i % 7: j1 revolute, j2 prismatic, j3 cylindrical, j4 universal, j5 spherical, j6 planar,
// j7 free, j8 revolute, j9 prismatic, j10 cylindrical.
flat::Mechanism DrivenTree(std::mt19937& rng, bool friction) {
  auto m = test::RandomTree(rng, {10, true, true, true});
  auto& e = m.exprs;
  auto sin_t = [&](double w) { return e.Unary(Op::Sin, e.Binary(Op::Mul, e.Constant(w), e.Time())); };
  m.joints[0].prescribed[0] = sin_t(2.0);                          // j1: no free speed
  m.joints[2].prescribed[0] = sin_t(1.5);                          // j3: its second speed free
  m.joints[3].prescribed[0] = sin_t(0.7);                          // j4: both prescribed
  m.joints[3].prescribed[1] = e.Binary(Op::Mul, e.Constant(0.3), e.Time());
  m.joints[5].prescribed[1] = sin_t(0.9);                          // j6: speeds 1 and 3 free
  m.joints[6].tau[4] = e.Constant(0.4);  // a torque on the free joint
  test::AddBusyForces(m, -0.2);
  if (friction) {
    m.joints[7].friction_mu = e.Constant(0.3);   // j8 revolute
    m.joints[7].friction_radius = e.Constant(0.05);
    m.joints[8].friction_mu = e.Constant(0.2);   // j9 prismatic
    m.joints[8].friction_v = e.Constant(0.01);
  }
  return m;
}

TEST(TreeSolver, AgreesWithDenseOnMixedTrees) {
  // If this fails, the recursive elimination is wrong for some joint type (1..6 free
  // speeds), an inverted joint, a welded body or a branching tree.
  std::mt19937 rng(2024);
  for (int trees = 0; trees < 4; ++trees)
    ExpectRecursiveAgreesWithDense(test::RandomTree(rng, {10, true, true, true}), rng, 4);
}

TEST(TreeSolver, AgreesWithDenseOnEveryRotationCoordinate) {
  // If this fails, a free or spherical joint with quaternion, Cardan or Euler
  // coordinates (21 bodies: j7, j14, j21 free with each; j5, j12, j19 spherical) is
  // solved wrongly.
  std::mt19937 rng(7);
  ExpectRecursiveAgreesWithDense(test::RandomTree(rng, {21, true, true, false}), rng, 4);
}

TEST(TreeSolver, AgreesWithDenseWithPrescribedCoordinatesAndForces) {
  // If this fails, joints whose speeds are partly prescribed (free columns gathered out
  // of order), joint forces, springs or wrenches enter the recursion wrongly.
  std::mt19937 rng(11);
  ExpectRecursiveAgreesWithDense(DrivenTree(rng, false), rng, 6);
}

TEST(TreeSolver, AgreesWithDenseWithCoulombFriction) {
  // If this fails, the friction iteration (which re-solves with new joint forces and
  // reads body accelerations) does not work on the recursive path.
  std::mt19937 rng(12);
  ExpectRecursiveAgreesWithDense(DrivenTree(rng, true), rng, 4);
}

// A tilted plane: its normal is no coordinate axis, so e1, e2 and every projection count.
const Eigen::Vector3d kTiltedNormal = Eigen::Vector3d(0.3, -0.5, 0.8).normalized();

bool Planar(const rt::CompileResult& r) { return r.program->tree && r.program->tree->planar; }

TEST(TreeSolver, PlanarTreesAreRecognised) {
  // If this fails, the planar recursion is taken for a tree that moves out of its plane
  // (axes alternating z, y; one axis tilted by 1e-6 rad; a prismatic joint), or refused
  // for one that cannot (parallel axes with flipped signs, several roots, a tilted plane).
  std::mt19937 rng(31);
  auto compile = [](const flat::Mechanism& m) { return CompileWith(m, rt::SolverPath::Recursive); };
  EXPECT_TRUE(Planar(compile(test::RandomPlanarTree(rng, 9, Eigen::Vector3d::UnitZ()))));
  EXPECT_TRUE(Planar(compile(test::RandomPlanarTree(rng, 9, kTiltedNormal))));
  EXPECT_TRUE(Planar(compile(test::Pendulum())));
  EXPECT_FALSE(Planar(compile(test::RandomPlanarTree(rng, 9, kTiltedNormal, 1e-6))));
  EXPECT_FALSE(Planar(compile(test::Chain(4))));
  EXPECT_FALSE(Planar(compile(test::RandomTree(rng, {8, true, true, true}))));
  const auto r = compile(test::RandomPlanarTree(rng, 5, Eigen::Vector3d::UnitY()));
  EXPECT_NE(r.program->solver_reason.find("planar"), std::string::npos) << r.program->solver_reason;
}

TEST(TreeSolver, PlanarAgreesWithDenseAndSpatial) {
  // If this fails, the 3x3 recursion of planar trees is wrong: a projection onto the
  // plane, a sign of an axis flipped against the normal, a branch's share, a root other
  // than the first, the welded body, a force element whose out-of-plane part must drop out.
  std::mt19937 rng(41);
  for (const Eigen::Vector3d& n : {Eigen::Vector3d(Eigen::Vector3d::UnitZ()), kTiltedNormal}) {
    for (int trees = 0; trees < 3; ++trees) {
      auto m = test::RandomPlanarTree(rng, 9, n);
      test::AddBusyForces(m, 0.3);
      ExpectRecursiveAgreesWithDense(m, rng, 4);
      // The same state on the spatial recursion: the same udot to rounding.
      auto r = CompileWith(m, rt::SolverPath::Recursive);
      ASSERT_TRUE(Planar(r));
      const rt::Program& p = *r.program;
      auto ws = rt::MakeWorkspace(p);
      Eigen::VectorXd y = test::RandomState(p, rng), yd(rt::StateSize(p));
      ASSERT_EQ(rt::Derivative(p, *ws, 0.2, y.data(), yd.data()), 0) << rt::ErrorMessage(*ws);
      const Eigen::VectorXd planar = ws->udot;
      ASSERT_EQ(rt::SolveTreeSpatial(p, *ws), 0);
      EXPECT_LT((ws->udot - planar).norm() / planar.norm(), kPathsAgreeTol);
    }
  }
}

TEST(TreeSolver, PlanarChainWithoutMassIsSingular) {
  // If this fails, a link without inertia about its joint on the planar recursion gives
  // garbage instead of the fatal status of the other paths. (A link with no mass at all is
  // K309 at compile time: compile/massless.cpp; a point mass on its joint's axis is not.)
  std::mt19937 rng(43);
  auto mech = test::RandomPlanarTree(rng, 4, Eigen::Vector3d::UnitZ());
  // b4: a leaf (parents come earlier), nothing welded on; its joint's origin is its frame's
  for (auto& e : mech.bodies[3].inertia) e = mech.exprs.Constant(0.0);
  for (auto& e : mech.bodies[3].r_cm) e = mech.exprs.Constant(0.0);
  auto r = CompileWith(mech, rt::SolverPath::Recursive);
  ASSERT_TRUE(r.errors.empty()) << r.errors[0].message;
  ASSERT_TRUE(Planar(r));
  auto ws = rt::MakeWorkspace(*r.program);
  Eigen::VectorXd y = test::RandomState(*r.program, rng), yd(y.size());
  EXPECT_LT(rt::Derivative(*r.program, *ws, 0.0, y.data(), yd.data()), 0);
  EXPECT_NE(rt::ErrorMessage(*ws).find("singular mass matrix"), std::string::npos) << rt::ErrorMessage(*ws);
}

TEST(TreeSolver, SolvesLongChainToWorkingPrecision) {
  // If this fails, the recursion loses accuracy down a chain of 60 revolute joints
  // (examples/chain.mech, the case the benchmark measures). cond(M) ~ 1e6 here, so two
  // correct solvers may differ by ~1e-12: the check is the backward error of udot in
  // M udot = f, with M and f assembled by the dense path.
  std::mt19937 rng(5);
  const auto m = test::Chain(60);
  auto d = CompileWith(m, rt::SolverPath::Dense);
  auto r = CompileWith(m, rt::SolverPath::Recursive);
  ASSERT_TRUE(d.errors.empty() && r.errors.empty());
  auto wd = rt::MakeWorkspace(*d.program);
  auto wr = rt::MakeWorkspace(*r.program);
  const int nq = rt::NumQ(*d.program), nu = rt::NumU(*d.program);
  for (int t = 0; t < 3; ++t) {
    Eigen::VectorXd y = test::RandomState(*d.program, rng), yd(nq + nu), yr(nq + nu);
    ASSERT_EQ(rt::Derivative(*d.program, *wd, 0.0, y.data(), yd.data()), 0);
    ASSERT_EQ(rt::Derivative(*r.program, *wr, 0.0, y.data(), yr.data()), 0);
    rt::AssembleDense(*d.program, *wd);  // M and f at y (the solve overwrote f)
    const Eigen::MatrixXd M = wd->M.selfadjointView<Eigen::Lower>();
    const Eigen::VectorXd x = yr.tail(nu);
    EXPECT_LT((M * x - wd->f).norm() / (M.norm() * x.norm()), kBackwardErrorTol) << "trial " << t;
  }
}

TEST(TreeSolver, SingularMassMatrixIsFatal) {
  // If this fails, a joint that moves nothing with inertia about it (a point mass on its
  // axis; a massless leaf is K309 at compile time) yields garbage or infinite
  // accelerations instead of a fatal status.
  std::mt19937 rng(3);
  auto mech = test::Chain(3);
  for (auto& e : mech.bodies[2].inertia) e = mech.exprs.Constant(0.0);
  for (auto& e : mech.bodies[2].r_cm) e = mech.exprs.Constant(0.0);
  auto r = CompileWith(mech, rt::SolverPath::Recursive);
  ASSERT_TRUE(r.errors.empty());
  auto ws = rt::MakeWorkspace(*r.program);
  Eigen::VectorXd y = test::RandomState(*r.program, rng), yd(y.size());
  EXPECT_LT(rt::Derivative(*r.program, *ws, 0.0, y.data(), yd.data()), 0);
  EXPECT_NE(rt::ErrorMessage(*ws).find("singular mass matrix"), std::string::npos) << rt::ErrorMessage(*ws);
}

TEST(TreeSolver, ChainConservesEnergy) {
  // If this fails, the accelerations of the recursive path are not those of the
  // conservative system (a chain under gravity): kinetic + potential energy drifts.
  auto r = CompileWith(test::Chain(8), rt::SolverPath::Recursive);
  ASSERT_TRUE(r.errors.empty());
  sim::SimOptions opt;
  opt.stop_time = 2.0;
  opt.interval = 0.01;
  opt.rtol = opt.atol = 1e-10;
  opt.integrator = rt::Integrator::CvodeAdams;
  opt.signals = {"kinetic_energy", "potential_energy"};
  sim::MemorySink sink;
  sim::SimResult res = sim::Simulate(*r.program, opt, sink);
  ASSERT_EQ(res.status, sim::SimResult::Status::kOk) << res.message;
  ASSERT_GT(sink.rows.size(), 100u);
  const double E0 = sink.rows[0][0] + sink.rows[0][1];
  double drift = 0.0, kmax = 0.0;
  for (const auto& row : sink.rows) {
    drift = std::max(drift, std::fabs(row[0] + row[1] - E0));
    kmax = std::max(kmax, row[0]);
  }
  ASSERT_GT(kmax, 1.0) << "the chain must actually swing";
  EXPECT_LT(drift / kmax, kEnergyDriftTol);
}

TEST(TreeSolver, DerivativeAllocatesNothing) {
  // If this fails, the recursive right-hand side (or the signals after it) allocates:
  // a dynamic-size temporary in the recursion, or a workspace array resized per call.
  std::mt19937 rng(2);
  for (const flat::Mechanism& m : {DrivenTree(rng, true), test::Chain(50), test::RandomPlanarTree(rng, 20, kTiltedNormal)}) {
    test::ExpectNoAllocation(m, rt::SolverPath::Recursive, rng);
  }
}

TEST(TreeSolver, AllocationCounterSeesAllocations) {
  // If this fails, the counter is not wired and the test above proves nothing.
  const long before = g_allocations.load();
  auto* v = new std::vector<int>(100);
  delete v;
  EXPECT_GT(g_allocations.load() - before, 0);
}

}  // namespace
}  // namespace kanesim
