// Start speeds that violate the velocity constraints are projected onto them by the
// assembly (compiler/loops.cpp, minimum-norm correction over the speeds not held)
// and warning W315 says so (issue 20). Checked against the projection computed here from
// the rolling disk's contact kinematics, independently of the compiler's rows.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "runtime/program/program.h"
#include "tests/support/load_util.h"
#include "compiler/compiler.h"

namespace kanesim::test {
namespace {

std::string G6(double x) {
  std::ostringstream o;
  o.precision(6);
  o << x;
  return o.str();
}

TEST(StartSpeeds, LeanRateOfARollingDiskIsProjectedAndNamed) {
  // If this fails, the start of a rolling disk given a lean rate is corrected silently
  // (no W315), or the warning names the wrong constraint or numbers, or the correction is
  // not the minimum-norm one onto the contact's velocity constraints.
  const double a = 0.3, theta = 0.2, lean_rate = 0.01;
  auto l = LoadModel(kRoot + "/examples/rolling_disk.mech", {{"lean_rate", "0.01"}});
  ASSERT_TRUE(l && l->prog);
  // The start the model gives: FreeMotion u = {v resolved in the world, w resolved in the
  // disk}; the disk leans by theta about world x (quaternion {cos(theta/2), -sin(theta/2), 0, 0}).
  const double g = 9.81, rc = 1.0;
  const double Omega = std::sqrt(g * std::sin(theta) / (std::cos(theta) * (a * std::sin(theta) / 4 + 1.5 * rc)));
  const double V = Omega * rc, s = -V / a - Omega * std::sin(theta);
  Eigen::Matrix<double, 6, 1> u0;
  u0 << V, 0, 0, lean_rate, Omega * std::cos(theta), Omega * std::sin(theta) + s;
  // Rolling: the rim point at the contact, r = (0, -a, 0) in the disk, is at rest:
  // v + R (w x r) = 0, i.e. A u = 0 with A = [I, -R [r]x].
  Eigen::Matrix3d R = Eigen::AngleAxisd(-theta, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const Eigen::Vector3d r(0, -a, 0);
  Eigen::Matrix3d rx;
  rx << 0, -r.z(), r.y(), r.z(), 0, -r.x(), -r.y(), r.x(), 0;
  Eigen::Matrix<double, 3, 6> A;
  A << Eigen::Matrix3d::Identity(), -R * rx;
  const Eigen::Matrix<double, 6, 1> du = -A.transpose() * (A * A.transpose()).ldlt().solve(A * u0);
  const Eigen::Matrix<double, 6, 1> u1 = u0 + du;
  EXPECT_NEAR(u1[3], 0.00917431, 1e-8);  // the 0.01 -> 0.00917

  std::vector<double> y(static_cast<size_t>(rt::StateSize(*l->prog)));
  rt::InitialState(*l->prog, y.data());
  const int nq = rt::NumQ(*l->prog);
  for (int i = 0; i < 6; ++i) EXPECT_NEAR(y[static_cast<size_t>(nq + i)], u1[i], 1e-12) << "u[" << i + 1 << "]";

  const rt::CompileMessage w = rt::StartSpeedsWarning(*l->prog);
  EXPECT_EQ(w.code, flat::DiagCode::StartSpeedsProjected);
  EXPECT_NE(w.message.find("velocity constraints of contact 'contact'"), std::string::npos) << w.message;
  EXPECT_NE(w.message.find("free.u[4] 0.01 -> " + G6(u1[3])), std::string::npos) << w.message;
  Eigen::Index k = 0;
  const double largest = du.cwiseAbs().maxCoeff(&k);
  EXPECT_NE(w.message.find("largest change " + G6(largest) + " (free.u[" + std::to_string(k + 1) + "])"),
            std::string::npos)
      << w.message;
  // The contact's rows are the normal (world y) and the two ground tangents (world x, z
  // here, rolling along x), so their residuals are the components of A u0 up to sign.
  EXPECT_NE(w.message.find("largest residual " + G6((A * u0).cwiseAbs().maxCoeff())), std::string::npos) << w.message;
  EXPECT_EQ(w.loc.line, 32);  // the RollingDisk line of examples/rolling_disk.mech
}

TEST(StartSpeeds, ConsistentStartsGiveNoWarning) {
  // If this fails, W315 fires on starts that already satisfy the constraints (the steady
  // rolling disk: round-off only), or on a loop whose dependent speeds start at zero for
  // the assembly to fill (the four-bar: its crank speed is held, the others start at 0).
  auto disk = LoadModel(kRoot + "/examples/rolling_disk.mech");
  ASSERT_TRUE(disk && disk->prog);
  EXPECT_EQ(rt::StartSpeedsWarning(*disk->prog).message, "");
  auto fourbar = LoadModel(kRoot + "/examples/fourbar.mech");
  ASSERT_TRUE(fourbar && fourbar->prog);
  EXPECT_EQ(rt::StartSpeedsWarning(*fourbar->prog).message, "");
  std::vector<double> y(static_cast<size_t>(rt::StateSize(*fourbar->prog)));
  rt::InitialState(*fourbar->prog, y.data());
  int moved = 0;  // the assembly did fill dependent speeds (else this case tests nothing)
  for (int i = rt::NumQ(*fourbar->prog); i < rt::StateSize(*fourbar->prog); ++i) moved += y[static_cast<size_t>(i)] != 0.0;
  EXPECT_GE(moved, 2);
}

}  // namespace
}  // namespace kanesim::test
