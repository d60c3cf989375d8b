// Constraint forces on request (runtime/constraints/reactions.*) against closed forms.
//
// Physical pendulum (tests/support/builders.h Pendulum): a thin rod of mass m and length
// L hanging along -y of its frame from a revolute joint about z at the origin; mass
// centre at L/2, I_O = m L^2 / 3, q measured from the downward vertical. Lagrange:
//   qdd = -(3 g / (2 L)) sin q                                                      (1)
// The pivot's force on the rod is F = m a_cm - m g. In the rod's frame (x_b along the
// direction the mass centre moves for increasing q, y_b from the mass centre to the
// pivot):
//   F . y_b = m (g cos q + (L/2) qd^2)          (radial: NOT L qd^2, the centre is at L/2)
//   F . x_b = m ((L/2) qdd + g sin q) = m g sin q / 4                              (2)
// and no torque about x_b, y_b (planar motion of a body symmetric about its plane).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "runtime/program/program.h"
#include "tests/support/load_util.h"
#include "tests/support/builders.h"
#include "compiler/compiler.h"

namespace kanesim::test {
namespace {

TEST(Reactions, PhysicalPendulumPivotForceMatchesClosedForm) {
  // If this fails, the joint reaction is not the subtree's Newton-Euler balance (wrong
  // point, sign or frame), or it misses the centripetal term at the mass centre.
  const double m = 1.3, L = 0.7, g = 9.81;
  auto cr = rt::Compile(Pendulum(m, L, g, 2.0), {});
  ASSERT_TRUE(cr.program);
  auto s = RunModel(*cr.program, 5.0, 0.01, 1e-10,
                    {"pivot.q", "pivot.u", "pivot.reaction_force[1]", "pivot.reaction_force[2]",
                     "pivot.reaction_force[3]", "pivot.reaction_torque[1]", "pivot.reaction_torque[2]",
                     "pivot.reaction_torque[3]"});
  double err = 0.0, fmax = 0.0;
  for (const auto& r : s.rows) {
    const double q = r[0], qd = r[1];
    const double radial = m * (g * std::cos(q) + L / 2 * qd * qd);  // (2)
    const double tangential = m * g * std::sin(q) / 4;
    fmax = std::max(fmax, std::fabs(radial));
    err = std::max({err, std::fabs(r[3] - radial), std::fabs(r[2] - tangential), std::fabs(r[4]), std::fabs(r[5]),
                    std::fabs(r[6]), std::fabs(r[7])});
  }
  EXPECT_GT(fmax, 20.0);           // released at 2 rad: the radial force peaks near 2.6 m g
  EXPECT_LT(err, 1e-10 * fmax);    // evaluated at the output state: round-off (measured below 1e-14 N)
}

TEST(Reactions, ConstraintForcesDoNoWorkOnAdmissibleMotions) {
  // If this fails, the reaction wrenches of tree joints or the loop multipliers are not
  // the ideal constraint forces of the motion (Kane's and Newton-Euler's projections
  // disagree), checked at every output instant.
  for (const char* ex : {"fourbar.mech", "slider_crank.mech"}) {
    auto l = LoadModel(kRoot + "/examples/" + ex);
    ASSERT_TRUE(l && l->prog);
    auto s = RunModel(*l->prog, 1.0, 0.005, 1e-8, {"constraint_power", "kinetic_energy"});
    double pmax = 0.0, kmax = 0.0;
    for (const auto& r : s.rows) {
      pmax = std::max(pmax, std::fabs(r[0]));
      kmax = std::max(kmax, r[1]);
    }
    // Scale: kinetic energy per second of motion; round-off of ~100 N forces at ~1 m/s.
    EXPECT_LT(pmax, 1e-10 * std::max(1.0, kmax)) << ex;
  }
}

TEST(Reactions, LoopForcesBalanceTheGroundReactionsOfTheFourBar) {
  // If this fails, the cut joint's force on the rocker is not the opposite of its force
  // on the coupler, or the tree reactions ignore the loop force: the rocker alone is
  // balanced by its pivot, its weight and the cut force (Newton's second law).
  auto l = LoadModel(kRoot + "/examples/fourbar.mech");
  ASSERT_TRUE(l && l->prog);
  const rt::Program& p = *l->prog;
  auto ws = rt::MakeWorkspace(p);
  std::vector<std::string> names = {"rocker_pivot.reaction_force[1]", "rocker_pivot.reaction_force[2]",
                                    "coupler_rocker.reaction_force[1]", "coupler_rocker.reaction_force[2]",
                                    "rocker.body.r[1]", "rocker.body.r[2]"};
  std::string err;
  auto plan = rt::PlanSignals(p, names, &err);
  ASSERT_TRUE(plan) << err;
  std::vector<double> y(static_cast<size_t>(rt::StateSize(p))), yd(y.size()), out(names.size());
  rt::InitialState(p, y.data());
  ASSERT_EQ(rt::EvalSignals(p, *plan, *ws, 0.0, y.data(), out.data()), 0);
  // Both forces act on the rocker and are resolved in axes parallel to its body frame
  // (rocker_pivot.frame_b is the rocker's frame_a, the cut's frame_b its tip):
  //   m_rocker a_cm = F_pivot + F_cut + m_rocker g.
  int L = p.joint_of_flat[static_cast<size_t>(p.mech->FindJoint("rocker_pivot"))];
  ASSERT_GE(L, 0);
  const rt::Vec3 a = ws->a_bias_cm[static_cast<size_t>(L)];  // full acceleration (include_free)
  const rt::Mat3 R = ws->R_WB[static_cast<size_t>(L)];
  const rt::Vec3 F = R * rt::Vec3(out[0] + out[2], out[1] + out[3], 0.0);
  const rt::Vec3 expect = 0.8 * (a - p.gravity_W);
  EXPECT_NEAR((F - expect).norm(), 0.0, 1e-10 * expect.norm());
}

}  // namespace
}  // namespace kanesim::test
