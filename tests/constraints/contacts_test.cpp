// Rolling contacts (runtime/constraints/contacts.*) against closed forms and known behaviour.
//
// Sphere on an incline of angle alpha (examples/sphere_incline.mech), solid sphere
// I = 2/5 m r^2, rolling without slip (Kane & Levinson 1985; any dynamics text):
//   s'' = g sin(alpha) / (1 + I / (m r^2)) = 5/7 g sin(alpha)                        (1)
//   N = m g cos(alpha),   friction = m g sin(alpha) - m s'' = 2/7 m g sin(alpha)      (2)
// Thin disk (examples/rolling_disk.mech): steady circular rolling at lean theta when
//   Omega^2 cos(theta) (a sin(theta) / 4 + 3/2 rc) = g sin(theta)                    (3)
// (Newton-Euler in the precessing frame, docs/constraints.md); upright straight rolling
// is stable above v_c = sqrt(g a / 3) (linearized lean equation of a uniform disk).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "runtime/program/program.h"
#include "tests/support/load_util.h"

namespace kanesim::test {
namespace {

double MaxAbs(const sim::MemorySink& s, size_t c) {
  double v = 0.0;
  for (const auto& r : s.rows) v = std::max(v, std::fabs(r[c]));
  return v;
}

TEST(Contacts, SphereRollsDownTheInclineAtFiveSeventhsGSinAlpha) {
  // If this fails, the rolling rows or their acceleration bias are wrong (the sphere
  // slides at g sin(alpha), or spins in place), or the contact forces are not the
  // multipliers of the rows.
  const double alpha = 0.3, g = 9.81, m = 2.0;
  auto l = LoadModel(kRoot + "/examples/sphere_incline.mech");
  ASSERT_TRUE(l && l->prog);
  EXPECT_EQ(rt::Summarize(*l->prog).dof, 3);
  auto s = RunModel(*l->prog, 2.0, 0.01, 1e-10,
                    {"ball.body.r[1]", "ball.body.r[2]", "contact.normal_force", "contact.longitudinal_force",
                     "contact.lateral_force", "contact.constraint_residual", "contact.constraint_residual_velocity",
                     "kinetic_energy", "potential_energy"});
  const double acc = 5.0 / 7.0 * g * std::sin(alpha);  // (1)
  const double x0 = s.rows[0][0], y0 = s.rows[0][1];
  double es = 0, en = 0, ef = 0, ee = 0;
  const double E0 = s.rows[0][7] + s.rows[0][8];
  for (size_t i = 0; i < s.rows.size(); ++i) {
    const auto& r = s.rows[i];
    const double t = s.times[i];
    const double dist = -((r[0] - x0) * std::cos(alpha) + (r[1] - y0) * std::sin(alpha));
    es = std::max(es, std::fabs(dist - 0.5 * acc * t * t));
    en = std::max(en, std::fabs(r[2] - m * g * std::cos(alpha)));            // (2)
    if (t > 0) ef = std::max(ef, std::fabs(-r[3] - 2.0 / 7.0 * m * g * std::sin(alpha)) + std::fabs(r[4]));
    ee = std::max(ee, std::fabs(r[7] + r[8] - E0));
  }
  EXPECT_LT(es, 1e-8);   // 4.1 m travelled; rtol 1e-10
  EXPECT_LT(en, 1e-10);  // forces at the output state: round-off
  EXPECT_LT(ef, 1e-10);
  EXPECT_LT(ee, 1e-8);   // rolling without slip does no work
  EXPECT_LT(MaxAbs(s, 5), 1e-12);
  EXPECT_LT(MaxAbs(s, 6), 1e-12);
}

TEST(Contacts, DiskRollsSteadilyOnTheAnalyticCircleAndConservesEnergy) {
  // If this fails, the disk's contact-point kinematics (the lowest rim point moving over
  // the rim) are wrong: the lean drifts from the steady value of eq. (3).
  auto l = LoadModel(kRoot + "/examples/rolling_disk.mech");
  ASSERT_TRUE(l && l->prog);
  auto s = RunModel(*l->prog, 5.0, 0.01, 1e-10,
                    {"lean", "kinetic_energy", "potential_energy", "contact.constraint_residual",
                     "contact.constraint_residual_velocity"});
  double dl = 0, de = 0;
  const double E0 = s.rows[0][1] + s.rows[0][2];
  for (const auto& r : s.rows) {
    dl = std::max(dl, std::fabs(r[0] - 0.2));
    de = std::max(de, std::fabs(r[1] + r[2] - E0));
  }
  EXPECT_LT(dl, 1e-6);  // measured 6e-8 at rtol 1e-9
  EXPECT_LT(de, 1e-8 * E0);
  EXPECT_LT(MaxAbs(s, 3), 1e-12);
  EXPECT_LT(MaxAbs(s, 4), 1e-12);
  // Discrimination: 0.1 m/s too fast for eq. (3) and the lean swings by 0.05 rad.
  auto off = LoadModel(kRoot + "/examples/rolling_disk.mech", {{"v_straight", "0.1"}});
  ASSERT_TRUE(off && off->prog);
  auto s2 = RunModel(*off->prog, 5.0, 0.01, 1e-10, {"lean"});
  double dl2 = 0;
  for (const auto& r : s2.rows) dl2 = std::max(dl2, std::fabs(r[0] - 0.2));
  EXPECT_GT(dl2, 0.02);
}

double MaxLean(double v) {
  auto l = LoadModel(kRoot + "/examples/rolling_disk.mech",
                     {{"theta", "0"}, {"v_straight", std::to_string(v)}, {"lean_rate", "0.1"}});
  EXPECT_TRUE(l && l->prog);
  if (!l || !l->prog) return 0.0;
  auto s = RunModel(*l->prog, 8.0, 0.01, 1e-9, {"lean"});
  return MaxAbs(s, 0);
}

TEST(Contacts, UprightDiskIsStableAboveTheCriticalSpeedAndFallsBelow) {
  // If this fails, the gyroscopic coupling of lean and heading through the rolling
  // constraints is wrong: v_c = sqrt(g a / 3) = 0.99 m/s for a = 0.3 m.
  const double vc = std::sqrt(9.81 * 0.3 / 3.0);
  EXPECT_LT(MaxLean(1.2 * vc), 0.05);  // measured 0.026 rad after a 0.1 rad/s lean kick
  EXPECT_LT(MaxLean(2.0 * vc), 0.02);
  EXPECT_GT(MaxLean(0.8 * vc), 0.3);   // measured 0.68 rad: it falls over (and rolls on its rim)
}

TEST(Contacts, SleighLateralVelocityStaysZeroAndItsTurningDecays) {
  // If this fails, the knife edge's rotating row (d = n x e) has a wrong rate term, or the
  // non-holonomic row is being projected as if it were a position constraint.
  auto l = LoadModel(kRoot + "/examples/sleigh.mech");
  ASSERT_TRUE(l && l->prog);
  EXPECT_EQ(rt::Summarize(*l->prog).dof, 2);
  auto s = RunModel(*l->prog, 20.0, 0.02, 1e-9, {"plane.u[3]", "kinetic_energy", "blade.constraint_residual_velocity"});
  const double E0 = s.rows[0][1];
  double de = 0;
  for (const auto& r : s.rows) de = std::max(de, std::fabs(r[1] - E0));
  EXPECT_LT(de, 1e-7 * E0);
  EXPECT_LT(MaxAbs(s, 2), 1e-12);
  EXPECT_GT(std::fabs(s.rows[0][0]), 1.0);
  EXPECT_LT(std::fabs(s.rows.back()[0]), 1e-6);  // turning rate 1.5 -> ~0
}

}  // namespace
}  // namespace kanesim::test
