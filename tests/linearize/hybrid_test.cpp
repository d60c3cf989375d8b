// linearize at hybrid operating points (issue 41; linearize/hybrid.h): a joint resting on
// its stop, a joint stuck by exact Coulomb friction and a body resting on a plane are
// constraint rows (their coordinates and speeds leave the states); impacts, contacts about
// to leave, joints about to slip and rolling contacts that would pull are refused.
//
// Two rods (L1 = 1, m1 = 1; L2 = 0.8, m2 = 0.7), the first held (on its stop or stuck): the
// second swings about a fixed pin, A = [[0, 1], [-3 g / (2 L2), 0]] about hanging.      (1)
// A mass m on a spring k along x, resting on the floor y = 0: A = [[0, 1], [-k / m, 0]]. (2)
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "linearize/linearize.h"
#include "tests/support/load_util.h"
#include "tests/support/model_texts.h"

namespace kanesim::test {
namespace {

constexpr double kG = 9.81;
const std::string kStopModel = kRoot + "/tests/linearize/models/stop_double_pendulum.mech";

std::string Rods(const std::string& j1_modifiers, double q1) {
  const std::string q = std::to_string(q1);
  return TwoRodText(", q(start = " + q + ")" + j1_modifiers, ", q(start = -pi / 2 - (" + q + "))");
}

// Eq. (1) for a model whose j1 is held at the operating point (named `held`).
void ExpectSecondRodAlone(const rt::Program& p, const std::string& held) {
  lin::LinearModel m;
  const lin::Status s = lin::Linearize(p, lin::StartPoint(p), {}, &m);
  ASSERT_TRUE(s.ok()) << s.message;
  ASSERT_EQ(m.states, (std::vector<std::string>{"j2.q", "j2.u"}));
  ASSERT_EQ(m.held, std::vector<std::string>{held});
  const double w2 = 1.5 * kG / 0.8;
  EXPECT_NEAR(m.A(0, 0), 0.0, 1e-9);
  EXPECT_NEAR(m.A(0, 1), 1.0, 1e-9);
  EXPECT_NEAR(m.A(1, 0), -w2, 1e-7 * w2);
  EXPECT_NEAR(m.A(1, 1), 0.0, 1e-9);
  EXPECT_LT(m.unsteady, 1e-6);  // an equilibrium of the held system
}

// If this fails, a joint resting on its stop is linearized as free (4 states, a motion that
// falls through the stop) instead of as a constraint row.
TEST(LinearizeHybrid, DoublePendulumOnItsStopIsTheSecondRodAlone) {
  auto l = LoadModel(kStopModel);
  ASSERT_TRUE(l && l->prog);
  ExpectSecondRodAlone(*l->prog, "j1 on q_min");
}

// If this fails, a joint stuck by exact Coulomb friction is linearized with the regularized
// law (a stiff damping of j1 instead of no j1 at all). Holding torque ~ 11 N m, at most
// mu_s r N = 0.5 * 2 * 16.7 N m.
TEST(LinearizeHybrid, StuckCoulombJointRemovesItsDegreeOfFreedom) {
  auto l = LoadModel(Rods(", mu = 0.5, friction_radius = 2, friction_exact = true", -0.3), {}, {}, true);
  ASSERT_TRUE(l && l->prog);
  ExpectSecondRodAlone(*l->prog, "j1 stuck");
}

// The outputs of the held motion (sim::HeldOutputs in linearize/hybrid.cpp): j1's
// acceleration is 0 whatever j2 does (C's row 0), and j2's is A's speed row (the held motion's
// acceleration; with the stop's reaction left out it was 5.5 q2 against A's -18.4 q2).
// If this fails, linearize's output matrices read the free motion at a held point.
TEST(LinearizeHybrid, OutputsOfAHeldJointAreTheHeldMotions) {
  for (const std::string& law : {std::string(", q_min = -0.3"), std::string(", mu = 0.5, friction_radius = 2, friction_exact = true")}) {
    auto l = LoadModel(Rods(law, -0.3), {}, {}, true);
    ASSERT_TRUE(l && l->prog);
    lin::LinearizeOptions o;
    o.outputs = {"j1.a", "j2.a"};
    lin::LinearModel m;
    const lin::Status s = lin::Linearize(*l->prog, lin::StartPoint(*l->prog), o, &m);
    ASSERT_TRUE(s.ok()) << s.message;
    ASSERT_EQ(m.C.rows(), 2) << law;
    ASSERT_EQ(m.C.cols(), 2) << law;
    for (int k = 0; k < 2; ++k) {
      EXPECT_EQ(m.C(0, k), 0.0) << law;
      EXPECT_NEAR(m.C(1, k), m.A(1, k), 1e-7 * (1 + std::abs(m.A(1, k)))) << law;
    }
  }
}

// If this fails, a point that slips at once (the needed friction above mu_s r N) is
// linearized with some law instead of refused.
TEST(LinearizeHybrid, JointAboutToSlipIsRefused) {
  auto l = LoadModel(Rods(", mu = 0.5, friction_radius = 0.1, friction_exact = true", -0.3), {}, {}, true);
  ASSERT_TRUE(l && l->prog);
  lin::LinearModel m;
  const lin::Status s = lin::Linearize(*l->prog, lin::StartPoint(*l->prog), {}, &m);
  EXPECT_EQ(s.code, 2);
  EXPECT_NE(s.message.find("joint 'j1' is at rest but slips"), std::string::npos) << s.message;
}

// If this fails, an impact instant, a rest whose reaction pulls, or a point past the stop
// gets a linear model.
TEST(LinearizeHybrid, ImpactsPullsAndPointsPastAStopAreRefused) {
  auto moving = LoadModel(kStopModel, {{"u1", "-1"}});
  ASSERT_TRUE(moving && moving->prog);
  lin::LinearModel m;
  lin::Status s = lin::Linearize(*moving->prog, lin::StartPoint(*moving->prog), {}, &m);
  EXPECT_EQ(s.code, 2);
  EXPECT_NE(s.message.find("joint 'j1' is on q_min and moving into it"), std::string::npos) << s.message;
  // q_max = 0 above the horizontal rod: gravity pulls it away.
  auto pulled = LoadModel(Rods(", q_max = 0", 0.0), {}, {}, true);
  ASSERT_TRUE(pulled && pulled->prog);
  s = lin::Linearize(*pulled->prog, lin::StartPoint(*pulled->prog), {}, &m);
  EXPECT_EQ(s.code, 2);
  EXPECT_NE(s.message.find("joint 'j1' is on q_max at rest, but the reaction that would hold it pulls"),
            std::string::npos)
      << s.message;
  auto l = LoadModel(kStopModel);
  ASSERT_TRUE(l && l->prog);
  lin::OperatingPoint op = lin::StartPoint(*l->prog);
  op.y[0] = -0.01;  // j1.q
  s = lin::Linearize(*l->prog, op, {}, &m);
  EXPECT_EQ(s.code, 1);
  EXPECT_NE(s.message.find("joint 'j1' is past q_min"), std::string::npos) << s.message;
  lin::EquilibriumResult eq;
  EXPECT_EQ(lin::FindEquilibrium(*l->prog, lin::StartPoint(*l->prog), &eq).code, 1);
}

// A mass on a spring along x over the floor y = 0 (eq. (2)); py's start and gravity given.
std::string Floor(const std::string& py_start, double g_y) {
  return "model Floor\n"
         "  parameter Real k(unit = \"N/m\") = 8;\n"
         "  World world(g = {0, " + std::to_string(g_y) + ", 0});\n"
         "  Prismatic px(axis = {1, 0, 0});\n"
         "  Prismatic py(axis = {0, 1, 0}, " + py_start + ");\n"
         "  Body b(m = 2);\n"
         "  PlaneContact floor(n = {0, 1, 0}, d = 0);\n"
         "equation\n"
         "  connect(world.frame_b, px.frame_a);\n"
         "  connect(px.frame_b, py.frame_a);\n"
         "  connect(py.frame_b, b.frame_a);\n"
         "  connect(py.frame_b, floor.frame_a);\n"
         "  px.tau = -k * px.q;\n"
         "end Floor;\n";
}

// If this fails, a plane contact at an impact or lift-off instant, or resting where the plane
// would have to pull (gravity upwards), gets a linear model, or a point below the plane is
// not refused as bad input (exit 1).
TEST(LinearizeHybrid, PlaneContactsMovingPullingOrPenetratedAreRefused) {
  struct Case {
    std::string py_start;
    double g_y;
    int code;
    std::string says;
  };
  for (const Case& c : {Case{"q(start = 0), u(start = -1)", -9.81, 2, "is on the plane and moving into it"},
                        Case{"q(start = 0), u(start = 1)", -9.81, 2, "is on the plane and leaving it"},
                        Case{"q(start = 0)", 9.81, 2, "is on the plane at rest, but the reaction that would hold it pulls"},
                        Case{"q(start = -0.01)", -9.81, 1, "is past the plane by 0.01"}}) {
    auto l = LoadModel(Floor(c.py_start, c.g_y), {}, {}, true);
    ASSERT_TRUE(l && l->prog);
    lin::LinearModel m;
    const lin::Status s = lin::Linearize(*l->prog, lin::StartPoint(*l->prog), {}, &m);
    EXPECT_EQ(s.code, c.code) << c.py_start << ": " << s.message;
    EXPECT_NE(s.message.find(c.says), std::string::npos) << s.message;
  }
}

// A sphere rolling on y = 0 (bilateral rows) pulled up by F: its normal force m g - F turns
// tensile above F = 9.81 N. If this fails, linearize gives a model of a contact that would
// have to pull (F = 20), or refuses one that presses (F = 5).
TEST(LinearizeHybrid, ARollingContactWhoseNormalForceIsTensileIsRefused) {
  for (double F : {5.0, 20.0}) {
    const std::string text = PulledSphereText(std::to_string(F), "{0, 0, 0, 0, 0, 0}");
    auto l = LoadModel(text, {}, {}, true);
    ASSERT_TRUE(l && l->prog);
    lin::LinearModel m;
    const lin::Status s = lin::Linearize(*l->prog, lin::StartPoint(*l->prog), {}, &m);
    if (F < 9.81) {
      EXPECT_TRUE(s.ok()) << s.message;
    } else {
      EXPECT_EQ(s.code, 2) << s.message;
      EXPECT_NE(s.message.find("contact 'contact': its normal force turns tensile"), std::string::npos) << s.message;
      EXPECT_NE(s.message.find("no linear model of a contact that pulls"), std::string::npos) << s.message;
    }
  }
}

// Eq. (2). If this fails, a body resting on a plane contact is linearized as free (it falls:
// not an equilibrium) instead of with the contact's row.
TEST(LinearizeHybrid, MassOnAFloorIsTheSpringAlong) {
  auto l = LoadModel(Floor("q(start = 0)", -9.81), {}, {}, true);
  ASSERT_TRUE(l && l->prog);
  lin::LinearModel m;
  const lin::Status s = lin::Linearize(*l->prog, lin::StartPoint(*l->prog), {}, &m);
  ASSERT_TRUE(s.ok()) << s.message;
  ASSERT_EQ(m.states, (std::vector<std::string>{"px.q", "px.u"}));
  EXPECT_EQ(m.held, std::vector<std::string>{"floor on the plane"});
  EXPECT_NEAR(m.A(1, 0), -4.0, 1e-8);
  EXPECT_NEAR(m.A(1, 1), 0.0, 1e-9);
}

}  // namespace
}  // namespace kanesim::test
