// Closed-form cases: physical pendulum, torque-free rigid body (Euler's equations),
// prescribed base motion, welded bodies, force elements, parameters and energies.
#include <gtest/gtest.h>

#include <cmath>

#include <Eigen/Geometry>
#include <random>

#include "compiler/compiler.h"
#include "tests/support/builders.h"

namespace kanesim {
namespace {

// Closed forms evaluated in double precision: a few ulps of the largest term.
constexpr double kClosedFormTol = 1e-12;
// Closed forms that go through a 3x3 inverse, rotations of inertia or a sum over two
// bodies: an order of magnitude more round-off.
constexpr double kClosedFormLooseTol = 1e-11;

TEST(Pendulum, AccelerationMatchesClosedForm) {
  // If this fails, Kane's equations for one revolute joint (gravity projected on the
  // tangent basis, or the inertia term I_O) are wrong.
  const double m = 1.3, L = 0.7, g = 9.81;
  auto r = rt::Compile(test::Pendulum(m, L, g), {});
  ASSERT_TRUE(r.errors.empty()) << r.errors[0].message;
  auto ws = rt::MakeWorkspace(*r.program);
  for (double q : {0.0, 0.3, 1.2, 2.9, -2.0}) {
    double y[2] = {q, 0.7}, yd[2];
    ASSERT_EQ(rt::Derivative(*r.program, *ws, 0.0, y, yd), 0) << rt::ErrorMessage(*ws);
    const double I_O = m * L * L / 3.0;
    EXPECT_NEAR(yd[0], 0.7, kClosedFormTol);
    EXPECT_NEAR(yd[1], -g * std::sin(q) * (m * L / 2) / I_O, kClosedFormTol);
  }
}


using test::Mat3;
using test::Vec3;
using flat::Op;

TEST(FreeBody, TorqueFreeMatchesEulerEquations) {
  // If this fails, the gyroscopic term or the free joint's speeds (body-fixed angular
  // velocity, translational u = d p_ab / dt) are wrong: I wdot = -w x I w and vdot = g.
  std::mt19937 rng(3);
  const Mat3 I = test::Diag(1.0, 2.0, 2.5);  // a rigid body's: 1 + 2 >= 2.5 (compile/inertia.cpp)
  for (auto rc : {flat::RotationCoords::Quaternion, flat::RotationCoords::CardanXYZ}) {
    for (double g : {0.0, 9.81}) {
      test::MechBuilder b;
      int w = b.World(Vec3(0, -g, 0));
      int f = b.Frame("box.frame");
      b.Body("box", f, 2.0, Vec3::Zero(), I);
      b.Joint("float", flat::JointType::Free, w, f, Vec3::UnitZ(), Vec3::UnitX(), rc);
      for (auto path : {rt::SolverPath::Dense, rt::SolverPath::Sparse}) {
        rt::CompileOptions o;
        o.solver = path;
        auto r = rt::Compile(b.m, o);
        ASSERT_TRUE(r.errors.empty());
        auto ws = rt::MakeWorkspace(*r.program);
        const int nq = rt::NumQ(*r.program);
        Eigen::VectorXd y = Eigen::VectorXd::Zero(nq + 6), yd(nq + 6);
        y.head(3) = test::RandomVec(rng);
        if (rc == flat::RotationCoords::Quaternion) {
          y.segment(3, 4) = Eigen::Vector4d(0.9, 0.1, -0.3, 0.2).normalized();
        } else {
          y.segment(3, 3) = test::RandomVec(rng);
        }
        const Vec3 v = test::RandomVec(rng), om = test::RandomVec(rng, 2.0);
        y.segment(nq, 3) = v;
        y.segment(nq + 3, 3) = om;
        ASSERT_EQ(rt::Derivative(*r.program, *ws, 0.0, y.data(), yd.data()), 0) << rt::ErrorMessage(*ws);
        const Vec3 wdot = I.inverse() * (-om.cross(I * om));
        EXPECT_LT((yd.segment(nq + 3, 3) - wdot).norm(), kClosedFormLooseTol);
        EXPECT_LT((yd.segment(nq, 3) - Vec3(0, -g, 0)).norm(), kClosedFormLooseTol);
        EXPECT_LT((yd.head(3) - v).norm(), kClosedFormTol);
      }
    }
  }
}

// A pendulum (uniform rod hanging along -y) on a cart whose position is prescribed,
// x(t) = A sin(W t). With the base acceleration xdd:
//   I_O qdd = -m (L/2) (g sin q + xdd cos q),   I_O = m L^2 / 3.
TEST(Prescribed, PendulumOnShakenBaseMatchesClosedForm) {
  // If this fails, prescribed coordinates (removed from the state, q/qdot/qddot from
  // the time jet) do not drive the rest of the system correctly, or the reported drive
  // force (the reaction along the prescribed coordinate) is wrong.
  const double m = 0.8, L = 0.6, g = 9.81, A = 0.2, W = 3.0;
  test::MechBuilder b;
  int w = b.World(Vec3(0, -g, 0));
  int cart = b.Frame("cart.frame");
  b.Body("cart", cart, 5.0, Vec3::Zero(), test::Diag(1, 1, 1));
  auto& base = b.Joint("base", flat::JointType::Prismatic, w, cart, Vec3::UnitX());
  auto& e = b.m.exprs;
  base.prescribed[0] = e.Binary(Op::Mul, b.C(A), e.Unary(Op::Sin, e.Binary(Op::Mul, b.C(W), e.Time())));
  int rod = b.Frame("rod.frame");
  b.Body("rod", rod, m, Vec3(0, -L / 2, 0), test::Diag(m * L * L / 12, 0.0, m * L * L / 12));
  b.Joint("swing", flat::JointType::Revolute, cart, rod, Vec3::UnitZ());
  for (auto path : {rt::SolverPath::Dense, rt::SolverPath::Sparse}) {
    rt::CompileOptions o;
    o.solver = path;
    auto r = rt::Compile(b.m, o);
    ASSERT_TRUE(r.errors.empty()) << r.errors[0].message;
    ASSERT_EQ(rt::StateSize(*r.program), 2);
    auto ws = rt::MakeWorkspace(*r.program);
    std::string err;
    auto plan = rt::PlanSignals(*r.program, {"base.q", "base.u", "swing.q", "base.drive"}, &err);
    ASSERT_TRUE(plan) << err;
    for (double t : {0.0, 0.4, 1.3}) {
      double y[2] = {0.5, -0.3}, yd[2], out[4];
      ASSERT_EQ(rt::Derivative(*r.program, *ws, t, y, yd), 0) << rt::ErrorMessage(*ws);
      const double xdd = -A * W * W * std::sin(W * t);
      EXPECT_NEAR(yd[1], -m * (L / 2) * (g * std::sin(0.5) + xdd * std::cos(0.5)) / (m * L * L / 3), kClosedFormTol);
      ASSERT_EQ(rt::EvalSignals(*r.program, *plan, *ws, t, y, out), 0);
      EXPECT_NEAR(out[0], A * std::sin(W * t), kClosedFormTol);
      EXPECT_NEAR(out[1], A * W * std::cos(W * t), kClosedFormTol);
      EXPECT_NEAR(out[2], 0.5, 0.0);
      // Drive force = horizontal momentum rate: M_cart xdd + m (xdd + (L/2)(cos q qdd - sin q qd^2)).
      const double drive = 5.0 * xdd + m * (xdd + (L / 2) * (std::cos(0.5) * yd[1] - std::sin(0.5) * 0.09));
      EXPECT_NEAR(out[3], drive, kClosedFormLooseTol);
    }
  }
}

TEST(Weld, WeldedBodiesMergeIntoOne) {
  // If this fails, merging welded bodies (mass, mass centre, parallel-axis inertia) is
  // wrong: a rod with a welded tip mass is one physical pendulum,
  //   qdd = -g sin q (m L/2 + m2 L) / (m L^2/3 + I2 + m2 L^2).
  const double m = 1.0, L = 0.5, m2 = 0.3, I2 = 0.01, g = 9.81;
  test::MechBuilder b;
  int w = b.World(Vec3(0, -g, 0));
  int f = b.Frame("rod.frame_a");
  b.Body("rod", f, m, Vec3(0, -L / 2, 0), test::Diag(m * L * L / 12, 0.0, m * L * L / 12));
  int tip = b.Frame("rod.frame_b");
  b.Fixed("rod.fix", f, tip, Vec3(0, -L, 0));
  int ball = b.Frame("ball.frame");
  b.Body("ball", ball, m2, Vec3::Zero(), test::Diag(I2, I2, I2));
  b.Joint("glue", flat::JointType::Weld, tip, ball);
  b.Joint("pivot", flat::JointType::Revolute, w, f, Vec3::UnitZ());
  auto r = rt::Compile(b.m, {});
  ASSERT_TRUE(r.errors.empty());
  EXPECT_EQ(rt::Summarize(*r.program).num_bodies, 1);
  auto ws = rt::MakeWorkspace(*r.program);
  double y[2] = {0.9, 0.4}, yd[2];
  ASSERT_EQ(rt::Derivative(*r.program, *ws, 0.0, y, yd), 0);
  EXPECT_NEAR(yd[1], -g * std::sin(0.9) * (m * L / 2 + m2 * L) / (m * L * L / 3 + I2 + m2 * L * L), kClosedFormTol);
}

// A slider on a prismatic joint along world x, tied to the world origin by a line
// force (k, s0, d), pushed by a wrench given in a frame turned 90 degrees about z, and
// by a joint force that reads the joint's own speed: for x > 0,
//   m xdd = -(k (x - s0) + d xd) - F - c xd.
TEST(Forces, LineForceWrenchAndJointForceMatchClosedForm) {
  // If this fails, a force element (spring-damper tension, frame-resolved wrench, or a
  // joint force expression of state) is projected on the tangent basis wrongly.
  const double m = 2.0, k = 30.0, s0 = 0.4, d = 1.5, F = 0.7, c = 0.25;
  test::MechBuilder b;
  int w = b.World(Vec3(0, -9.81, 0));
  int f = b.Frame("slider.frame");
  b.Body("slider", f, m, Vec3::Zero(), test::Diag(1, 1, 1));
  int turned = b.Frame("slider.turned");
  b.Fixed("slider.turn", f, turned, Vec3::Zero(), Eigen::AngleAxisd(M_PI / 2, Vec3::UnitZ()).toRotationMatrix());
  auto& j = b.Joint("rail", flat::JointType::Prismatic, w, f, Vec3::UnitX());
  const int ref = b.m.AddStateRef({flat::StateKind::JointU, 0, 0});
  j.tau[0] = b.m.exprs.Binary(Op::Mul, b.C(-c), b.m.exprs.State(ref));
  flat::LineForce lf;
  lf.name = "spring";
  lf.frame_a = w;
  lf.frame_b = f;
  lf.k = b.C(k);
  lf.s0 = b.C(s0);
  lf.d = b.C(d);
  b.m.line_forces.push_back(lf);
  flat::Wrench wr;
  wr.name = "push";
  wr.frame = turned;
  wr.force = b.V(Vec3(0, F, 0));  // frame y = world -x
  wr.torque = b.V(Vec3::Zero());
  wr.resolve_in_world = false;
  b.m.wrenches.push_back(wr);
  auto r = rt::Compile(b.m, {});
  ASSERT_TRUE(r.errors.empty()) << r.errors[0].message;
  auto ws = rt::MakeWorkspace(*r.program);
  for (double x : {0.3, 1.1}) {
    double y[2] = {x, 0.6}, yd[2];
    ASSERT_EQ(rt::Derivative(*r.program, *ws, 0.0, y, yd), 0) << rt::ErrorMessage(*ws);
    EXPECT_NEAR(yd[1], (-(k * (x - s0) + d * 0.6) - F - c * 0.6) / m, kClosedFormTol);
  }
}

TEST(Forces, NaNFromAnExpressionIsRecoverableAndNamed) {
  // If this fails, a NaN from a user expression silently propagates into the state
  // instead of stopping with a message naming the expression, or it is fatal, so that a
  // solver stage probing past the NaN's onset ends the run before the rows up to it
  // (recoverable, > 0: the solver retries shorter; engine.cpp NotFinite).
  auto mech = test::Pendulum();
  auto& e = mech.exprs;
  mech.joints[0].tau[0] = e.Unary(Op::Sqrt, e.Binary(Op::Sub, e.Time(), e.Constant(5.0)));
  auto r = rt::Compile(mech, {});
  ASSERT_TRUE(r.errors.empty());
  auto ws = rt::MakeWorkspace(*r.program);
  double y[2] = {0.1, 0.0}, yd[2];
  EXPECT_GT(rt::Derivative(*r.program, *ws, 0.0, y, yd), 0);
  EXPECT_NE(rt::ErrorMessage(*ws).find("force of joint 'pivot'"), std::string::npos) << rt::ErrorMessage(*ws);
  EXPECT_NE(rt::ErrorMessage(*ws).find("sqrt"), std::string::npos) << rt::ErrorMessage(*ws);
  EXPECT_EQ(rt::Derivative(*r.program, *ws, 6.0, y, yd), 0);
}

TEST(Signals, PendulumEnergiesAndPositions) {
  // If this fails, an output signal (kinetic or potential energy, a body's mass-centre
  // position, a frame position, a declared output) is computed wrongly.
  const double m = 1.0, L = 0.5, g = 9.81, q = 0.7, u = -1.3;
  auto mech = test::Pendulum(m, L, g);
  flat::Output out;
  out.name = "twice_q";
  const int ref = mech.AddStateRef({flat::StateKind::JointQ, 0, 0});
  out.expr = mech.exprs.Binary(Op::Mul, mech.exprs.Constant(2.0), mech.exprs.State(ref));
  mech.outputs.push_back(out);
  auto r = rt::Compile(mech, {});
  ASSERT_TRUE(r.errors.empty());
  const auto avail = rt::AvailableSignals(*r.program);
  for (const char* n : {"pivot.q", "pivot.u", "twice_q", "kinetic_energy", "potential_energy", "rod.r[1]", "rod.v[2]",
                        "rod.w[3]", "rod.R[1,2]", "rod.frame_a.r[3]"})
    EXPECT_NE(std::find(avail.begin(), avail.end(), n), avail.end()) << n;
  EXPECT_EQ(rt::DefaultSignals(*r.program), (std::vector<std::string>{"pivot.q", "pivot.u", "twice_q"}));
  std::string err;
  EXPECT_FALSE(rt::PlanSignals(*r.program, {"nope"}, &err));
  EXPECT_NE(err.find("nope"), std::string::npos);
  auto plan = rt::PlanSignals(*r.program, {"kinetic_energy", "potential_energy", "rod.r[1]", "rod.r[2]", "twice_q",
                                           "rod.v[1]", "rod.w[3]"},
                              &err);
  ASSERT_TRUE(plan) << err;
  auto ws = rt::MakeWorkspace(*r.program);
  double y[2] = {q, u}, o[7];
  ASSERT_EQ(rt::EvalSignals(*r.program, *plan, *ws, 0.0, y, o), 0);
  EXPECT_NEAR(o[0], 0.5 * (m * L * L / 3) * u * u, kClosedFormTol);
  EXPECT_NEAR(o[1], -m * g * (L / 2) * std::cos(q), kClosedFormTol);
  EXPECT_NEAR(o[2], (L / 2) * std::sin(q), kClosedFormTol);
  EXPECT_NEAR(o[3], -(L / 2) * std::cos(q), kClosedFormTol);
  EXPECT_NEAR(o[4], 2 * q, kClosedFormTol);
  EXPECT_NEAR(o[5], (L / 2) * std::cos(q) * u, kClosedFormTol);
  EXPECT_NEAR(o[6], u, kClosedFormTol);
}

TEST(Singular, MasslessLinkIsFatalOnEveryPath) {
  // If this fails, a mass matrix that is singular (a joint that moves nothing with
  // mass or inertia) yields garbage accelerations instead of a fatal status. A joint whose
  // subtree has no mass at all is K309 at compile time (compile/massless.cpp); a point
  // mass on the joint's axis (no inertia about it) is singular only at run time.
  auto massless = test::Pendulum();
  massless.bodies[0].mass = massless.exprs.Constant(0.0);
  for (auto& e : massless.bodies[0].inertia) e = massless.exprs.Constant(0.0);
  auto k309 = rt::Compile(massless, {});
  ASSERT_EQ(k309.errors.size(), 1u);
  EXPECT_EQ(k309.errors[0].code, flat::DiagCode::MovesNoMass);
  auto mech = test::Pendulum();
  for (auto& e : mech.bodies[0].inertia) e = mech.exprs.Constant(0.0);
  for (auto& e : mech.bodies[0].r_cm) e = mech.exprs.Constant(0.0);
  for (auto path : {rt::SolverPath::Dense, rt::SolverPath::Sparse, rt::SolverPath::Recursive}) {
    rt::CompileOptions o;
    o.solver = path;
    auto r = rt::Compile(mech, o);
    ASSERT_TRUE(r.errors.empty());
    auto ws = rt::MakeWorkspace(*r.program);
    double y[2] = {0.2, 0.0}, yd[2];
    EXPECT_LT(rt::Derivative(*r.program, *ws, 0.0, y, yd), 0);
    EXPECT_NE(rt::ErrorMessage(*ws).find("singular mass matrix"), std::string::npos) << rt::ErrorMessage(*ws);
  }
}

TEST(Rebind, NewParameterValuesSameStructure) {
  // If this fails, Rebind does not fold the new parameter values into every number
  // (mass centre, inertia) while keeping the structure.
  test::MechBuilder b;
  const int iL = b.Param("L", 0.5);
  auto& e = b.m.exprs;
  const flat::ExprId L = e.Parameter(iL);
  const flat::ExprId I = e.Binary(Op::Div, e.Binary(Op::Mul, L, L), b.C(12.0));
  int w = b.World(Vec3(0, -9.81, 0));
  int f = b.Frame("rod.frame_a");
  flat::Body body;
  body.name = "rod";
  body.frame = f;
  body.mass = b.C(1.0);
  body.r_cm = {b.C(0.0), e.Binary(Op::Mul, L, b.C(-0.5)), b.C(0.0)};
  body.inertia = {I, b.C(0), b.C(0), b.C(0), b.C(0), b.C(0), b.C(0), b.C(0), I};
  b.m.bodies.push_back(body);
  b.Joint("pivot", flat::JointType::Revolute, w, f, Vec3::UnitZ());
  auto r = rt::Compile(b.m, {});
  ASSERT_TRUE(r.errors.empty());
  auto p2 = rt::Rebind(*r.program, {2.0}).program;
  ASSERT_TRUE(p2);
  rt::CompileResult wrong = rt::Rebind(*r.program, {2.0, 3.0});  // wrong size
  EXPECT_FALSE(wrong.program);
  ASSERT_EQ(wrong.errors.size(), 1u);
  EXPECT_NE(wrong.errors[0].message.find("2 parameter values for 1"), std::string::npos);
  for (auto [prog, len] : {std::pair{r.program, 0.5}, std::pair{p2, 2.0}}) {
    auto ws = rt::MakeWorkspace(*prog);
    double y[2] = {0.4, 0.0}, yd[2];
    ASSERT_EQ(rt::Derivative(*prog, *ws, 0.0, y, yd), 0);
    EXPECT_NEAR(yd[1], -1.5 * 9.81 / len * std::sin(0.4), kClosedFormTol);
  }
}

}  // namespace
}  // namespace kanesim
