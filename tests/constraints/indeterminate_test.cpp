// Statically indeterminate constraint-force components (compiler/indeterminate.cpp):
// written as NaN, the determinate ones against an independent planar Newton-Euler solve.
//
// examples/fourbar.mech is a planar loop built from spatial revolute joints: the cut
// joint's rows "translation along z" and the two tilts are redundant, so the force along
// z and the torques about x and y of every pin are indeterminate (only what the pins carry
// together out of the plane is fixed), while the in-plane forces and the torque about the
// pin axis are determined.
//
// Independent planar Newton-Euler of the three links (unknowns: the angular accelerations
// alpha_1..3 and the pin forces F_O (ground on crank at O), F_A (crank on coupler at A),
// F_B (coupler on rocker at B), F_D (ground on rocker at D), all in world axes):
//   crank    m1 aG1 = F_O - F_A + m1 g,   I1 alpha1 = (O - G1) x F_O - (A - G1) x F_A      (1)
//   coupler  m2 aG2 = F_A - F_B + m2 g,   I2 alpha2 = (A - G2) x F_A - (B - G2) x F_B      (2)
//   rocker   m3 aG3 = F_D + F_B + m3 g,   I3 alpha3 = (D - G3) x F_D + (B - G3) x F_B      (3)
//   loop     a_B(coupler side) = a_B(rocker side)  (2 equations)                            (4)
// with aP = alpha k x (P - C) - w^2 (P - C) about a point C of known acceleration, Gi the
// rods' midpoints and Ii = mi Li^2 / 12: 11 linear equations in 11 unknowns, solved at the
// positions and rates the simulation outputs.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "runtime/program/program.h"
#include "tests/support/load_util.h"
#include "compiler/compiler.h"

namespace kanesim::test {
namespace {

// The twelve out-of-plane components of the four pins.
std::vector<std::string> OutOfPlane() {
  std::vector<std::string> v;
  for (const char* j : {"crank_pivot", "crank_coupler", "rocker_pivot", "coupler_rocker"})
    for (const char* c : {".reaction_force[3]", ".reaction_torque[1]", ".reaction_torque[2]"})
      v.push_back(std::string(j) + c);
  return v;
}

std::vector<std::string> InPlane() {
  std::vector<std::string> v;
  for (const char* j : {"crank_pivot", "crank_coupler", "rocker_pivot", "coupler_rocker"})
    for (const char* c : {".reaction_force[1]", ".reaction_force[2]", ".reaction_torque[3]"})
      v.push_back(std::string(j) + c);
  return v;
}

const std::vector<std::string> kState = {"crank_pivot.q", "crank_pivot.u", "crank_coupler.q", "crank_coupler.u",
                                         "rocker_pivot.q", "rocker_pivot.u"};

std::shared_ptr<const rt::Program> Recompile(const Loaded& l, rt::IndeterminateReactions mode) {
  rt::CompileOptions o;
  o.indeterminate = mode;
  rt::CompileResult cr = rt::Compile(l.mech, o);
  EXPECT_TRUE(cr.errors.empty());
  return cr.program;
}

std::vector<std::string> Concat(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

// (1)-(4) at crank angle th1, coupler angle th2, rocker angle th3 (absolute) and rates:
// x = [alpha1..3, F_O, F_A, F_B, F_D].
Eigen::Matrix<double, 11, 1> PlanarPinForces(double th1, double w1, double th2, double w2, double th3, double w3) {
  const double a = 0.2, b = 0.6, c = 0.5, d = 0.6, m1 = 0.5, m2 = 1.0, m3 = 0.8, g = 9.81;
  const double I1 = m1 * a * a / 12, I2 = m2 * b * b / 12, I3 = m3 * c * c / 12;
  using V = Eigen::Vector2d;
  auto e = [](double t) { return V(std::cos(t), std::sin(t)); };
  auto perp = [](const V& r) { return V(-r.y(), r.x()); };  // k x r
  const V O(0, 0), D(d, 0), A = a * e(th1), B = A + b * e(th2);
  const V G1 = A / 2, G2 = (A + B) / 2, G3 = (D + B) / 2, grav(0, -g);
  // Accelerations as (coefficient of alpha_i) and (known part).
  const V aA0 = -w1 * w1 * A, aA1 = perp(A);
  Eigen::Matrix<double, 11, 11> M = Eigen::Matrix<double, 11, 11>::Zero();
  Eigen::Matrix<double, 11, 1> rhs = Eigen::Matrix<double, 11, 1>::Zero();
  enum { kA1 = 0, kA2, kA3, kFO, kFA = 5, kFB = 7, kFD = 9 };
  auto force = [&](int row, int col, double sign) {
    M(row, col) += sign;
    M(row + 1, col + 1) += sign;
  };
  auto moment = [&](int row, const V& r, int col, double sign) {
    M(row, col) += sign * -r.y();
    M(row, col + 1) += sign * r.x();
  };
  // (1) crank: m1 (alpha1 k x G1 - w1^2 G1) = F_O - F_A + m1 g
  M.block<2, 1>(0, kA1) = m1 * perp(G1);
  force(0, kFO, -1), force(0, kFA, 1);
  rhs.segment<2>(0) = m1 * grav + m1 * w1 * w1 * G1;
  M(2, kA1) = I1;
  moment(2, O - G1, kFO, -1), moment(2, A - G1, kFA, 1);
  // (2) coupler: m2 (aA + alpha2 k x (G2 - A) - w2^2 (G2 - A)) = F_A - F_B + m2 g
  M.block<2, 1>(3, kA1) = m2 * aA1;
  M.block<2, 1>(3, kA2) = m2 * perp(G2 - A);
  force(3, kFA, -1), force(3, kFB, 1);
  rhs.segment<2>(3) = m2 * grav - m2 * aA0 + m2 * w2 * w2 * (G2 - A);
  M(5, kA2) = I2;
  moment(5, A - G2, kFA, -1), moment(5, B - G2, kFB, 1);
  // (3) rocker: m3 (alpha3 k x (G3 - D) - w3^2 (G3 - D)) = F_D + F_B + m3 g
  M.block<2, 1>(6, kA3) = m3 * perp(G3 - D);
  force(6, kFD, -1), force(6, kFB, -1);
  rhs.segment<2>(6) = m3 * grav + m3 * w3 * w3 * (G3 - D);
  M(8, kA3) = I3;
  moment(8, D - G3, kFD, -1), moment(8, B - G3, kFB, -1);
  // (4): aA + alpha2 k x (B - A) - w2^2 (B - A) = alpha3 k x (B - D) - w3^2 (B - D)
  M.block<2, 1>(9, kA1) = aA1;
  M.block<2, 1>(9, kA2) = perp(B - A);
  M.block<2, 1>(9, kA3) = -perp(B - D);
  rhs.segment<2>(9) = -aA0 + w2 * w2 * (B - A) - w3 * w3 * (B - D);
  return M.fullPivLu().solve(rhs);
}

TEST(Indeterminate, PlanarFourBarNamesTheOutOfPlaneComponents) {
  // If this fails, the null space of the constraint-force map is wrong or mapped to the
  // wrong signals: exactly the out-of-plane force and the two tilting torques of every pin
  // are moved by the redundant rows (translation along z, the two tilts).
  auto l = LoadModel(kRoot + "/examples/fourbar.mech");
  ASSERT_TRUE(l && l->prog);
  const auto all = rt::IndeterminateSignals(*l->prog, rt::AvailableSignals(*l->prog));
  auto want = OutOfPlane();
  auto got = all;
  std::sort(want.begin(), want.end());
  std::sort(got.begin(), got.end());
  EXPECT_EQ(got, want);
  // The warning names the cut joint with its location and the redundant rows.
  const rt::CompileMessage w = rt::IndeterminateWarning(*l->prog, all);
  EXPECT_STREQ(flat::DiagCodeString(w.code), "W313");
  EXPECT_NE(w.loc.file.str().find("fourbar.mech"), std::string::npos);
  ASSERT_EQ(w.notes.size(), 1u);
  EXPECT_NE(w.notes[0].second.find("joint 'coupler_rocker': translation along z, tilt of the axis towards e1, "
                                   "tilt of the axis towards e2"),
            std::string::npos)
      << w.notes[0].second;
  EXPECT_NE(w.hint.find("--reactions min-norm"), std::string::npos);
}

TEST(Indeterminate, PlanarFourBarWritesNaNAndTheInPlaneForcesOfNewtonEuler) {
  // If this fails, an indeterminate component is written as a number (the minimum-norm
  // share passed off as the reaction), or the determinate in-plane pin forces disagree
  // with an independent planar Newton-Euler solve of the same state (wrong loop
  // multipliers, frame or sign).
  auto l = LoadModel(kRoot + "/examples/fourbar.mech");
  ASSERT_TRUE(l && l->prog);
  const auto in_plane = InPlane(), out_of_plane = OutOfPlane();
  auto s = RunModel(*l->prog, 1.0, 0.01, 1e-9, Concat(Concat(kState, in_plane), out_of_plane));
  ASSERT_GT(s.rows.size(), 90u);
  double err = 0.0, fmax = 0.0, tz = 0.0;
  for (const auto& r : s.rows) {
    for (size_t k = 0; k < out_of_plane.size(); ++k) EXPECT_TRUE(std::isnan(r[6 + in_plane.size() + k]));
    const double th1 = r[0], w1 = r[1], th2 = th1 + r[2], w2 = w1 + r[3], th3 = r[4], w3 = r[5];
    const auto x = PlanarPinForces(th1, w1, th2, w2, th3, w3);
    // Each pin's force resolved in its frame_b: crank (th1), coupler (th2), rocker (th3),
    // and the cut's frame_b, the rocker's tip (th3).
    const double frame_b[4] = {th1, th2, th3, th3};
    const int col[4] = {3, 5, 9, 7};  // F_O, F_A, F_D, F_B
    for (int j = 0; j < 4; ++j) {
      const double cth = std::cos(frame_b[j]), sth = std::sin(frame_b[j]);
      const Eigen::Vector2d F(x[col[j]], x[col[j] + 1]);
      const Eigen::Vector2d Fb(cth * F.x() + sth * F.y(), -sth * F.x() + cth * F.y());
      fmax = std::max(fmax, F.norm());
      err = std::max({err, std::fabs(r[6 + 3 * j] - Fb.x()), std::fabs(r[7 + 3 * j] - Fb.y())});
      tz = std::max(tz, std::fabs(r[8 + 3 * j]));  // no torque about a frictionless pin's axis
    }
  }
  EXPECT_GT(fmax, 10.0);           // the pins carry tens of newtons at 6 rad/s
  EXPECT_LT(err, 1e-9 * fmax);     // the same state, two exact solves: round-off (measured 3e-16 relative)
  EXPECT_LT(tz, 1e-9 * fmax);
}

TEST(Indeterminate, MinNormOptionWritesTheMinimumNormShare) {
  // If this fails, `--reactions min-norm` does not restore numbers for the indeterminate
  // components, or it changes the determinate ones. Nothing loads the four-bar out of its
  // plane, so the minimum-norm share of every out-of-plane component is zero.
  auto l = LoadModel(kRoot + "/examples/fourbar.mech");
  ASSERT_TRUE(l && l->prog);
  auto mn = Recompile(*l, rt::IndeterminateReactions::MinNorm);
  ASSERT_TRUE(mn);
  const auto names = Concat(InPlane(), OutOfPlane());
  auto a = RunModel(*l->prog, 0.5, 0.01, 1e-9, names);
  auto b = RunModel(*mn, 0.5, 0.01, 1e-9, names);
  ASSERT_EQ(a.rows.size(), b.rows.size());
  double out = 0.0;
  for (size_t i = 0; i < a.rows.size(); ++i) {
    for (size_t k = 0; k < InPlane().size(); ++k) EXPECT_EQ(a.rows[i][k], b.rows[i][k]);
    for (size_t k = InPlane().size(); k < names.size(); ++k) {
      ASSERT_TRUE(std::isfinite(b.rows[i][k])) << names[k];
      out = std::max(out, std::fabs(b.rows[i][k]));
    }
  }
  EXPECT_LT(out, 1e-9);  // round-off of forces of tens of newtons
}

TEST(Indeterminate, NonRedundantLoopsHaveNoIndeterminateComponent) {
  // If this fails, determinate components are reported as indeterminate (a tolerance too
  // tight, or the null space taken of the wrong map): a loop closed by a spherical joint
  // after a universal one has independent constraint rows, so every reaction is a number.
  auto l = LoadModel(kRoot + "/tests/constraints/models/rusr_fourbar.mech");
  ASSERT_TRUE(l && l->prog);
  EXPECT_TRUE(l->prog->redundant_rows.empty());
  const auto all = rt::AvailableSignals(*l->prog);
  EXPECT_TRUE(rt::IndeterminateSignals(*l->prog, all).empty());
  std::vector<std::string> reactions;
  for (const auto& n : all)
    if (n.find(".reaction_") != std::string::npos) reactions.push_back(n);
  ASSERT_EQ(reactions.size(), 24u);  // 3 tree joints and the cut, 6 components each
  auto s = RunModel(*l->prog, 1.0, 0.01, 1e-9, reactions);
  for (const auto& r : s.rows)
    for (double v : r) ASSERT_TRUE(std::isfinite(v));
}

}  // namespace
}  // namespace kanesim::test
