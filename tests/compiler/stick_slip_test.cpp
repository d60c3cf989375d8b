// Exact Coulomb stick-slip on joints (issue 41): the Coulomb oscillator against its closed
// form (half-cycles of pi / w, the amplitude down by 2 F / k each, sticking for good once
// within F_s / k), and a block on an incline that stays stuck while tan(theta) <= mu_s and
// otherwise slides with g (sin(theta) - mu cos(theta)).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "tests/compiler/compile_test_util.h"

namespace kanesim::test {
namespace {

constexpr double kG = 9.81;

// A block (m = 2) on a horizontal prismatic joint, spring k = 20 to x = 0, friction mu = 0.1
// against the normal force N = m g: F = mu m g. Released at rest at x0 = 1 it slides while
// k |x| > F_s: each half-cycle is pi / w long (w^2 = k / m, about the shifted centre +-F/k) and
// ends at rest at x_n = (-1)^n (x0 - 2 n F / k) (4 F / k a cycle); it sticks for good at the
// first n with k |x_n| <= F_s = mu_s m g, at t = n pi / w.
// If this fails, the sliding friction is not -mu N sign(u) exactly, the joint does not stop
// and reverse where the closed form does, it creeps instead of sticking, or it sticks
// where the spring overcomes static friction.
TEST(StickSlip, CoulombOscillatorAgainstTheClosedForm) {
  const double m = 2, k = 20, mu = 0.1, x0 = 1, F = mu * m * kG, w = std::sqrt(k / m);
  const double pi = std::acos(-1.0);
  const std::string text =
      "model C\n"
      "  World world(g = {0, -9.81, 0});\n"
      "  Prismatic slider(axis = {1, 0, 0}, q(start = " + Num(x0) + "), mu = " + Num(mu) +
      ", friction_exact = true);\n"
      "  Body box(m = " + Num(m) + ");\n"
      "equation\n"
      "  connect(world.frame_b, slider.frame_a);\n"
      "  connect(slider.frame_b, box.frame_a);\n"
      "  slider.tau = -" + Num(k) + " * slider.q;\n"
      "end C;\n";
  auto l = LoadModel(text, {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  int n_stick = 0;
  while (k * std::abs(x0 - 2 * (n_stick) * F / k) > F) ++n_stick;  // mu_s = mu
  ASSERT_EQ(n_stick, 5);  // amplitudes 1, 0.8038, 0.6076, 0.4114, 0.2152, then 0.019 < F / k
  const double t_stick = n_stick * pi / w, x_stick = std::pow(-1.0, n_stick) * (x0 - 2 * n_stick * F / k);
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    sim::MemorySink s = RunWith(*l->prog, how, t_stick + 1.0, 0.05, {"slider.q", "slider.u"}, &r, 1e-11);
    ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
    const auto& ev = r.stats.events;
    ASSERT_EQ(ev.size(), static_cast<size_t>(n_stick + 1)) << how.name;  // start, 4 reversals, stick
    EXPECT_EQ(ev[0].time, 0.0);
    EXPECT_NE(ev[0].kind.find("slips"), std::string::npos) << ev[0].kind;
    for (int n = 1; n <= n_stick; ++n) {
      EXPECT_NEAR(ev[static_cast<size_t>(n)].time, n * pi / w, 1e-9) << how.name << " n = " << n;
      const bool sticks = n == n_stick;
      EXPECT_EQ(ev[static_cast<size_t>(n)].kind.find("sticks") == 0, sticks) << ev[static_cast<size_t>(n)].kind;
    }
    for (size_t i = 0; i < s.rows.size(); ++i) {
      const double t = s.times[i];
      if (t < t_stick) {  // the half-cycle's closed form
        const int n = static_cast<int>(t / (pi / w));
        const double sgn = n % 2 == 0 ? 1.0 : -1.0;  // the sign of x_n
        const double xn = sgn * (x0 - 2 * n * F / k), c = sgn * F / k;  // centre of that half-cycle
        EXPECT_NEAR(s.rows[i][0], c + (xn - c) * std::cos(w * (t - n * pi / w)), 1e-8) << how.name << " t = " << t;
      } else if (t > t_stick + 1e-6) {  // (the stick event's left-limit row is at t_stick itself)
        EXPECT_NEAR(s.rows[i][0], x_stick, 1e-8) << how.name << " t = " << t;  // IDA: 1.1e-9 off
        EXPECT_EQ(s.rows[i][1], 0.0) << how.name << " t = " << t;
      }
    }
  }
}

// A block on a prismatic joint along an incline of angle theta (gravity -y), mu = 0.3,
// mu_s = 0.5, at rest: stuck for good while tan(theta) <= mu_s (exactly still, where the
// regularized law creeps downhill); above, it slides from the start with acceleration
// g (sin(theta) - mu cos(theta)) down the slope. If this fails, static friction does not
// hold a block it can hold, or holds one it cannot.
TEST(StickSlip, BlockOnAnInclineStaysStuckWhileTanThetaBelowMuS) {
  for (double tan_theta : {0.45, 0.55}) {
    const double theta = std::atan(tan_theta), c = std::cos(theta), sn = std::sin(theta);
    const std::string text =
        "model Incline\n"
        "  World world(g = {0, -9.81, 0});\n"
        "  Prismatic slide(axis = {" + Num(c) + ", " + Num(sn) + ", 0}, mu = 0.3, mu_s = 0.5, friction_exact = true);\n"
        "  Body box(m = 1.5);\n"
        "equation\n"
        "  connect(world.frame_b, slide.frame_a);\n"
        "  connect(slide.frame_b, box.frame_a);\n"
        "end Incline;\n";
    auto l = LoadModel(text, {}, {}, true);
    ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
    for (const IntegratorChoice& how : AllIntegrators()) {
      sim::SimResult r;
      sim::MemorySink s = RunWith(*l->prog, how, 2.0, 0.1, {"slide.q", "slide.u"}, &r, 1e-10);
      ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
      ASSERT_EQ(r.stats.events.size(), 1u) << how.name;
      const bool stuck = tan_theta <= 0.5;
      EXPECT_EQ(r.stats.events[0].kind.find(stuck ? "sticks" : "slips, backwards"), 0u) << r.stats.events[0].kind;
      const double a = -kG * (sn - 0.3 * c);
      for (size_t i = 0; i < s.rows.size(); ++i) {
        const double t = s.times[i];
        if (stuck) {
          EXPECT_EQ(s.rows[i][0], 0.0) << how.name << " t = " << t;
        } else {
          const double x = 0.5 * a * t * t;
          EXPECT_NEAR(s.rows[i][0], x, 1e-9 * (1 + std::abs(x))) << how.name << " t = " << t;
        }
      }
    }
  }
}

// A rod (m = 1.5, L = 0.2) on a pin with exact friction, released at rest at an angle phi off
// the vertical. Stuck, the pin carries the weight (N = m g) and must hold the torque
// m g (L / 2) sin(phi); it stays stuck while that is within mu_s N r (static coefficient mu_s,
// pin radius r = 0.05), else slips with mu N r. sin(phi) = 0.2 needs 0.2943 N m: within
// mu_s = 0.5's bound 0.3679, beyond mu = 0.3's 0.2207 (so it sticks only by mu_s, and slips
// where mu_s is left at mu); sin(phi) = 0.3 needs 0.4415 and slips either way. If this fails,
// a Revolute's static coefficient or its normal force is not the closed form's.
TEST(StickSlip, RodOnAPinStaysStuckWhileItsTorqueIsWithinMuSNr) {
  const double m = 1.5, L = 0.2, r = 0.05, mu = 0.3, pi = std::acos(-1.0);
  struct Case {
    double sin_phi, mu_s;
    bool stuck;
  };
  for (const Case& c : {Case{0.2, 0.5, true}, Case{0.2, 0.3, false}, Case{0.3, 0.5, false}}) {
    const double q0 = -pi / 2 + std::asin(c.sin_phi);
    const std::string text =
        "model R\n"
        "  World world(g = {0, -9.81, 0});\n"
        "  Revolute pin(axis = {0, 0, 1}, q(start = " + Num(q0) + "), mu = " + Num(mu) + ", mu_s = " + Num(c.mu_s) +
        ", friction_radius = " + Num(r) + ", friction_exact = true);\n"
        "  Rod rod(L = " + Num(L) + ", m = " + Num(m) + ");\n"
        "equation\n"
        "  connect(world.frame_b, pin.frame_a);\n"
        "  connect(pin.frame_b, rod.frame_a);\n"
        "end R;\n";
    auto l = LoadModel(text, {}, {}, true);
    ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
    const double needed = m * kG * (L / 2) * c.sin_phi, bound = c.mu_s * m * kG * r;
    for (const IntegratorChoice& how : AllIntegrators()) {
      SCOPED_TRACE(std::string(how.name) + " sin(phi) " + Num(c.sin_phi) + " mu_s " + Num(c.mu_s));
      sim::SimResult res;
      sim::MemorySink s = RunWith(*l->prog, how, 0.2, 0.01, {"pin.q"}, &res, 1e-10);
      ASSERT_EQ(res.status, sim::SimResult::Status::kOk) << res.message;
      ASSERT_GE(res.stats.events.size(), 1u);
      const std::string& kind = res.stats.events[0].kind;
      EXPECT_EQ(res.stats.events[0].time, 0.0);
      double a = 0.0, b = 0.0;
      if (c.stuck) {
        ASSERT_EQ(std::sscanf(kind.c_str(), "sticks (friction %lf within %lf", &a, &b), 2) << kind;
        EXPECT_EQ(res.stats.events.size(), 1u);
        for (size_t i = 0; i < s.rows.size(); ++i) EXPECT_EQ(s.rows[i][0], q0) << "t = " << s.times[i];
      } else {
        ASSERT_EQ(std::sscanf(kind.c_str(), "slips, backwards (friction needed %lf, at most %lf", &a, &b), 2) << kind;
        EXPECT_LT(s.rows.back()[0], q0 - 1e-3);  // it swings down
      }
      EXPECT_NEAR(a, needed, 1e-12 * needed);
      EXPECT_NEAR(b, bound, 1e-12 * bound);
    }
  }
}

}  // namespace
}  // namespace kanesim::test
