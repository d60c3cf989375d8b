// A when clause's reinit where contacts rest (docs/events.md "Statements"): a plane contact
// whose motion the reinit sets is released like a joint on its stop (away: free flight; into
// the plane: an impact by its restitution), and a contact held through the jump is held only
// while its impulse pushes: one the impulse would pull leaves with the free jump. Before, a
// reinit in a mechanism with plane contacts was refused (K321), and a joint resting on its
// stop was held through another joint's reinit even where its stop had to pull.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "tests/compiler/compile_test_util.h"
#include "tests/support/model_texts.h"

namespace kanesim::test {
namespace {

constexpr double kG = 9.81;

// A point mass (m = 2) at rest on the floor y = 0 (restitution 1/2); `when` the clause.
std::string Ball(const std::string& when) {
  return "model Ball\n  World world(g = {0, -9.81, 0});\n  Prismatic lift(axis = {0, 1, 0});\n"
         "  Body ball(m = 2);\n  PlaneContact floor(n = {0, 1, 0}, d = 0, restitution = 0.5);\nequation\n"
         "  connect(world.frame_b, lift.frame_a);\n  connect(lift.frame_b, ball.frame_a);\n"
         "  connect(lift.frame_b, floor.frame_a);\n" + when + "end Ball;\n";
}

const sim::EventRecord* Find(const sim::SimResult& r, const std::string& kind, double after = -1) {
  for (const sim::EventRecord& e : r.stats.events)
    if (e.time > after && e.kind.rfind(kind, 0) == 0) return &e;
  return nullptr;
}

// reinit(lift.u, v) at t = 1 of the ball resting on the floor: v = 3 throws it up, and it lands
// at 1 + 2 v / g at speed -v (rebounding at v / 2); v = -2 drives it into the floor, an impact
// that leaves it at +1, landing at 1 + 2 / g. If this fails, the reinit is refused (K321), or
// the contact holds the ball down, or the impact law is not applied to the reinit's speed.
TEST(WhenContact, ReinitOfABallRestingOnThePlane) {
  for (double v : {3.0, -2.0}) {
    auto l = LoadModel(Ball("  when time > 1 then\n    reinit(lift.u, " + Num(v) + ");\n  end when;\n"), {}, {}, true);
    ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
    const double up = v > 0 ? v : -0.5 * v, land = 1 + 2 * up / kG;
    for (const IntegratorChoice& how : AllIntegrators()) {
      sim::SimResult r;
      sim::MemorySink s = RunWith(*l->prog, how, 1.8, 0.05, {"lift.q", "lift.u"}, &r, 1e-12);
      ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
      for (size_t i = 0; i < s.times.size(); ++i)
        if (s.times[i] < 1) {
          EXPECT_EQ(s.rows[i][0], 0.0) << how.name << ": resting until the reinit";
        }
      ASSERT_NE(Find(r, "fires"), nullptr);
      EXPECT_NEAR(Find(r, "fires")->time, 1.0, 1e-12) << how.name;
      if (v < 0) {
        ASSERT_NE(Find(r, "impact at the plane, speed -2 -> 1", 0.5), nullptr) << how.name;
      }
      // (after the jump's own impact, at the clause's time: 1 within the root finding's tolerance)
      const sim::EventRecord* hit = Find(r, "impact at the plane", v < 0 ? Find(r, "fires")->time : 0.5);
      ASSERT_NE(hit, nullptr) << how.name;
      EXPECT_NEAR(hit->time, land, 1e-9) << how.name << " v " << v;
      for (size_t i = 0; i < s.times.size(); ++i) {
        const double t = s.times[i] - 1;
        if (t > 1e-9 && s.times[i] < land - 1e-9) {
          EXPECT_NEAR(s.rows[i][0], up * t - kG * t * t / 2, 1e-9) << how.name << " t " << s.times[i];
        }
      }
    }
  }
}

// The ball on a slider along x above its lift: reinit(slide.u, 2) of the ball at rest on the
// floor keeps the floor's row held (it has the lift's speed, not set): the ball slides at
// x = 2 (t - 1) and stays on the floor. If this fails, a contact whose row the clause does not
// set is released (the ball would rest again at once, or fail), or the held row moves the lift.
TEST(WhenContact, AContactTheReinitDoesNotSetStaysHeld) {
  std::string text = Ball("  when time > 1 then\n    reinit(slide.u, 2);\n  end when;\n");
  text.replace(text.find("  Prismatic lift"), 0, "  Prismatic slide(axis = {1, 0, 0});\n");
  const std::string to_lift = "connect(world.frame_b, lift.frame_a)";
  text.replace(text.find(to_lift), to_lift.size(),
               "connect(world.frame_b, slide.frame_a);\n  connect(slide.frame_b, lift.frame_a)");
  auto l = LoadModel(text, {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    sim::MemorySink s = RunWith(*l->prog, how, 1.5, 0.1, {"slide.q", "lift.q", "lift.u"}, &r, 1e-12);
    ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
    EXPECT_EQ(Find(r, "leaves"), nullptr) << how.name;
    for (size_t i = 0; i < s.times.size(); ++i) {
      EXPECT_EQ(s.rows[i][1], 0.0) << how.name << " t " << s.times[i];
      EXPECT_EQ(s.rows[i][2], 0.0) << how.name << " t " << s.times[i];
      if (s.times[i] > 1 || (i > 0 && s.times[i] == s.times[i - 1])) {
        EXPECT_NEAR(s.rows[i][0], 2 * (s.times[i] - 1), 1e-10) << how.name << " t " << s.times[i];
      }
    }
  }
}

// Two rods without gravity, j2 pressed onto q_min = 0.3 by its torque -1 (at rest, held by its
// stop). reinit(j1.u, v) at 0.5: the free jump would move j2 by -c v, c = 1 + 3 L1 cos(q2) / (2 L2)
// (tests/compiler/when_events_test.cpp). v = 1 drives j2 into its stop, whose impulse pushes:
// held, u2 = 0. v = -1 pulls it off: the stop cannot pull, so j2 leaves with u2 = c. If this
// fails, a resting joint is held by a pulling impulse (u2 = 0 for v = -1, as before), or let
// go where its stop pushes.
TEST(WhenContact, AHeldStopLetsGoWhereItsImpulseWouldPull) {
  const double L1 = 1, L2 = 0.8, c = 1 + 3 * L1 * std::cos(0.3) / (2 * L2);
  for (double v : {1.0, -1.0}) {
    const std::string when = "  when time > 0.5 then\n    reinit(j1.u, " + Num(v) + ");\n  end when;\n";
    std::string text = TwoRodText("", ", q(start = 0.3), q_min = 0.3", "  j2.tau = -1;\n" + when);
    text.replace(text.find("g = {0, -9.81, 0}"), 17, "g = {0, 0, 0}");
    auto l = LoadModel(text, {}, {}, true);
    ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
    for (const IntegratorChoice& how : AllIntegrators()) {
      sim::SimResult r;
      sim::MemorySink s = RunWith(*l->prog, how, 0.6, 0.1, {"j1.u", "j2.q", "j2.u"}, &r, 1e-11);
      ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
      size_t at = 0;
      while (at + 1 < s.times.size() && s.times[at] != s.times[at + 1]) ++at;
      ASSERT_LT(at + 1, s.times.size()) << how.name << ": no event rows";
      EXPECT_EQ(s.rows[at][2], 0.0) << how.name << ": at rest on the stop before";
      EXPECT_EQ(s.rows[at + 1][0], v);
      EXPECT_NEAR(s.rows[at + 1][2], v > 0 ? 0.0 : c, 1e-10) << how.name << " v " << v;
      EXPECT_EQ(Find(r, "leaves q_min", 0.4) != nullptr, v < 0) << how.name << " v " << v;
    }
  }
}

}  // namespace
}  // namespace kanesim::test
