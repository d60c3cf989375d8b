// A rolling contact in a speed jump (issue 41, docs/events.md "Rolling contacts in a jump"):
// the jump's impulse carries an impulsive normal force at the contact, which no plane can
// exert as a pull. A sphere rolling on the floor (n = y) carries a point mass on a vertical
// slider through its centre; a reinit of the slider's speed u_s by du_s acts along the
// vertical through the contact point, so (hand balance, the sphere's centre held at v_y = 0)
// the hammer takes the impulse m2 du_s and the sphere -m2 du_s, which the floor must cancel:
// P_N = m2 du_s. Thrown up (du_s > 0) the floor pushes and the sphere rolls on unchanged
// (no horizontal impulse, no moment about the contact: v_x and w_z keep their values);
// thrown down (du_s < 0) the floor would have to pull: the run stops there (exit 2).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "tests/compiler/compile_test_util.h"

namespace kanesim::test {
namespace {

constexpr double kM2 = 0.5, kG = 9.81, kT = 0.05;  // hammer's mass, gravity, the reinit's time

// The sphere and hammer; `slide` the Prismatic's extra parameters, `when` its when clause.
std::string Hammer(const std::string& slide, const std::string& when) {
  // The centre C on two slides (it does not turn), the ball on a Spherical joint at C, the
  // hammer on C's vertical slide: the slide's axis stays vertical while the ball rolls.
  return "model Hammer\n"
         "  parameter Real r(unit = \"m\") = 0.1;\n"
         "  World world(g = {0, -9.81, 0});\n"
         "  Prismatic px(axis = {1, 0, 0}, u(start = 0.4));\n"
         "  Prismatic py(axis = {0, 1, 0}, q(start = r));\n"
         "  Spherical turn(u(start = {0, 0, -4}));\n"
         "  Sphere ball(radius = r, m = 2);\n"
         "  RollingSphere contact(radius = r, n = {0, 1, 0}, p = {0, 0, 0});\n"
         "  Prismatic slide(axis = {0, 1, 0}" + slide + ");\n"
         "  Body hammer(m = " + Num(kM2) + ");\n"
         "equation\n"
         "  connect(world.frame_b, px.frame_a);\n"
         "  connect(px.frame_b, py.frame_a);\n"
         "  connect(py.frame_b, turn.frame_a);\n"
         "  connect(turn.frame_b, ball.frame_a);\n"
         "  connect(ball.frame_a, contact.frame_a);\n"
         "  connect(py.frame_b, slide.frame_a);\n"
         "  connect(slide.frame_b, hammer.frame_a);\n" +
         when + "end Hammer;\n";
}
std::string Hammer(double target) {
  return Hammer("", "  when time > " + Num(kT) + " then\n    reinit(slide.u, " + Num(target) + ");\n  end when;\n");
}

double After(const sim::SimResult& r, const std::string& name) {
  for (const sim::EventChange& c : r.stats.events.at(0).changes)
    if (c.name == name) return c.after;
  return NAN;  // not changed by the jump
}

// If this fails, the hammer thrown up (P_N = m2 (1 + g t) > 0: the floor pushes) was refused,
// or its impulse leaked into the sphere's rolling, which the hand balance leaves unchanged.
TEST(WhenPull, HammerThrownUpPushesTheFloorAndTheSphereRollsOn) {
  auto l = LoadModel(Hammer(1.0), {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  sim::SimResult r;
  RunWith(*l->prog, AllIntegrators()[0], 0.1, 0.01, {"px.u", "turn.u[3]", "slide.u"}, &r, 1e-10);
  ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << r.message;
  ASSERT_EQ(r.stats.events.size(), 1u);
  EXPECT_NEAR(r.stats.events[0].time, kT, 1e-8);
  EXPECT_EQ(After(r, "slide.u"), 1.0);
  const double v = After(r, "px.u"), w = After(r, "turn.u[3]");
  if (!std::isnan(v)) {  // unchanged (a change would be logged)
    EXPECT_NEAR(v, 0.4, 1e-10);
  }
  if (!std::isnan(w)) {
    EXPECT_NEAR(w, -4.0, 1e-9);
  }
}

// If this fails, the hammer thrown down (P_N = m2 (-1 + g t) < 0) left the sphere held to the
// floor by a pull instead of stopping at the event, or the message lost the contact or time.
TEST(WhenPull, HammerThrownDownWouldPullTheFloorAndStopsTheRun) {
  auto l = LoadModel(Hammer(-1.0), {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    const sim::MemorySink s = RunWith(*l->prog, how, 0.1, 0.01, {"slide.u"}, &r, 1e-10);
    EXPECT_EQ(r.status, sim::SimResult::Status::kNumericalFailure) << how.name << ": " << r.message;
    EXPECT_NE(r.message.find("contact 'contact'"), std::string::npos) << how.name << ": " << r.message;
    EXPECT_NE(r.message.find("tensile"), std::string::npos) << how.name << ": " << r.message;
    // The impulse named: m2 (-1 - (-g t)), the hammer free-falling before the event.
    EXPECT_NE(r.message.find(Num(kM2 * (-1.0 + kG * kT)).substr(0, 6)), std::string::npos) << r.message;
    EXPECT_NEAR(r.fail_time, kT, 1e-8) << how.name;
    ASSERT_FALSE(s.times.empty()) << how.name;  // the rows before it kept
    EXPECT_NEAR(s.times.back(), kT, 1e-8) << how.name;
  }
}

// If this fails, an end stop's impact that throws the sphere up (the hammer thrown up at
// u_s = 3 hits q_max = 0.05 at v = sqrt(9 - 2 g 0.05), t = (3 - v) / g, and rebounds at
// -e v: P_N = -m2 (1 + e) v < 0) left the sphere held to the floor by a pull.
TEST(WhenPull, StopImpactThrowingTheSphereUpStopsTheRun) {
  auto l = LoadModel(Hammer(", q_max = 0.05, restitution = 0.5, u(start = 3)", ""), {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  const double v = std::sqrt(9.0 - 2.0 * kG * 0.05), t = (3.0 - v) / kG;
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    const sim::MemorySink s = RunWith(*l->prog, how, 0.1, 0.01, {"slide.u"}, &r, 1e-10);
    EXPECT_EQ(r.status, sim::SimResult::Status::kNumericalFailure) << how.name << ": " << r.message;
    EXPECT_NE(r.message.find("contact 'contact'"), std::string::npos) << how.name << ": " << r.message;
    EXPECT_NE(r.message.find(Num(-kM2 * 1.5 * v).substr(0, 6)), std::string::npos) << how.name << ": " << r.message;
    EXPECT_NEAR(r.fail_time, t, 1e-7) << how.name;
    ASSERT_FALSE(s.times.empty()) << how.name;
  }
}

// If this fails, the impact the other way (the hammer falling onto q_min = -0.05 pushes the
// sphere onto the floor: P_N = m2 (1 + e) v > 0) was refused, or its rebound was not -e v.
TEST(WhenPull, StopImpactPushingTheSphereDownKeepsItRolling) {
  auto l = LoadModel(Hammer(", q_min = -0.05, restitution = 0.5", ""), {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  sim::SimResult r;
  const sim::MemorySink s = RunWith(*l->prog, AllIntegrators()[0], 0.12, 0.01, {"slide.u", "px.u"}, &r, 1e-10);
  ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << r.message;
  ASSERT_GE(r.stats.events.size(), 1u);
  const double t = std::sqrt(2.0 * 0.05 / kG);  // free fall of 0.05
  EXPECT_NEAR(r.stats.events[0].time, t, 1e-7);
  EXPECT_NEAR(s.rows.back()[1], 0.4, 1e-9);  // rolling on at v_x = 0.4
}

}  // namespace
}  // namespace kanesim::test
