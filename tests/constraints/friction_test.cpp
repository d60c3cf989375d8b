// Coulomb friction that follows a joint's normal force (runtime/kane/friction.cpp).
//
// A bead (mass m) slides in a tube that turns at constant rate w about the vertical,
// without gravity. In the tube's frame the radial equation is m r'' = m w^2 r + Q_f and
// the tube's wall carries the Coriolis force N = 2 m w r' across the axis, so with
// Q_f = -mu N sign(r') and r' > 0:
//   r'' = w^2 r - 2 mu w r'                                                          (1)
// a linear ODE: r = A e^(l1 t) + B e^(l2 t), l1,2 = -mu w +- w sqrt(mu^2 + 1),
// A + B = r0, l1 A + l2 B = v0 (the regularization tanh(r'/v) is 1 to double precision
// for r' >= 0.1 and v = 1e-6).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "runtime/program/program.h"
#include "tests/support/load_util.h"
#include "tests/support/builders.h"
#include "compiler/compiler.h"

namespace kanesim::test {
namespace {

flat::Mechanism Tube(double mu, double w, double r0, double v0) {
  MechBuilder b;
  const int world = b.World(Vec3::Zero());
  const int tube = b.Frame("tube.frame");
  const int bead = b.Frame("bead.frame");
  b.Body("tube", tube, 1.0, Vec3::Zero(), Diag(0.1, 0.1, 0.1));
  b.Body("bead", bead, 0.5, Vec3::Zero(), Diag(1e-3, 1e-3, 1e-3));
  auto& spin = b.Joint("spin", JointType::Revolute, world, tube, Vec3::UnitY());
  spin.prescribed[0] = b.m.exprs.Binary(flat::Op::Mul, b.C(w), b.m.exprs.Time());
  auto& slide = b.Joint("slide", JointType::Prismatic, tube, bead, Vec3::UnitX());
  slide.q_start[0] = b.C(r0);
  slide.u_start[0] = b.C(v0);
  slide.friction_mu = b.C(mu);
  slide.friction_v = b.C(1e-6);
  b.m.model_name = "Tube";
  return b.m;
}

TEST(Friction, BeadInASpinningTubeFollowsTheClosedForm) {
  // If this fails, the friction force does not follow the joint's normal (Coriolis)
  // force, or the fixed point between Kane's equations and the reactions is wrong.
  const double mu = 0.3, w = 2.0, r0 = 0.2, v0 = 0.1;
  auto cr = rt::Compile(Tube(mu, w, r0, v0), {});
  ASSERT_TRUE(cr.program) << (cr.errors.empty() ? "" : cr.errors[0].message);
  auto s = RunModel(*cr.program, 2.0, 0.01, 1e-11, {"slide.q", "slide.u", "slide.reaction_force[3]"});
  const double l1 = -mu * w + w * std::sqrt(mu * mu + 1), l2 = -mu * w - w * std::sqrt(mu * mu + 1);
  const double A = (v0 - l2 * r0) / (l1 - l2), B = r0 - A;
  double err = 0.0, rmax = 0.0, nerr = 0.0;
  for (size_t i = 0; i < s.rows.size(); ++i) {
    const double t = s.times[i];
    const double r = A * std::exp(l1 * t) + B * std::exp(l2 * t);
    const double rd = l1 * A * std::exp(l1 * t) + l2 * B * std::exp(l2 * t);
    err = std::max(err, std::fabs(s.rows[i][0] - r));
    rmax = std::max(rmax, r);
    // The wall's force on the bead: 2 m w r' across the tube (frame z = -tangential).
    nerr = std::max(nerr, std::fabs(std::fabs(s.rows[i][2]) - 2 * 0.5 * w * rd));
  }
  EXPECT_LT(err, 1e-8 * rmax);  // rtol 1e-11; the closed form of eq. (1)
  EXPECT_LT(nerr, 1e-8);
  // Without friction the bead flies out faster: the test is sensitive to mu.
  auto free_cr = rt::Compile(Tube(0.0, w, r0, v0), {});
  ASSERT_TRUE(free_cr.program);
  auto s0 = RunModel(*free_cr.program, 2.0, 0.01, 1e-11, {"slide.q"});
  EXPECT_GT(s0.rows.back()[0] - s.rows.back()[0], 0.1);
}

// Cart (mass M) on a horizontal prismatic guide with friction, a point bob (mass m) on
// a massless arm of length l hanging from it (angle th from the downward vertical). The
// guide's normal force depends on the bob's acceleration, which depends on the friction:
// both projections are coupled. Lagrange, with Q_f = -mu |N| tanh(x'/v):
//   (M + m) x'' + m l (th'' cos th - th'^2 sin th) = Q_f                                (2)
//   m l^2 th'' + m l x'' cos th + m g l sin th = 0                                       (3)
//   N = (M + m) g + m l (th'' sin th + th'^2 cos th)                                     (4)
// solved here by its own fixed point on (2)-(4), compared with rt::Derivative.
TEST(Friction, CartPendulumCouplesFrictionAndTheNormalForce) {
  // If this fails, the friction force is computed from a normal force that ignores the
  // accelerations it causes (one projection solved after the other, not together).
  const double M = 1.0, m = 0.7, l = 0.5, g = 9.81, mu = 0.4, v = 1e-3;
  MechBuilder b;
  const int world = b.World(Vec3(0, -g, 0));
  const int cart = b.Frame("cart.frame"), arm = b.Frame("arm.frame");
  b.Body("cart", cart, M, Vec3::Zero(), Diag(0.01, 0.01, 0.01));
  b.Body("bob", arm, m, Vec3(0, -l, 0), Mat3::Zero());
  auto& slide = b.Joint("slide", JointType::Prismatic, world, cart, Vec3::UnitX());
  slide.friction_mu = b.C(mu);
  slide.friction_v = b.C(v);
  b.Joint("hinge", JointType::Revolute, cart, arm, Vec3::UnitZ());
  auto cr = rt::Compile(b.m, {});
  ASSERT_TRUE(cr.program);
  const rt::Program& p = *cr.program;
  auto ws = rt::MakeWorkspace(p);
  const double states[3][4] = {{0.0, 0.9, 0.8, -1.5}, {0.3, -0.4, -0.5, 2.0}, {0.1, 1.3, 0.02, 0.0}};
  for (const auto& st : states) {
    std::vector<double> y = {st[0], st[1], st[2], st[3]}, yd(4);  // x, th, x', th'
    ASSERT_EQ(rt::Derivative(p, *ws, 0.0, y.data(), yd.data()), 0) << rt::ErrorMessage(*ws);
    const double th = st[1], thd = st[3], c = std::cos(th), sn = std::sin(th);
    double Qf = 0.0, xdd = 0.0, thdd = 0.0;
    for (int it = 0; it < 200; ++it) {
      // (2)-(3) for x'', th'' given Qf (Cramer).
      const double a11 = M + m, a12 = m * l * c, b1 = Qf + m * l * thd * thd * sn;
      const double a21 = m * l * c, a22 = m * l * l, b2 = -m * g * l * sn;
      const double det = a11 * a22 - a12 * a21;
      xdd = (b1 * a22 - a12 * b2) / det;
      thdd = (a11 * b2 - a21 * b1) / det;
      const double N = (M + m) * g + m * l * (thdd * sn + thd * thd * c);  // (4)
      Qf = -mu * std::fabs(N) * std::tanh(st[2] / v);
    }
    EXPECT_NEAR(yd[2], xdd, 1e-10);
    EXPECT_NEAR(yd[3], thdd, 1e-10);
  }
}

TEST(Friction, OnlyPrismaticAndRevoluteJointsTakeFriction) {
  // If this fails, friction on an unsupported joint is silently ignored.
  auto m = Tube(0.3, 2.0, 0.2, 0.1);
  m.joints[0].friction_mu = m.exprs.Constant(0.1);  // the prescribed spin joint
  auto cr = rt::Compile(m, {});
  EXPECT_FALSE(cr.program);
  ASSERT_FALSE(cr.errors.empty());
  EXPECT_STREQ(flat::DiagCodeString(cr.errors[0].code), "K312");
}

}  // namespace
}  // namespace kanesim::test
