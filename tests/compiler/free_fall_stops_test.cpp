// End stops on a floating mechanism in free fall (issue 41): every reaction is zero in exact
// arithmetic, so the sign the run computes is round-off (and the tolerance's error of the
// state, amplified by a stiff friction law). Leaving on that sign made a joint leave and strike
// its stop again every step (Talos --floating: about 16 000 events per second). A resting
// joint leaves only where its reaction pulls beyond that scale, and a touch slower than the
// tolerance's reach is no impact.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "tests/compiler/compile_test_util.h"

namespace kanesim::test {
namespace {

// A floating base (offset centre of mass) with two links: j1 starts on its q_min, j2 on its
// q_max, both from rest; by default each joint has damping and URDF's regularized friction
// (stiff at rest).
std::string FreeFall(const std::string& j1_torque, const std::string& j2_torque = "-(0.1 * j2.u + 0.5 * tanh(j2.u / 0.001))") {
  return "model FreeFall\n"
         "  World world(g = {0, -9.81, 0});\n"
         "  FreeMotion free;\n"
         "  Body base(m = 3, r_CM = {0.1, 0.05, 0.02}, I = diagonal({0.1, 0.2, 0.15}));\n"
         "  Revolute j1(axis = {0, 0, 1}, q(start = -0.3), q_min = -0.3, q_max = 1);\n"
         "  Rod rod1(L = 0.7, m = 1.2);\n"
         "  Revolute j2(axis = {0, 1, 0}, q(start = 0.4), q_min = -1, q_max = 0.4);\n"
         "  Rod rod2(L = 0.3, m = 0.05);\n"
         "equation\n"
         "  connect(world.frame_b, free.frame_a);\n"
         "  connect(free.frame_b, base.frame_a);\n"
         "  connect(free.frame_b, j1.frame_a);\n"
         "  connect(j1.frame_b, rod1.frame_a);\n"
         "  connect(rod1.frame_b, j2.frame_a);\n"
         "  connect(j2.frame_b, rod2.frame_a);\n"
         "  j1.tau = " + j1_torque + ";\n"
         "  j2.tau = " + j2_torque + ";\n"
         "end FreeFall;\n";
}

// Released from rest in free fall, nothing moves relative to the base: both joints rest on
// their stops for the whole run. If this fails, a stop whose reaction is zero leaves on its
// round-off sign (thousands of leave/strike events, the angle drifting off the stop).
TEST(FreeFallStops, JointsOnTheirStopsStayThere) {
  auto l = LoadModel(FreeFall("-(0.1 * j1.u + 0.5 * tanh(j1.u / 0.001))"), {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  for (const IntegratorChoice& how : AllIntegrators()) {
    for (double tol : {1e-6, 1e-10}) {
      sim::SimResult r;
      sim::MemorySink s = RunWith(*l->prog, how, 1.0, 0.01, {"j1.q", "j1.u", "j2.q", "j2.u"}, &r, tol);
      ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
      EXPECT_EQ(r.stats.events.size(), 2u) << how.name << " " << tol;  // j1, j2: rests on, at t = 0
      for (const sim::EventRecord& ev : r.stats.events) {
        EXPECT_EQ(ev.time, 0.0) << how.name << " " << tol << ": " << ev.element << " " << ev.kind;
        EXPECT_EQ(ev.kind.rfind("rests on", 0), 0u) << how.name << " " << tol << ": " << ev.kind;
      }
      for (size_t i = 0; i < s.rows.size(); ++i) {
        ASSERT_EQ(s.rows[i][0], -0.3) << how.name << " " << tol << " t = " << s.times[i];
        ASSERT_EQ(s.rows[i][1], 0.0) << how.name << " " << tol << " t = " << s.times[i];
        ASSERT_EQ(s.rows[i][2], 0.4) << how.name << " " << tol << " t = " << s.times[i];
        ASSERT_EQ(s.rows[i][3], 0.0) << how.name << " " << tol << " t = " << s.times[i];
      }
    }
  }
}

// The same with j1 driven by tau = 2 (t - 0.3): in free fall the stop holds the rigid motion
// with the reaction lambda = -tau (the internal torques cancel in the base's equations and the
// gravity terms cancel in the joint's), pushing before t = 0.3 and pulling after: j1 leaves
// its stop at t = 0.3 exactly. If this fails, the hysteresis on leaving delays (or advances) a
// genuine leave beyond the tolerance's reach, or the joint never leaves.
TEST(FreeFallStops, LeavesWhereTheDrivingTorquePullsItOff) {
  auto l = LoadModel(FreeFall("2 * (time - 0.3)", "-0.1 * j2.u"), {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    sim::MemorySink s = RunWith(*l->prog, how, 0.6, 0.01, {"j1.q", "j1.u"}, &r, 1e-10);
    ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
    double t_leave = -1.0;
    int leaves = 0;
    for (const sim::EventRecord& ev : r.stats.events)
      if (ev.element == "j1" && ev.kind == "leaves q_min") t_leave = ev.time, ++leaves;
    EXPECT_EQ(leaves, 1) << how.name;
    EXPECT_NEAR(t_leave, 0.3, 1e-8) << how.name;
    EXPECT_LE(r.stats.events.size(), 4u) << how.name;
    for (size_t i = 0; i < s.rows.size(); ++i) {
      if (s.times[i] < 0.3) {
        ASSERT_EQ(s.rows[i][0], -0.3) << how.name << " t = " << s.times[i];
      }
    }
    EXPECT_GT(s.rows.back()[0], -0.3 + 1e-3) << how.name << ": it left the stop";
  }
}

}  // namespace
}  // namespace kanesim::test
