// Elaboration semantics (the positive side; errors are covered by tests/lang/diagnostics):
// modifier precedence, extends, arrays and `each`, for/if equations, conditional
// components, --set, structural parameters, and what reaches the flat mechanism.
#include <gtest/gtest.h>

#include <cmath>

#include "lang/elaborate.h"
#include "stdlib/stdlib.h"

namespace kanesim::lang {
namespace {

struct Elab {
  Program program;
  flat::Mechanism mech;
  std::string errors;
  bool ok = false;
  std::vector<double> values;
  double P(const std::string& name) const {
    int i = mech.FindParam(name);
    EXPECT_GE(i, 0) << "no parameter " << name;
    return i >= 0 ? values[static_cast<size_t>(i)] : NAN;
  }
};

std::unique_ptr<Elab> ElabText(const std::string& text, std::vector<ParamOverride> sets = {}) {
  auto e = std::make_unique<Elab>();
  Diagnostics diags(&e->program.sources);
  ElaborateOptions opt;
  opt.overrides = std::move(sets);
  bool loaded = LoadProgramFromText("test.mech", text, stdlib::Files(), &e->program, diags);
  e->ok = loaded && Elaborate(e->program, opt, &e->mech, diags);
  e->errors = diags.RenderAll();
  if (e->ok) e->values = flat::EvaluateParams(e->mech);
  return e;
}

const char* kPendulum = R"(
model P
  parameter Real L = 1.5;
  World world;
  Revolute j(q(start = 0.2));
  Rod rod(L = L, m = 2);
equation
  connect(world.frame_b, j.frame_a);
  connect(j.frame_b, rod.frame_a);
end P;
)";

// If this fails, modifier values do not flow from the model into the library classes.
TEST(Elaborate, ModifiersReachPrimitives) {
  auto e = ElabText(kPendulum);
  ASSERT_TRUE(e->ok) << e->errors;
  EXPECT_DOUBLE_EQ(e->P("rod.body.r_CM[1]"), 0.75);
  EXPECT_DOUBLE_EQ(e->P("rod.body.I[3,3]"), 2 * 1.5 * 1.5 / 12);
  ASSERT_EQ(e->mech.joints.size(), 1u);
  EXPECT_EQ(e->mech.exprs.ToString(e->mech.joints[0].q_start[0]), "0.20000000000000001");
  ASSERT_EQ(e->mech.bodies.size(), 1u);
  // World frame, joint's moving frame (= rod.frame_a = body frame = tip.frame_a), rod tip.
  EXPECT_EQ(e->mech.frames.size(), 3u);
}

// Outer modifiers win over inner ones; --set wins over all and is marked as set.
TEST(Elaborate, OuterModifierAndSetWin) {
  const char* text = R"(
model Inner
  parameter Real a = 1;
  parameter Real b = a * 2;
end Inner;
model Outer
  Inner x(a = 3);
  Inner y(a = 3, b = 10);
  World world;
end Outer;
)";
  auto e = ElabText(text);
  ASSERT_TRUE(e->ok) << e->errors;
  EXPECT_DOUBLE_EQ(e->P("x.a"), 3);
  EXPECT_DOUBLE_EQ(e->P("x.b"), 6);  // binding re-evaluated with the new a
  EXPECT_DOUBLE_EQ(e->P("y.b"), 10);
  auto s = ElabText(text, {{"x.a", "5"}});
  ASSERT_TRUE(s->ok) << s->errors;
  EXPECT_DOUBLE_EQ(s->P("x.b"), 10);
  EXPECT_TRUE(s->mech.params[static_cast<size_t>(s->mech.FindParam("x.a"))].user_set);
}

// Derived parameters stay symbolic: changing a leaf value re-evaluates them (sweeps).
TEST(Elaborate, DerivedParametersFollowTheirLeaves) {
  auto e = ElabText(kPendulum);
  ASSERT_TRUE(e->ok) << e->errors;
  int L = e->mech.FindParam("L");
  ASSERT_GE(L, 0);
  e->mech.params[static_cast<size_t>(L)].value = 3.0;
  auto v = flat::EvaluateParams(e->mech);
  EXPECT_DOUBLE_EQ(v[static_cast<size_t>(e->mech.FindParam("rod.body.r_CM[1]"))], 1.5);
}

TEST(Elaborate, ExtendsWithModifiersAndShortClasses) {
  const char* text = R"(
model Base
  parameter Real k = 1;
  parameter Real twice = 2 * k;
end Base;
model Derived
  extends Base(k = 4);
end Derived;
model Short = Derived(k = 7);
model T
  Derived d;
  Short s;
  World world;
end T;
)";
  auto e = ElabText(text);
  ASSERT_TRUE(e->ok) << e->errors;
  EXPECT_DOUBLE_EQ(e->P("d.twice"), 8);
  EXPECT_DOUBLE_EQ(e->P("s.twice"), 14);
}

// The chain example: N joints and rods from arrays, for-loops and a comprehension.
TEST(Elaborate, ChainExampleBuildsAlternatingAxes) {
  auto e = ElabText(R"(
model Chain
  parameter Integer N = 4;
  World world;
  Revolute j[N](axis = {if mod(i, 2) == 1 then {0, 0, 1} else {0, 1, 0} for i in 1:N}, each q(start = 0.1));
  Rod links[N](each L = 0.5, each m = 1);
equation
  connect(world.frame_b, j[1].frame_a);
  for i in 1:N loop
    connect(j[i].frame_b, links[i].frame_a);
  end for;
  for i in 2:N loop
    connect(links[i - 1].frame_b, j[i].frame_a);
  end for;
end Chain;
)");
  ASSERT_TRUE(e->ok) << e->errors;
  ASSERT_EQ(e->mech.joints.size(), 4u);
  EXPECT_DOUBLE_EQ(e->P("j[1].axis[3]"), 1);
  EXPECT_DOUBLE_EQ(e->P("j[2].axis[2]"), 1);
  EXPECT_DOUBLE_EQ(e->P("j[2].axis[3]"), 0);
  EXPECT_TRUE(e->mech.params[static_cast<size_t>(e->mech.FindParam("N"))].structural);
  // j[i+1].frame_a is the tip of rod i: the chain is one connected tree.
  for (size_t i = 1; i < 4; ++i) {
    int tip = e->mech.FindFrame("links[" + std::to_string(i) + "].frame_b");
    EXPECT_EQ(e->mech.joints[i].frame_a, tip);
  }
  auto e8 = ElabText(R"(model C parameter Integer N = 2; World world; Revolute j[N]; end C;)", {{"N", "8"}});
  ASSERT_TRUE(e8->ok) << e8->errors;
  EXPECT_EQ(e8->mech.joints.size(), 8u);
}

TEST(Elaborate, SlicedArrayModifiersAndMatrices) {
  auto e = ElabText(R"(
model T
  World world;
  Rod r[3](L = {1, 2, 3}, each m = 1);
  parameter Real[2, 2] A = [1, 2; 3, 4];
  parameter Real[2, 2] B = {{1, 2}, {3, 4}};
  parameter Real[2] v = A * {1, 1};
  parameter Real s = sum({i ^ 2 for i in 1:4});
  parameter Real c[3] = cross({1, 0, 0}, {0, 1, 0});
end T;
)");
  ASSERT_TRUE(e->ok) << e->errors;
  EXPECT_DOUBLE_EQ(e->P("r[2].L"), 2);
  EXPECT_DOUBLE_EQ(e->P("r[3].body.r_CM[1]"), 1.5);
  EXPECT_DOUBLE_EQ(e->P("A[2,1]"), 3);
  EXPECT_DOUBLE_EQ(e->P("B[2,1]"), 3);
  EXPECT_DOUBLE_EQ(e->P("v[2]"), 7);
  EXPECT_DOUBLE_EQ(e->P("s"), 30);
  EXPECT_DOUBLE_EQ(e->P("c[3]"), 1);
}

TEST(Elaborate, ConditionalComponentsAndIfEquations) {
  const char* text = R"(
model T
  parameter Boolean withDamper = true;
  parameter Boolean driven = false;
  World world;
  Revolute j;
  Rod rod;
  RotationalDamper d(d = 0.5) if withDamper;
equation
  connect(world.frame_b, j.frame_a);
  connect(j.frame_b, rod.frame_a);
  connect(d.flange_b, j.drive);
  if driven then
    j.tau = 1;
  else
    j.tau = 0.25;
  end if;
end T;
)";
  auto e = ElabText(text);
  ASSERT_TRUE(e->ok) << e->errors;
  // tau = 0.25 + (-(d (u_b - 0))) from the damper on the drive flange.
  std::vector<std::string> sn;
  for (const auto& r : e->mech.state_refs) sn.push_back(e->mech.StateRefName(r));
  std::string tau = e->mech.exprs.ToString(e->mech.joints[0].tau[0], nullptr, &sn);
  EXPECT_NE(tau.find("0.25"), std::string::npos) << tau;
  EXPECT_NE(tau.find("j.u"), std::string::npos) << tau;
  auto off = ElabText(text, {{"withDamper", "false"}});
  ASSERT_TRUE(off->ok) << off->errors;
  EXPECT_EQ(off->mech.exprs.ToString(off->mech.joints[0].tau[0]), "0.25");
}

TEST(Elaborate, PrescribedMotionForceLawsAndOutputs) {
  auto e = ElabText(R"(
model T
  World world;
  Revolute a;
  Rod r1;
  Revolute b;
  Rod r2;
  output Real tipx = r2.frame_b.r[1];
equation
  connect(world.frame_b, a.frame_a);
  connect(a.frame_b, r1.frame_a);
  connect(r1.frame_b, b.frame_a);
  connect(b.frame_b, r2.frame_a);
  a.q = 0.2 * sin(3 * time);
  b.tau = -0.5 * b.u + 2 * sin(time);
end T;
)");
  ASSERT_TRUE(e->ok) << e->errors;
  EXPECT_NE(e->mech.joints[0].prescribed[0], flat::kNoExpr);
  EXPECT_TRUE(e->mech.exprs.DependsOnTimeOrState(e->mech.joints[0].prescribed[0]));
  EXPECT_FALSE(e->mech.exprs.DependsOnState(e->mech.joints[0].prescribed[0]));
  EXPECT_TRUE(e->mech.exprs.DependsOnState(e->mech.joints[1].tau[0]));
  ASSERT_EQ(e->mech.outputs.size(), 1u);
  const auto& o = e->mech.exprs[e->mech.outputs[0].expr];
  ASSERT_EQ(o.op, flat::Op::State);
  const auto& ref = e->mech.state_refs[static_cast<size_t>(o.index)];
  EXPECT_EQ(ref.kind, flat::StateKind::FramePosition);
  EXPECT_EQ(e->mech.frames[static_cast<size_t>(ref.target)].name, "r2.frame_b");
}

TEST(Elaborate, ImportsAndRedeclare) {
  auto e = ElabText(R"(
package Lib
  model Holder
    replaceable Rod part(m = 2);
    Frame frame_a;
  equation
    connect(frame_a, part.frame_a);
  end Holder;
end Lib;
model T
  import H = Lib.Holder;
  World world;
  H h(redeclare Box part(lx = 1, ly = 1, lz = 1));
equation
  connect(world.frame_b, h.frame_a);
end T;
)");
  ASSERT_TRUE(e->ok) << e->errors;
  EXPECT_DOUBLE_EQ(e->P("h.part.m"), 2);  // the original modifier applies to the new type
  EXPECT_DOUBLE_EQ(e->P("h.part.body.I[1,1]"), 2.0 * 2 / 12);
}

TEST(Elaborate, ExperimentAnnotation) {
  auto e = ElabText(R"(model T World world; annotation(experiment(StartTime = 1, StopTime = 4, Tolerance = 1e-9, Interval = 0.5)); end T;)");
  ASSERT_TRUE(e->ok) << e->errors;
  EXPECT_DOUBLE_EQ(e->mech.experiment.start_time, 1);
  EXPECT_DOUBLE_EQ(e->mech.experiment.stop_time, 4);
  EXPECT_DOUBLE_EQ(e->mech.experiment.tolerance, 1e-9);
  EXPECT_DOUBLE_EQ(e->mech.experiment.interval, 0.5);
}

}  // namespace
}  // namespace kanesim::lang
