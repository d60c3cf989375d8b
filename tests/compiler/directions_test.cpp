// User-given directions (joint axes, start quaternions, contact normals, FixedRotation
// axes) normalized without overflow or underflow (runtime/kinematics/joint_kinematics.h
// NormalizeScaled), and refused with a located K306 when they have no direction (issue 38:
// a start quaternion {1e200, 1e200, 0, 0} normalized to zeros, the body never turned).
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

#include "runtime/kinematics/joint_kinematics.h"
#include "tests/compiler/compile_test_util.h"
#include "tests/support/model_texts.h"
#include "compiler/compiler.h"

namespace kanesim::test {
namespace {

// If this fails, scaling a vector by a power of two (exact in floating point) changes its
// direction, or a vector with no direction is accepted: every scale from the subnormals
// to near the largest double must give the unit vector of the unscaled one, to the bit.
TEST(NormalizeScaled, EveryScaleGivesTheSameUnitVector) {
  std::mt19937 rng(38);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 50; ++trial) {
    double ref[4] = {u(rng), u(rng), u(rng), u(rng)};
    const long double n = std::sqrt(static_cast<long double>(ref[0]) * ref[0] + static_cast<long double>(ref[1]) * ref[1] +
                                    static_cast<long double>(ref[2]) * ref[2] + static_cast<long double>(ref[3]) * ref[3]);
    double unit[4] = {ref[0], ref[1], ref[2], ref[3]};
    ASSERT_TRUE(rt::NormalizeScaled(unit, 4));
    for (int i = 0; i < 4; ++i) EXPECT_NEAR(unit[i], static_cast<double>(ref[i] / n), 4e-16);  // long double: independent
    for (int e : {-1060, -1000, -600, -300, -10, 0, 10, 300, 600, 1000, 1020}) {
      double v[4];
      for (int i = 0; i < 4; ++i) v[i] = std::ldexp(ref[i], e);
      if (e < -1022) {  // subnormal components keep 1074 + e - 1 bits (13 here): the direction to that
        ASSERT_TRUE(rt::NormalizeScaled(v, 4)) << e;
        for (int i = 0; i < 4; ++i) EXPECT_NEAR(v[i], unit[i], 1e-3) << e;
        continue;
      }
      ASSERT_TRUE(rt::NormalizeScaled(v, 4)) << e;
      for (int i = 0; i < 4; ++i) EXPECT_EQ(v[i], unit[i]) << "scale 2^" << e;
    }
  }
  double zero[3] = {0, 0, 0}, inf[3] = {1, INFINITY, 0}, nan[3] = {NAN, 0, 1};
  EXPECT_FALSE(rt::NormalizeScaled(zero, 3));
  EXPECT_FALSE(rt::NormalizeScaled(inf, 3));
  EXPECT_FALSE(rt::NormalizeScaled(nan, 3));
  EXPECT_EQ(rt::WhyNoDirection(zero, 3), "is zero");
  EXPECT_EQ(rt::WhyNoDirection(inf, 3), "is not finite");
  EXPECT_EQ(inf[1], INFINITY);  // refused vectors are left as they were
}

// A free body started with quaternion `quat` and spun at 3 rad/s about y: free.q rows.
std::unique_ptr<Loaded> FreeBody(const std::string& quat) {
  return LoadModel("model M\n"
                   "  parameter Real qs[7] = {0, 0, 0, " + quat + "};\n"
                   "  World world(g = {0, -9.81, 0});\n"
                   "  FreeMotion free(q(start = qs), u(start = {0, 0, 0, 0.2, 3.0, 0.3}));\n"
                   "  Body b(m = 1, I = diagonal({1, 2, 3}));\n"
                   "equation\n"
                   "  connect(world.frame_b, free.frame_a);\n"
                   "  connect(free.frame_b, b.frame_a);\n"
                   "end M;\n",
                   {}, {}, true);
}

// If this fails, a start quaternion of huge or tiny components (wrong_quat_overflow.mech)
// normalizes to zeros (the body never turns) or to another rotation: each must move
// exactly as {1, 1, 0, 0} (a 90-degree turn about x) does.
TEST(StartQuaternion, HugeAndTinyComponentsNormalizeLikeOrdinaryOnes) {
  const std::vector<std::string> sig = {"free.q[4]", "free.q[5]", "free.q[6]", "free.q[7]"};
  auto run = [&](const std::string& quat) {
    auto l = FreeBody(quat);
    EXPECT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
    if (!l || !l->prog) return sim::MemorySink{};
    sim::SimResult r;
    sim::MemorySink s = RunWith(*l->prog, AllIntegrators()[0], 1.0, 0.5, sig, &r);
    EXPECT_EQ(r.status, sim::SimResult::Status::kOk) << r.message;
    return s;
  };
  const sim::MemorySink ref = run("1, 1, 0, 0");
  ASSERT_EQ(ref.rows.size(), 3u);
  EXPECT_NEAR(ref.rows[0][0], std::sqrt(0.5), 1e-15);
  EXPECT_GT(std::fabs(ref.rows[2][2]) + std::fabs(ref.rows[2][3]), 0.1);  // it turns
  for (const char* q : {"1e200, 1e200, 0, 0", "1e-200, 1e-200, 0, 0", "1e300, 1e300, 0, 0", "3e-300 * 1e-10, 3e-300 * 1e-10, 0, 0"}) {
    const sim::MemorySink s = run(q);
    ASSERT_EQ(s.rows.size(), 3u) << q;
    for (size_t k = 0; k < 3; ++k)
      for (size_t c = 0; c < 4; ++c)  // 1e-200 is not 2^k: the start may be an ulp off 1/sqrt(2)
        EXPECT_NEAR(s.rows[k][c], ref.rows[k][c], 1e-12) << q << " row " << k << " " << sig[c];
  }
}

// If this fails, a start quaternion with no direction is silently replaced: a zero one is
// K306 at the joint, saying so.
TEST(StartQuaternion, ZeroIsK306) {
  auto zero = FreeBody("0, 0, 0, 0");
  ASSERT_TRUE(zero);
  const rt::CompileMessage* e = Find(zero->errors, "K306", "joint 'free' starts with a quaternion that is zero");
  ASSERT_TRUE(e) << Messages(zero->errors);
  EXPECT_EQ(e->loc.line, 4);
  // (A non-finite one never gets here: the elaborator refuses the parameter, E213.)
}

// A pendulum about `axis` (a rod along x, gravity along -y): j.q at t = 1.
double PendulumAngle(const std::string& axis) {
  auto l = LoadModel(PendulumText{.model = "M", .name = "j", .axis = axis, .mods = ", q(start = 0.3)"}.Text(), {}, {},
                     true);
  EXPECT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  if (!l || !l->prog) return NAN;
  sim::SimResult r;
  sim::MemorySink s = RunWith(*l->prog, AllIntegrators()[0], 1.0, 1.0, {"j.q"}, &r);
  EXPECT_EQ(r.status, sim::SimResult::Status::kOk) << r.message;
  return s.rows.empty() ? NAN : s.rows.back()[0];
}

// If this fails, a joint axis of huge or tiny length (a direction all the same) is
// refused as zero or overflows into a singular mass matrix: it must swing as {0, 0, 1}.
TEST(JointAxis, HugeAndTinyAxesAreDirections) {
  const double ref = PendulumAngle("{0, 0, 1}");
  EXPECT_LT(ref, 0.0);  // it swung through the bottom
  for (const char* a : {"{0, 0, 1e300}", "{0, 0, 1e-300}", "{0, 0, 1e-13}"}) EXPECT_EQ(PendulumAngle(a), ref) << a;
}

// If this fails, a FixedRotation about an axis of huge length overflows norm(n) and
// turns nothing: it must place the pendulum as the unit axis does.
TEST(FixedRotationAxis, HugeAxisTurnsAsTheUnitOne) {
  auto angle = [](const char* n) {
    auto l = LoadModel(std::string("model M\n  World world(g = {0, -9.81, 0});\n"
                                   "  FixedRotation fr(n = ") + n + ", angle = 0.5);\n"
                       "  Revolute j(axis = {0, 0, 1}, q(start = 0.3));\n  Rod rod(L = 1, m = 1);\nequation\n"
                       "  connect(world.frame_b, fr.frame_a);\n  connect(fr.frame_b, j.frame_a);\n"
                       "  connect(j.frame_b, rod.frame_a);\nend M;\n",
                       {}, {}, true);
    EXPECT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
    if (!l || !l->prog) return std::nan("");
    sim::SimResult r;
    sim::MemorySink s = RunWith(*l->prog, AllIntegrators()[0], 1.0, 1.0, {"rod.body.r[2]"}, &r);
    EXPECT_EQ(r.status, sim::SimResult::Status::kOk) << r.message;
    return s.rows.empty() ? std::nan("") : s.rows.back()[0];
  };
  const double ref = angle("{0, 0, 1}");
  EXPECT_EQ(angle("{0, 0, 1e300}"), ref);
  EXPECT_EQ(angle("{0, 0, 1e-300}"), ref);
}

}  // namespace
}  // namespace kanesim::test
