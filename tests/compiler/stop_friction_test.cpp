// End stops beside Coulomb friction mu N (issue 41, docs/events.md "Friction beside end
// stops"). A carrier (m_c) on a prismatic joint along x with an end stop, and on it a slider
// (m_s) on a prismatic joint of axis a = (cos th, sin th, 0) with friction mu.
// Resting (gravity -g y, the slider sliding down, u_s < 0): the carrier pressed on its stop
// q_max is fixed, so the slider's joint carries N = m_s g cos th across its axis (hand
// statics) and the slider accelerates by a_s = -g sin th + mu g cos th along it; the stop's
// reaction is the system's horizontal momentum rate, m_s a_s cos th (< 0: it pushes).
// Impact (no gravity, so N = 0 in flight and the speeds before are the start values): the
// stop sets the carrier's speed to -e u_c; the slider's joint meets the normal impulse
// m_s |du_c| sin th, and sticks or slides by Coulomb's law on impulses (the closed form of
// tests/compiler/when_friction_test.cpp).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "tests/compiler/compile_test_util.h"
#include "tests/support/model_texts.h"

namespace kanesim::test {
namespace {

constexpr double kTh = 0.9, kMc = CarrierSliderText::kMc, kMs = CarrierSliderText::kMs, kMu = 0.3, kG = 9.81;

std::string Carrier(double g, double q0, double uc0, double us0, double e, const std::string& friction) {
  return CarrierSliderText{.gy = Num(-g),
                           .cx_mods = ", q_max = 0.1, restitution = " + Num(e) + ", q(start = " + Num(q0) +
                                      "), u(start = " + Num(uc0) + ")",
                           .th = kTh,
                           .mu = kMu,
                           .us0 = us0,
                           .friction = friction}
      .Text();
}

const std::vector<std::string> kSignals = {"cx.q", "cx.u", "s.u", "kinetic_energy"};
const std::vector<std::string> kLaws = {", friction_v = 1e-7", ", friction_exact = true"};

// If this fails, end stops beside mu are refused (K318, before this change), or the resting
// carrier's reaction is left out of the slider's normal force (the friction is not mu N with
// N from the statics of the fixed incline), or the stop lets go while it pushes.
TEST(StopFriction, SliderOnACarrierRestingOnItsStopByHandStatics) {
  const double a_s = -kG * std::sin(kTh) + kMu * kG * std::cos(kTh);  // mu N / m_s = mu g cos th
  const double lambda = kMs * a_s * std::cos(kTh);  // the stop's reaction on cx (pushes: -x)
  ASSERT_LT(lambda, 0.0);
  for (const std::string& law : kLaws)
    for (const IntegratorChoice& how : AllIntegrators()) {
      const std::string who = how.name + law;
      auto l = LoadModel(Carrier(kG, 0.1, 0.0, -1.0, 0.0, law), {}, {}, true);
      ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
      sim::SimResult r;
      const sim::MemorySink s = RunWith(*l->prog, how, 0.3, 0.05, kSignals, &r, 1e-10);
      ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << who << ": " << r.message;
      ASSERT_GE(s.times.size(), 7u) << who;
      for (size_t i = 0; i < s.times.size(); ++i) {
        EXPECT_NEAR(s.rows[i][0], 0.1, 1e-12) << who << " t = " << s.times[i] << ": the carrier left its stop";
        EXPECT_NEAR(s.rows[i][1], 0.0, 1e-12) << who;
        EXPECT_NEAR(s.rows[i][2], -1.0 + a_s * s.times[i], 1e-7) << who << " t = " << s.times[i]
                                                                  << ": the slider's friction is not mu N (statics)";
      }
    }
}

// Speed `name` before or after the run's first event (its record; unchanged: `fallback`).
double Speed(const sim::SimResult& r, const std::string& name, bool after, double fallback) {
  for (const sim::EventChange& c : r.stats.events.at(0).changes)
    if (c.name == name) return after ? c.after : c.before;
  return fallback;
}

// The slider's speed after the carrier's speed jumps from uc to uc_after (header).
double ClosedForm(double uc, double us, double uc_after) {
  const double duc = uc_after - uc, n = std::abs(duc) * std::sin(kTh);  // N / m_s
  const double w = us - duc * std::cos(kTh);
  if (std::abs(w) <= kMu * n) return 0.0;
  return w - kMu * n * (w > 0 ? 1.0 : -1.0);
}

// If this fails, end stops beside mu are refused (K318, before this change), the stop's
// impulse does not enter the slider joint's normal impulse (the friction impulse is not
// Coulomb's: sticking within mu N, sliding with mu N against the slip), or the impact gains
// energy.
TEST(StopFriction, ImpactAtTheStopSticksOrSlidesTheSliderByTheClosedForm) {
  for (const std::string& law : kLaws)
    for (double e : {0.0, 0.5})
      for (double us0 : {-0.9, 0.5, -2.0})
        for (const IntegratorChoice& how : AllIntegrators()) {
          const std::string who = how.name + law + " e " + Num(e) + " u_s " + Num(us0);
          auto l = LoadModel(Carrier(0.0, 0.0, 1.0, us0, e, law), {}, {}, true);
          ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
          sim::SimResult r;
          const sim::MemorySink s = RunWith(*l->prog, how, 0.15, 0.05, kSignals, &r, 1e-11);
          ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << who << ": " << r.message;
          ASSERT_FALSE(r.stats.events.empty()) << who;
          EXPECT_NEAR(r.stats.events[0].time, 0.1, 1e-9) << who;
          const double uc = Speed(r, "cx.u", false, NAN), us = Speed(r, "s.u", false, us0);
          EXPECT_NEAR(uc, 1.0, 1e-9) << who;
          EXPECT_NEAR(us, us0, 1e-9) << who;
          EXPECT_NEAR(Speed(r, "cx.u", true, NAN), -e, 1e-12) << who;
          EXPECT_NEAR(Speed(r, "s.u", true, us), ClosedForm(uc, us, -e * uc), 1e-9) << who;
          size_t i = 0;  // the event's rows: energy never rises
          while (i + 1 < s.times.size() && s.times[i] != s.times[i + 1]) ++i;
          ASSERT_LT(i + 1, s.times.size()) << who;
          EXPECT_LE(s.rows[i + 1][3], s.rows[i][3] * (1.0 + 1e-12)) << who;
          EXPECT_LE(s.rows.back()[0], 0.1 + 1e-12) << who;
        }
}

}  // namespace
}  // namespace kanesim::test
