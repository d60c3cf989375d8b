// The output signals of held rows (issue 41; docs/events.md "Outputs"): a joint resting on its
// stop, a joint stuck by exact friction and a point resting on a PlaneContact read the held
// motion's accelerations (0), body accelerations and joint reactions (the statics), not the
// free motion's, in every integrator; after leaving, the free motion's.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "tests/compiler/compile_test_util.h"
#include "tests/support/model_texts.h"

namespace kanesim::test {
namespace {

constexpr double kG = 9.81;

// Column `name` of a run's rows.
size_t Col(const sim::MemorySink& s, const std::string& name) {
  for (size_t i = 0; i < s.names.size(); ++i)
    if (s.names[i] == name) return i;
  ADD_FAILURE() << "no column " << name;
  return 0;
}

// A rod (L = 1, m = 1, J = m L^2 / 3 about the pin) on a hinge at rest on its stop q_min = q0
// under gravity, driven by tau = k t: the stop holds it (a = 0) with the reaction
// lambda = m g (L/2) cos q0 - k t, so the hinge's axial reaction torque is the static torque
// m g (L/2) cos q0, until lambda reaches 0 at t* = m g (L/2) cos q0 / k; then it swings free,
// a = (k t - m g (L/2) cos q) / J.
// If this fails, a resting joint's acceleration, its rod's accelerations or its reaction are
// computed as if the stop were not there (they read -14.4 rad/s^2 and 0 N m before the fix).
TEST(HeldSignals, PendulumOnItsStopReadsZeroAccelerationAndTheStaticTorque) {
  const double q0 = 0.2, k = 10.0, m = 1.0, L = 1.0, J = m * L * L / 3, t_leave = m * kG * L / 2 * std::cos(q0) / k;
  auto l = LoadModel(
      PendulumText{.mods = ", q(start = " + Num(q0) + "), q_min = " + Num(q0) + ", tau = " + Num(k) + " * time"}.Text(),
      {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  const std::vector<std::string> signals = {"j1.q",       "j1.u",       "j1.a", "j1.reaction_torque[3]", "j1.reaction_force[1]",
                                            "j1.reaction_force[2]", "rod.body.a[1]", "rod.body.a[2]", "rod.body.alpha[3]"};
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    sim::MemorySink s = RunWith(*l->prog, how, 0.7, 0.05, signals, &r, 1e-10);
    ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
    ASSERT_EQ(r.stats.events.size(), 2u) << how.name;
    EXPECT_EQ(r.stats.events[1].kind, "leaves q_min") << how.name;
    EXPECT_NEAR(r.stats.events[1].time, t_leave, 1e-9) << how.name;
    const double t_ev = r.stats.events[1].time;  // the rows' own event (to round-off of t_leave)
    size_t resting = 0, free = 0;
    for (size_t i = 0; i < s.rows.size(); ++i) {
      const std::vector<double>& row = s.rows[i];
      const double t = s.times[i], q = row[Col(s, "j1.q")];
      if (t <= t_ev) {  // on the stop (the leave's rows too: lambda = 0 there, the right limit free)
        ++resting;
        const double held = t < t_ev ? 0.0 : 1e-12;  // held exactly on the stop
        EXPECT_NEAR(row[Col(s, "j1.a")], 0.0, held) << how.name << " t = " << t;
        EXPECT_NEAR(row[Col(s, "rod.body.alpha[3]")], 0.0, held) << how.name << " t = " << t;
        EXPECT_NEAR(row[Col(s, "rod.body.a[1]")], 0.0, 1e-14) << how.name << " t = " << t;
        EXPECT_NEAR(row[Col(s, "rod.body.a[2]")], 0.0, 1e-14) << how.name << " t = " << t;
        EXPECT_NEAR(row[Col(s, "j1.reaction_torque[3]")], m * kG * L / 2 * std::cos(q0), 1e-12) << how.name << " t = " << t;
        // The pin carries the weight: m g up, in frame_b's axes (rotated by q0).
        EXPECT_NEAR(row[Col(s, "j1.reaction_force[1]")], m * kG * std::sin(q0), 1e-12) << how.name << " t = " << t;
        EXPECT_NEAR(row[Col(s, "j1.reaction_force[2]")], m * kG * std::cos(q0), 1e-12) << how.name << " t = " << t;
      } else {
        ++free;
        const double a = (k * t - m * kG * L / 2 * std::cos(q)) / J;
        EXPECT_NEAR(row[Col(s, "j1.a")], a, 1e-9 * (1 + std::abs(a))) << how.name << " t = " << t;
        EXPECT_NEAR(row[Col(s, "j1.reaction_torque[3]")], k * t, 1e-9) << how.name << " t = " << t;  // its own tau only
      }
    }
    EXPECT_GE(resting, 10u) << how.name;
    EXPECT_GE(free, 4u) << how.name;
  }
}

// The same rod released above its stop falls onto it (restitution 0) and rests there: from the
// impact on, a = 0 and the stop's reaction is the static torque m g (L/2) cos q_min.
// If this fails, a rest reached by an impact reads the free motion (a = -(3 g / 2 L) cos q).
TEST(HeldSignals, PendulumThatFallsOntoItsStopRestsWithTheStaticTorque) {
  const double q_min = -0.4, m = 1.0, L = 1.0;
  auto l = LoadModel(PendulumText{.mods = ", q(start = 0.3), q_min = " + Num(q_min)}.Text(), {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    sim::MemorySink s = RunWith(*l->prog, how, 1.0, 0.05, {"j1.q", "j1.a", "j1.reaction_torque[3]"}, &r, 1e-10);
    ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
    ASSERT_FALSE(r.stats.events.empty()) << how.name;
    const double t_rest = r.stats.events.back().time;
    EXPECT_EQ(r.stats.events.back().kind.find("rests on q_min"), 0u) << how.name << ": " << r.stats.events.back().kind;
    size_t resting = 0;
    for (size_t i = 0; i < s.rows.size(); ++i) {
      if (s.times[i] <= t_rest && !(i > 0 && s.times[i - 1] == s.times[i])) continue;  // before, and the left limit
      ++resting;
      EXPECT_EQ(s.rows[i][1], 0.0) << how.name << " t = " << s.times[i];
      EXPECT_NEAR(s.rows[i][2], m * kG * L / 2 * std::cos(q_min), 1e-12) << how.name << " t = " << s.times[i];
    }
    EXPECT_GE(resting, 10u) << how.name;
  }
}

// A box (m = 1.5) stuck by exact friction on an incline (tan theta = 0.45, mu_s = 0.5, mu = 0.3:
// N = m g cos theta), pushed up the slope by f = k t: the friction holds it (a = 0, the box's
// acceleration 0) until k t - m g sin theta passes mu_s N, at t* = m g (sin theta + mu_s cos
// theta) / k; then it slides up, a = (k t - m g (sin theta + mu cos theta)) / m. The same with a
// constant friction force instead of mu N (its own solve, no Newton).
// If this fails, a stuck joint reads the acceleration of a friction force solved at another
// state (the integrator's last stage: -0.45 m/s^2 before the fix) or the free motion's.
TEST(HeldSignals, StuckSliderReadsZeroAccelerationUntilItSlips) {
  const double tan_theta = 0.45, theta = std::atan(tan_theta), c = std::cos(theta), sn = std::sin(theta);
  const double m = 1.5, k = 20.0, N = m * kG * c;
  struct Law {
    std::string mods;
    double bound, sliding;  // static and sliding friction forces
  };
  for (const Law& law : {Law{"mu = 0.3, mu_s = 0.5", 0.5 * N, 0.3 * N}, Law{"friction_force = 6, friction_force_s = 7", 7, 6}}) {
    const std::string text = "model Incline\n  World world(g = {0, -9.81, 0});\n  Prismatic slide(axis = {" + Num(c) + ", " +
                             Num(sn) + ", 0}, " + law.mods + ", friction_exact = true, tau = " + Num(k) +
                             " * time);\n  Body box(m = " + Num(m) +
                             ");\nequation\n  connect(world.frame_b, slide.frame_a);\n"
                             "  connect(slide.frame_b, box.frame_a);\nend Incline;\n";
    auto l = LoadModel(text, {}, {}, true);
    ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
    const double t_slip = (m * kG * sn + law.bound) / k;
    for (const IntegratorChoice& how : AllIntegrators()) {
      sim::SimResult r;
      sim::MemorySink s = RunWith(*l->prog, how, 0.8, 0.04, {"slide.a", "box.a[1]", "box.a[2]"}, &r, 1e-10);
      ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
      ASSERT_EQ(r.stats.events.size(), 2u) << how.name << " " << law.mods;
      EXPECT_NEAR(r.stats.events[1].time, t_slip, 1e-9) << how.name << " " << law.mods;
      const double t_ev = r.stats.events[1].time;  // the rows' own event (to round-off of t_slip)
      size_t stuck = 0, sliding = 0;
      for (size_t i = 0; i < s.rows.size(); ++i) {
        const double t = s.times[i];
        const std::vector<double>& row = s.rows[i];
        if (t < t_ev || (t == t_ev && i + 1 < s.times.size() && s.times[i + 1] == t)) {  // stuck, and the slip's left limit
          ++stuck;
          EXPECT_EQ(row[0], 0.0) << how.name << " " << law.mods << " t = " << t;
          EXPECT_NEAR(row[1], 0.0, 1e-14) << how.name << " " << law.mods << " t = " << t;
          EXPECT_NEAR(row[2], 0.0, 1e-14) << how.name << " " << law.mods << " t = " << t;
        } else {
          ++sliding;
          const double a = (k * t - m * kG * sn - law.sliding) / m;
          EXPECT_NEAR(row[0], a, 1e-9) << how.name << " " << law.mods << " t = " << t;
          EXPECT_NEAR(row[1], a * c, 1e-9) << how.name << " " << law.mods << " t = " << t;
        }
      }
      EXPECT_GE(stuck, 10u) << how.name;
      EXPECT_GE(sliding, 3u) << how.name;
    }
  }
}

// A rod (L = 1, m = 2) whose tip rests on a floor (PlaneContact) at q0 = -0.3, driven by
// tau = k t: the floor carries the tip with lambda = (m g (L/2) cos q0 - k t) / (L cos q0), the
// rod stays (a = 0) and the hinge's axial torque is its own tau alone (the floor's force is
// outside the joint), until lambda reaches 0 at t* = m g (L/2) cos q0 / k; then it swings free.
// If this fails, a point resting on a plane reads the free motion (a = -14 rad/s^2 before the
// fix), or the plane's force is counted as the joint's own torque.
TEST(HeldSignals, RodOnAFloorReadsTheHeldMotion) {
  const double q0 = -0.3, k = 12.0, m = 2.0, L = 1.0, J = m * L * L / 3, t_leave = m * kG * L / 2 * std::cos(q0) / k;
  const std::string text =
      "model Rest\n  World world(g = {0, -9.81, 0});\n  Revolute hinge(axis = {0, 0, 1}, q(start = " + Num(q0) +
      "), tau = " + Num(k) + " * time);\n  Rod rod(L = 1, m = 2);\n  FixedTranslation tip(r = {1, 0, 0});\n"
      "  PlaneContact floor(n = {0, 1, 0}, d = " + Num(std::sin(q0)) + ");\nequation\n"
      "  connect(world.frame_b, hinge.frame_a);\n  connect(hinge.frame_b, rod.frame_a);\n"
      "  connect(hinge.frame_b, tip.frame_a);\n  connect(tip.frame_b, floor.frame_a);\nend Rest;\n";
  auto l = LoadModel(text, {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    sim::MemorySink s = RunWith(*l->prog, how, 1.0, 0.05,
                                {"hinge.q", "hinge.a", "hinge.reaction_torque[3]", "hinge.reaction_force[2]"}, &r, 1e-10);
    ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
    ASSERT_EQ(r.stats.events.size(), 2u) << how.name;
    EXPECT_NEAR(r.stats.events[1].time, t_leave, 1e-9) << how.name;
    const double t_ev = r.stats.events[1].time;  // the rows' own event (to round-off of t_leave)
    size_t resting = 0, free = 0;
    for (size_t i = 0; i < s.rows.size(); ++i) {
      const double t = s.times[i], q = s.rows[i][0];
      EXPECT_NEAR(s.rows[i][2], k * t, 1e-9) << how.name << " t = " << t;  // the hinge's own torque
      if (t <= t_ev) {
        ++resting;
        EXPECT_NEAR(s.rows[i][1], 0.0, 1e-12) << how.name << " t = " << t;
        // The pin's share of the weight, m g - lambda, along frame_b's y (rotated by q0).
        const double lambda = (m * kG * L / 2 * std::cos(q0) - k * t) / (L * std::cos(q0));
        EXPECT_NEAR(s.rows[i][3], (m * kG - lambda) * std::cos(q0), 1e-10) << how.name << " t = " << t;
      } else {
        ++free;
        const double a = (k * t - m * kG * L / 2 * std::cos(q)) / J;
        EXPECT_NEAR(s.rows[i][1], a, 1e-9 * (1 + std::abs(a))) << how.name << " t = " << t;
      }
    }
    EXPECT_GE(resting, 10u) << how.name;
    EXPECT_GE(free, 3u) << how.name;
  }
}

// A rack pair: block 1 (m1 = 1) on a stop q1 >= 0, driven by tau1 = 5 (t - 0.5); block 2
// (m2 = 2, mu = 0.3 exact) geared to it, q2 = -0.5 q1. Until t = 0.5 the stop holds block 1
// and, through the gear, block 2 (held by the stop: its friction force undetermined, zero),
// so nothing acts along the axes: both axial reactions 0. From 0.5 to the slip at
// 0.5 + 0.3 * 2 g / 10 block 2's friction holds the pair: block 1's axial reaction is its
// drive's 5 (t - 0.5), block 2's the gear's force tau1 / 0.5 = 10 (t - 0.5).
// If this fails, the output rows' held solve treats the follower as stuck by its own friction
// beside the stop's row (dependent rows): before the fix the reactions read -26.7 N at
// t = 0.2 and the event row's acceleration 1.6e21.
TEST(HeldSignals, FollowerHeldThroughAGearByARestingStopReadsTheStatics) {
  const std::string text = RackPairText{}.Text();
  auto l = LoadModel(text, {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  const double t_slip = 0.5 + 0.3 * 2 * kG / 10;
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    sim::MemorySink s = RunWith(*l->prog, how, 1.0, 0.05,
                                {"j1.a", "j2.a", "j1.reaction_force[1]", "j2.reaction_force[1]"}, &r, 1e-10);
    ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
    size_t resting = 0, stuck = 0;
    for (size_t i = 0; i < s.rows.size(); ++i) {
      const double t = s.times[i];
      const std::vector<double>& row = s.rows[i];
      EXPECT_NEAR(row[0], 0.0, 1e-12) << how.name << " t = " << t;
      EXPECT_NEAR(row[1], 0.0, 1e-12) << how.name << " t = " << t;
      const double f = t < 0.5 ? 0.0 : 5 * (t - 0.5);
      EXPECT_NEAR(row[2], f, 1e-9) << how.name << " t = " << t;
      EXPECT_NEAR(std::abs(row[3]), 2 * f, 1e-9) << how.name << " t = " << t;
      (t < 0.5 ? resting : stuck) += 1;
    }
    EXPECT_EQ(s.times.back(), 1.0) << how.name;
    EXPECT_LT(1.0, t_slip);
    EXPECT_GE(resting, 10u) << how.name;
    EXPECT_GE(stuck, 10u) << how.name;
  }
}

}  // namespace
}  // namespace kanesim::test
