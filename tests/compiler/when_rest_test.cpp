// A when clause's reinit of a joint resting on its end stop (docs/events.md "Statements"):
// away from the stop it releases the joint, which then swings as the free pendulum started
// there (checked against the elliptic-integral closed form); into the stop it is an impact by
// the stop's restitution; the other joint of a double pendulum follows through the impulse.
// Before, each of these stopped the run (exit 2: "a reinit of a resting joint's speed is not
// handled yet"), and a reinit of the coordinate left the joint held (and its rows snapped) at
// the stop.
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
const double kHalfPi = std::acos(0.0);
const double kW = std::sqrt(1.5 * kG);  // the rod pendulum's w^2 = 3 g / (2 L), L = 1
constexpr double kStop = -2.0;          // q_max: gravity presses the rod (hanging at -pi/2) onto it

// The rod pendulum swinging with amplitude phi_a (angle from hanging): the time from the
// turning point to the angle phi, (K(k) - F(psi, k)) / w, k = sin(phi_a / 2), sin psi = sin(|phi| / 2) / k.
double FromTurn(double phi, double phi_a) {
  const double k = std::sin(phi_a / 2);
  return (std::comp_ellint_1(k) - std::ellint_1(k, std::asin(std::min(1.0, std::sin(std::abs(phi) / 2) / k)))) / kW;
}

// The amplitude of the swing through phi at speed u: u^2 = 2 w^2 (cos phi - cos phi_a).
double Amplitude(double phi, double u) { return std::acos(std::cos(phi) - u * u / (2 * kW * kW)); }

// The rod at rest on q_max = kStop (restitution e); `when` the clause.
std::string Resting(double e, const std::string& when) {
  return PendulumText{.mods = ", q(start = " + Num(kStop) + "), q_max = " + Num(kStop) + ", restitution = " + Num(e),
                      .equations = when}
      .Text();
}

bool Logged(const sim::SimResult& r, double t, const std::string& kind) {
  for (const sim::EventRecord& e : r.stats.events)
    if (std::abs(e.time - t) < 1e-9 && e.kind.rfind(kind, 0) == 0) return true;
  return false;
}

// reinit(j1.u, -2) at t = 1 moves the rod off its stop: from then on it is the free pendulum
// started at (q_max, -2): every row's angle at the time the elliptic integral gives (its error
// times the speed below 1e-8, a distance), back on the stop at t = 1 + 2 T(phi0), where its
// plastic stop holds it again. If this fails, the reinit is refused, the joint stays held, or
// it moves as something other than the free pendulum.
TEST(WhenRest, ReinitAwayFromTheStopReleasesIt) {
  const double phi0 = kStop + kHalfPi, phi_a = Amplitude(phi0, -2.0), back = 1 + 2 * FromTurn(phi0, phi_a);
  auto l = LoadModel(Resting(0.0, "  when time > 1 then\n    reinit(j1.u, -2);\n  end when;\n"), {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    sim::MemorySink s = RunWith(*l->prog, how, 2.0, 0.02, {"j1.q", "j1.u"}, &r, 1e-12);
    ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
    const std::vector<size_t> at = EventRows(s);
    ASSERT_EQ(at.size(), 2u) << how.name << ": the reinit and the return to the stop";
    EXPECT_NEAR(s.times[at[0]], 1.0, 1e-12) << how.name;
    EXPECT_EQ(s.rows[at[0]][1], 0.0);
    EXPECT_EQ(s.rows[at[0] + 1][0], kStop);
    EXPECT_EQ(s.rows[at[0] + 1][1], -2.0);
    EXPECT_TRUE(Logged(r, 1.0, "leaves q_max")) << how.name;
    EXPECT_NEAR(s.times[at[1]], back, 1e-9) << how.name;
    EXPECT_TRUE(Logged(r, back, "impact at q_max")) << how.name;
    int checked = 0;
    for (size_t i = 0; i < s.times.size(); ++i) {
      const double t = s.times[i], q = s.rows[i][0], u = s.rows[i][1];
      if (t < 1.0 || t > s.times[at[1]]) {
        EXPECT_EQ(q, kStop) << how.name << " t " << t << ": resting";
        EXPECT_EQ(u, 0.0) << how.name << " t " << t;
        continue;
      }
      if (t == 1.0 || t == s.times[at[1]]) continue;
      const double phi = q + kHalfPi;  // out (u < 0) towards -phi_a, then back
      const double t_exact = 1 + FromTurn(phi0, phi_a) + (u < 0 ? -1 : 1) * FromTurn(phi, phi_a);
      EXPECT_LT(std::abs(t - t_exact) * std::abs(u), 1e-8) << how.name << " t " << t << " q " << q;
      EXPECT_NEAR(u * u, 2 * kW * kW * (std::cos(phi) - std::cos(phi_a)), 1e-8) << how.name << " t " << t;
      ++checked;
    }
    EXPECT_GE(checked, 10) << how.name;
  }
}

// reinit(j1.u, 2) pushes the rod into its stop: an impact with the stop's restitution, so the
// right limit has u = -e 2 (e = 0.5: it swings away at -1 and returns at 1 + 2 T(phi0)); with
// e = 0 it stays resting, u = 0 on every later row. If this fails, a reinit into the stop is
// refused or leaves the joint moving into the stop.
TEST(WhenRest, ReinitIntoTheStopIsAnImpact) {
  for (double e : {0.5, 0.0}) {
    auto l = LoadModel(Resting(e, "  when time > 1 then\n    reinit(j1.u, 2);\n  end when;\n"), {}, {}, true);
    ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
    const double phi0 = kStop + kHalfPi, back = 1 + 2 * FromTurn(phi0, Amplitude(phi0, 2 * e));
    for (const IntegratorChoice& how : AllIntegrators()) {
      sim::SimResult r;
      sim::MemorySink s = RunWith(*l->prog, how, 2.0, 0.05, {"j1.q", "j1.u"}, &r, 1e-12);
      ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
      const std::vector<size_t> at = EventRows(s);
      ASSERT_GE(at.size(), 1u) << how.name;
      EXPECT_NEAR(s.times[at[0]], 1.0, 1e-12) << how.name;
      EXPECT_EQ(s.rows[at[0] + 1][1], -e * 2) << how.name << " e " << e;
      EXPECT_TRUE(Logged(r, 1.0, "impact at q_max, speed 2 ->")) << how.name;
      if (e == 0.0) {
        EXPECT_EQ(at.size(), 1u) << how.name;
        for (size_t i = at[0]; i < s.times.size(); ++i) EXPECT_EQ(s.rows[i][1], 0.0) << how.name << " t " << s.times[i];
      } else {
        ASSERT_GE(at.size(), 2u) << how.name;
        EXPECT_NEAR(s.times[at[1]], back, 1e-9) << how.name;
        EXPECT_NEAR(s.rows[at[1]][1], 1.0, 1e-9) << how.name << ": back at the speed it left with";
      }
    }
  }
}

// Two rods, j1 resting on q_max = -2 (restitution 1/2), rod 2 hanging straight down
// (q2 = 2 - pi/2). A reinit of j1's speed is an impulse on joint 1 alone (and, into the stop,
// the stop's impact on the same joint), so joint 2's generalized momentum is kept:
//   u2+ = u2- + (1 + 3 L1 cos(q2) / (2 L2)) (u1- - u1+)   (tests/compiler/when_events_test.cpp)
// with u1+ = -2 (away) or -e 1.5 (into the stop). If this fails, u2 is left stale or the jump
// breaks the momentum balance, or the reinit is refused.
TEST(WhenRest, OtherJointFollowsTheImpulse) {
  const double L1 = 1, L2 = 0.8, e = 0.5;
  for (double set : {-2.0, 1.5}) {
    const std::string text =
        TwoRodText(", q(start = -2), q_max = -2, restitution = 0.5", ", q(start = " + Num(2 - kHalfPi) + ")",
                   "  when time > 0.5 then\n    reinit(j1.u, " + Num(set) + ");\n  end when;\n");
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
      EXPECT_EQ(a[0], -2.0) << how.name << ": resting until the reinit";
      EXPECT_EQ(a[1], 0.0) << how.name;
      EXPECT_NEAR(a[3], 0.0, 1e-9) << how.name << ": rod 2 hangs still";
      const double u1 = set < 0 ? set : -e * set;
      EXPECT_EQ(b[1], u1) << how.name;
      EXPECT_EQ(b[0], a[0]);
      EXPECT_EQ(b[2], a[2]);
      const double u2 = a[3] + (1 + 3 * L1 * std::cos(a[2]) / (2 * L2)) * (a[1] - u1);
      EXPECT_NEAR(b[3], u2, 1e-10) << how.name << " reinit " << set;
      EXPECT_LT(s.rows.back()[0], -2.0) << how.name << ": j1 swung off its stop";
    }
  }
}

// reinit(j1.q, -2.3) of the rod resting on q_max = -2 sets it down off the stop at rest: it
// swings from there (amplitude 0.73 from hanging) and strikes the stop at
// t = 1 + T(phi_stop), T the time from the turning point. If this fails, the joint stays held with its rows snapped
// to the stop, or the coordinate is not set.
TEST(WhenRest, ReinitOfTheCoordinateReleasesIt) {
  const double phi_a = 2.3 - kHalfPi, hit = 1 + FromTurn(kStop + kHalfPi, phi_a);
  auto l = LoadModel(Resting(0.0, "  when time > 1 then\n    reinit(j1.q, -2.3);\n  end when;\n"), {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    sim::MemorySink s = RunWith(*l->prog, how, 1.5, 0.02, {"j1.q", "j1.u"}, &r, 1e-12);
    ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
    const std::vector<size_t> at = EventRows(s);
    ASSERT_EQ(at.size(), 2u) << how.name;
    EXPECT_EQ(s.rows[at[0] + 1][0], -2.3) << how.name;
    EXPECT_EQ(s.rows[at[0] + 1][1], 0.0) << how.name;
    EXPECT_LT(s.rows[at[0] + 2][0], -2.0) << how.name << ": not held at the stop";
    EXPECT_NEAR(s.times[at[1]], hit, 1e-9) << how.name;
  }
}

}  // namespace
}  // namespace kanesim::test
