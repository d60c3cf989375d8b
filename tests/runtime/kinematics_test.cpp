// Kinematics against finite differences of positions and orientations: the tangent
// basis (partial velocities), the kinematic differential equations qdot = N(q) u for
// every rotation parameterization, quaternion normalization and gimbal lock.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>

#include "compiler/compiler.h"
#include "runtime/kane/kane_tree.h"
#include "runtime/kinematics/kinematics.h"
#include "runtime/program/program.h"
#include "tests/support/builders.h"
#include "tests/support/random_state.h"

namespace kanesim {
namespace {

using test::Mat3;
using test::Vec3;

// Central differences with h = 1e-6: truncation ~h^2 |x'''| ~ 1e-12, round-off
// ~1e-16 / h = 1e-10 on O(1) positions.
constexpr double kFdStep = 1e-6;
constexpr double kFdTol = 1e-8;
// Two evaluations of the same quantity through different round-off paths (normalizing
// a quaternion, mirrored coordinates): a few ulps of O(10) accelerations.
constexpr double kRoundoffTol = 1e-12;

Vec3 Vee(const Mat3& W) { return Vec3(W(2, 1) - W(1, 2), W(0, 2) - W(2, 0), W(1, 0) - W(0, 1)) / 2.0; }

// A chain of revolute joints about coordinate axes, each rod's tip frame turned by
// `R_tip` (identity: R_PJ = 1 exactly, the cheapest case), with random inertias.
flat::Mechanism AxisChain(int N, const Mat3& R_tip, std::mt19937& rng) {
  test::MechBuilder b;
  int prev = b.World(Vec3(0, -9.81, 0));
  for (int i = 1; i <= N; ++i) {
    const std::string rod = "rod" + std::to_string(i);
    const int fa = b.Frame(rod + ".frame_a"), fb = b.Frame(rod + ".frame_b");
    b.Fixed(rod + ".fixed", fa, fb, Vec3(0.5, 0.1 * i, -0.05), R_tip);
    b.Body(rod, fa, 1.0 + 0.1 * i, test::RandomVec(rng, 0.3), test::RandomInertia(rng));
    b.Joint("j" + std::to_string(i), flat::JointType::Revolute, prev, fa, Vec3::Unit(i % 3));
    prev = fb;
  }
  return b.m;
}

// The finite-difference checks' mechanism, compiled (null, and a failure, on errors).
std::shared_ptr<const rt::Program> CompileForFd(const flat::Mechanism& m) {
  auto r = rt::Compile(m, {});
  EXPECT_TRUE(r.errors.empty()) << (r.errors.empty() ? "" : r.errors[0].message);
  return r.program;
}

// Each column of the tangent basis against central differences of the body positions and
// orientations along qdot = N(q) e_i.
void ExpectTangentBasisMatchesFd(const flat::Mechanism& m, std::mt19937& rng) {
  const auto program = CompileForFd(m);
  ASSERT_TRUE(program);
  const rt::Program& p = *program;
  auto ws = rt::MakeWorkspace(p), ws2 = rt::MakeWorkspace(p);
  const Eigen::VectorXd y = test::RandomState(p, rng);
  for (int i = 0; i < p.nu; ++i) {
    // qdot = N(q) e_i: the coordinate direction of the unit pseudo-speed u = e_i.
    Eigen::VectorXd yi = y, ydot(y.size());
    yi.tail(p.nu).setZero();
    yi[p.nq + i] = 1.0;
    ASSERT_EQ(rt::Derivative(p, *ws, 0.0, yi.data(), ydot.data()), 0) << rt::ErrorMessage(*ws);
    std::vector<Vec3> pos[2];
    std::vector<Mat3> rot[2];
    for (int side = 0; side < 2; ++side) {
      Eigen::VectorXd ys = y;
      ys.head(p.nq) += (side == 0 ? kFdStep : -kFdStep) * ydot.head(p.nq);
      ASSERT_EQ(rt::UnpackState(p, *ws2, 0.0, ys.data()), 0);
      rt::PositionKinematics(p, *ws2);
      pos[side] = ws2->p_WBcm;
      rot[side] = ws2->R_WB;
    }
    for (size_t L = 0; L < p.bodies.size(); ++L) {
      const rt::Vec6 t = rt::TangentColumn(p, *ws, static_cast<int>(L), p.u_free[static_cast<size_t>(i)]);
      const Vec3 v_fd = (pos[0][L] - pos[1][L]) / (2 * kFdStep);
      const Vec3 w_fd = Vee((rot[0][L] - rot[1][L]) / (2 * kFdStep) * ws->R_WB[L].transpose());
      EXPECT_LT((t.head<3>() - v_fd).norm(), kFdTol) << "body " << p.bodies[L].name << " speed " << i;
      EXPECT_LT((t.tail<3>() - w_fd).norm(), kFdTol) << "body " << p.bodies[L].name << " speed " << i;
    }
  }
}

TEST(Kinematics, TangentBasisMatchesFiniteDifferencesOfPositions) {
  // If this fails, a partial velocity or partial angular velocity (tau, Lesser eq. 22)
  // is wrong for some joint type, rotation parameterization, inverted joint or merged body.
  std::mt19937 rng(1234);
  for (int tree = 0; tree < 3; ++tree) ExpectTangentBasisMatchesFd(test::RandomTree(rng, {14, true, true, true}), rng);
  // Revolute joints about coordinate axes take the shortcuts of PositionKinematics and
  // VelocityKinematics (two columns turned, h = R_WB e_k); random trees never do.
  ExpectTangentBasisMatchesFd(AxisChain(9, Mat3::Identity(), rng), rng);
  ExpectTangentBasisMatchesFd(AxisChain(9, test::RandomRotation(rng), rng), rng);
}

// The bias accelerations against central differences of the velocities with u held fixed.
void ExpectBiasMatchesFd(const flat::Mechanism& m, std::mt19937& rng) {
  const auto program = CompileForFd(m);
  ASSERT_TRUE(program);
  const rt::Program& p = *program;
  auto ws = rt::MakeWorkspace(p), ws2 = rt::MakeWorkspace(p);
  const Eigen::VectorXd y = test::RandomState(p, rng);
  Eigen::VectorXd ydot(y.size());
  ASSERT_EQ(rt::Derivative(p, *ws, 0.0, y.data(), ydot.data()), 0) << rt::ErrorMessage(*ws);
  std::vector<Vec3> v[2], w[2];
  for (int side = 0; side < 2; ++side) {
    Eigen::VectorXd ys = y;  // q moves along qdot = N(q) u, u stays: udot = 0
    ys.head(p.nq) += (side == 0 ? kFdStep : -kFdStep) * ydot.head(p.nq);
    ASSERT_EQ(rt::UnpackState(p, *ws2, 0.0, ys.data()), 0);
    rt::PositionKinematics(p, *ws2);
    rt::VelocityKinematics(p, *ws2);
    v[side] = ws2->v_WBcm;
    w[side] = ws2->w_WB;
  }
  for (size_t L = 0; L < p.bodies.size(); ++L) {
    EXPECT_LT((ws->a_bias_cm[L] - (v[0][L] - v[1][L]) / (2 * kFdStep)).norm(), kFdTol) << p.bodies[L].name;
    EXPECT_LT((ws->alpha_bias[L] - (w[0][L] - w[1][L]) / (2 * kFdStep)).norm(), kFdTol) << p.bodies[L].name;
  }
}

TEST(Kinematics, BiasAccelerationsMatchFiniteDifferencesOfVelocities) {
  // If this fails, the velocity-dependent accelerations with udot = 0 (centripetal,
  // Coriolis, gyroscopic; seed 000 eq. 11.17) are wrong for some joint type or an
  // inverted joint: they must equal d/dt of the velocities with u held fixed.
  std::mt19937 rng(4321);
  for (int tree = 0; tree < 3; ++tree) ExpectBiasMatchesFd(test::RandomTree(rng, {14, true, true, true}), rng);
  ExpectBiasMatchesFd(AxisChain(9, Mat3::Identity(), rng), rng);  // the coordinate-axis shortcuts
  ExpectBiasMatchesFd(AxisChain(9, test::RandomRotation(rng), rng), rng);
}

flat::Mechanism Ball(flat::RotationCoords rc, flat::JointType type = flat::JointType::Spherical) {
  test::MechBuilder b;
  int w = b.World(Vec3::Zero());
  int f = b.Frame("ball_body.frame");
  b.Body("ball_body", f, 1.0, Vec3(0.1, 0.2, -0.3), test::Diag(1.0, 2.0, 3.0));
  b.Joint("ball", type, w, f, Vec3::UnitZ(), Vec3::UnitX(), rc);
  return b.m;
}

TEST(Kinematics, RotationRatesMatchFiniteDifferencesOfR) {
  // If this fails, N(q) (Lesser eqs. 44-47) for quaternion, Cardan xyz or Euler zyz
  // coordinates does not produce the body-fixed angular velocity u.
  std::mt19937 rng(55);
  for (auto rc : {flat::RotationCoords::Quaternion, flat::RotationCoords::CardanXYZ, flat::RotationCoords::EulerZYZ}) {
    auto r = rt::Compile(Ball(rc), {});
    ASSERT_TRUE(r.errors.empty());
    const rt::Program& p = *r.program;
    auto ws = rt::MakeWorkspace(p);
    std::vector<std::string> names;
    for (int i = 1; i <= 3; ++i)
      for (int j = 1; j <= 3; ++j) names.push_back("ball_body.R[" + std::to_string(i) + "," + std::to_string(j) + "]");
    std::string err;
    auto plan = rt::PlanSignals(p, names, &err);
    ASSERT_TRUE(plan) << err;
    const Eigen::VectorXd y = test::RandomState(p, rng);
    auto R_at = [&](const Eigen::VectorXd& yy) {
      double out[9];
      EXPECT_EQ(rt::EvalSignals(p, *plan, *ws, 0.0, yy.data(), out), 0);
      Mat3 R;
      for (int k = 0; k < 9; ++k) R(k / 3, k % 3) = out[k];
      return R;
    };
    const Mat3 R0 = R_at(y);
    for (int i = 0; i < 3; ++i) {
      Eigen::VectorXd yi = y, ydot(y.size());
      yi.tail(3) = Vec3::Unit(i);
      ASSERT_EQ(rt::Derivative(p, *ws, 0.0, yi.data(), ydot.data()), 0) << rt::ErrorMessage(*ws);
      Eigen::VectorXd yp = y, ym = y;
      yp.head(p.nq) += kFdStep * ydot.head(p.nq);
      ym.head(p.nq) -= kFdStep * ydot.head(p.nq);
      // Body-fixed angular velocity: [w_b]x = R^T Rdot.
      const Vec3 w_b = Vee(R0.transpose() * (R_at(yp) - R_at(ym)) / (2 * kFdStep));
      EXPECT_LT((w_b - Vec3::Unit(i)).norm(), kFdTol) << flat::RotationCoordsName(rc) << " u = e" << i;
    }
  }
}

TEST(Kinematics, QuaternionIsNormalizedWhenUsed) {
  // If this fails, a quaternion that drifted off unit norm changes the dynamics, or
  // qdot = 1/2 q (x) (0, w) does not keep |q| constant.
  auto r = rt::Compile(Ball(flat::RotationCoords::Quaternion), {});
  ASSERT_TRUE(r.errors.empty());
  const rt::Program& p = *r.program;
  auto ws = rt::MakeWorkspace(p);
  std::mt19937 rng(8);
  Eigen::VectorXd y = test::RandomState(p, rng), y3 = y, d1(7), d3(7);
  y3.head(4) *= 3.0;
  ASSERT_EQ(rt::Derivative(p, *ws, 0.0, y.data(), d1.data()), 0);
  ASSERT_EQ(rt::Derivative(p, *ws, 0.0, y3.data(), d3.data()), 0);
  EXPECT_LT((d1.tail(3) - d3.tail(3)).norm(), kRoundoffTol);
  EXPECT_NEAR(y3.head(4).dot(d3.head(4)), 0.0, kRoundoffTol);
}

TEST(Kinematics, GimbalLockIsFatalWithAClearMessage) {
  // If this fails, Cardan/Euler coordinates at their singularity produce garbage
  // instead of stopping with a message that names the joint, the angle and the remedy.
  struct Case {
    flat::RotationCoords rc;
    double q2;
    const char* text;
  };
  for (const Case& c : {Case{flat::RotationCoords::CardanXYZ, M_PI / 2, "Cardan angle q[2] = 1.5707963"},
                        Case{flat::RotationCoords::EulerZYZ, 0.0, "Euler angle q[2] = 0"}}) {
    auto r = rt::Compile(Ball(c.rc), {});
    ASSERT_TRUE(r.errors.empty());
    auto ws = rt::MakeWorkspace(*r.program);
    double y[6] = {0.3, c.q2, -0.2, 0.1, 0.2, 0.3}, yd[6];
    EXPECT_LT(rt::Derivative(*r.program, *ws, 0.0, y, yd), 0);
    const std::string& msg = rt::ErrorMessage(*ws);
    EXPECT_NE(msg.find("gimbal lock in joint 'ball'"), std::string::npos) << msg;
    EXPECT_NE(msg.find(c.text), std::string::npos) << msg;
    EXPECT_NE(msg.find("quaternion"), std::string::npos) << msg;
  }
}

// A pendulum whose joint frame on the rod is offset and rotated; `inverted` connects
// the joint with frame_a on the rod and frame_b on the world.
flat::Mechanism OffsetPendulum(bool inverted) {
  test::MechBuilder b;
  int w = b.World(Vec3(0, -9.81, 0));
  int f = b.Frame("rod.frame");
  b.Body("rod", f, 1.5, Vec3(0.2, -0.3, 0.1), test::Diag(0.05, 0.02, 0.06));
  int pivot = b.Frame("rod.pivot");
  b.Fixed("rod.pivot_fix", f, pivot, Vec3(0.05, 0.1, 0.0), Eigen::AngleAxisd(0.4, Vec3::UnitX()).toRotationMatrix());
  if (inverted)
    b.Joint("pivot", flat::JointType::Revolute, pivot, w, Vec3::UnitZ());
  else
    b.Joint("pivot", flat::JointType::Revolute, w, pivot, Vec3::UnitZ());
  return b.m;
}

TEST(Kinematics, CoordinateAxisShortcutsMatchTheGeneralJointPath) {
  // If this fails, the revolute-about-a-coordinate-axis shortcuts of PositionKinematics
  // and VelocityKinematics (two columns of R_WJ turned; h = R_WB e_k) or the recursive
  // solve's angular-column elimination differ from the general joint path they skip.
  std::mt19937 rng(77);
  for (const Mat3& R_tip : {Mat3(Mat3::Identity()), test::RandomRotation(rng)}) {
    auto r = rt::Compile(AxisChain(9, R_tip, rng), {});
    ASSERT_TRUE(r.errors.empty()) << r.errors[0].message;
    const rt::Program& fast = *r.program;
    ASSERT_EQ(fast.solver, rt::SolverPath::Recursive);
    for (const rt::TreeJoint& j : fast.joints) ASSERT_GE(j.axis_index, 0);
    rt::Program general = fast;  // the same program with every shortcut switched off
    for (rt::TreeJoint& j : general.joints) {
      j.axis_index = -1;
      j.single_axis = false;
      j.R_PJ_identity = false;
    }
    rt::BuildTree(general);
    auto wf = rt::MakeWorkspace(fast);
    auto wg = rt::MakeWorkspace(general);
    const Eigen::Index n = rt::StateSize(fast);
    for (int trial = 0; trial < 4; ++trial) {
      const Eigen::VectorXd y = test::RandomState(fast, rng);
      Eigen::VectorXd yf(n), yg(n);
      ASSERT_EQ(rt::Derivative(fast, *wf, 0.0, y.data(), yf.data()), 0) << rt::ErrorMessage(*wf);
      ASSERT_EQ(rt::Derivative(general, *wg, 0.0, y.data(), yg.data()), 0) << rt::ErrorMessage(*wg);
      EXPECT_LT((yf - yg).norm(), kRoundoffTol * yg.norm()) << "trial " << trial;
      for (size_t L = 0; L < fast.bodies.size(); ++L) {
        EXPECT_LT((wf->R_WB[L] - wg->R_WB[L]).norm(), kRoundoffTol) << "body " << L;
        EXPECT_LT((wf->p_WBcm[L] - wg->p_WBcm[L]).norm(), kRoundoffTol) << "body " << L;
        EXPECT_LT((wf->I_W[L] - wg->I_W[L]).norm(), kRoundoffTol) << "body " << L;
        EXPECT_LT((wf->w_WB[L] - wg->w_WB[L]).norm(), kRoundoffTol) << "body " << L;
        EXPECT_LT((wf->a_bias_cm[L] - wg->a_bias_cm[L]).norm(), kRoundoffTol * 10) << "body " << L;
      }
      EXPECT_LT((wf->H_W - wg->H_W).norm(), kRoundoffTol);
    }
  }
}

TEST(Kinematics, InvertedJointMirrorsTreeDirection) {
  // If this fails, a joint connected with frame_b on the parent side is not the inverse
  // motion: qddot_inv(q, u) must equal -qddot(-q, -u) for a revolute joint.
  for (auto path : {rt::SolverPath::Dense, rt::SolverPath::Sparse}) {
    rt::CompileOptions o;
    o.solver = path;
    auto a = rt::Compile(OffsetPendulum(false), o);
    auto b = rt::Compile(OffsetPendulum(true), o);
    ASSERT_TRUE(a.errors.empty() && b.errors.empty());
    auto wa = rt::MakeWorkspace(*a.program);
    auto wb = rt::MakeWorkspace(*b.program);
    for (double q : {0.0, 0.7, -2.1}) {
      double ya[2] = {-q, -0.8}, yb[2] = {q, 0.8}, da[2], db[2];
      ASSERT_EQ(rt::Derivative(*a.program, *wa, 0.0, ya, da), 0);
      ASSERT_EQ(rt::Derivative(*b.program, *wb, 0.0, yb, db), 0);
      EXPECT_NEAR(db[1], -da[1], kRoundoffTol);
    }
  }
}

}  // namespace
}  // namespace kanesim
