// Exact stick-slip of a constant Coulomb friction (stdlib friction_torque / friction_force,
// URDF <dynamics friction>; issue 41) against closed forms: a driven joint that sticks below
// the static bound and slides with (T - F) / J above it; a pendulum whose swings lose
// F times their path and that rests at the angle and time the energy balance gives; a
// double pendulum whose stuck joint's holding torque is Lagrange's and that slips where that
// torque reaches the static bound; a block driven against an end stop through its friction
// (impacts, the rebound's friction reversed, rest, then leaving and sticking).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <string>

#include "sim/stick_slip.h"
#include "tests/compiler/compile_test_util.h"
#include "tests/support/model_texts.h"

namespace kanesim::test {
namespace {

constexpr double kG = 9.81;

// The output row at time t (an event's left-limit row is the first one there).
size_t RowAt(const sim::MemorySink& s, double t) {
  return static_cast<size_t>(std::find(s.times.begin(), s.times.end(), t) - s.times.begin());
}

// A disk (J = 0.5 about the vertical axis: no gravity torque) driven by a constant torque T,
// friction_torque F = 1, friction_torque_s F_s = 1.5, from speed u0: it sticks while |T| <=
// F_s at rest, else slides with q'' = (T - F sign u) / J; from u0 > 0 with |T| < F it stops at
// t = u0 J / (F - T) and sticks. If this fails, the constant friction is not -F sign(u)
// exactly, or the static bound is not F_s.
TEST(ConstantFriction, DrivenJointSticksBelowTheStaticBoundAndSlidesAbove) {
  const double J = 0.5, F = 1.0;
  struct Case {
    double T, u0;
    const char* first;  // the start's event
  };
  for (const Case& c : {Case{0.8, 0, "sticks"}, Case{1.2, 0, "sticks"}, Case{2.0, 0, "slips, forwards"},
                        Case{-2.0, 0, "slips, backwards"}, Case{0.5, 3.0, ""}}) {
    const std::string text =
        "model Disk\n"
        "  World world(g = {0, -9.81, 0});\n"
        "  Revolute j(axis = {0, 1, 0}, u(start = " + Num(c.u0) + "), friction_torque = " + Num(F) +
        ", friction_torque_s = 1.5, friction_exact = true);\n"
        "  Body disk(m = 3, I = [0.2, 0, 0; 0, " + Num(J) + ", 0; 0, 0, 0.3]);\n"
        "equation\n"
        "  connect(world.frame_b, j.frame_a);\n"
        "  connect(j.frame_b, disk.frame_a);\n"
        "  j.tau = " + Num(c.T) + ";\n"
        "end Disk;\n";
    auto l = LoadModel(text, {}, {}, true);
    ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
    for (const IntegratorChoice& how : AllIntegrators()) {
      sim::SimResult r;
      sim::MemorySink s = RunWith(*l->prog, how, 5.0, 0.25, {"j.q", "j.u"}, &r, 1e-11);
      ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
      const auto& ev = r.stats.events;
      const double t_stop = c.u0 > 0 ? c.u0 * J / (F - c.T) : 0.0;  // the moving case's stop
      ASSERT_EQ(ev.size(), 1u) << how.name;  // the start's decision, or the stop
      if (c.u0 > 0) {
        EXPECT_NEAR(ev[0].time, t_stop, 1e-9) << how.name;
        double held = 0, bound = 0;
        ASSERT_EQ(std::sscanf(ev[0].kind.c_str(), "sticks (friction %lf within %lf)", &held, &bound), 2) << ev[0].kind;
        EXPECT_NEAR(held, -c.T, 1e-12);  // friction balances the drive
        EXPECT_EQ(bound, 1.5);
      } else {
        EXPECT_EQ(ev[0].kind.find(c.first), 0u) << how.name << ": " << ev[0].kind;
      }
      const bool stuck_at_start = c.u0 == 0 && std::abs(c.T) <= 1.5;
      const double a0 = c.u0 > 0 ? (c.T - F) / J : (c.T - F * (c.T > 0 ? 1 : -1)) / J;
      const double q_stop = c.u0 * t_stop + 0.5 * a0 * t_stop * t_stop;
      for (size_t i = 0; i < s.rows.size(); ++i) {
        const double t = s.times[i];
        if (stuck_at_start) {
          EXPECT_EQ(s.rows[i][0], 0.0) << how.name << " t = " << t;
        } else if (c.u0 == 0 || t <= t_stop) {
          const double q = c.u0 * t + 0.5 * a0 * t * t;
          EXPECT_NEAR(s.rows[i][0], q, 1e-9 * (1 + std::abs(q))) << how.name << " t = " << t;
        } else if (t > t_stop + 1e-6) {  // (the stop's left-limit row is at the event's time)
          EXPECT_NEAR(s.rows[i][0], q_stop, 1e-9) << how.name << " t = " << t;
          EXPECT_EQ(s.rows[i][1], 0.0) << how.name << " t = " << t;
        }
      }
    }
  }
}

// The same law on a prismatic joint: a block (m = 2) pushed by P = 5 N against
// friction_force = 3 N slides with a = (P - F) / m = 1. If this fails, friction_force is not
// the prismatic joint's constant friction.
TEST(ConstantFriction, PrismaticFrictionForce) {
  const std::string text =
      "model Block\n"
      "  World world(g = {0, -9.81, 0});\n"
      "  Prismatic s(axis = {1, 0, 0}, friction_force = 3, friction_exact = true);\n"
      "  Body box(m = 2);\n"
      "equation\n"
      "  connect(world.frame_b, s.frame_a);\n"
      "  connect(s.frame_b, box.frame_a);\n"
      "  s.tau = 5;\n"
      "end Block;\n";
  auto l = LoadModel(text, {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  sim::SimResult r;
  sim::MemorySink s = RunWith(*l->prog, AllIntegrators()[0], 2.0, 0.25, {"s.q"}, &r, 1e-11);
  ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << r.message;
  for (size_t i = 0; i < s.rows.size(); ++i) EXPECT_NEAR(s.rows[i][0], 0.5 * s.times[i] * s.times[i], 1e-9);
}

// First root of f on the way from x0 in direction d (f(x0 + d h) > 0 at the first step),
// by a scan then bisection to round-off.
double FirstRoot(const std::function<double(double)>& f, double x0, double d) {
  const double h = 1e-3;
  double a = x0 + d * h, b = a;
  while (f(b) > 0) a = b, b += d * h;
  for (int it = 0; it < 200; ++it) {
    const double m = 0.5 * (a + b);
    (f(m) > 0 ? a : b) = m;
  }
  return 0.5 * (a + b);
}

// A point mass (m = 1, L = 1) on a revolute joint with friction_torque F = 0.8, released at
// rest from theta0 = 1.2 rad. Each swing from rest at a_n ends at rest at a_{n+1}, where the
// energy balance m g L (cos a_{n+1} - cos a_n) = F |a_{n+1} - a_n| holds (energy lost =
// friction times path), in the time int da / sqrt(2 E(a) / J); it sticks for good at the first
// a_n with m g L |sin a_n| <= F. If this fails, the pendulum loses energy other than F times
// its path, turns at the wrong angles or times, or does not come to rest where statics says.
TEST(ConstantFriction, PendulumComesToRestAtTheEnergyBalanceAngleAndTime) {
  const double m = 1, L = 1, F = 0.8, th0 = 1.2, J = m * L * L, mgL = m * kG * L;
  std::vector<double> a{th0}, t_turn{0.0};
  while (mgL * std::abs(std::sin(a.back())) > F) {
    const double an = a.back(), d = std::sin(an) > 0 ? -1.0 : 1.0;  // slides downhill
    auto E = [&](double x) { return mgL * (std::cos(x) - std::cos(an)) - F * std::abs(x - an); };
    const double next = FirstRoot(E, an, d);
    // x = mid + h sin(phi): the endpoints' 1/sqrt singularities become a smooth integrand.
    const double mid = 0.5 * (an + next), h = 0.5 * (next - an);
    const double gl_x[3] = {-std::sqrt(0.6), 0.0, std::sqrt(0.6)}, gl_w[3] = {5.0 / 9, 8.0 / 9, 5.0 / 9};
    const int n = 400;
    const double pi = std::acos(-1.0), dphi = pi / n;
    double T = 0;
    for (int k = 0; k < n; ++k)
      for (int g = 0; g < 3; ++g) {
        const double phi = -pi / 2 + dphi * (k + 0.5 + 0.5 * gl_x[g]);
        const double x = mid + h * std::sin(phi);
        T += 0.5 * dphi * gl_w[g] * std::abs(h) * std::cos(phi) / std::sqrt(2 * E(x) / J);
      }
    a.push_back(next);
    t_turn.push_back(t_turn.back() + T);
  }
  ASSERT_EQ(a.size(), 8u);  // 7 swings, then rest
  const std::string text =
      "model P\n"
      "  World world(g = {0, -9.81, 0});\n"
      "  Revolute j(axis = {0, 0, 1}, q(start = " + Num(th0) + "), friction_torque = " + Num(F) +
      ", friction_exact = true);\n"
      "  Body bob(m = " + Num(m) + ", r_CM = {0, -" + Num(L) + ", 0});\n"
      "equation\n"
      "  connect(world.frame_b, j.frame_a);\n"
      "  connect(j.frame_b, bob.frame_a);\n"
      "end P;\n";
  auto l = LoadModel(text, {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    sim::MemorySink s = RunWith(*l->prog, how, t_turn.back() + 1.0, 0.1, {"j.q", "j.u"}, &r, 1e-11);
    ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
    const auto& ev = r.stats.events;
    ASSERT_EQ(ev.size(), a.size()) << how.name;  // the start's slip, 6 reversals, the rest
    double path = 0, q_prev = th0;
    for (size_t n = 1; n < a.size(); ++n) {
      EXPECT_NEAR(ev[n].time, t_turn[n], 1e-8) << how.name << " n = " << n;
      const size_t row = RowAt(s, ev[n].time);
      ASSERT_LT(row, s.rows.size()) << how.name;
      EXPECT_NEAR(s.rows[row][0], a[n], 1e-8) << how.name << " n = " << n;  // CVODE-BDF: 2.2e-9 off at rtol 1e-11
      path += std::abs(s.rows[row][0] - q_prev);
      q_prev = s.rows[row][0];
    }
    EXPECT_EQ(ev.back().kind.find("sticks"), 0u) << ev.back().kind;
    // Energy lost (kinetic 0 at both ends) = friction times path.
    EXPECT_NEAR(mgL * (std::cos(q_prev) - std::cos(th0)), F * path, 1e-8) << how.name;
    EXPECT_EQ(s.rows.back()[0], q_prev) << how.name;  // still there a second later
  }
}

// A double pendulum in the vertical plane: link 1 (m1 = 1, L1 = 1, centre 0.5, I1 = 1/12) on a
// frictionless joint, link 2 (m2 = 0.5, centre 0.4, I2 = 0.02) on a joint with friction_torque
// 1.5, static 2, started at q = {0, 0.5} at rest. Joint 2 stuck, the pair swings as one body
// (M11 constant); Lagrange's equations M q'' + h + G = tau with q2'' = u2 = 0 give
//   q1'' = -G1 / M11,   tau2 = M12 q1'' + m2 L1 c2 sin(q2) u1^2 + G2                     (1)
// the torque the stuck joint's row must supply, with u1^2 = 2 (V(0) - V(q1)) / M11 (energy:
// friction does no work while stuck). It slips at the first q1 where |tau2| = 2.
// If this fails, the stuck joint's constraint-row reaction is not Lagrange's, or the slip is
// not where it reaches the static bound.
TEST(ConstantFriction, StuckJointOfADoublePendulumHoldsLagrangesTorqueAndSlipsAtTheBound) {
  const double m1 = 1, L1 = 1, c1 = 0.5, I1 = 1.0 / 12, m2 = 0.5, c2 = 0.4, I2 = 0.02, q2 = 0.5, Fs = 2.0;
  const double M11 = I1 + m1 * c1 * c1 + I2 + m2 * (L1 * L1 + c2 * c2 + 2 * L1 * c2 * std::cos(q2));
  const double M12 = I2 + m2 * (c2 * c2 + L1 * c2 * std::cos(q2));
  auto V = [&](double q1) { return kG * ((m1 * c1 + m2 * L1) * std::sin(q1) + m2 * c2 * std::sin(q1 + q2)); };
  auto tau2 = [&](double q1, double u1) {  // (1)
    const double G1 = kG * ((m1 * c1 + m2 * L1) * std::cos(q1) + m2 * c2 * std::cos(q1 + q2));
    const double G2 = kG * m2 * c2 * std::cos(q1 + q2);
    return M12 * (-G1 / M11) + m2 * L1 * c2 * std::sin(q2) * u1 * u1 + G2;
  };
  const std::string text =
      ElbowPendulumText{.i1 = Num(I1),
                        .j2_mods = ", q(start = 0.5), friction_torque = 1.5, friction_torque_s = 2, friction_exact = true"}
          .Text();
  auto l = LoadModel(text, {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  const rt::Program& p = *l->prog;
  const std::vector<std::string> names = rt::StateNames(p);
  auto at = [&](const std::string& n) { return static_cast<size_t>(std::find(names.begin(), names.end(), n) - names.begin()); };
  ASSERT_EQ(names.size(), 4u);
  // The row's reaction at states off the run's path too (u1 free, joint 2 at rest).
  for (double q1 : {0.0, -0.7, 1.3})
    for (double u1 : {0.0, 0.9, -2.0}) {
      std::vector<double> y(4, 0.0);
      y[at("j1.q")] = q1, y[at("j2.q")] = q2, y[at("j1.u")] = u1;
      auto ws = rt::MakeWorkspace(p);
      sim::StickSlipEvents stick(p);
      ASSERT_EQ(stick.Start(*ws, 0.0, y.data()), 0);
      const double expect = tau2(q1, u1);
      if (std::abs(expect) > Fs) continue;  // slips at once: no holding torque
      ASSERT_EQ(stick.Modes()[0], 0.0) << "q1 = " << q1 << " u1 = " << u1;
      EXPECT_NEAR(stick.Modes()[1], expect, 1e-9 * (1 + std::abs(expect))) << "q1 = " << q1 << " u1 = " << u1;
    }
  // The run: stuck from the start, slipping at q1* with |tau2(q1*)| = Fs.
  auto margin = [&](double q1) { return Fs - std::abs(tau2(q1, std::sqrt(2 * (V(0) - V(q1)) / M11))); };
  const double q1_slip = FirstRoot(margin, 0.0, -1.0);
  EXPECT_NEAR(q1_slip, -1.15, 0.05);  // (where the table of (1) puts it)
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    sim::MemorySink s = RunWith(p, how, 1.5, 0.05, {"j1.q", "j2.q"}, &r, 1e-11);
    ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
    const auto& ev = r.stats.events;
    ASSERT_GE(ev.size(), 2u) << how.name;
    EXPECT_EQ(ev[0].kind.find("sticks"), 0u) << ev[0].kind;
    EXPECT_EQ(ev[1].kind.find("slips, backwards"), 0u) << ev[1].kind;
    const size_t row = RowAt(s, ev[1].time);
    ASSERT_LT(row, s.rows.size());
    EXPECT_NEAR(s.rows[row][0], q1_slip, 1e-8) << how.name;
    for (size_t i = 0; i <= row; ++i) EXPECT_EQ(s.rows[i][1], q2) << how.name << " t = " << s.times[i];
  }
}


// A block (m = 2) on a rail with friction_force F = 1 (static 1.5) and a stop at q_max = 1
// (e = 0.5). Pushed by P = 5 from rest at 0 it reaches the stop at t1 = 1 (a_down = (P - F)/m
// = 2, speed v1 = 2); each rebound (speed e v) flies back against P and friction together
// (a_up = (P + F)/m = 3: the friction reversed with the speed) for e v / a_up, slips forwards
// again at its apex and returns with a_down: impact k + 1 after e v_k (1/a_up + 1/sqrt(a_up
// a_down)) at speed v_{k+1} = e v_k sqrt(a_down / a_up), and rests at their accumulation.
// Then, started at rest on the stop and pushed by P = 3 - 2t, the stop and the friction hold
// it together (one state: the reaction's zero at P = 0, t = 1.5, is no event) until the pull
// passes the static friction, -P = 1.5 at t = 2.25, where it leaves the stop sliding back,
// q'' = (P + F)/m. Started on the stop pulled off by P = -1 + 2t instead (within the static
// friction, 1.5 or 1), it is held there for good: one event, its rest at the start (before:
// a stick, a slip into the stop and a rest again, the block never moving).
// If this fails, an impact does not pass through the friction, the rebound's friction keeps
// the old direction, the stop and the friction hold the block at the wrong times, or a held
// block logs events while it does not move.
TEST(ConstantFriction, BlockAgainstAnEndStopBouncesRestsLeavesAndSlips) {
  auto model = [](const std::string& start, const std::string& push, const std::string& fs = "1.5") {
    return "model B\n"
           "  World world(g = {0, -9.81, 0});\n"
           "  Prismatic s(axis = {1, 0, 0}, q(start = " + start + "), q_max = 1, restitution = 0.5, friction_force = 1, "
           "friction_force_s = " + fs + ", friction_exact = true);\n"
           "  Body box(m = 2);\n"
           "equation\n"
           "  connect(world.frame_b, s.frame_a);\n"
           "  connect(s.frame_b, box.frame_a);\n"
           "  s.tau = " + push + ";\n"
           "end B;\n";
  };
  auto l = LoadModel(model("0", "5"), {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  const double e = 0.5, a_up = 3, a_down = 2;
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    sim::MemorySink s = RunWith(*l->prog, how, 3.0, 0.1, {"s.q", "s.u"}, &r, 1e-11);
    ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
    std::vector<double> impacts;
    for (const auto& ev : r.stats.events)
      if (ev.kind.find("impact") == 0) impacts.push_back(ev.time);
    ASSERT_GE(impacts.size(), 3u) << how.name;
    double t_k = 1, v_k = 2;
    for (size_t k = 0; k < 3; ++k) {
      EXPECT_NEAR(impacts[k], t_k, 1e-8) << how.name << " k = " << k;
      t_k += e * v_k * (1 / a_up + 1 / std::sqrt(a_up * a_down));
      v_k *= e * std::sqrt(a_down / a_up);
    }
    for (const auto& row : s.rows) EXPECT_LE(row[0], 1.0 + 1e-9) << how.name;
    EXPECT_EQ(s.rows.back()[0], 1.0) << how.name;  // at rest on the stop from t = 2.253
    EXPECT_EQ(s.rows.back()[1], 0.0) << how.name;
  }
  auto leave = LoadModel(model("1", "3 - 2 * time"), {}, {}, true);
  ASSERT_TRUE(leave && leave->prog) << (leave ? Messages(leave->errors) : "");
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    sim::MemorySink s = RunWith(*leave->prog, how, 3.0, 0.125, {"s.q"}, &r, 1e-11);
    ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
    std::string log;
    for (const auto& ev : r.stats.events) log += std::to_string(ev.time) + " " + ev.kind + "\n";
    ASSERT_EQ(r.stats.events.size(), 2u) << how.name << "\n" << log;
    EXPECT_EQ(r.stats.events[0].kind, "rests on q_max") << how.name << "\n" << log;
    EXPECT_EQ(r.stats.events[1].kind.find("leaves q_max, slides"), 0u) << how.name << "\n" << log;
    EXPECT_NEAR(r.stats.events[1].time, 2.25, 1e-9) << how.name << "\n" << log;
    for (size_t i = 0; i < s.rows.size(); ++i) {
      const double t = s.times[i], d = t - 2.25;
      // q'' = (P + F) / m = 2 - t = -0.25 - d from rest at d = 0: q = 1 - 0.125 d^2 - d^3 / 6.
      const double q = t <= 2.25 ? 1.0 : 1.0 - 0.125 * d * d - d * d * d / 6;
      EXPECT_NEAR(s.rows[i][0], q, 1e-9) << how.name << " t = " << t;
    }
  }
  // (With static = sliding friction 1 the pull at the start is at the bound: still held.)
  for (const char* fs : {"1.5", "1"}) {
  auto into = LoadModel(model("1", "-1 + 2 * time", fs), {}, {}, true);
  ASSERT_TRUE(into && into->prog) << (into ? Messages(into->errors) : "");
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    sim::MemorySink s = RunWith(*into->prog, how, 2.0, 0.125, {"s.q"}, &r, 1e-11);
    ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
    std::string log;
    for (const auto& ev : r.stats.events) log += std::to_string(ev.time) + " " + ev.element + ": " + ev.kind + "\n";
    ASSERT_EQ(r.stats.events.size(), 1u) << how.name << "\n" << log;
    EXPECT_EQ(r.stats.events[0].kind, "rests on q_max") << log;
    EXPECT_EQ(r.stats.events[0].time, 0.0) << log;
    for (const auto& row : s.rows) EXPECT_EQ(row[0], 1.0) << how.name;
  }
  }
}

}  // namespace
}  // namespace kanesim::test
