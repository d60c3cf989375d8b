// Plane contacts beside Coulomb friction mu N (issue 41; docs/stdlib.md "PlaneContact"). A
// carriage (m_c) on a prismatic joint cx along x with friction mu, and on it a leg: a
// revolute about z at the carriage's origin, a massless rod of length L and a point mass m_l
// at its tip, which touches the floor y = -L cos(phi) (the leg at angle q = phi).
// Resting, the tip keeps its height, so q stays phi and the tip moves with the carriage
// (acceleration a). The rod's force T along it, the floor's lambda, the rail's N (hand statics):
//   tip:      m_l a = -T sin phi,   0 = T cos phi - m_l g + lambda
//   carriage: N = m_c g + T cos phi = m_c g - m_l a cot phi,   lambda = m_l (g + a cot phi)
// and the whole: (m_c + m_l) a = F - s mu N (sliding in direction s), so
//   a = (F - s mu m_c g) / D_s,   D_s = m_c + m_l - s mu m_l cot phi                   (1)
// Stuck: a = 0, N = m_c g (the floor carries the leg), the bound mu m_c g. The speed
// between a slip at t_a and the next stop is the integral of (1), zero where
//   F0 (cos w t_a - cos w t) / w - s mu m_c g (t - t_a) = 0   (F = F0 sin w t)        (2)
// Lift-off: lambda = 0 where a = -g tan phi.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "tests/compiler/compile_test_util.h"
#include "tests/support/model_texts.h"

namespace kanesim::test {
namespace {

constexpr double kMc = CarriageLegText::kMc, kMl = CarriageLegText::kMl, kL = CarriageLegText::kL;
constexpr double kPhi = CarriageLegText::kPhi, kMu = CarriageLegText::kMu, kG = 9.81;
const double kCot = 1.0 / std::tan(kPhi);

std::string Leg(double g, double uc0, double q0, double w0, double e, const std::string& law, const std::string& drive) {
  return CarriageLegText{.g = g, .uc0 = uc0, .q0 = q0, .w0 = w0, .e = e, .law = law, .equations = drive}.Text();
}

const std::vector<std::string> kLaws = {", friction_v = 1e-9", ", friction_exact = true"};

// If this fails, the floor's force is left out of the rail's normal force (the leg's weight
// counted in N: a bound mu (m_c + m_l) g, a later slip), or the acceleration's share of N
// (m_l a cot phi) is missing (the speeds off (1)), or the tip leaves the floor while it pushes.
TEST(PlaneFriction, DrivenCarriageSticksAndSlipsAtTheHandTimes) {
  const double F0 = 8.0, w = 3.0, c = kMu * kMc * kG;
  const double t1 = std::asin(c / F0) / w;  // F reaches the bound mu m_c g: slips forwards
  auto bracket = [&](double ta, double s) {
    return [=](double t) { return F0 * (std::cos(w * ta) - std::cos(w * t)) / w - s * c * (t - ta); };  // (2)
  };
  const double t2 = Bisect(bracket(t1, 1.0), t1 + 0.5, t1 + 1.0);  // stops (F(t2) within the bound: sticks)
  const double t3 = (M_PI + std::asin(c / F0)) / w;               // F reaches -mu m_c g: slips backwards
  const double t4 = Bisect(bracket(t3, -1.0), t3 + 0.5, t3 + 1.0);
  ASSERT_LT(std::abs(F0 * std::sin(w * t2)), c);
  ASSERT_LT(std::abs(F0 * std::sin(w * t4)), c);
  auto speed = [&](double t) {  // (1) integrated
    if (t > t1 && t < t2) return bracket(t1, 1.0)(t) / (kMc + kMl - kMu * kMl * kCot);
    if (t > t3 && t < t4) return bracket(t3, -1.0)(t) / (kMc + kMl + kMu * kMl * kCot);
    return 0.0;
  };
  const std::string drive = "  cx.tau = " + Num(F0) + " * sin(" + Num(w) + " * time);\n";
  for (const IntegratorChoice& how : AllIntegrators()) {
    auto l = LoadModel(Leg(kG, 0.0, kPhi + 1e-12, 0.0, 0.0, ", friction_exact = true", drive), {}, {}, true);
    ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
    sim::SimResult r;
    const sim::MemorySink s = RunWith(*l->prog, how, 2.3, 0.05, {"cx.u", "leg.q"}, &r, 1e-11);
    ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
    const std::vector<double> slips = EventTimes(r, "cx", "slips");
    std::vector<double> sticks;  // (after the start's)
    for (double t : EventTimes(r, "cx", "sticks"))
      if (t > 0.1) sticks.push_back(t);
    ASSERT_EQ(slips.size(), 2u) << how.name;
    ASSERT_EQ(sticks.size(), 2u) << how.name;
    EXPECT_NEAR(slips[0], t1, 1e-8) << how.name;
    EXPECT_NEAR(sticks[0], t2, 1e-8) << how.name;
    EXPECT_NEAR(slips[1], t3, 1e-8) << how.name;
    EXPECT_NEAR(sticks[1], t4, 1e-8) << how.name;
    EXPECT_TRUE(EventTimes(r, "foot", "leaves").empty()) << how.name;
    for (size_t i = 0; i < s.times.size(); ++i) {
      // (the start 1e-12 above the floor: the tip lands at 1e-6 s with a tiny impact, whose
      // friction impulse moves the carriage by ~1e-7 until it sticks again)
      if (s.times[i] > 1e-3) {
        EXPECT_NEAR(s.rows[i][0], speed(s.times[i]), 1e-8) << how.name << " t = " << s.times[i];
      }
      EXPECT_NEAR(s.rows[i][1], kPhi, 1e-9) << how.name << " t = " << s.times[i];
    }
  }
}

// If this fails, the floor's force is not in the rail's normal force (the speeds off (1)), or
// the tip does not leave where that force turns tensile (lambda = m_l (g + a cot phi) = 0).
TEST(PlaneFriction, TipLiftsOffWhereTheFloorsForceVanishes) {
  const double k = 20.0, u0 = 5.0, c = kMu * kMc * kG, D = kMc + kMl - kMu * kMl * kCot;
  const double t_lift = (D * kG * std::tan(kPhi) - c) / k;  // (1) with F = -k t at a = -g tan phi
  const double u_lift = u0 + (-0.5 * k * t_lift * t_lift - c * t_lift) / D;
  ASSERT_GT(u_lift, 1.0);
  for (const std::string& law : kLaws)
    for (const IntegratorChoice& how : AllIntegrators()) {
      const std::string who = how.name + law;
      auto l = LoadModel(Leg(kG, u0, kPhi + 1e-12, 0.0, 0.0, law, "  cx.tau = " + Num(-k) + " * time;\n"), {}, {}, true);
      ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
      sim::SimResult r;
      const sim::MemorySink s = RunWith(*l->prog, how, t_lift + 0.02, 0.05, {"cx.u"}, &r, 1e-11);
      ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << who << ": " << r.message;
      // Resting from the landing (t_r, u_r: the start 1e-12 above the floor, a tiny impact at
      // t_r ~ 1e-6 s): (1) integrated.
      ASSERT_FALSE(r.stats.events.empty()) << who;
      const double t_r = r.stats.events[0].time, u_r = ChangeOf(r.stats.events[0], "cx.u", true);
      ASSERT_LT(t_r, 1e-4) << who;
      for (size_t i = 0; i < s.times.size(); ++i)
        if (s.times[i] > t_r && s.times[i] <= t_lift) {
          const double t = s.times[i];
          EXPECT_NEAR(s.rows[i][0], u_r + (-0.5 * k * (t * t - t_r * t_r) - c * (t - t_r)) / D, 1e-8) << who << " t = " << t;
        }
      const std::vector<double> leaves = EventTimes(r, "foot", "leaves");
      ASSERT_EQ(leaves.size(), 1u) << who;
      EXPECT_NEAR(leaves[0], t_lift, 1e-8) << who;
      ASSERT_FALSE(EventTimes(r, "foot", "rests").empty()) << who;
      EXPECT_LT(EventTimes(r, "foot", "rests")[0], 1e-4) << who;
    }
}

double Kinetic(double u, double qd) {
  const double vx = u + qd * kL * std::cos(kPhi), vy = qd * kL * std::sin(kPhi);
  return 0.5 * kMc * u * u + 0.5 * kMl * (vx * vx + vy * vy);
}

// Impact (no gravity): the tip's normal speed -> -e times (only the leg's rate moves it:
// dq+ = -e dq-, w = dq+ - dq-); the floor's impulse reaches the rail as a normal impulse
// P_N = T cos phi, and the carriage slides on (forwards) with the friction impulse
// -mu |P_N|: momentum and the rod's impulse T give, by hand,
//   P_f = -mu m_l m_c w L cos phi cot phi / (M + mu m_l cot phi),  M = m_c + m_l
//   du = (P_f - m_l w L cos phi) / M
// If this fails, the floor's impulse is not in the rail's normal impulse (no friction
// impulse: du without P_f), or the impact is refused, or it gains energy.
TEST(PlaneFriction, ImpactOfTheTipSlowsTheCarriageByTheFrictionImpulse) {
  for (const std::string& law : kLaws)
    for (double e : {0.0, 0.5, 1.0})
      for (const IntegratorChoice& how : AllIntegrators()) {
        const std::string who = how.name + law + " e " + Num(e);
        auto l = LoadModel(Leg(0.0, 2.0, 0.68, -2.0, e, law, ""), {}, {}, true);
        ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
        sim::SimResult r;
        const sim::MemorySink s = RunWith(*l->prog, how, 0.1, 0.05, {"kinetic_energy"}, &r, 1e-11);
        ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << who << ": " << r.message;
        ASSERT_FALSE(r.stats.events.empty()) << who;
        const sim::EventRecord& ev = r.stats.events[0];
        ASSERT_EQ(ev.element, "foot") << who << ": " << ev.kind;
        const double u = ChangeOf(ev, "cx.u", false), qd = ChangeOf(ev, "leg.u", false);
        const double wq = -(1.0 + e) * qd, M = kMc + kMl;
        const double Pf = -kMu * kMl * kMc * wq * kL * std::cos(kPhi) * kCot / (M + kMu * kMl * kCot);
        EXPECT_NEAR(ChangeOf(ev, "leg.u", true), -e * qd, 1e-9) << who;
        EXPECT_NEAR(ChangeOf(ev, "cx.u", true), u + (Pf - kMl * wq * kL * std::cos(kPhi)) / M, 1e-9) << who;
        EXPECT_LT(Kinetic(ChangeOf(ev, "cx.u", true), ChangeOf(ev, "leg.u", true)), Kinetic(u, qd)) << who;
        size_t i = 0;  // the event's rows: energy never rises
        while (i + 1 < s.times.size() && s.times[i] != s.times[i + 1]) ++i;
        ASSERT_LT(i + 1, s.times.size()) << who;
        EXPECT_LE(s.rows[i + 1][0], s.rows[i][0]) << who;
      }
}

}  // namespace
}  // namespace kanesim::test
