// When clauses (issue 41): event times located by every integrator's root finding against
// closed forms (a bouncing ball's impact times, the pendulum's elliptic-integral swing), the
// reinit of one speed of a double pendulum against the momentum balance of the other joint,
// terminate, and a condition that only touches zero (a graze).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include "sim/sensitivity.h"
#include "tests/compiler/compile_test_util.h"
#include "tests/support/model_texts.h"

namespace kanesim::test {
namespace {

constexpr double kG = 9.81;
const double kHalfPi = std::acos(0.0);
const double kW = std::sqrt(1.5 * kG);  // the rod pendulum's w^2 = 3 g / (2 L), L = 1

// A point mass on a vertical slider dropped from h; `body` the when clauses.
std::string Ball(double h, const std::string& body) {
  return "model Ball\n"
         "  World world(g = {0, -9.81, 0});\n"
         "  Prismatic p(axis = {0, 1, 0}, q(start = " + Num(h) + "));\n"
         "  Body b(m = 1, I = diagonal({1, 1, 1}));\n"
         "equation\n"
         "  connect(world.frame_b, p.frame_a);\n"
         "  connect(p.frame_b, b.frame_a);\n" + body +
         "end Ball;\n";
}

// If this fails, a when clause does not fire where its condition becomes true (the impact
// times of a ball bouncing with reinit(u, -e pre(u)): t1 = sqrt(2h/g), t_{k+1} - t_k = 2 e^k t1),
// the firing depends on the integrator or the output grid, or reinit does not set the speed.
TEST(WhenEvents, BouncingBallFiresAtTheClosedFormTimes) {
  const double h = 1.0, e = 0.8, t1 = std::sqrt(2 * h / kG);
  const double times[3] = {t1, t1 + 2 * e * t1, t1 + 2 * e * t1 + 2 * e * e * t1};
  auto l = LoadModel(Ball(h, "  when p.q < 0 then\n    reinit(p.u, -0.8 * pre(p.u));\n  end when;\n"), {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  for (double interval : {0.1, 0.07}) {
    for (const IntegratorChoice& how : AllIntegrators()) {
      sim::SimResult r;
      sim::MemorySink s = RunWith(*l->prog, how, 2.0, interval, {"p.q", "p.u"}, &r, 1e-12);
      ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
      const std::vector<size_t> at = EventRows(s);
      ASSERT_EQ(at.size(), 3u) << how.name;
      ASSERT_EQ(r.stats.events.size(), 3u) << how.name;
      for (size_t k = 0; k < 3; ++k) {
        EXPECT_NEAR(s.times[at[k]], times[k], 1e-10 * times[k]) << how.name << " interval " << interval << " impact " << k;
        EXPECT_EQ(s.rows[at[k] + 1][1], -0.8 * s.rows[at[k]][1]) << how.name;
        EXPECT_EQ(r.stats.events[k].time, s.times[at[k]]);
        ASSERT_EQ(r.stats.events[k].changes.size(), 1u);
        EXPECT_EQ(r.stats.events[k].changes[0].name, "p.u");
      }
    }
  }
}

// If this fails, a condition on a coordinate does not fire where the exact (elliptic-integral)
// motion reaches it, in some integrator. The rod pendulum released at rest at phi0 (from
// hanging down) reaches phi = -0.5 at t = (K(k) + F(psi, k)) / w, k = sin(phi0/2),
// sin(psi) = sin(0.25) / k; reinit(u, 0) stops it there, and it swings back.
TEST(WhenEvents, PendulumFiresAtTheEllipticIntegralTime) {
  const double phi0 = 1.0, phis = -0.5, k = std::sin(phi0 / 2);
  const double t1 = (std::comp_ellint_1(k) + std::ellint_1(k, std::asin(std::sin(0.25) / k))) / kW;
  const std::string text =
      PendulumText{.mods = ", q(start = " + Num(phi0 - kHalfPi) + ")",
                   .equations = "  when j1.q + pi / 2 < " + Num(phis) + " then\n    reinit(j1.u, 0);\n  end when;\n"}
          .Text();
  auto l = LoadModel(text, {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    sim::MemorySink s = RunWith(*l->prog, how, 1.5, 0.1, {"j1.q", "j1.u"}, &r, 1e-12);
    ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
    const std::vector<size_t> at = EventRows(s);
    ASSERT_EQ(at.size(), 1u) << how.name << ": at rest at -0.5 it swings back and does not cross again";
    EXPECT_NEAR(s.times[at[0]], t1, 1e-9) << how.name;
    EXPECT_EQ(s.rows[at[0] + 1][1], 0.0) << how.name;
  }
}

// A condition on a frame's position: the rod's tip x = sin(phi) passes sin(-0.5) where phi
// passes -0.5, at the same elliptic-integral time as above. If this fails, conditions on
// frame signals (docs/events.md "Relations of any signal") fire elsewhere or not at all.
TEST(WhenEvents, ConditionOnAFrameSignalFiresAtTheEllipticIntegralTime) {
  const double phi0 = 1.0, k = std::sin(phi0 / 2);
  const double t1 = (std::comp_ellint_1(k) + std::ellint_1(k, std::asin(std::sin(0.25) / k))) / kW;
  const std::string text =
      PendulumText{.mods = ", q(start = " + Num(phi0 - kHalfPi) + ")",
                   .equations = "  when rod.frame_b.r[1] < sin(-0.5) then\n    reinit(j1.u, 0);\n  end when;\n"}
          .Text();
  auto l = LoadModel(text, {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    RunWith(*l->prog, how, 1.0, 0.1, {"j1.q"}, &r, 1e-12);
    ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
    ASSERT_GE(r.stats.events.size(), 1u) << how.name;
    EXPECT_NEAR(r.stats.events[0].time, t1, 1e-9) << how.name;
  }
}

// Two rods (L1 = 1, m1 = 1; L2 = 0.8, m2 = 0.7), q2 the relative angle. reinit(j1.u, 0) is the
// impulse e1 lambda on joint 1 alone, so joint 2's generalized momentum
//   p2 = dT/du2 = m2 (L2^2/3 + L1 L2 cos(q2)/2) u1 + m2 L2^2/3 u2
// (rod 2's angular momentum about joint 2) is the same before and after:
//   u2+ = u2- + (1 + 3 L1 cos(q2) / (2 L2)) (u1- - u1+).
// If this fails, the other speed is left stale or does not follow through the mass matrix, or
// a coordinate moves at a speed jump.
TEST(WhenEvents, ReinitOfOneSpeedKeepsTheOtherJointsMomentum) {
  const double L1 = 1, L2 = 0.8;
  const std::string text = TwoRodText(", q(start = -0.3), u(start = 1.2)", ", q(start = 0.3), u(start = 0.5)",
                                      "  when time > 0.35 then\n    reinit(j1.u, 0);\n  end when;\n");
  auto l = LoadModel(text, {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    sim::MemorySink s = RunWith(*l->prog, how, 0.6, 0.1, {"j1.q", "j1.u", "j2.q", "j2.u"}, &r, 1e-11);
    ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
    const std::vector<size_t> at = EventRows(s);
    ASSERT_EQ(at.size(), 1u) << how.name;
    const std::vector<double>& a = s.rows[at[0]];
    const std::vector<double>& b = s.rows[at[0] + 1];
    EXPECT_NEAR(s.times[at[0]], 0.35, 1e-12) << how.name;
    EXPECT_EQ(b[0], a[0]);
    EXPECT_EQ(b[2], a[2]);
    EXPECT_EQ(b[1], 0.0);
    const double u2 = a[3] + (1 + 3 * L1 * std::cos(a[2]) / (2 * L2)) * (a[1] - b[1]);
    EXPECT_NEAR(b[3], u2, 1e-10 * (std::abs(a[1]) + std::abs(a[3]))) << how.name;
    EXPECT_GT(std::abs(b[3] - a[3]), 0.5) << how.name << ": the jump is large, so a stale u2 fails";
  }
}

// If this fails, terminate does not end the run at the event (rows past it written, a failure
// status, or the event time off the closed form t1 = sqrt(2h/g)).
TEST(WhenEvents, TerminateEndsTheRunAtTheEventTime) {
  const double h = 2.0, t1 = std::sqrt(2 * h / kG);
  auto l = LoadModel(Ball(h, "  when p.q < 0 then\n    terminate(\"ground\");\n  end when;\n"), {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    sim::MemorySink s = RunWith(*l->prog, how, 3.0, 0.1, {"p.q"}, &r, 1e-12);
    ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
    EXPECT_TRUE(r.stats.terminated) << how.name;
    EXPECT_EQ(r.stats.terminate_message, "ground");
    EXPECT_NEAR(r.stats.terminate_time, t1, 1e-9) << how.name;
    EXPECT_EQ(s.times.back(), r.stats.terminate_time) << how.name;
    EXPECT_EQ(s.times.size(), static_cast<size_t>(std::floor(t1 / 0.1)) + 3) << how.name << ": the rows up to t1, then its two";
  }
}

// The vector form and change(): change(b) fires where b becomes true and where it becomes
// false. A uniform motion x = t crosses 0.25 once up; `change(x > 0.25 and x < 0.5)` fires at
// 0.25 and 0.5. If this fails, change() or and/or/not indicators are wrong.
TEST(WhenEvents, ChangeFiresBothWays) {
  const std::string text =
      "model C\n"
      "  World world;\n"
      "  Prismatic p(axis = {1, 0, 0}, u(start = 1));\n"
      "  Body b(m = 1, I = diagonal({1, 1, 1}));\n"
      "equation\n"
      "  connect(world.frame_b, p.frame_a);\n"
      "  connect(p.frame_b, b.frame_a);\n"
      "  when {change(p.q > 0.25 and not p.q >= 0.5), time > 0.8} then\n    reinit(p.u, 1);\n  end when;\n"
      "end C;\n";
  auto l = LoadModel(text, {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    RunWith(*l->prog, how, 1.0, 0.1, {"p.q"}, &r, 1e-12);
    ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
    ASSERT_EQ(r.stats.events.size(), 3u) << how.name;
    EXPECT_NEAR(r.stats.events[0].time, 0.25, 1e-12) << how.name;
    EXPECT_NEAR(r.stats.events[1].time, 0.5, 1e-12) << how.name;
    EXPECT_NEAR(r.stats.events[2].time, 0.8, 1e-12) << how.name;
  }
}

// edge(b) is b: a clause on edge(p.q > 0.25) fires where p.q first exceeds 0.25, once (a
// uniform motion x = t), as the clause on the relation itself. If this fails, edge() is
// refused, fires elsewhere, or fires where b becomes false too.
TEST(WhenEvents, EdgeFiresWhereItsConditionBecomesTrue) {
  const std::string text =
      "model E\n  World world;\n  Prismatic p(axis = {1, 0, 0}, u(start = 1));\n"
      "  Body b(m = 1, I = diagonal({1, 1, 1}));\nequation\n"
      "  connect(world.frame_b, p.frame_a);\n  connect(p.frame_b, b.frame_a);\n"
      "  when edge(p.q > 0.25 and p.q < 0.5) then\n    reinit(p.u, 1);\n  end when;\nend E;\n";
  auto l = LoadModel(text, {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    RunWith(*l->prog, how, 1.0, 0.1, {"p.q"}, &r, 1e-12);
    ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
    ASSERT_EQ(r.stats.events.size(), 1u) << how.name;
    EXPECT_NEAR(r.stats.events[0].time, 0.25, 1e-12) << how.name;
  }
}

// If this fails, a reinit of a coordinate in a closed loop compiles, where the jump would
// break the loop's position constraints (K321 instead; a speed may be set: WhenLoop.*).
TEST(WhenEvents, CoordinateReinitInClosedLoopsIsRefusedWithK321) {
  std::ifstream in(kRoot + "/examples/fourbar.mech");
  std::stringstream buf;
  buf << in.rdbuf();
  std::string text = buf.str();
  ASSERT_NE(text.find("  annotation(experiment"), std::string::npos);
  text.replace(text.find("  annotation(experiment"), 0, "  when time > 1 then\n    reinit(crank_pivot.q, 0);\n  end when;\n");
  auto l = LoadModel(text, {}, {}, true);
  ASSERT_TRUE(l);
  EXPECT_FALSE(l->prog);
  EXPECT_NE(Find(l->errors, "K321", "position constraints"), nullptr) << Messages(l->errors);
}

// If this fails, --sensitivity runs a model with when clauses without their events (its
// derivatives would be those of a motion that never fires) instead of refusing it.
TEST(WhenEvents, SensitivitiesRefuseWhenClauses) {
  auto l = LoadModel(Ball(1.0, "  when p.q < 0 then\n    reinit(p.u, -pre(p.u));\n  end when;\n"), {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  sim::SimOptions o;
  o.stop_time = 1.0;
  o.interval = 0.1;
  sim::MemorySink sink;
  const sim::SimResult r = sim::SimulateSensitivities(*l->prog, {}, o, sink);
  EXPECT_EQ(r.status, sim::SimResult::Status::kUsageError);
  EXPECT_NE(r.message.find("when clauses"), std::string::npos) << r.message;
  EXPECT_TRUE(sink.rows.empty());
}

// The accumulation point a run's message names ("... at t = 4.06... (estimated"), or NaN.
double AccumulationTime(const std::string& message) {
  const size_t at = message.find("accumulation point at t = ");
  return at == std::string::npos ? NAN : std::stod(message.substr(at + 26));
}

// A ball written by hand, when p.q < 0 then reinit(p.u, -e pre(p.u)): its impacts accumulate
// at t_inf = t1 (1 + e) / (1 - e). If this fails, the run ended in a step-size underflow at
// t_inf (DOP853), or fell through the floor after a missed crossing (CVODE, IDA, ARKODE ran
// on to the stop time with the ball below the floor), instead of stopping (exit 2) there with
// a message naming the clause and t_inf, the rows before it kept.
TEST(WhenEvents, AccumulatingBouncesStopAtTheirAccumulationPoint) {
  const double h = 1.0, t1 = std::sqrt(2 * h / kG);
  for (double e : {0.8, 0.5}) {
    const double t_inf = t1 * (1 + e) / (1 - e);
    auto l = LoadModel(Ball(h, "  when p.q < 0 then\n    reinit(p.u, -" + Num(e) + " * pre(p.u));\n  end when;\n"), {},
                       {}, true);
    ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
    for (double tol : {1e-12, 1e-10})
      for (const IntegratorChoice& how : AllIntegrators()) {
        sim::SimResult r;
        sim::MemorySink s = RunWith(*l->prog, how, 2 * t_inf, 0.05, {"p.q", "p.u"}, &r, tol);
        ASSERT_EQ(r.status, sim::SimResult::Status::kNumericalFailure) << how.name << " e " << e << ": " << r.message;
        EXPECT_NE(r.message.find("when (") , std::string::npos) << r.message;
        EXPECT_NE(r.message.find("accumulate"), std::string::npos) << r.message;
        EXPECT_NE(r.message.find("PlaneContact"), std::string::npos) << r.message;
        // t_inf from the events' geometric series: to the 1e-10 relative (measured
        // <= 1.2e-11; CVODE-Adams 2e-7 before its careful restart after each event).
        // CVODE-BDF, its restarts' error held to 1e-9 of the weights (RestartWeights): each
        // flight ends about 2.4e-9 atol off, which the last flights (1e-10 s at 5e-10 m/s)
        // magnify by g/v^2 (measured 1.9e-11 / 6.0e-12 for e = 0.8 / 0.5 at 1e-12, 1.7e-10 /
        // 1.0e-10 at 1e-10; 5.6e-10 / 1.3e-10 and 5.0e-9 / 9.4e-10 at 1e-6 of the weights;
        // docs/events.md "Location and its limits").
        const double est = AccumulationTime(r.message);
        const double rel = how.kind == rt::Integrator::CvodeBdf && tol > 1e-11 ? 1e-9 : 1e-10;
        EXPECT_NEAR(est, t_inf, rel * t_inf) << how.name << " e " << e << " tol " << tol;
        // Every impact up to the last against the closed form t_{k+1} = t_k + 2 e^k t1, at
        // the tight tolerance to the 1e-10 relative (measured <= 2.2e-11, CVODE-BDF;
        // 5.4e-10 at 1e-6 of the weights, its late impacts at 2e-8 m/s).
        if (tol < 1e-11) {
          double tk = t1, ek = 1.0;
          for (const sim::EventRecord& ev : r.stats.events) {
            EXPECT_NEAR(ev.time, tk, 1e-10 * tk) << how.name << " e " << e << " impact at " << tk;
            ek *= e;
            tk += 2 * ek * t1;
          }
        }
        // Every row before it: the grid up to t_inf (and the events' pairs), none below the floor.
        ASSERT_FALSE(s.times.empty());
        EXPECT_LT(s.times.back(), t_inf) << how.name;
        EXPECT_GT(s.times.back(), t_inf - 0.05 - 1e-9) << how.name;
        for (size_t i = 0; i < s.rows.size(); ++i) EXPECT_GE(s.rows[i][0], -1e-6) << how.name << " t = " << s.times[i];
      }
  }
}

// If this fails, a clause whose events slow down or keep their pace (a ball bouncing with
// e = 1; a clock) was taken for accumulating.
TEST(WhenEvents, EventsAtAnEvenPaceDoNotAccumulate) {
  auto l = LoadModel(Ball(1.0, "  when p.q < 0 then\n    reinit(p.u, -pre(p.u));\n  end when;\n"), {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  sim::SimResult r;
  RunWith(*l->prog, AllIntegrators()[0], 10.0, 0.1, {"p.q"}, &r, 1e-10);
  EXPECT_EQ(r.status, sim::SimResult::Status::kOk) << r.message;
  EXPECT_EQ(r.stats.events.size(), 11u);  // at t1, 3 t1, ..., 21 t1 < 10 (t1 = 0.4515)
}

}  // namespace
}  // namespace kanesim::test
