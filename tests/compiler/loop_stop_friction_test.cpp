// End stops beside Coulomb friction mu N in mechanisms with constraint rows (issue 41;
// docs/events.md "Friction beside end stops"). A rack pair: two blocks on prismatic joints
// along x, coupled q2 = r q1 (JointCoupling, r = -1/2), gravity -g y, block 1 on an end stop
// q_min = 0 and driven by F(t) = k (t - t0), block 2's joint with friction mu. Block 2 moves
// along its axis only, so its joint carries N = m2 g across it (hand statics) and its friction
// reflects onto q1 as |r| mu m2 g: the reduced model is one block of mass m1 + r^2 m2 with a
// constant friction force |r| mu m2 g (and, regularized, the speed scale v / |r|).
// Resting: F < 0 presses block 1 on its stop, whose reaction is -F (the blocks at rest, no
// friction needed): it leaves at t0. Exactly stuck after that while F <= C = |r| mu m2 g, it
// slips at t_s = t0 + C / k and moves by (m1 + r^2 m2) q1'' = k (t - t_s).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "tests/compiler/compile_test_util.h"
#include "tests/support/model_texts.h"

namespace kanesim::test {
namespace {

constexpr double kM1 = RackPairText::kM1, kM2 = RackPairText::kM2, kR = RackPairText::kR, kMu = RackPairText::kMu;
constexpr double kG = RackPairText::kG, kK = 5.0, kT0 = 0.5;
constexpr double kMeff = kM1 + kR * kR * kM2;
constexpr double kC = 0.5 * kMu * kM2 * kG;  // |r| mu m2 g

// The rack pair; `j2_law` in joint 2's modifiers after mu, `q0`, `u0` block 1's start.
std::string RackPair(const std::string& j2_law, double q0 = 0.0, double u0 = 0.0, const std::string& drive = "",
                     double e = 0.0) {
  return RackPairText{.j1_mods = ", q_max = 5, restitution = " + Num(e) + ", q(start = " + Num(q0) + "), u(start = " +
                                 Num(u0) + ")",
                      .j2_law = j2_law,
                      .equations = drive.empty() ? "  j1.tau = " + Num(kK) + " * (time - " + Num(kT0) + ");\n" : drive}
      .Text();
}

// The reduced model: one block, the friction reflected.
std::string Reduced(const std::string& law) {
  return "model Reduced\n"
         "  World world(g = {0, " + Num(-kG) + ", 0});\n"
         "  Prismatic j1(axis = {1, 0, 0}, q_min = 0, q_max = 5, friction_force = " + Num(kC) + law + ");\n"
         "  Body b(m = " + Num(kMeff) + ");\n"
         "equation\n"
         "  connect(world.frame_b, j1.frame_a);\n"
         "  connect(j1.frame_b, b.frame_a);\n"
         "  j1.tau = " + Num(kK) + " * (time - " + Num(kT0) + ");\n"
         "end Reduced;\n";
}

// q1 after the slip at ts: (m1 + r^2 m2) q1'' = k (t - ts) from rest at 0.
double SlidOut(double t, double ts) { return t <= ts ? 0.0 : kK * std::pow(t - ts, 3) / (6.0 * kMeff); }

// The rows of `s` at the multiples of `interval` (the last row at each).
std::vector<std::vector<double>> GridRows(const sim::MemorySink& s, double interval) {
  std::vector<std::vector<double>> out;
  for (size_t i = 0; i < s.times.size(); ++i) {
    const double k = std::round(s.times[i] / interval);
    if (std::abs(s.times[i] - k * interval) > 1e-12) continue;
    if (out.size() == static_cast<size_t>(k) + 1) out.back() = s.rows[i];
    else out.push_back(s.rows[i]);
  }
  return out;
}

// If this fails, end stops beside mu with constraint rows are refused (K318, before this
// change), the block leaves its stop before or after the stop's reaction -F(t) turns to
// pull, the exact friction of the follower (held through the coupling by the stop) is not
// the reflected |r| mu m2 g, or the integrators disagree on the events.
TEST(LoopStopFriction, RackPairLeavesItsStopAndSlipsByHandStatics) {
  auto l = LoadModel(RackPair(", friction_exact = true"), {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  const double ts = kT0 + kC / kK;
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    const sim::MemorySink s = RunWith(*l->prog, how, 1.6, 0.1, {"j1.q", "j1.u", "j2.q", "j2.u"}, &r, 1e-11);
    ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
    std::string log;
    for (const sim::EventRecord& e : r.stats.events) log += std::to_string(e.time) + " " + e.element + " " + e.kind + "\n";
    const sim::EventRecord* leave = nullptr;
    const sim::EventRecord* slip = nullptr;
    for (const sim::EventRecord& e : r.stats.events) {
      if (e.element == "j1" && e.kind.find("leaves") != std::string::npos) leave = &e;
      if (e.element == "j2" && e.kind.rfind("slips", 0) == 0) slip = &e;
    }
    ASSERT_NE(leave, nullptr) << how.name << "\n" << log;
    ASSERT_NE(slip, nullptr) << how.name << "\n" << log;
    EXPECT_NEAR(leave->time, kT0, 1e-8) << how.name << "\n" << log;
    EXPECT_NEAR(slip->time, ts, 1e-8) << how.name << "\n" << log;
    for (size_t i = 0; i < s.times.size(); ++i) {
      const std::vector<double>& y = s.rows[i];
      EXPECT_GE(y[0], -1e-15) << how.name << " t = " << s.times[i];  // no row past the stop (round-off)
      EXPECT_NEAR(y[0], SlidOut(s.times[i], ts), 1e-8) << how.name << " t = " << s.times[i];
      EXPECT_NEAR(y[2], kR * y[0], 1e-12) << how.name;
      EXPECT_NEAR(y[3], kR * y[1], 1e-10) << how.name;
    }
  }
}

// The same rack pair against its reduced model, with both laws (the regularized one's speed
// scale reflected: tanh(u2 / v) = -tanh(u1 / (v / |r|))): events and rows agree. If this
// fails, the rows' reactions are left out of the resting stop's chord (the follower's
// friction then fed back wrongly), or the friction's normal force misses the coupling.
TEST(LoopStopFriction, RackPairEqualsTheReducedModelWithReflectedFriction) {
  struct Law {
    std::string geared, reduced;
  };
  const std::vector<Law> laws = {{", friction_exact = true", ", friction_exact = true"},
                                 {", friction_v = 1e-3", ", friction_v = 2e-3"}};
  for (const Law& law : laws) {
    auto a = LoadModel(RackPair(law.geared), {}, {}, true);
    auto b = LoadModel(Reduced(law.reduced), {}, {}, true);
    ASSERT_TRUE(a && a->prog) << (a ? Messages(a->errors) : "");
    ASSERT_TRUE(b && b->prog) << (b ? Messages(b->errors) : "");
    double t_ref = NAN;
    for (const IntegratorChoice& how : AllIntegrators()) {
      const std::string who = how.name + law.geared;
      sim::SimResult ra, rb;
      const sim::MemorySink sa = RunWith(*a->prog, how, 1.6, 0.1, {"j1.q", "j1.u"}, &ra, 1e-11);
      const sim::MemorySink sb = RunWith(*b->prog, how, 1.6, 0.1, {"j1.q", "j1.u"}, &rb, 1e-11);
      ASSERT_EQ(ra.status, sim::SimResult::Status::kOk) << who << ": " << ra.message;
      ASSERT_EQ(rb.status, sim::SimResult::Status::kOk) << who << ": " << rb.message;
      std::string log;
      for (const sim::SimStats* st : {&ra.stats, &rb.stats})
        for (const sim::EventRecord& e : st->events) log += std::to_string(e.time) + " " + e.element + " " + e.kind + "\n";
      // The last event, where the block starts to move: the geared pair's slip of j2 (after
      // its leave at t0), the reduced joint's leave and slide off its stop (a joint with exact
      // friction resting on its stop is one held state in a tree).
      ASSERT_FALSE(ra.stats.events.empty()) << who;
      ASSERT_FALSE(rb.stats.events.empty()) << who;
      EXPECT_NEAR(ra.stats.events.back().time, rb.stats.events.back().time, 1e-8) << who << "\n" << log;
      if (std::isnan(t_ref)) t_ref = ra.stats.events.back().time;
      EXPECT_NEAR(ra.stats.events.back().time, t_ref, 1e-8) << who;  // the five integrators agree
      for (const std::vector<double>& y : sa.rows) EXPECT_GE(y[0], -1e-15) << who;  // no row past the stop
      // The rows on the output grid (an event's two rows at the grid time: the right limit);
      // the leave's event rows may fall an event location (3e-12 s) apart from the grid's.
      const std::vector<std::vector<double>> ga = GridRows(sa, 0.1), gb = GridRows(sb, 0.1);
      ASSERT_EQ(ga.size(), 17u) << who;
      ASSERT_EQ(gb.size(), 17u) << who;
      for (size_t i = 0; i < ga.size(); ++i) {
        EXPECT_NEAR(ga[i][0], gb[i][0], 1e-8) << who << " t = " << 0.1 * static_cast<double>(i);
        EXPECT_NEAR(ga[i][1], gb[i][1], 1e-8) << who << " t = " << 0.1 * static_cast<double>(i);
      }
    }
  }
}

// An impact at the stop beside mu N with constraint rows (the friction impulse law with the
// rows' impulses in the normal impulses): block 1 starts at q1 = 0.02 moving at -1 m/s
// towards its stop (restitution 1/2), undriven, decelerated by the reflected friction
// a = C / (m1 + r^2 m2): it strikes at t1 = (1 - sqrt(1 - 2 a 0.02)) / a with speed
// -v = -sqrt(1 - 2 a 0.02), leaves at v / 2 (block 2's joint meets no impulse across its
// axis, so no friction impulse), and stops for good at t1 + v / (2 a), at q1 = v^2 / (8 a).
// If this fails, the impact beside mu in a loop is refused (before this change) or its
// impulse is not Newton's law through the coupling.
TEST(LoopStopFriction, RackPairStrikesItsStopAtTheClosedFormTimeAndSticks) {
  auto l = LoadModel(RackPair(", friction_exact = true", 0.02, -1.0, "  j1.tau = 0;\n", 0.5), {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  const double a = kC / kMeff, v = std::sqrt(1.0 - 2.0 * a * 0.02);
  const double t1 = (1.0 - v) / a, t2 = t1 + v / (2.0 * a);
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    const sim::MemorySink s = RunWith(*l->prog, how, 0.5, 0.05, {"j1.q", "j1.u", "j2.u"}, &r, 1e-11);
    ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
    const std::vector<sim::EventRecord>& ev = r.stats.events;
    ASSERT_EQ(ev.size(), 2u) << how.name;
    EXPECT_EQ(ev[0].element, "j1");
    EXPECT_EQ(ev[0].kind.rfind("impact at q_min", 0), 0u) << ev[0].kind;
    EXPECT_NEAR(ev[0].time, t1, 1e-8) << how.name;
    EXPECT_EQ(ev[1].element, "j2");
    EXPECT_EQ(ev[1].kind.rfind("sticks", 0), 0u) << ev[1].kind;
    EXPECT_NEAR(ev[1].time, t2, 1e-8) << how.name;
    for (const sim::EventChange& c : ev[0].changes)
      if (c.name == "j1.u") {
        EXPECT_NEAR(c.before, -v, 1e-8) << how.name;
        EXPECT_NEAR(c.after, 0.5 * v, 1e-8) << how.name;  // Newton's law at the stop
      }
    for (size_t i = 0; i < s.times.size(); ++i) {
      // No row past the stop (the impact's left limit: located within the tolerance).
      EXPECT_GE(s.rows[i][0], -1e-12) << how.name << " t = " << s.times[i];
      EXPECT_NEAR(s.rows[i][2], kR * s.rows[i][1], 1e-10) << how.name;
    }
    EXPECT_NEAR(s.rows.back()[0], v * v / (8.0 * a), 1e-8) << how.name;
    EXPECT_LE(std::abs(s.rows.back()[1]), 1e-12) << how.name;
  }
}

// examples/fourbar.mech at rest, its crank on an end stop q_min = 0.3 (its start angle),
// driven by tau = kDrive t, with `rocker_law` (mu) on the rocker's joint.
constexpr double kDrive = 2.0;
constexpr double kHold = 1.4109147004724838;  // the torque gravity needs at the crank (LoopFriction, virtual work)

std::string FourBarOnStop(const std::string& rocker_law) {
  FourBarText bar;
  bar.omega0 = 0;
  bar.crank_mods = ", q_min = 0.3";
  bar.rocker_mods = rocker_law;
  bar.equations = "  crank_pivot.tau = " + Num(kDrive) + " * time;\n";
  return bar.Text();
}

// The crank rests on its stop, gravity pressing it on through the loop with the torque kHold,
// until the drive takes that over: it leaves at kHold / kDrive (hand statics), in all five
// integrators, both laws of the rocker's mu (whose joint, held through the loop by the stop,
// needs no friction). If this fails, stops beside mu with loops are refused (K318, before
// this change), the resting reaction misses the loop's (a chord without the rows' reactions)
// or the stuck rocker's friction takes a share of the stop's reaction.
TEST(LoopStopFriction, FourBarCrankLeavesItsStopWhereTheDriveTakesOverGravity) {
  for (const std::string law : {", mu = 0.3, friction_v = 1e-4", ", mu = 0.3, friction_exact = true"}) {
    auto l = LoadModel(FourBarOnStop(law), {}, {}, true);
    ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
    for (const IntegratorChoice& how : AllIntegrators()) {
      const std::string who = how.name + law;
      sim::SimResult r;
      const sim::MemorySink s = RunWith(*l->prog, how, 0.8, 0.05, {"crank_pivot.q", "crank_pivot.u", "rocker_pivot.u"},
                                        &r, 1e-11);
      ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << who << ": " << r.message;
      const sim::EventRecord* leave = nullptr;
      for (const sim::EventRecord& e : r.stats.events)
        if (e.element == "crank_pivot" && e.kind.find("leaves") != std::string::npos) leave = &e;
      ASSERT_NE(leave, nullptr) << who;
      EXPECT_NEAR(leave->time, kHold / kDrive, 1e-8) << who;
      for (size_t i = 0; i < s.times.size(); ++i) {
        // No row past the stop (the loop's projection moves the crank within the tolerance).
        EXPECT_GE(s.rows[i][0], 0.3 - 1e-12) << who << " t = " << s.times[i];
        if (s.times[i] < leave->time) {
          EXPECT_NEAR(s.rows[i][0], 0.3, 1e-12) << who << " t = " << s.times[i];
          EXPECT_LE(std::abs(s.rows[i][1]), 1e-12) << who << " t = " << s.times[i];
          EXPECT_LE(std::abs(s.rows[i][2]), 1e-12) << who << " t = " << s.times[i];
        }
      }
    }
  }
}

}  // namespace
}  // namespace kanesim::test
