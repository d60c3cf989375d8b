// The two solution paths against each other, and Kane's udot against Newton-Euler:
// body accelerations rebuilt from udot must balance applied, inertia and joint reaction
// wrenches, and the reactions must do no work along the tangent directions.
#include <gtest/gtest.h>

#include <random>

#include "compiler/compiler.h"
#include "runtime/kinematics/kinematics.h"
#include "runtime/program/program.h"
#include "tests/support/builders.h"
#include "tests/support/random_state.h"

namespace kanesim {
namespace {

// Both paths solve the same equations in double precision; normwise relative difference
// is round-off of two factorizations with cond(M) ~ 1e2..1e4 here (observed <= 3e-14).
constexpr double kPathsAgreeTol = 1e-12;
// Newton-Euler balance: round-off of sums of O(10) terms.
constexpr double kBalanceTol = 1e-10;

rt::CompileResult CompileWith(const flat::Mechanism& m, rt::SolverPath path) {
  rt::CompileOptions o;
  o.solver = path;
  return rt::Compile(m, o);
}

void ExpectPathsAgree(const flat::Mechanism& m, std::mt19937& rng, int trials) {
  auto d = CompileWith(m, rt::SolverPath::Dense);
  auto s = CompileWith(m, rt::SolverPath::Sparse);
  ASSERT_TRUE(d.errors.empty()) << d.errors[0].message;
  ASSERT_TRUE(s.errors.empty()) << s.errors[0].message;
  auto wd = rt::MakeWorkspace(*d.program);
  auto wsp = rt::MakeWorkspace(*s.program);
  const int n = rt::StateSize(*d.program);
  for (int t = 0; t < trials; ++t) {
    Eigen::VectorXd y = test::RandomState(*d.program, rng), yd(n), ys(n);
    ASSERT_EQ(rt::Derivative(*d.program, *wd, 0.1 * t, y.data(), yd.data()), 0) << rt::ErrorMessage(*wd);
    ASSERT_EQ(rt::Derivative(*s.program, *wsp, 0.1 * t, y.data(), ys.data()), 0) << rt::ErrorMessage(*wsp);
    const double err = (yd - ys).norm() / yd.norm();
    EXPECT_LT(err, kPathsAgreeTol) << "trial " << t;
  }
}

TEST(KanePaths, DenseAndSparseAgreeOnMixedTrees) {
  // If this fails, one of the two solution paths (dense tau^T M tau or the sparse
  // K-vector system) is wrong for some joint type, an inverted joint or a welded body.
  std::mt19937 rng(31337);
  for (int trees = 0; trees < 4; ++trees) ExpectPathsAgree(test::RandomTree(rng, {10, true, true, true}), rng, 4);
}

TEST(KanePaths, DenseAndSparseAgreeOnChain) {
  // If this fails, the paths disagree on examples/chain.mech.
  std::mt19937 rng(4);
  ExpectPathsAgree(test::Chain(12), rng, 3);
}

TEST(KanePaths, NewtonEulerBalanceWithReactionsInComplement) {
  // If this fails, Kane's udot does not satisfy Newton-Euler for every body with the
  // joint reactions the sparse path reports, or those reactions do work along the
  // tangent directions (Lesser eq. 27: they must lie in the complement).
  std::mt19937 rng(99);
  auto r = CompileWith(test::RandomTree(rng, {9, true, true, true}), rt::SolverPath::Sparse);
  ASSERT_TRUE(r.errors.empty());
  const rt::Program& p = *r.program;
  auto ws = rt::MakeWorkspace(p);
  Eigen::VectorXd y = test::RandomState(p, rng), ydot(y.size());
  ASSERT_EQ(rt::Derivative(p, *ws, 0.0, y.data(), ydot.data()), 0) << rt::ErrorMessage(*ws);
  const size_t K = p.bodies.size();
  for (size_t L = 0; L < K; ++L) {
    // A_L = A_bias_L + sum_r tau_{L,r} udot_r.
    rt::Vec6 A;
    A.head<3>() = ws->a_bias_cm[L];
    A.tail<3>() = ws->alpha_bias[L];
    for (int s : rt::PathSpeeds(p, static_cast<int>(L))) A += rt::TangentColumn(p, *ws, static_cast<int>(L), s) * ws->udot[s];
    // Wrench balance at c_L: applied + parent reaction - children reactions - inertia.
    const rt::Vec3 c = ws->p_WBcm[L];
    auto at_c = [&](const rt::Vec6& w, const rt::Vec3& o) {
      rt::Vec6 x;
      x.head<3>() = w.head<3>();
      x.tail<3>() = w.tail<3>() + (o - c).cross(w.head<3>());
      return x;
    };
    rt::Vec6 sum;
    sum.head<3>() = ws->F_W[L] - p.bodies[L].mass * A.head<3>();
    sum.tail<3>() = ws->T_W[L] - ws->I_W[L] * A.tail<3>() - ws->w_WB[L].cross(ws->I_W[L] * ws->w_WB[L]);
    sum += at_c(ws->lambda_W[L], ws->p_WB[L]);
    for (size_t C = 0; C < K; ++C)
      if (p.joints[C].parent == static_cast<int>(L)) sum -= at_c(ws->lambda_W[C], ws->p_WB[C]);
    EXPECT_LT(sum.cwiseAbs().maxCoeff(), kBalanceTol) << "body " << p.bodies[L].name;
    // The reaction's power along each free speed of its joint is the joint force Q_r.
    const rt::TreeJoint& j = p.joints[L];
    for (int k = 0; k < j.nu; ++k)
      EXPECT_NEAR(ws->H_W.col(j.u0 + k).dot(ws->lambda_W[L]), ws->Q[j.u0 + k], kBalanceTol) << j.name;
  }
}

}  // namespace
}  // namespace kanesim
