// Redundant rows against singular ones (issue 38 §1; docs/constraints.md "Redundant or
// singular"). An overconstrained linkage has a loop row that is redundant at every
// configuration; a change point is where the loop's rows lose rank. If these failed, the
// branch monitor would take the orthogonal Bricard (no change point anywhere) for a change
// point, as it did when the loop's fourth-best row was left out for good (its four other
// rows lose rank at the odd joints' angle +-2 pi / 3), or would measure a loop built in
// millimetres as a thousand times nearer to singular than the same loop in metres.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "runtime/constraints/constraints.h"
#include "runtime/runtime.h"
#include "runtime/kinematics/kinematics.h"
#include "runtime/program/program.h"
#include "tests/support/load_util.h"

namespace kanesim::test {
namespace {

TEST(RedundantRows, AnOverconstrainedLoopKeepsItsRedundantRowAPlanarLoopLeavesItsZeroRowsOut) {
  auto bricard = LoadModel(kRoot + "/tests/stress/models/bricard.mech");
  ASSERT_TRUE(bricard && bricard->prog);
  EXPECT_EQ(bricard->prog->dof, 1);
  EXPECT_EQ(bricard->prog->redundant_rows.size(), 1u);
  EXPECT_EQ(bricard->prog->active_rows.size(), 5u);  // the redundant row is not zero: kept
  auto fourbar = LoadModel(kRoot + "/examples/fourbar.mech");
  ASSERT_TRUE(fourbar && fourbar->prog);
  EXPECT_EQ(fourbar->prog->redundant_rows.size(), 3u);
  EXPECT_EQ(fourbar->prog->active_rows.size(), 2u);  // out-of-plane rows, zero: left out
}

// rho of the Bricard's loop on its motion, odd joints at x, even ones at y(x) from
// (1 + cos x)(1 + cos y) = 1, with links of length a.
std::vector<double> BricardRho(double a) {
  auto l = LoadModel(kRoot + "/tests/stress/models/bricard.mech", {{"a", std::to_string(a)}});
  EXPECT_TRUE(l && l->prog);
  if (!l || !l->prog) return {};
  const rt::Program& p = *l->prog;
  auto ws = rt::MakeWorkspace(p);
  std::vector<double> y(static_cast<size_t>(rt::StateSize(p)), 0.0), out;
  for (int k = -12; k <= 12; ++k) {
    const double x = k * (2 * M_PI / 3) / 12;
    for (double sign : {1.0, -1.0}) {
      const double c = 1.0 / (1.0 + std::cos(x)) - 1.0;
      const double yy = sign * std::acos(std::max(-1.0, std::min(1.0, c)));
      for (const rt::TreeJoint& j : p.joints) {
        const bool odd = j.name == "j1" || j.name == "j3" || j.name == "j5";
        y[static_cast<size_t>(j.q0)] = odd ? x : yy;
      }
      EXPECT_EQ(rt::UnpackState(p, *ws, 0.0, y.data()), 0);
      rt::PositionKinematics(p, *ws);
      rt::VelocityKinematics(p, *ws);
      rt::ConstraintResiduals(p, *ws);
      EXPECT_LT(ws->phi.cwiseAbs().maxCoeff(), 1e-12 * a) << "x " << x;  // on the motion
      rt::ConstraintJacobian(p, *ws);
      double length = 0.0;
      out.push_back(rt::LoopSingularRatio(p, *ws, 0, &length));
    }
  }
  return out;
}

TEST(RedundantRows, TheBricardIsNowhereNearAChangePointInAnyUnitOfLength) {
  const std::vector<double> m = BricardRho(1.0), mm = BricardRho(1e-3), km = BricardRho(1e3);
  ASSERT_EQ(m.size(), 50u);
  ASSERT_EQ(mm.size(), m.size());
  ASSERT_EQ(km.size(), m.size());
  for (size_t i = 0; i < m.size(); ++i) {
    // Measured 0.3 ... 0.6 (the zone of a change point is rho < 1e-2).
    EXPECT_GT(m[i], 0.2) << i;
    EXPECT_NEAR(mm[i], m[i], 1e-9) << i;
    EXPECT_NEAR(km[i], m[i], 1e-9) << i;
  }
}

}  // namespace
}  // namespace kanesim::test
