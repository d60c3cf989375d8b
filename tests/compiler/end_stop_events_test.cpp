// End stops as events (issue 41): impacts located by every integrator's root finding against
// the pendulum's exact (elliptic-integral) motion, Newton's law at the impact, the double
// pendulum's impulse against its momentum balance and energy, a joint resting on its stop and
// leaving it when the reaction would pull, and rows that never pass a stop.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "tests/compiler/compile_test_util.h"
#include "tests/support/model_texts.h"

namespace kanesim::test {
namespace {

constexpr double kG = 9.81;
const double kHalfPi = std::acos(0.0);

// A uniform rod (L = 1, m = 1) on a revolute about z under gravity -y: with phi = q + pi/2
// the angle from hanging down, phi'' = -w^2 sin(phi), w^2 = 3 g / (2 L).
const double kW = std::sqrt(1.5 * kG);

std::string Pendulum(double q0, const std::string& stop, const std::string& extra_eq = "") {
  return PendulumText{.mods = ", q(start = " + Num(q0) + ")" + stop, .equations = extra_eq}.Text();
}

// Time for the pendulum released at rest at phi0 > 0 to swing down through 0 to phi < 0
// (sin(phi/2) = k sin(psi), k = sin(phi0/2): t = (K(k) + F(psi, k)) / w).
double SwingTime(double phi0, double phi) {
  const double k = std::sin(phi0 / 2);
  return (std::comp_ellint_1(k) + std::ellint_1(k, std::asin(std::sin(std::abs(phi) / 2) / k))) / kW;
}

// If this fails, an impact on a stop is not located where the exact motion reaches it, the
// speed after is not -e times the speed before, the location depends on the integrator or
// the output grid, a row passes the stop, or the energy rises at an impact.
TEST(EndStopEvents, PendulumImpactsAtTheEllipticIntegralTimes) {
  const double phi0 = 1.0, phis = -0.5, e = 0.8;
  const double q_min = phis - kHalfPi;
  const double t1 = SwingTime(phi0, phis);
  const double v1 = -std::sqrt(2 * kW * kW * (std::cos(phis) - std::cos(phi0)));
  // After the rebound it swings up to phi1 and back: twice the swing from phi1 to phis.
  const double phi1 = std::acos(std::cos(phis) - (e * v1) * (e * v1) / (2 * kW * kW));
  const double t2 = t1 + 2 * SwingTime(phi1, phis);
  auto l = LoadModel(Pendulum(phi0 - kHalfPi, ", q_min = " + Num(q_min) + ", restitution = 0.8"), {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  for (double interval : {0.1, 0.07}) {
    for (const IntegratorChoice& how : AllIntegrators()) {
      sim::SimResult r;
      sim::MemorySink s = RunWith(*l->prog, how, 2.0, interval, {"j1.q", "j1.u", "kinetic_energy"}, &r, 1e-11);
      ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
      const std::vector<size_t> at = EventRows(s);
      ASSERT_EQ(at.size(), 2u) << how.name;
      ASSERT_EQ(r.stats.events.size(), 2u) << how.name;
      EXPECT_NEAR(s.times[at[0]], t1, 1e-9) << how.name << " interval " << interval;
      EXPECT_NEAR(s.times[at[1]], t2, 1e-9) << how.name << " interval " << interval;
      EXPECT_EQ(r.stats.events[0].time, s.times[at[0]]);
      EXPECT_EQ(r.stats.events[0].element, "j1");
      EXPECT_NEAR(s.rows[at[0]][1], v1, 1e-9 * std::abs(v1)) << how.name;
      EXPECT_EQ(s.rows[at[0] + 1][1], -e * s.rows[at[0]][1]) << how.name;  // Newton's law
      EXPECT_NEAR(s.rows[at[1]][1], e * v1, 1e-8 * std::abs(v1)) << how.name;  // after 1.8 s of motion
      EXPECT_EQ(s.rows[at[1] + 1][1], -e * s.rows[at[1]][1]) << how.name;
      for (size_t i : at) {
        EXPECT_EQ(s.rows[i + 1][0], q_min) << how.name;  // on the stop
        EXPECT_LE(s.rows[i + 1][2], s.rows[i][2] * (1 + 1e-12)) << how.name << ": energy rose at t = " << s.times[i];
        EXPECT_NEAR(s.rows[i + 1][2], e * e * s.rows[i][2], 1e-9 * s.rows[i][2]) << how.name;
      }
      for (size_t i = 0; i < s.rows.size(); ++i)
        EXPECT_GE(s.rows[i][0], q_min - 1e-12) << how.name << ": row " << i << " passed the stop";
    }
  }
}

// A pendulum from its bottom with amplitude phi_m = 0.8 towards a stop at phi_s = phi_m - d:
// for d > 0 it reaches the stop at t = F(psi, k) / w (sin(phi_s / 2) = k sin(psi), k =
// sin(phi_m / 2)) at the speed -sqrt(2 w^2 (cos(phi_s) - cos(phi_m))), slow for small d: the
// gap dips below zero and back inside one solver step (a graze). For d = 0 it touches the
// stop at zero speed every period: no impulse, the energy kept. If this fails, a near-graze
// impact is missed (the motion passes through the stop between two steps' ends, as before the
// graze guards), located off the closed form, or a touch chatters or costs energy.
TEST(EndStopEvents, GrazesAreNeitherMissedNorChattering) {
  const double phi_m = 0.8, k = std::sin(phi_m / 2), u0 = -2 * kW * k;
  for (double d : {1e-3, 1e-6, 0.0}) {
    const double phi_s = phi_m - d, q_min = -kHalfPi - phi_s;
    const double t_hit = std::ellint_1(k, std::asin(std::sin(phi_s / 2) / k)) / kW;
    const double v_hit = -std::sqrt(2 * kW * kW * (std::cos(phi_s) - std::cos(phi_m)));
    auto l = LoadModel(Pendulum(-kHalfPi, ", u(start = " + Num(u0) + "), q_min = " + Num(q_min) + ", restitution = 0.5"),
                       {}, {}, true);
    ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
    for (const IntegratorChoice& how : AllIntegrators()) {
      sim::SimResult r;
      sim::MemorySink s = RunWith(*l->prog, how, 6.0, 0.05, {"j1.q", "j1.u", "kinetic_energy", "potential_energy"}, &r, 1e-10);
      ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << " d " << d << ": " << r.message;
      const std::vector<size_t> at = EventRows(s);
      for (size_t i = 0; i < s.rows.size(); ++i)
        ASSERT_GE(s.rows[i][0], q_min - 1e-9) << how.name << " d " << d << ": row " << i << " passed the stop";
      if (d > 0.0) {
        ASSERT_GE(at.size(), 1u) << how.name << " d " << d << ": the impact was missed";
        EXPECT_NEAR(s.times[at[0]], t_hit, d > 1e-5 ? 1e-8 : 1e-6) << how.name << " d " << d;
        EXPECT_NEAR(s.rows[at[0]][1], v_hit, (d > 1e-5 ? 1e-6 : 1e-3) * std::abs(v_hit)) << how.name << " d " << d;
        EXPECT_NEAR(s.rows[at[0] + 1][1], -0.5 * s.rows[at[0]][1], 1e-12) << how.name;
      } else {
        EXPECT_LE(at.size(), 4u) << how.name << ": touches at T/4 + n T (T = 1.703 s) chatter";
        const double e0 = s.rows.front()[2] + s.rows.front()[3], e1 = s.rows.back()[2] + s.rows.back()[3];
        EXPECT_NEAR(e1, e0, 1e-7 * std::abs(e0)) << how.name << ": a touch took energy";
      }
    }
  }
}

// If this fails, a plastic impact does not leave the joint resting on its stop (q at the
// limit, u = 0 exactly) while the stop pushes, or it does not leave when the reaction would
// pull: the torque tau = 2 t balances gravity's on the rod held at phi_s when
// 2 t = (m g L / 2) sin(phi_s).
TEST(EndStopEvents, RestsOnTheStopUntilTheReactionWouldPull) {
  const double phis = 0.5, q_min = phis - kHalfPi;
  const double t_leave = 0.5 * kG * std::sin(phis) / 2.0;
  auto l = LoadModel(Pendulum(1.0 - kHalfPi, ", q_min = " + Num(q_min), "  j1.tau = 2 * time;\n"), {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    sim::MemorySink s = RunWith(*l->prog, how, 1.5, 0.05, {"j1.q", "j1.u"}, &r, 1e-11);
    ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
    ASSERT_EQ(r.stats.events.size(), 3u) << how.name;  // impact, rests on, leaves
    EXPECT_NE(r.stats.events[1].kind.find("rests on q_min"), std::string::npos) << r.stats.events[1].kind;
    EXPECT_EQ(r.stats.events[2].kind, "leaves q_min");
    const double t1 = r.stats.events[0].time;
    EXPECT_NEAR(r.stats.events[2].time, t_leave, 1e-9) << how.name;
    for (size_t i = 0; i < s.rows.size(); ++i) {
      EXPECT_GE(s.rows[i][0], q_min - 1e-12) << how.name << ": row " << i;
      if (s.times[i] > t1 && s.times[i] < t_leave) {
        EXPECT_EQ(s.rows[i][0], q_min) << how.name << " t = " << s.times[i];
        EXPECT_EQ(s.rows[i][1], 0.0) << how.name << " t = " << s.times[i];
      }
    }
    EXPECT_GT(s.rows.back()[0], q_min + 1e-3) << how.name << ": it left the stop";
  }
}

// Two rods (L1 = 1, m1 = 1; L2 = 0.8, m2 = 0.7) whose first joint stops at q_min.
std::string DoublePendulum(double q_min, double e) {
  return TwoRodText(", q_min = " + Num(q_min) + ", restitution = " + Num(e), ", q(start = 0.3), u(start = 0.5)");
}

// Two rods (L1 = 1, m1 = 1; L2 = 0.8, m2 = 0.7); j1 hits q_min. Kane's impulsive form
// M du = e1 lambda: du1 = -(1 + e) u1, and the second row (the angular momentum of rod 2
// about joint 2) gives du2 = -(M21 / M22) du1, with q2 the relative angle:
//   M11 = m1 L1^2/3 + m2 (L1^2 + L2^2/3 + L1 L2 cos q2), M12 = m2 (L2^2/3 + L1 L2 cos(q2)/2),
//   M22 = m2 L2^2/3.
// If this fails, the other joint's speed does not follow through the mass matrix, an elastic
// impact (e = 1) changes the kinetic energy, or one with restitution e loses other than
// (1 - e)/(1 + e) (1/2) du^T M du (all of it when plastic, e = 0). (Up to t = 0.8: with e = 0.4 the bounces accumulate near t = 0.87.)
TEST(EndStopEvents, DoublePendulumImpulseThroughTheMassMatrix) {
  const double L1 = 1, m1 = 1, L2 = 0.8, m2 = 0.7, q_min = -0.6;
  for (double e : {1.0, 0.0, 0.4}) {
    const std::string text = DoublePendulum(q_min, e);
    auto l = LoadModel(text, {}, {}, true);
    ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
    for (const IntegratorChoice& how : AllIntegrators()) {
      sim::SimResult r;
      sim::MemorySink s =
          RunWith(*l->prog, how, 0.8, 0.1, {"j1.q", "j1.u", "j2.q", "j2.u", "kinetic_energy"}, &r, 1e-11);
      ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
      const std::vector<size_t> at = EventRows(s);
      ASSERT_GE(at.size(), 1u) << how.name;
      const std::vector<double>& a = s.rows[at[0]];
      const std::vector<double>& b = s.rows[at[0] + 1];
      const double c2 = std::cos(a[2]);
      const double M11 = m1 * L1 * L1 / 3 + m2 * (L1 * L1 + L2 * L2 / 3 + L1 * L2 * c2);
      const double M12 = m2 * (L2 * L2 / 3 + L1 * L2 * c2 / 2), M22 = m2 * L2 * L2 / 3;
      const double du1 = -(1 + e) * a[1], du2 = -M12 / M22 * du1;
      const double scale = std::abs(a[1]) + std::abs(a[3]);
      EXPECT_EQ(b[2], a[2]) << how.name;
      EXPECT_NEAR(b[1], a[1] + du1, 1e-12 * scale) << how.name << " e = " << e;
      EXPECT_NEAR(b[3], a[3] + du2, 1e-9 * scale) << how.name << " e = " << e;
      const double T_before = 0.5 * (M11 * a[1] * a[1] + 2 * M12 * a[1] * a[3] + M22 * a[3] * a[3]);
      EXPECT_NEAR(a[4], T_before, 1e-9 * T_before) << how.name << ": the closed-form M";
      // One row struck: T+ - T- = v lambda + lambda^2 / (2 m_eff) with lambda = -(1 + e) v m_eff,
      // so the loss is (1 - e)/(1 + e) of 1/2 du' M du (all of it plastic, none elastic).
      const double half_duMdu = 0.5 * (M11 * du1 * du1 + 2 * M12 * du1 * du2 + M22 * du2 * du2);
      EXPECT_NEAR(a[4] - b[4], (1 - e) / (1 + e) * half_duMdu, 1e-9 * a[4]) << how.name << " e = " << e;
      if (e == 1.0) {
        EXPECT_NEAR(b[4], a[4], 1e-9 * a[4]) << how.name << ": elastic";
      }
      for (size_t i : at) EXPECT_LE(s.rows[i + 1][4], s.rows[i][4] * (1 + 1e-12)) << how.name;
      for (size_t i = 0; i < s.rows.size(); ++i) EXPECT_GE(s.rows[i][0], q_min - 1e-12) << how.name << " row " << i;
    }
  }
}

// Past t = 0.87 the e = 0.4 bounces of the double pendulum above accumulate (a Zeno
// sequence): they pass to rest on the stop at their accumulation point, where j2 keeps
// swinging and pulls j1 off the stop again. If this fails, such a run ends in a step-size
// underflow or stops at a missed impact (exit 2) instead of resting, or a row passes the stop.
TEST(EndStopEvents, AccumulatingImpactsPassToRest) {
  const double q_min = -0.6;
  const std::string text = DoublePendulum(q_min, 0.4);
  auto l = LoadModel(text, {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  for (const IntegratorChoice& how : AllIntegrators()) {
    for (double tol : {1e-6, 1e-11}) {
      sim::SimResult r;
      sim::MemorySink s = RunWith(*l->prog, how, 3.0, 0.01, {"j1.q", "j1.u"}, &r, tol);
      ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << " " << tol << ": " << r.message;
      for (size_t i = 0; i < s.rows.size(); ++i)
        EXPECT_GE(s.rows[i][0], q_min - 10 * (tol + tol * 1.0)) << how.name << " " << tol << " row " << i;
      bool accumulated = false;
      for (const sim::EventRecord& ev : r.stats.events)
        accumulated = accumulated || ev.kind == "rests on q_min (accumulation point of the bounces)";
      EXPECT_TRUE(accumulated) << how.name << " " << tol;
    }
  }
}

// A carriage (jA, m = 1) thrust up by 39.62 N towards a ceiling (q_max = 0.15, restitution e)
// carries a block (jB, m = 1) resting on it (q_min = 0): both rise at a = 10, pressed together,
// and reach the ceiling at t1 = sqrt(0.03) with speed sqrt(3). The blow on the carriage pulls
// it down, away from the block; the block's stop can only push, so it leaves: the carriage's
// speed becomes -e sqrt(3), the block keeps its sqrt(3) (uB = (1 + e) sqrt(3), relative). If
// this fails, an impact holds a resting side whose impulse pulls: the block is dragged down
// with the carriage (uB stays 0), a silent wrong answer.
TEST(EndStopEvents, AnImpactNeverPullsOnARestingStop) {
  for (double e : {0.0, 0.5, 1.0}) {
    const std::string text =
        "model Carriage\n"
        "  World world(g = {0, -9.81, 0});\n"
        "  Prismatic jA(axis = {0, 1, 0}, q_max = 0.15, restitution = " + Num(e) + ");\n"
        "  Body carriage(m = 1);\n"
        "  Prismatic jB(axis = {0, 1, 0}, q_min = 0, restitution = 0);\n"
        "  Body box(m = 1);\n"
        "equation\n"
        "  jA.tau = 39.62;\n"
        "  connect(world.frame_b, jA.frame_a);\n"
        "  connect(jA.frame_b, carriage.frame_a);\n"
        "  connect(jA.frame_b, jB.frame_a);\n"
        "  connect(jB.frame_b, box.frame_a);\n"
        "end Carriage;\n";
    auto l = LoadModel(text, {}, {}, true);
    ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
    const double t1 = std::sqrt(0.03), v = std::sqrt(3.0);
    for (const IntegratorChoice& how : AllIntegrators()) {
      sim::SimResult r;
      sim::MemorySink s = RunWith(*l->prog, how, 0.25, 0.01, {"jA.q", "jA.u", "jB.q", "jB.u"}, &r, 1e-11);
      ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
      const std::vector<size_t> at = EventRows(s);
      ASSERT_GE(at.size(), 1u) << how.name;
      const size_t i = at[0];
      EXPECT_NEAR(s.times[i], t1, 1e-9) << how.name << " e = " << e;
      EXPECT_NEAR(s.rows[i][1], v, 1e-9) << how.name;
      EXPECT_NEAR(s.rows[i][3], 0.0, 1e-12) << how.name << ": resting on the carriage before";
      EXPECT_NEAR(s.rows[i + 1][1], -e * v, 1e-9) << how.name << " e = " << e;
      EXPECT_NEAR(s.rows[i + 1][3], (1 + e) * v, 1e-9) << how.name << " e = " << e << ": the block keeps its speed";
      for (size_t k = 0; k < s.rows.size(); ++k) EXPECT_GE(s.rows[k][2], -1e-12) << how.name << " row " << k;
    }
  }
}

// A five-link chain (heavy links, then a light damped tip) with plastic stops on four joints.
std::string ChainText() {
  return
      "model Chain\n"
      "  parameter Real d(unit = \"N.m.s\") = 0.02;\n"
      "  World world(g = {0, -9.81, 0});\n"
      "  Revolute j1(axis = {0, 0, 1}, q(start = -1.2));\n"
      "  Revolute j2(axis = {0, 0, 1}, q(start = 0.9), q_min = 0, q_max = 2.5, restitution = 0);\n"
      "  Revolute j3(axis = {0, 0, 1}, q(start = -0.8), q_min = -1.0, q_max = 1.0, restitution = 0);\n"
      "  Revolute j4(axis = {0, 0, 1}, q(start = 0.5), q_min = -0.3, q_max = 0.6, restitution = 0);\n"
      "  Revolute j5(axis = {0, 0, 1}, q(start = 0), q_min = -0.5, q_max = 0, restitution = 0);\n"
      "  Rod r1(L = 1, m = 5);\n"
      "  Rod r2(L = 0.8, m = 3);\n"
      "  Rod r3(L = 0.5, m = 1);\n"
      "  Rod r4(L = 0.3, m = 0.5);\n"
      "  Rod r5(L = 0.05, m = 0.01);\n"
      "equation\n"
      "  j5.tau = -d * j5.u;\n"
      "  connect(world.frame_b, j1.frame_a);\n"
      "  connect(j1.frame_b, r1.frame_a);\n"
      "  connect(r1.frame_b, j2.frame_a);\n"
      "  connect(j2.frame_b, r2.frame_a);\n"
      "  connect(r2.frame_b, j3.frame_a);\n"
      "  connect(j3.frame_b, r3.frame_a);\n"
      "  connect(r3.frame_b, j4.frame_a);\n"
      "  connect(j4.frame_b, r4.frame_a);\n"
      "  connect(r4.frame_b, j5.frame_a);\n"
      "  connect(j5.frame_b, r5.frame_a);\n"
      "end Chain;\n";
}

// A five-link chain (heavy links, then a light damped tip) with plastic stops on four joints:
// several joints come to rest on their stops at once, an impact on one pushes another that
// sits on its stop, and the tip is stiff (a small inertia, damped). If this fails, a column
// of M^-1 is lost to rounding at a trial stage with large accelerations ("the mass matrix is
// singular for an impulse", before the fix under DOP853), a side left resting while it pulls
// or sitting on its stop while pushed in is missed (a row past the stop), or an impact adds
// energy.
TEST(EndStopEvents, ChainWithManyStopsRestsAndStrikesTogether) {
  const std::string text = ChainText();
  auto l = LoadModel(text, {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  const double lo[4] = {0, -1.0, -0.3, -0.5}, hi[4] = {2.5, 1.0, 0.6, 0};
  for (const IntegratorChoice& how : AllIntegrators()) {
    const double tol = 1e-6;
    sim::SimResult r;
    sim::MemorySink s = RunWith(*l->prog, how, 3.0, 0.01, {"j2.q", "j3.q", "j4.q", "j5.q", "kinetic_energy"}, &r, tol);
    ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
    EXPECT_EQ(s.times.back(), 3.0) << how.name;
    for (size_t i = 0; i < s.rows.size(); ++i)
      for (int k = 0; k < 4; ++k) {
        EXPECT_GE(s.rows[i][k], lo[k] - 10 * (tol + tol * std::max(1.0, std::abs(lo[k])))) << how.name << " row " << i;
        EXPECT_LE(s.rows[i][k], hi[k] + 10 * (tol + tol * std::max(1.0, std::abs(hi[k])))) << how.name << " row " << i;
      }
    const std::vector<size_t> at = EventRows(s);
    EXPECT_GE(at.size(), 4u) << how.name;
    for (size_t i : at) EXPECT_LE(s.rows[i + 1][4], s.rows[i][4] * (1 + 1e-9) + 1e-12) << how.name << " t = " << s.times[i];
    int rests = 0;
    for (const sim::EventRecord& ev : r.stats.events) rests += ev.kind.rfind("rests on", 0) == 0 ? 1 : 0;
    EXPECT_GE(rests, 2) << how.name;
  }
}

// The chain above under ARKODE at every tolerance from 1e-5 to 1e-9, against DOP853 at 1e-11:
// the same events (element and kind) at the same times, and the same rows, each to 10 times
// the tolerance. If this fails, ERKStep began each step from a stale first stage (SUNDIALS
// 6.4 reuses a last stage at c = 1 as the next step's first although its state is not the
// step's solution: seven error-test failures in a row down to h ~ 5e-7 in smooth motion, exit
// 2 at rtol 1e-5, 1e-8 and 1e-9 before the fix), or its rows come from its degree-5
// interpolant across steps of an 8th-order pair (1e-7 off at rtol 1e-9 where a joint rests).
TEST(EndStopEvents, ChainUnderArkodeAgreesWithDop853AtEveryTolerance) {
  auto l = LoadModel(ChainText(), {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  const std::vector<std::string> signals = {"j1.q", "j2.q", "j3.q", "j4.q", "j5.q"};
  sim::SimResult ref;
  const sim::MemorySink rs = RunWith(*l->prog, {"DOP853", rt::Integrator::Dop853}, 3.0, 0.01, signals, &ref, 1e-11);
  ASSERT_EQ(ref.status, sim::SimResult::Status::kOk) << ref.message;
  ASSERT_GE(ref.stats.events.size(), 20u);
  auto what = [](const sim::EventRecord& e) { return e.element + " " + e.kind.substr(0, e.kind.find(',')); };
  for (double tol : {1e-5, 1e-6, 1e-7, 1e-8, 1e-9}) {
    sim::SimResult r;
    const sim::MemorySink s = RunWith(*l->prog, {"ARKODE", rt::Integrator::ArkodeErk}, 3.0, 0.01, signals, &r, tol);
    ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << "rtol " << tol << ": " << r.message;
    ASSERT_EQ(r.stats.events.size(), ref.stats.events.size()) << "rtol " << tol;
    for (size_t i = 0; i < ref.stats.events.size(); ++i) {
      EXPECT_EQ(what(r.stats.events[i]), what(ref.stats.events[i])) << "rtol " << tol << " event " << i;
      EXPECT_NEAR(r.stats.events[i].time, ref.stats.events[i].time, 10 * tol) << "rtol " << tol << " event " << i;
    }
    // Rows at the output grid's times (the first row at each time: an event's left limit).
    size_t k = 0, compared = 0;
    for (size_t i = 0; i < s.times.size(); ++i) {
      if (i > 0 && s.times[i] == s.times[i - 1]) continue;
      while (k < rs.times.size() && rs.times[k] < s.times[i]) ++k;
      if (k == rs.times.size() || rs.times[k] != s.times[i]) continue;
      for (size_t c = 0; c < signals.size(); ++c)
        EXPECT_NEAR(s.rows[i][c], rs.rows[k][c], 10 * tol) << "rtol " << tol << " " << signals[c] << " t = " << s.times[i];
      ++compared;
    }
    EXPECT_GE(compared, 300u) << "rtol " << tol;
  }
}

}  // namespace
}  // namespace kanesim::test
