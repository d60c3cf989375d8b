// The branch monitor (runtime/engine/branch_monitor.cpp, issue 20) on constructed states of the
// equal-link parallelogram (tests/stress/models/parallelogram.mech with a = b = 0.6): at
// crank angle pi all four links are in line and three assembly branches meet, the
// parallelogram (rocker angle = crank angle, coupler relative angle = -crank angle, all
// speeds equal up to sign) and the folded one where the rocker tip rests on the crank
// pivot (rocker angle pi, coupler relative angle pi, only the crank turning). Both are
// exact closed-form configurations, so the states below are on the constraints without
// any integrator: a step from the parallelogram onto the folded branch near the change
// point must be refused, and continuing on the parallelogram (also backwards) must not.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "runtime/runtime.h"
#include "runtime/program/program.h"
#include "sim/change_point_bridge.h"
#include "tests/support/load_util.h"

namespace kanesim::test {
namespace {

struct Rig {
  std::unique_ptr<Loaded> l;
  int q_crank = -1, q_coupler = -1, q_rocker = -1;
  std::vector<double> y;
  int Index(const char* joint, bool speed) const {
    for (const rt::TreeJoint& j : l->prog->joints)
      if (j.name == joint) return speed ? l->prog->nq + j.u0 : j.q0;
    ADD_FAILURE() << joint;
    return 0;
  }
  // The parallelogram at crank angle th, all links turning at w.
  const double* Parallelogram(double th, double w) {
    Set(th, -th, th, w, -w, w);
    return y.data();
  }
  // The folded branch: rocker at pi (its tip on the crank pivot), coupler folded back.
  const double* Folded(double th, double w) {
    Set(th, M_PI, M_PI, w, 0.0, 0.0);
    return y.data();
  }
  void Set(double a, double b, double c, double wa, double wb, double wc) {
    y[static_cast<size_t>(Index("crank_pivot", false))] = a;
    y[static_cast<size_t>(Index("crank_coupler", false))] = b;
    y[static_cast<size_t>(Index("rocker_pivot", false))] = c;
    y[static_cast<size_t>(Index("crank_pivot", true))] = wa;
    y[static_cast<size_t>(Index("crank_coupler", true))] = wb;
    y[static_cast<size_t>(Index("rocker_pivot", true))] = wc;
  }
};

Rig MakeRig() {
  Rig r;
  r.l = LoadModel(kRoot + "/tests/stress/models/parallelogram.mech", {{"a", "0.6"}});
  EXPECT_TRUE(r.l && r.l->prog);
  if (r.l && r.l->prog) r.y.assign(static_cast<size_t>(rt::StateSize(*r.l->prog)), 0.0);
  return r;
}

TEST(BranchMonitor, RefusesATurnOntoTheFoldedBranchAtTheChangePoint) {
  // If this fails, a solution that turns from the parallelogram onto the folded branch at
  // the change point passes unnoticed (the run would end with exit code 0 off the branch).
  Rig r = MakeRig();
  ASSERT_TRUE(r.l && r.l->prog);
  const rt::Program& p = *r.l->prog;
  auto m = rt::MakeBranchMonitor(p);
  ASSERT_TRUE(rt::BranchMonitorActive(p));
  EXPECT_EQ(rt::CheckBranch(p, *m, 1.0, r.Parallelogram(M_PI - 0.3, 11.0)), 0);
  EXPECT_EQ(rt::CheckBranch(p, *m, 1.02, r.Parallelogram(M_PI - 1e-3, 11.0)), 0) << rt::BranchMonitorError(*m);
  EXPECT_EQ(rt::CheckBranch(p, *m, 1.0201, r.Folded(M_PI - 5e-4, 19.0)), -1);
  const std::string& e = rt::BranchMonitorError(*m);
  EXPECT_NE(e.find("closed loop 'coupler_rocker' left its assembly branch"), std::string::npos) << e;
  EXPECT_NE(e.find("at time 1.0201"), std::string::npos) << e;
}

TEST(BranchMonitor, LetsTheParallelogramThroughForwardAndBack) {
  // If this fails, the monitor refuses the physical continuation: through the change point
  // at constant speed, or stopping there and turning back (the speed changes sign, the
  // line of the motion does not).
  Rig r = MakeRig();
  ASSERT_TRUE(r.l && r.l->prog);
  const rt::Program& p = *r.l->prog;
  auto m = rt::MakeBranchMonitor(p);
  const double ths[] = {M_PI - 0.3, M_PI - 1e-3, M_PI - 1e-6, M_PI + 1e-6, M_PI + 1e-3, M_PI + 0.3};
  double t = 0.0;
  for (double th : ths) EXPECT_EQ(rt::CheckBranch(p, *m, t += 0.01, r.Parallelogram(th, 11.0)), 0) << rt::BranchMonitorError(*m);
  for (double th : {M_PI + 1e-3, M_PI + 1e-5, M_PI + 1e-3, M_PI + 0.3})
    EXPECT_EQ(rt::CheckBranch(p, *m, t += 0.01, r.Parallelogram(th, th == M_PI + 1e-5 ? 1e-2 : -5.0)), 0)
        << rt::BranchMonitorError(*m);
}

// What the bridge over a change point (sim/change_point_bridge.h) reads of the loops through
// runtime/runtime.h, on exact states of the parallelogram: rho falls linearly toward the
// change point (a simple crossing: the rows' smallest singular value goes as the angle to
// it), a state on the constraints is a fixed point of the partition's projection, and the
// kinetic-metric projection of speeds that differ from the state's by a motion along the
// branch returns those speeds unchanged. If this fails, the bridge measures the wrong
// distance to a crossing or moves the states it extrapolates.
TEST(BranchMonitor, WhatTheBridgeReadsOfTheLoops) {
  Rig r = MakeRig();
  ASSERT_TRUE(r.l && r.l->prog);
  const rt::Program& p = *r.l->prog;
  auto m = rt::MakeBranchMonitor(p);
  const double rho1 = rt::SingularRatioAt(p, *m, 0.0, r.Parallelogram(M_PI - 1e-3, 11.0));
  const double rho2 = rt::SingularRatioAt(p, *m, 0.0, r.Parallelogram(M_PI - 2e-3, 11.0));
  int near_loops = 0;
  const double far = rt::SingularRatioAt(p, *m, 0.0, r.Parallelogram(M_PI - 0.3, 11.0), &near_loops);
  EXPECT_GT(far, 1e-2);
  EXPECT_EQ(near_loops, 0);
  EXPECT_LT(rho1, 1e-2);
  EXPECT_NEAR(rho2 / rho1, 2.0, 1e-2);  // linear to first order in the angle (1e-3 rad)
  rt::Workspace& ws = rt::MonitorWorkspace(*m);
  const size_t n = r.y.size();
  const std::vector<double> y(r.Parallelogram(M_PI - 0.3, 11.0), r.Parallelogram(M_PI - 0.3, 11.0) + n);
  std::vector<double> z(n);
  ASSERT_EQ(rt::ProjectByPartition(p, ws, 0.0, y.data(), z.data()), 0);
  for (size_t i = 0; i < n; ++i) EXPECT_NEAR(z[i], y[i], 1e-12) << i;
  std::vector<double> raw(y), speeds(y);
  for (size_t i = static_cast<size_t>(rt::NumQ(p)); i < n; ++i) raw[i] *= 1.01;  // along the branch
  ASSERT_EQ(rt::ProjectSpeedsInKineticMetric(p, ws, 0.0, raw.data(), speeds.data()), 0);
  for (size_t i = 0; i < n; ++i) EXPECT_NEAR(speeds[i], raw[i], 1e-9 * (1.0 + std::fabs(raw[i]))) << i;
}

// Feeds the monitor the exact motion of the lumped crank (theta'' = -(G/J) cos theta; the
// model's gravity, J and G as in change_point_bridge_test.cpp) through the change point at
// theta = pi in accepted steps of 1 ms, the speed off by dw once past it; returns the first
// non-zero check (0: none up to pi + 0.05).
int PassTheChangePoint(Rig& r, double dw, const std::function<int(double t, const double* y)>& check) {
  const double a = 0.6, J = (0.5 + 0.8) * a * a / 3.0 + 1.0 * a * a, G = 9.81 * a * ((0.5 + 0.8) / 2.0 + 1.0);
  double th = M_PI - 0.3, w = 11.0, t = 0.0;
  const auto acc = [&](double x) { return -(G / J) * std::cos(x); };
  while (th < M_PI + 0.05) {
    const int s = check(t, r.Parallelogram(th, w + (th > M_PI ? dw : 0.0)));
    if (s != 0) return s;
    for (int i = 0; i < 100; ++i) {  // classical Runge-Kutta, h = 1e-5 s
      const double h = 1e-5;
      const double k1x = w, k1v = acc(th);
      const double k2x = w + 0.5 * h * k1v, k2v = acc(th + 0.5 * h * k1x);
      const double k3x = w + 0.5 * h * k2v, k3v = acc(th + 0.5 * h * k2x);
      const double k4x = w + h * k3v, k4v = acc(th + h * k3x);
      th += h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
      w += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
      t += h;
    }
  }
  return 0;
}

TEST(BranchMonitor, ChecksAPassageTheSolverMadeByItself) {
  // If this fails, a solver stepping over a change point by itself (no bridge) with a wrong
  // speed passes unnoticed: the turn check cannot see a speed off by 1e-6 rad/s (measured:
  // ARKODE at rtol 1e-12 ended 3.6e-5 rad off the lumped crank that way). The exact motion
  // passes the check; 1e-6 rad/s off (8e4 tolerance units at rtol 1e-12) fails the step and
  // hands the integrator the bridge over the crossing.
  Rig r = MakeRig();
  ASSERT_TRUE(r.l && r.l->prog);
  const rt::Program& p = *r.l->prog;
  auto exact = sim::MakeChangePointBridge(p);
  ASSERT_TRUE(exact);
  sim::EnableEarlyBridge(*exact, 1e-12, 1e-12);
  EXPECT_EQ(PassTheChangePoint(r, 0.0, [&](double t, const double* y) { return sim::CheckStep(p, *exact, t, y); }), 0)
      << sim::BridgeError(*exact);
  auto off = sim::MakeChangePointBridge(p);
  sim::EnableEarlyBridge(*off, 1e-12, 1e-12);
  ASSERT_EQ(PassTheChangePoint(r, 1e-6, [&](double t, const double* y) { return sim::CheckStep(p, *off, t, y); }), -1);
  const std::string& e = sim::BridgeError(*off);
  EXPECT_NE(e.find("closed loop 'coupler_rocker' at a singular configuration"), std::string::npos) << e;
  EXPECT_NE(e.find("passed the change point"), std::string::npos) << e;
  double t_from = 0.0, t_b = 0.0;
  std::vector<double> yb(r.y.size());
  ASSERT_EQ(sim::BridgeChangePoint(p, *off, 1e-12, 1e-12, &t_from, &t_b, yb.data()), 0) << off->bridge_refused;
  EXPECT_LT(t_from, t_b);
}

}  // namespace
}  // namespace kanesim::test
