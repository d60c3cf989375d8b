// Coulomb friction (`mu`) in a when clause's speed jump (issue 41, docs/events.md "Friction
// in a jump"). A slider (m_s) on a prismatic joint of axis a = (cos th, sin th, 0), friction
// mu, on a carrier (m_c) moving along x, no gravity. Setting the carrier's speed by du_c
// gives the slider the impulse m_s du_c across its axis: its joint's normal impulse
// N = m_s |du_c| sin th. Along the axis the slider's momentum changes by the friction impulse
// P alone: m_s (du_c cos th + du_s) = P. Without friction the slip after the jump would be
// w = u_s- - du_c cos th; the joint sticks (u_s+ = 0) when |w| <= mu N / m_s, else it slides
// on with u_s+ = w - mu (N / m_s) sign(w). Before the jump nothing moves the slider across
// its axis (N = 0: no friction), so the speeds before are the start values exactly.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <utility>

#include "tests/compiler/compile_test_util.h"
#include "tests/support/model_texts.h"

namespace kanesim::test {
namespace {

constexpr double kTh = 0.6, kMc = CarrierSliderText::kMc, kMs = CarrierSliderText::kMs, kMu = 0.4;

std::string Slider(double uc0, double us0, const std::string& value, const std::string& friction = "") {
  return CarrierSliderText{.model = "S",
                           .cx_mods = ", u(start = " + Num(uc0) + ")",
                           .th = kTh,
                           .mu = kMu,
                           .us0 = us0,
                           .friction = friction,
                           .equations = "  when time > 0.1 then\n    reinit(cx.u, " + value + ");\n  end when;\n"}
      .Text();
}

// Speed `name` before or after the run's one event (its record; unchanged: `fallback`).
double Speed(const sim::SimResult& r, const std::string& name, bool after, double fallback) {
  for (const sim::EventChange& c : r.stats.events.at(0).changes)
    if (c.name == name) return after ? c.after : c.before;
  return fallback;
}

struct Jump {
  double uc_before, us_before, uc_after, us_after;
};

bool RunJump(const std::string& text, Jump* j, const IntegratorChoice& how = AllIntegrators()[0]) {
  auto l = LoadModel(text, {}, {}, true);
  EXPECT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  if (!l || !l->prog) return false;
  sim::SimResult r;
  RunWith(*l->prog, how, 0.2, 0.1, {"cx.u", "s.u"}, &r, 1e-11);
  EXPECT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
  if (r.status != sim::SimResult::Status::kOk || r.stats.events.empty()) return false;
  j->uc_before = Speed(r, "cx.u", false, NAN);
  j->uc_after = Speed(r, "cx.u", true, NAN);
  j->us_before = Speed(r, "s.u", false, NAN);
  j->us_after = Speed(r, "s.u", true, j->us_before);
  return true;
}

// The closed form of the header: the slider's speed after the jump.
double ClosedForm(double uc_before, double us_before, double uc_after, double mu_stick) {
  const double duc = uc_after - uc_before, n = std::abs(duc) * std::sin(kTh);  // N / m_s
  const double w = us_before - duc * std::cos(kTh);
  if (std::abs(w) <= mu_stick * n) return 0.0;
  return w - kMu * n * (w > 0 ? 1.0 : -1.0);
}

// If this fails, the reinit is refused (K321, before this change), the friction impulse is
// not Coulomb's on impulses (sticking inside mu N, sliding with mu N against the slip), or
// the slider's momentum along its axis does not balance the friction impulse.
TEST(WhenFriction, SliderOnACarrierSticksOrSlidesByTheClosedForm) {
  const double c = std::cos(kTh), s = std::sin(kTh), v0 = 1.0;
  // Sticking for V in [v0 / (c + mu s), v0 / (c - mu s)] (carrier from rest, w = v0 - V c).
  const double lo = v0 / (c + kMu * s), hi = v0 / (c - kMu * s);
  ASSERT_NEAR(lo, 0.95130, 1e-5);
  ASSERT_NEAR(hi, 1.66812, 1e-5);
  int stuck = 0;
  for (double V : {lo * (1 - 1e-6), lo * (1 + 1e-6), 1.3, hi * (1 - 1e-6), hi * (1 + 1e-6), 3.0, -2.0, 0.5}) {
    Jump j;
    ASSERT_TRUE(RunJump(Slider(0.0, v0, Num(V)), &j)) << V;
    EXPECT_EQ(j.uc_before, 0.0);
    EXPECT_EQ(j.us_before, v0);
    EXPECT_EQ(j.uc_after, V);
    const double want = ClosedForm(0.0, v0, V, kMu);
    EXPECT_NEAR(j.us_after, want, 1e-10 * (1 + std::abs(want))) << "V = " << V;
    stuck += want == 0.0;
    if (want == 0.0) {
      EXPECT_EQ(j.us_after, 0.0) << "V = " << V << ": a stuck joint at rest exactly";
    }
    // Momentum along the axis: the friction impulse, at most mu N, mu N when sliding.
    const double P = kMs * (V * c + j.us_after - v0), N = kMs * std::abs(V) * s;
    EXPECT_LE(std::abs(P), kMu * N * (1 + 1e-10)) << "V = " << V;
    if (want != 0.0) {
      EXPECT_NEAR(std::abs(P), kMu * N, 1e-10 * N) << "V = " << V;
      EXPECT_LE(P * j.us_after, 0.0) << "V = " << V << ": friction against the slip after the jump";
    }
  }
  EXPECT_EQ(stuck, 3);  // lo (1 + 1e-6), 1.3, hi (1 - 1e-6)
}

// If this fails, an integrator's event path takes another jump (the friction law is in the
// event, shared by all five), or exact stick-slip (friction_exact, mu_s) does not stick the
// joint by its static coefficient and keep it stuck after the jump.
TEST(WhenFriction, EveryIntegratorAndExactStickSlipTakeTheSameImpulse) {
  const double V = 1.9;  // slides with mu = 0.4 (V > 1.668); sticks with mu_s = 0.6 (V < 2.055)
  for (const IntegratorChoice& how : AllIntegrators()) {
    Jump j;
    ASSERT_TRUE(RunJump(Slider(0.0, 1.0, Num(V)), &j, how)) << how.name;
    EXPECT_NEAR(j.us_after, ClosedForm(0.0, 1.0, V, kMu), 1e-10) << how.name;
    EXPECT_NE(j.us_after, 0.0) << how.name;
  }
  ASSERT_LT(V, 1.0 / (std::cos(kTh) - 0.6 * std::sin(kTh)));
  auto l = LoadModel(Slider(0.0, 1.0, Num(V), ", friction_exact = true, mu_s = 0.6"), {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  sim::SimResult r;
  sim::MemorySink out = RunWith(*l->prog, AllIntegrators()[0], 0.3, 0.05, {"cx.u", "s.u", "s.q"}, &r, 1e-11);
  ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << r.message;
  EXPECT_EQ(Speed(r, "s.u", true, NAN), 0.0);
  for (size_t i = 0; i < out.rows.size(); ++i)
    if (out.times[i] > 0.1 || (out.times[i] == 0.1 && i + 1 < out.rows.size() && out.times[i + 1] != 0.1)) {
      EXPECT_EQ(out.rows[i][1], 0.0) << "t = " << out.times[i] << ": stuck after the jump";
      EXPECT_EQ(out.rows[i][0], V) << "t = " << out.times[i];
    }
}

// Bringing a speed to rest (reinit to 0, a plastic jump) with friction impulses that oppose
// the slip after it: T+ - T- = sum P_f u+ - (1/2) du^T M du <= 0. Here the carrier moving at
// U with the slider slipping is stopped: T+ = (1/2) m_s u_s+^2 (carrier at rest), against
// T- = (1/2) (m_c + m_s) U^2 + m_s U u_s- cos th + (1/2) m_s u_s-^2.
// If this fails, the friction impulse adds energy in a jump that takes it out.
TEST(WhenFriction, StoppingTheCarrierNeverRaisesTheEnergy) {
  const double c = std::cos(kTh);
  for (double U : {-2.0, -0.5, 0.7, 3.0})
    for (double us : {-1.5, -0.2, 0.0, 0.4, 2.0}) {
      Jump j;
      ASSERT_TRUE(RunJump(Slider(U, us, "0"), &j)) << U << " " << us;
      EXPECT_EQ(j.uc_before, U);
      EXPECT_EQ(j.us_before, us);
      const double want = ClosedForm(U, us, 0.0, kMu);
      EXPECT_NEAR(j.us_after, want, 1e-10 * (1 + std::abs(want))) << U << " " << us;
      const double T0 = 0.5 * (kMc + kMs) * U * U + kMs * U * us * c + 0.5 * kMs * us * us;
      const double T1 = 0.5 * kMs * j.us_after * j.us_after;
      EXPECT_LE(T1, T0 * (1 + 1e-14)) << U << " " << us;
    }
}

// The slider's closed form does not depend on the masses. If this fails, a carrier 1e12
// times the slider's mass made the rows' block look singular (a case skipped, or the jump
// refused as having no unique solution).
TEST(WhenFriction, MassesOfVeryDifferentScalesKeepTheClosedForm) {
  for (double V : {1.3, 3.0}) {
    std::string text = Slider(0.0, 1.0, Num(V));
    for (const auto& [from, to] : {std::pair<std::string, std::string>{"carrier(m = 2)", "carrier(m = 1e8)"},
                                   {"slider(m = 0.5)", "slider(m = 1e-4)"}}) {
      ASSERT_NE(text.find(from), std::string::npos) << from;
      text.replace(text.find(from), from.size(), to);
    }
    Jump j;
    ASSERT_TRUE(RunJump(text, &j)) << V;
    const double want = ClosedForm(0.0, 1.0, V, kMu);
    // (M's condition, ~1e12, costs digits: 1.1e-8 measured in the sliding case)
    EXPECT_NEAR(j.us_after, want, 1e-7) << "V = " << V;
    if (want == 0.0) {
      EXPECT_EQ(j.us_after, 0.0) << "V = " << V;
    }
  }
}

// The rail of the two tests below: a carrier (m_c) on a prismatic joint `rail` along x with
// friction mu, moving at U, carrying point masses A (m_A at l_A, angle a) and B (m_B at l_B,
// angle b) on hinges ha, hb about z; no gravity; A's rate set to W at t = 0.1. `hb_mods`
// follow B's start angle, `equations` the six connects.
struct Rail {
  double mc, mA, lA, mB, lB, a, b, mu;
};
std::string RailText(const Rail& p, double U, double W, const std::string& hb_mods, const std::string& equations) {
  return "model R\n"
         "  World world(g = {0, 0, 0});\n"
         "  Prismatic rail(axis = {1, 0, 0}, u(start = " + Num(U) + "), mu = " + Num(p.mu) + ");\n"
         "  Body carrier(m = " + Num(p.mc) + ");\n"
         "  Revolute ha(axis = {0, 0, 1}, q(start = " + Num(p.a) + "));\n"
         "  Body pa(m = " + Num(p.mA) + ", r_CM = {" + Num(p.lA) + ", 0, 0});\n"
         "  Revolute hb(axis = {0, 0, 1}, q(start = " + Num(p.b) + ")" + hb_mods + ");\n"
         "  Body pb(m = " + Num(p.mB) + ", r_CM = {" + Num(p.lB) + ", 0, 0});\n"
         "equation\n"
         "  connect(world.frame_b, rail.frame_a);\n"
         "  connect(rail.frame_b, carrier.frame_a);\n"
         "  connect(carrier.frame_a, ha.frame_a);\n"
         "  connect(ha.frame_b, pa.frame_a);\n"
         "  connect(carrier.frame_a, hb.frame_a);\n"
         "  connect(hb.frame_b, pb.frame_a);\n" +
         equations +
         "  when time > 0.1 then\n"
         "    reinit(ha.u, " + Num(W) + ");\n"
         "  end when;\n"
         "end R;\n";
}

// A carrier (m_c) on an x rail with friction mu carries two point masses on hinges about z:
// A (m_A at l_A, angle a) and B (m_B at l_B, angle b), no gravity, the carrier moving at U.
// Setting A's rate to W: B's hinge takes no impulse (m_B l_B (l_B dw_B - sin b du_c) = 0), the
// rail's along x, M' du_c - k0 = P (M' = m_c + m_A + m_B cos^2 b, k0 = m_A l_A W sin a), its
// normal impulse across x N = |n0 + n1 du_c| (n0 = m_A l_A W cos a, n1 = m_B sin b cos b):
// N depends on the friction impulse, through B. The cases solved by hand: stick (du_c = -U,
// |P| <= mu N) or slide s (P = -s mu N, s (U + du_c) >= 0), the abs by its sign.
// If this fails, the sliding impulse is not the fixed point of its own normal impulse (a
// normal force taken before the friction's response), or the rail sticks or slides wrongly.
TEST(WhenFriction, RailWhoseNormalImpulseDependsOnItsFrictionByTheClosedForm) {
  const double mc = 1, mA = 0.7, lA = 0.5, mB = 1.2, lB = 0.8, a = -1.0, b = -2.2, mu = 0.5;
  const double Mp = mc + mA + mB * std::cos(b) * std::cos(b), n1 = mB * std::sin(b) * std::cos(b);
  int kinds[3] = {0, 0, 0};
  for (double U : {1.0, 0.1, -0.4})
    for (double W : {-6.0, -2.0, -0.5, 0.5, 0.7, 2.0, 6.0}) {
      const double k0 = mA * lA * W * std::sin(a), n0 = mA * lA * W * std::cos(a);
      double want = NAN;  // the rail's speed after
      if (std::abs(-Mp * U - k0) <= mu * std::abs(n0 - n1 * U)) want = 0.0;
      for (double sgn : {1.0, -1.0})
        for (double sigma : {1.0, -1.0}) {
          const double x = (k0 - mu * sgn * sigma * n0) / (Mp + mu * sgn * sigma * n1);
          if (std::isnan(want) && sigma * (n0 + n1 * x) >= 0 && sgn * (U + x) > 0) want = U + x;
        }
      ASSERT_FALSE(std::isnan(want)) << U << " " << W;
      ++kinds[want == 0.0 ? 0 : want > 0 ? 1 : 2];
      const std::string text = RailText({mc, mA, lA, mB, lB, a, b, mu}, U, W, "", "");
      auto l = LoadModel(text, {}, {}, true);
      ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
      sim::SimResult r;
      RunWith(*l->prog, AllIntegrators()[0], 0.2, 0.1, {"rail.u"}, &r, 1e-11);
      ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << r.message;
      EXPECT_EQ(Speed(r, "rail.u", false, U), U);
      const double got = Speed(r, "rail.u", true, U);
      EXPECT_NEAR(got, want, 1e-10 * (1 + std::abs(want))) << "U = " << U << ", W = " << W;
      // B's hinge took no impulse: its generalized momentum l_B w_B - sin b u_c is kept (0 before).
      const double wb = Speed(r, "hb.u", true, 0.0);
      EXPECT_NEAR(lB * wb - std::sin(b) * got, -std::sin(b) * U, 1e-10) << "U = " << U << ", W = " << W;
    }
  EXPECT_GT(kinds[0], 0);
  EXPECT_GT(kinds[1], 0);
  EXPECT_GT(kinds[2], 0);
}

// If this fails, a speed reinit with mu friction in a mechanism with closed loops is refused
// (K321, before this change) or its speeds after the jump leave the loop's velocity
// constraints, or a constant friction (no impulse) takes one.
TEST(WhenFriction, LoopsWithMuFrictionTakeTheJumpConstantFrictionNone) {
  std::string text = Slider(0.0, 1.0, "2", ", friction_exact = true");
  const size_t mu = text.find("mu = ");
  text.replace(mu, text.find(',', mu) - mu, "friction_force = 0.3");
  auto l = LoadModel(text, {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  Jump j;
  ASSERT_TRUE(RunJump(text, &j));
  // (the constant friction slowed both before the jump: its speeds before from the record)
  EXPECT_NEAR(j.us_after, j.us_before - (2.0 - j.uc_before) * std::cos(kTh), 1e-12) << "a bounded friction has no impulse";

  FourBarText bar;
  bar.rocker_mods = ", mu = 0.1";
  bar.equations = "  when time > 0.3 then\n    reinit(crank_pivot.u, 2);\n  end when;\n";
  auto loop = LoadModel(bar.Text(), {}, {}, true);
  ASSERT_TRUE(loop && loop->prog) << (loop ? Messages(loop->errors) : "");
  sim::SimResult r;
  sim::MemorySink out = RunWith(*loop->prog, AllIntegrators()[0], 0.3, 0.3,
                                {"crank_pivot.q", "crank_pivot.u", "crank_coupler.q", "crank_coupler.u",
                                 "rocker_pivot.q", "rocker_pivot.u"}, &r, 1e-10);
  ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << r.message;
  ASSERT_EQ(r.stats.events.size(), 1u);
  const std::vector<double>& y = out.rows.back();  // the right limit at 0.3
  ASSERT_EQ(out.times.back(), 0.3);
  EXPECT_NEAR(y[1], 2.0, 1e-12);  // (the row recomputes a dependent speed from the others)
  const double t2 = y[0], t3 = y[0] + y[2], t4 = y[4], u3 = y[1] + y[3];
  const double a = 0.2, b = 0.6, c = 0.5;  // examples/fourbar.mech
  const double rx = -a * y[1] * std::sin(t2) - b * u3 * std::sin(t3) + c * y[5] * std::sin(t4);
  const double ry = a * y[1] * std::cos(t2) + b * u3 * std::cos(t3) - c * y[5] * std::cos(t4);
  EXPECT_LE(std::hypot(rx, ry), 1e-12) << "the loop's velocity constraints after the jump";
}

// The rail of the test above, with B resting on its end stop (q_max = b, pressed on by a
// torque) when A's rate is set to W. While the stop holds B (its impulse pushes:
// m_B l_B sin b du_c >= 0, the impulse on B's speed that keeps it at 0) B moves with the
// carrier: M du_c - k0 = P with M = m_c + m_A + m_B, the normal impulse N = |n0| (A's alone).
// Where the stop's impulse would pull, B leaves it and the free jump of the test above holds.
// If this fails, a reinit beside a joint resting on its stop with mu (sim/end_stops_friction.cpp
// HeldJumpMu) takes another impulse than this hand-computed one.
TEST(WhenFriction, RailBesideAJointRestingOnItsStopByTheClosedForm) {
  const double mc = 1, mA = 0.7, lA = 0.5, mB = 1.2, lB = 0.8, a = -1.0, b = -2.2, mu = 0.5;
  const double M = mc + mA + mB, Mp = mc + mA + mB * std::cos(b) * std::cos(b), n1 = mB * std::sin(b) * std::cos(b);
  int held = 0, left = 0;
  for (double U : {1.0, 0.1, -0.4})
    for (double W : {-6.0, -0.5, 0.7, 6.0}) {
      const double k0 = mA * lA * W * std::sin(a), n0 = mA * lA * W * std::cos(a);
      double want = NAN;  // held: the rail's speed after
      if (std::abs(-M * U - k0) <= mu * std::abs(n0)) want = 0.0;
      for (double s : {1.0, -1.0})
        if (std::isnan(want) && s * (U + (k0 - s * mu * std::abs(n0)) / M) > 0) want = U + (k0 - s * mu * std::abs(n0)) / M;
      ASSERT_FALSE(std::isnan(want));
      const bool holds = std::sin(b) * (want - U) >= 0;
      if (!holds) {  // the free jump (the test above)
        want = NAN;
        if (std::abs(-Mp * U - k0) <= mu * std::abs(n0 - n1 * U)) want = 0.0;
        for (double sgn : {1.0, -1.0})
          for (double sigma : {1.0, -1.0}) {
            const double x = (k0 - mu * sgn * sigma * n0) / (Mp + mu * sgn * sigma * n1);
            if (std::isnan(want) && sigma * (n0 + n1 * x) >= 0 && sgn * (U + x) > 0) want = U + x;
          }
        ASSERT_FALSE(std::isnan(want));
      }
      (holds ? held : left)++;
      const std::string text = RailText({mc, mA, lA, mB, lB, a, b, mu}, U, W, ", q_max = " + Num(b), "  hb.tau = 1;\n");
      auto l = LoadModel(text, {}, {}, true);
      ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
      sim::SimResult r;
      RunWith(*l->prog, AllIntegrators()[0], 0.2, 0.1, {"rail.u", "hb.u"}, &r, 1e-11);
      ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << r.message;
      const sim::EventRecord* ev = nullptr;
      for (const sim::EventRecord& e : r.stats.events)
        if (e.element.rfind("when", 0) == 0 && !ev) ev = &e;
      ASSERT_NE(ev, nullptr);
      double got = U, wb = 0.0;
      for (const sim::EventChange& c : ev->changes) {
        if (c.name == "rail.u") got = c.after;
        if (c.name == "hb.u") wb = c.after;
      }
      EXPECT_NEAR(got, want, 1e-10 * (1 + std::abs(want))) << "U = " << U << ", W = " << W << (holds ? " held" : " left");
      if (holds) {
        EXPECT_EQ(wb, 0.0) << "U = " << U << ", W = " << W;
      } else {
        EXPECT_NEAR(lB * wb - std::sin(b) * got, -std::sin(b) * U, 1e-10) << "U = " << U << ", W = " << W;
      }
    }
  EXPECT_GT(held, 0);
  EXPECT_GT(left, 0);
}

}  // namespace
}  // namespace kanesim::test
