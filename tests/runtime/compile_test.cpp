// Compile: topology errors with stable codes and locations, the summary (sizes, chosen
// solver and integrator with reasons), prescribed-coordinate bookkeeping, jets.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "compiler/compile_internal.h"
#include "compiler/compiler.h"
#include "runtime/program/tape.h"
#include "tests/support/builders.h"

namespace kanesim {
namespace {

using flat::Op;
using test::Vec3;

bool HasError(const rt::CompileResult& r, const std::string& code, const std::string& text) {
  for (const auto& e : r.errors)
    if (flat::DiagCodeString(e.code) == code && e.message.find(text) != std::string::npos) return true;
  return false;
}

std::string Dump(const rt::CompileResult& r) {
  std::string s;
  for (const auto& e : r.errors) s += std::string(flat::DiagCodeString(e.code)) + ": " + e.message + "\n";
  return s;
}

TEST(Compile, ClosedLoopIsReportedWithTheJoint) {
  // If this fails, a kinematic loop is silently accepted (or not attributed to the
  // joint that closes it) before loops are supported (issue #4).
  auto m = test::Chain(2);
  const int tip = m.FindFrame("rod[2].frame_b");
  test::MechBuilder b;
  b.m = m;
  b.Joint("closer", flat::JointType::Revolute, tip, m.worlds[0].frame, Vec3::UnitZ());
  auto r = rt::Compile(b.m, {});
  EXPECT_FALSE(r.program);
  ASSERT_TRUE(HasError(r, "K310", "joint 'closer'")) << Dump(r);
  EXPECT_GT(r.errors[0].loc.line, 0);
}

TEST(Compile, ContactsAreNotSimulatedYet) {
  // If this fails, a rolling contact is silently dropped instead of reported.
  auto m = test::Pendulum();
  flat::Contact c;
  c.name = "wheel";
  c.frame = 1;
  m.contacts.push_back(c);
  auto r = rt::Compile(m, {});
  EXPECT_TRUE(HasError(r, "K311", "contact 'wheel'")) << Dump(r);
}

TEST(Compile, FloatingBodyAndUnconnectedFrameAreErrors) {
  // If this fails, a body with no path to the world, or a joint with a dangling frame,
  // reaches the runtime.
  test::MechBuilder b;
  b.World(Vec3(0, -9.81, 0));
  int f = b.Frame("lost.frame");
  b.Body("lost", f, 1.0, Vec3::Zero(), test::Diag(1, 1, 1));
  auto r = rt::Compile(b.m, {});
  EXPECT_TRUE(HasError(r, "K303", "body 'lost'")) << Dump(r);

  auto& j = b.Joint("dangling", flat::JointType::Revolute, 0, f);
  j.frame_b = -1;
  r = rt::Compile(b.m, {});
  EXPECT_TRUE(HasError(r, "K302", "joint 'dangling': frame_b")) << Dump(r);

  test::MechBuilder none;
  none.Frame("x");
  r = rt::Compile(none.m, {});
  EXPECT_TRUE(HasError(r, "K301", "no world")) << Dump(r);
}

// An API misuse is a message (code K300), not a crash: Rebind with a value too few.
TEST(Compile, RebindWithTheWrongNumberOfValuesIsK300) {
  const flat::Mechanism chain = test::Chain(2);
  auto r = rt::Compile(chain, {});
  ASSERT_TRUE(r.program) << Dump(r);
  std::vector<double> one_too_many(chain.params.size() + 1, 1.0);
  rt::CompileResult bad = rt::Rebind(*r.program, one_too_many);
  EXPECT_FALSE(bad.program);
  EXPECT_TRUE(HasError(bad, "K300", std::to_string(one_too_many.size()) + " parameter values for")) << Dump(bad);
}

TEST(Compile, SummaryCountsAndChoices) {
  // If this fails, `kanesim check` reports wrong sizes or an unexplained or wrong
  // choice of solution path or integrator.
  auto r = rt::Compile(test::Chain(5), {});
  ASSERT_TRUE(r.program);
  auto s = rt::Summarize(*r.program);
  EXPECT_EQ(s.num_bodies, 5);
  EXPECT_EQ(s.num_joints, 5);
  EXPECT_EQ(s.nq, 5);
  EXPECT_EQ(s.nu, 5);
  EXPECT_EQ(s.dof, 5);
  EXPECT_EQ(s.grubler_dof, 5);
  EXPECT_EQ(s.solver, rt::SolverPath::Recursive);
  EXPECT_EQ(s.integrator, rt::Integrator::Dop853);  // smooth and non-stiff
  EXPECT_FALSE(s.solver_reason.empty());
  EXPECT_FALSE(s.integrator_reason.empty());

  auto big = rt::Compile(test::Chain(200), {});
  ASSERT_TRUE(big.program);
  EXPECT_EQ(rt::Summarize(*big.program).solver, rt::SolverPath::Recursive);

  // A stiff spring (sqrt(k/m) = 3162 1/s) makes the scene stiff: IDA.
  auto m = test::Pendulum();
  flat::LineForce lf;
  lf.name = "stiff";
  lf.frame_a = 0;
  lf.frame_b = 1;
  lf.k = m.exprs.Constant(1e7);
  lf.d = m.exprs.Constant(0.0);
  lf.s0 = m.exprs.Constant(0.1);
  m.line_forces.push_back(lf);
  auto st = rt::Compile(m, {});
  ASSERT_TRUE(st.program);
  EXPECT_EQ(rt::Summarize(*st.program).integrator, rt::Integrator::IDA);
  EXPECT_NE(rt::Summarize(*st.program).integrator_reason.find("stiff"), std::string::npos);

  rt::CompileOptions o;
  o.solver = rt::SolverPath::Sparse;
  o.integrator = rt::Integrator::ArkodeErk;
  auto forced = rt::Compile(test::Chain(3), o);
  EXPECT_EQ(rt::Summarize(*forced.program).solver, rt::SolverPath::Sparse);
  EXPECT_EQ(rt::Summarize(*forced.program).integrator, rt::Integrator::ArkodeErk);
}

TEST(Compile, InitialStateFromStartValues) {
  // If this fails, start values (or the identity default of a quaternion) do not reach
  // the integrator's y0.
  auto r = rt::Compile(test::Chain(4), {});
  std::vector<double> y(static_cast<size_t>(rt::StateSize(*r.program)));
  rt::InitialState(*r.program, y.data());
  EXPECT_EQ(y, (std::vector<double>{0.1, 0.1, 0.1, 0.1, 0, 0, 0, 0}));
  test::MechBuilder b;
  int w = b.World(Vec3::Zero());
  int f = b.Frame("b.frame");
  b.Body("b", f, 1.0, Vec3::Zero(), test::Diag(1, 1, 1));
  b.Joint("ball", flat::JointType::Spherical, w, f);
  auto s = rt::Compile(b.m, {});
  std::vector<double> y2(7);
  rt::InitialState(*s.program, y2.data());
  EXPECT_EQ(y2, (std::vector<double>{1, 0, 0, 0, 0, 0, 0}));
  const auto names = rt::DefaultSignals(*s.program);
  EXPECT_EQ(names.front(), "ball.q[1]");
  EXPECT_EQ(names.back(), "ball.u[3]");
}

TEST(Signals, NamesResolveToTheFirstSignalOfThatName) {
  // If this fails, planning a joint's q or u, an output or an energy by name (the quick path
  // a run's start takes without naming every signal) finds another signal than the first of
  // that name in AvailableSignals: each state name must read its own entry of y, an output
  // named "kinetic_energy" shadows the energy, a joint's "b1.q" shadows an output of that name.
  std::mt19937 rng(11);
  auto mech = test::RandomTree(rng, {14, true, true, true});  // j1 revolute, j2 prismatic
  int j1 = 0;
  while (mech.joints[static_cast<size_t>(j1)].name != "j1") ++j1;
  const int ref = mech.AddStateRef({flat::StateKind::JointQ, j1, 0});
  flat::Output twice, seven;
  twice.name = "kinetic_energy";
  twice.expr = mech.exprs.Binary(Op::Mul, mech.exprs.Constant(2.0), mech.exprs.State(ref));
  seven.name = "j2.q";
  seven.expr = mech.exprs.Constant(7.0);
  mech.outputs = {twice, seven};
  auto r = rt::Compile(mech, {});
  ASSERT_TRUE(r.errors.empty()) << Dump(r);
  const rt::Program& p = *r.program;
  std::vector<double> y(static_cast<size_t>(rt::StateSize(p)));
  for (size_t i = 0; i < y.size(); ++i) y[i] = 0.1 + 0.01 * static_cast<double>(i);
  rt::InitialState(p, y.data());  // unit quaternions where the state has them
  for (size_t i = 0; i < y.size(); ++i) y[i] += 1e-3 * static_cast<double>(i);
  auto ws = rt::MakeWorkspace(p);
  auto read = [&](const std::string& name) {
    std::string err;
    auto plan = rt::PlanSignals(p, {name}, &err);
    EXPECT_TRUE(plan) << name << ": " << err;
    double v = 0.0;
    if (plan) {
      EXPECT_EQ(rt::EvalSignals(p, *plan, *ws, 0.0, y.data(), &v), 0) << name;
    }
    return v;
  };
  const auto state = rt::StateNames(p);
  for (size_t i = 0; i < state.size(); ++i) EXPECT_EQ(read(state[i]), y[i]) << state[i];
  EXPECT_EQ(read("kinetic_energy"), 2.0 * read("j1.q"));
  EXPECT_NE(read("j2.q"), 7.0);
  auto sorted = [](std::vector<std::string> v) { std::sort(v.begin(), v.end()); return v; };
  std::vector<std::string> expected = state;
  expected.insert(expected.end(), {twice.name, seven.name});
  EXPECT_EQ(sorted(rt::DefaultSignals(p)), sorted(expected));
  std::string err;
  EXPECT_FALSE(rt::PlanSignals(p, {"j2.q[1]"}, &err));  // one coordinate: no index
  EXPECT_FALSE(rt::PlanSignals(p, {"b99.q"}, &err));
}

TEST(Tape, JetsMatchAnalyticDerivatives) {
  // If this fails, the forward-mode jets that give prescribed speeds and accelerations
  // are wrong for some operator. f(t) = t^2 sin(2t) + exp(t/3) / (1 + t) + atan2(t, 2).
  flat::ExprPool e;
  const flat::ExprId t = e.Time();
  auto c = [&](double v) { return e.Constant(v); };
  const flat::ExprId f = e.Binary(
      Op::Add,
      e.Binary(Op::Add, e.Binary(Op::Mul, e.Binary(Op::Pow, t, c(2)), e.Unary(Op::Sin, e.Binary(Op::Mul, c(2), t))),
               e.Binary(Op::Div, e.Unary(Op::Exp, e.Binary(Op::Div, t, c(3))), e.Binary(Op::Add, c(1), t))),
      e.Binary(Op::Atan2, t, c(2)));
  std::vector<double> params;
  rt::TapeBuilder tb(e, params);
  tb.AddRoot(f, "f", "f");
  rt::Tape tape = tb.Finish();
  std::vector<double> r(3 * tape.init.size(), 0.0);
  for (size_t i = 0; i < tape.init.size(); ++i) r[3 * i] = tape.init[i];
  const double T = 0.7;
  r[3 * static_cast<size_t>(tape.time_reg)] = T;
  r[3 * static_cast<size_t>(tape.time_reg) + 1] = 1.0;
  tape.EvalJet(r.data());
  const size_t o = 3 * static_cast<size_t>(tape.roots[0]);
  // Analytic: with s = sin 2t, k = cos 2t, E = exp(t/3), D = 1 + t.
  const double s = std::sin(2 * T), k = std::cos(2 * T), E = std::exp(T / 3), D = 1 + T;
  const double f0 = T * T * s + E / D + std::atan2(T, 2.0);
  const double f1 = 2 * T * s + 2 * T * T * k + (E / 3) / D - E / (D * D) + 2.0 / (4 + T * T);
  const double f2 = 2 * s + 8 * T * k - 4 * T * T * s + (E / 9) / D - 2 * (E / 3) / (D * D) + 2 * E / (D * D * D) -
                    4.0 * T / ((4 + T * T) * (4 + T * T));
  // Jets and the analytic formulas round differently: a few ulps of each term, more
  // for the second derivative, which sums more terms.
  constexpr double kJetTol = 1e-12;
  EXPECT_NEAR(r[o], f0, kJetTol);
  EXPECT_NEAR(r[o + 1], f1, kJetTol);
  EXPECT_NEAR(r[o + 2], f2, kJetTol);
}


// Eq. (1)-(3) of compile/inertia.cpp over a generator of rotated tensors: every rigid
// body's inertia passes (and comes back symmetric), and a tensor broken in one way
// (asymmetric, a negative principal moment, the triangle inequality, a non-finite entry)
// is refused with that reason, whatever its orientation.
TEST(InertiaCheck, RigidBodiesPassBrokenTensorsFailInEveryOrientation) {
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> u(0.2, 1.0);
  auto rotated = [&](double a, double b, double c) {
    const test::Mat3 R = test::RandomRotation(rng);
    return test::Mat3(R * test::Diag(a, b, c) * R.transpose());
  };
  auto why = [](const test::Mat3& I) {
    test::Mat3 sym;
    return rt::CheckInertia(I, &sym);
  };
  for (int k = 0; k < 300; ++k) {
    const test::Mat3 I = test::RandomInertia(rng);
    test::Mat3 sym;
    EXPECT_EQ(rt::CheckInertia(I, &sym), "") << I;
    EXPECT_LE((sym - I).cwiseAbs().maxCoeff(), 1e-15);
    EXPECT_NE(why(rotated(0, u(rng), 0)).find("triangle"), std::string::npos) << "a line of mass has no such moments";
    const double a = u(rng), b = u(rng);
    EXPECT_EQ(why(rotated(a, b, a + b)), "") << "a plane lamina";
    EXPECT_EQ(why(rotated(0, a, a)), "") << "a thin rod";
    EXPECT_NE(why(rotated(a, b, (a + b) * (1 + 1e-3))).find("triangle"), std::string::npos);
    EXPECT_NE(why(rotated(-1e-3 * a, b, b)).find("negative principal"), std::string::npos);
    test::Mat3 skew = I;
    const int i = static_cast<int>(rng() % 3), j = (i + 1 + static_cast<int>(rng() % 2)) % 3;
    skew(i, j) += 1e-4 * I.trace();
    EXPECT_NE(why(skew).find("not symmetric"), std::string::npos) << skew;
    skew(i, j) = I(i, j) + 1e-8 * I.trace();  // inside the tolerance (1e-6): accepted, symmetrized
    EXPECT_EQ(why(skew), "");
    test::Mat3 bad = I;
    bad(i, j) = std::nan("");
    EXPECT_NE(why(bad).find("non-finite"), std::string::npos);
  }
}

// Every path that makes a program checks: Compile and Rebind (sweeps, --set through
// re-elaboration compiles anew), with K308 at the body's declaration.
TEST(InertiaCheck, CompileAndRebindReportK308AtTheBody) {
  test::MechBuilder b;
  const int iJ = b.Param("J", 1.0);
  auto& e = b.m.exprs;
  const flat::ExprId J = e.Parameter(iJ);
  int w = b.World(Vec3(0, -9.81, 0));
  int f = b.Frame("wheel.frame_a");
  flat::Body body;
  body.name = "wheel";
  body.frame = f;
  body.mass = b.C(1.0);
  body.r_cm = {b.C(0.0), b.C(0.0), b.C(0.0)};
  body.inertia = {J, b.C(0), b.C(0), b.C(0), b.C(1), b.C(0), b.C(0), b.C(0), b.C(1)};
  body.loc = {"w.mech", 7, 3};
  b.m.bodies.push_back(body);
  b.Joint("pivot", flat::JointType::Revolute, w, f, Vec3::UnitZ());
  auto r = rt::Compile(b.m, {});
  ASSERT_TRUE(r.errors.empty()) << Dump(r);
  for (double j : {-1.0, 2.5, std::nan("")}) {  // negative; 1 + 1 < 2.5; not a number
    rt::CompileResult bad = rt::Rebind(*r.program, {j});
    EXPECT_FALSE(bad.program) << j;
    ASSERT_TRUE(HasError(bad, "K308", "body 'wheel'")) << j << "\n" << Dump(bad);
    EXPECT_EQ(bad.errors[0].loc.line, 7);
    EXPECT_EQ(bad.errors[0].loc.col, 3);
  }
  EXPECT_TRUE(rt::Rebind(*r.program, {1.9}).program);
}

}  // namespace
}  // namespace kanesim
