// The resting set after an event, settled as a complementarity problem (sim/end_stops.cpp
// Settle), against a closed form (issue 41): two joints of a double pendulum start on their
// stops, both pulled off by gravity when both are held, yet with the second released the
// first is pushed on again; so exactly one must leave and one stay.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "tests/compiler/compile_test_util.h"

namespace kanesim::test {
namespace {

constexpr double kG = 9.81, kL1 = 1, kM1 = 1, kL2 = 2, kM2 = 2, kQ1 = 1.3;
const double kTheta0 = std::acos(-1.0) - 0.2;  // rod 2's absolute angle at the start

// Rod 2 swinging about joint 2 while joint 1 rests (q1 = kQ1, u1 = 0), at its absolute angle
// theta: its speed from the energy, u2^2 = 3 g (sin theta0 - sin theta) / L2; joint 1's
// reaction from Lagrange's equation of q1 with u1 = a1 = 0:
//   lambda1 = M12 a2 - (m2 L1 L2 / 2) sin(q2) u2^2 - Q1,  a2 = Q2 / M22,
//   Q1 = -g (m1 L1/2 cos q1 + m2 (L1 cos q1 + L2/2 cos theta)),  Q2 = -g m2 L2/2 cos theta.
double U2Squared(double theta) { return 3 * kG * (std::sin(kTheta0) - std::sin(theta)) / kL2; }
double Lambda1(double theta) {
  const double q2 = theta - kQ1;
  const double M12 = kM2 * (kL2 * kL2 / 3 + kL1 * kL2 * std::cos(q2) / 2), M22 = kM2 * kL2 * kL2 / 3;
  const double Q1 = -kG * (kM1 * kL1 / 2 * std::cos(kQ1) + kM2 * (kL1 * std::cos(kQ1) + kL2 / 2 * std::cos(theta)));
  const double Q2 = -kG * kM2 * kL2 / 2 * std::cos(theta);
  return M12 * Q2 / M22 - kM2 * kL1 * kL2 / 2 * std::sin(q2) * U2Squared(theta) - Q1;
}

// If this fails, the start's resting set is not the complementarity problem's solution (both
// held, both reactions pull: -12.7 and -19.2 N.m; the one pulled hardest, j2, leaves, and then
// j1 is pushed, lambda1 = 5.5 N.m, and stays), j1 leaves elsewhere than where its closed-form
// reaction lambda1 crosses zero (theta*, reached at t* = int dtheta / u2), or rod 2 does not
// swing as a pendulum about a fixed pivot while j1 rests.
TEST(Settle, OneOfTwoStopsPulledAtOnceLeavesAndTheOtherStays) {
  // theta* by bisection (lambda1 > 0 at theta0, < 0 half a radian on), t* by the midpoint
  // rule in s (theta = theta0 + s^2 takes out the start's 1/sqrt singularity).
  double a = kTheta0, b = kTheta0 + 0.5;
  ASSERT_GT(Lambda1(a), 5.0);
  ASSERT_LT(Lambda1(b), 0.0);
  for (int i = 0; i < 200; ++i) (Lambda1(0.5 * (a + b)) > 0 ? a : b) = 0.5 * (a + b);
  const double theta_star = 0.5 * (a + b), s_star = std::sqrt(theta_star - kTheta0);
  double t_star = 0.0;
  const int n = 200000;
  for (int i = 0; i < n; ++i) {
    const double s = (i + 0.5) * s_star / n;
    t_star += 2 * s / std::sqrt(U2Squared(kTheta0 + s * s)) * s_star / n;
  }
  char q2[40];
  std::snprintf(q2, sizeof q2, "%.17g", kTheta0 - kQ1);
  const std::string text =
      "model Two\n  World world(g = {0, -9.81, 0});\n"
      "  Revolute j1(axis = {0, 0, 1}, q(start = 1.3), q_min = 1.3);\n  Rod rod1(L = 1, m = 1);\n"
      "  Revolute j2(axis = {0, 0, 1}, q(start = " + std::string(q2) + "), q_min = " + q2 + ");\n"
      "  Rod rod2(L = 2, m = 2);\nequation\n"
      "  connect(world.frame_b, j1.frame_a);\n  connect(j1.frame_b, rod1.frame_a);\n"
      "  connect(rod1.frame_b, j2.frame_a);\n  connect(j2.frame_b, rod2.frame_a);\nend Two;\n";
  auto l = LoadModel(text, {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    sim::MemorySink s = RunWith(*l->prog, how, 0.3, 0.01, {"j1.q", "j1.u", "j2.q", "j2.u"}, &r, 1e-11);
    ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
    ASSERT_GE(r.stats.events.size(), 2u) << how.name;
    EXPECT_EQ(r.stats.events[0].time, 0.0);
    EXPECT_EQ(r.stats.events[0].element, "j1");
    EXPECT_EQ(r.stats.events[0].kind, "rests on q_min");
    EXPECT_EQ(r.stats.events[1].element, "j1") << how.name << ": j2 rested at the start";
    EXPECT_EQ(r.stats.events[1].kind, "leaves q_min") << how.name;
    const double t_leave = r.stats.events[1].time;
    EXPECT_NEAR(t_leave, t_star, 1e-8) << how.name;
    for (size_t i = 0; i < s.rows.size() && s.times[i] <= t_leave; ++i) {
      ASSERT_EQ(s.rows[i][0], kQ1) << how.name << " t = " << s.times[i];
      const double theta = kQ1 + s.rows[i][2];
      EXPECT_NEAR(s.rows[i][3] * s.rows[i][3], U2Squared(theta), 1e-7) << how.name << " t = " << s.times[i];
      EXPECT_GT(Lambda1(theta), -1e-8) << how.name << " t = " << s.times[i];
    }
  }
}

}  // namespace
}  // namespace kanesim::test
