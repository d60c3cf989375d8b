// Joints whose two frames end up on one rigid body (the world, or bodies merged by welds
// and fixed elements), and rigid loops of welds: compile/loops.cpp LockJoint and
// compile/compile.cpp CheckRigidLoop (issue 38). Each case either runs, checked against
// the same mechanism written without the locked joint, or is K310 at the joint.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "tests/compiler/compile_test_util.h"
#include "compiler/compiler.h"

namespace kanesim::test {
namespace {

// A model `body` with `StopTime = 1, Interval = 0.5` around it.
std::string Model(const std::string& body) {
  return "model M\n" + body + "  annotation(experiment(StopTime = 1, Interval = 0.5));\nend M;\n";
}

// Runs `p` with every integrator: each must write the three rows 0, 0.5, 1.
void RunsEverywhere(const rt::Program& p, const std::vector<std::string>& signals) {
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    sim::MemorySink s = RunWith(p, how, 1.0, 0.5, signals, &r);
    EXPECT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
    EXPECT_EQ(s.times, (std::vector<double>{0.0, 0.5, 1.0})) << how.name;
  }
}

const char* kBothFramesOnWorld =
    "  World world;\n"
    "  Revolute j1(axis = {0, 0, 1});\n"
    "equation\n"
    "  connect(world.frame_b, j1.frame_a);\n"
    "  connect(j1.frame_b, world.frame_b);\n";

// If this fails, a joint between two frames of the world crashes the compiler (SIGSEGV in
// AssembleLoops) or is not reported as locked.
TEST(LockedJoint, JointWithBothFramesOnTheWorldRunsWithNoDegreeOfFreedom) {
  auto l = LoadModel(Model(kBothFramesOnWorld), {}, {}, true);
  ASSERT_TRUE(l && l->prog) << Messages(l->errors);
  EXPECT_EQ(SummaryOf(*l).dof, 0);
  EXPECT_EQ(SummaryOf(*l).nu, 0);
  const auto w = rt::LockedJointWarnings(*l->prog);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_EQ(flat::DiagCodeString(w[0].code), std::string("W316"));
  EXPECT_NE(w[0].message.find("joint 'j1' cannot move: both its frames are fixed to the world"), std::string::npos);
  EXPECT_EQ(w[0].loc.line, 3);
  RunsEverywhere(*l->prog, {"kinetic_energy"});
}

// If this fails, a prismatic closing a loop of fixed elements on the world crashes, or
// its frames held where the joint cannot put them are not reported at the joint.
TEST(LockedJoint, BodylessPrismaticLoopToTheWorld) {
  auto loop = [](const char* axis) {
    return Model(std::string("  World world;\n"
                             "  FixedTranslation ft(r = {1, 0, 0});\n"
                             "  Prismatic p(axis = ") +
                 axis +
                 ");\n"
                 "equation\n"
                 "  connect(world.frame_b, ft.frame_a);\n"
                 "  connect(ft.frame_b, p.frame_a);\n"
                 "  connect(p.frame_b, world.frame_b);\n");
  };
  auto along = LoadModel(loop("{1, 0, 0}"), {}, {}, true);  // frame_b 1 m back along the axis: allowed
  ASSERT_TRUE(along && along->prog) << Messages(along->errors);
  EXPECT_EQ(rt::LockedJointWarnings(*along->prog).size(), 1u);
  RunsEverywhere(*along->prog, {"kinetic_energy"});

  auto across = LoadModel(loop("{0, 1, 0}"), {}, {}, true);  // 1 m across the axis: impossible
  ASSERT_TRUE(across);
  EXPECT_FALSE(across->prog);
  const rt::CompileMessage* e = Find(across->errors, "K310", "joint 'p' cannot move");
  ASSERT_TRUE(e) << Messages(across->errors);
  EXPECT_NE(e->message.find("translation across the axis"), std::string::npos) << e->message;
  EXPECT_NE(e->message.find("off by 1"), std::string::npos) << e->message;
  EXPECT_EQ(e->loc.line, 4);
}

// The rod of a pendulum `how` attached: the signals of one run by DOP853.
sim::MemorySink Pendulum(const std::string& extra_decl, const std::string& extra_eq, const std::vector<std::string>& sig,
                         int expect_locked) {
  const std::string text = Model(
      "  World world(g = {0, -9.81, 0});\n"
      "  Revolute j1(axis = {0, 0, 1}, q(start = 0.7));\n"
      "  Rod rod(L = 1, m = 1);\n"
      "  Rod rod2(L = 0.5, m = 2);\n" +
      extra_decl +
      "equation\n"
      "  connect(world.frame_b, j1.frame_a);\n"
      "  connect(j1.frame_b, rod.frame_a);\n" +
      extra_eq);
  auto l = LoadModel(text, {}, {}, true);
  EXPECT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  if (!l || !l->prog) return {};
  EXPECT_EQ(static_cast<int>(rt::LockedJointWarnings(*l->prog).size()), expect_locked);
  EXPECT_EQ(SummaryOf(*l).dof, 1);
  sim::SimResult r;
  sim::MemorySink s = RunWith(*l->prog, AllIntegrators()[0], 1.0, 0.5, sig, &r, 1e-11);
  EXPECT_EQ(r.status, sim::SimResult::Status::kOk) << r.message;
  return s;
}

// If this fails, a weld between two bodies already joined by a revolute does not lock
// that revolute: the motion differs from rod2 fixed to rod by a plain connect.
TEST(LockedJoint, WeldOverARevoluteBetweenTwoBodiesLocksIt) {
  const std::vector<std::string> sig = {"j1.q", "j1.u", "kinetic_energy"};
  sim::MemorySink welded = Pendulum("  Revolute j2(axis = {0, 0, 1}, q(start = 0.4));\n  Weld w;\n",
                                    "  connect(rod.frame_b, j2.frame_a);\n  connect(j2.frame_b, rod2.frame_a);\n"
                                    "  connect(rod.frame_b, w.frame_a);\n  connect(w.frame_b, rod2.frame_a);\n",
                                    sig, 1);
  sim::MemorySink plain = Pendulum("", "  connect(rod.frame_b, rod2.frame_a);\n", sig, 0);
  ASSERT_EQ(welded.rows.size(), 3u);
  ASSERT_EQ(plain.rows.size(), 3u);
  for (size_t k = 0; k < 3; ++k)
    for (size_t c = 0; c < sig.size(); ++c) EXPECT_NEAR(welded.rows[k][c], plain.rows[k][c], 1e-9) << sig[c] << " row " << k;
  EXPECT_GT(std::fabs(plain.rows[2][0] - 0.7), 0.1);  // it swings
}

// If this fails, a revolute with both frames on one moving body changes the motion (or
// crashes): it must be dropped, and one with its frames 1 m apart refused.
TEST(LockedJoint, RevoluteWithBothFramesOnAMovingBody) {
  const std::vector<std::string> sig = {"j1.q", "j1.u"};
  sim::MemorySink locked = Pendulum("  Revolute j2(axis = {0, 1, 0});\n",
                                    "  connect(rod.frame_b, rod2.frame_a);\n"
                                    "  connect(rod.frame_b, j2.frame_a);\n  connect(j2.frame_b, rod2.frame_a);\n",
                                    sig, 1);
  sim::MemorySink plain = Pendulum("", "  connect(rod.frame_b, rod2.frame_a);\n", sig, 0);
  ASSERT_EQ(locked.rows.size(), 3u);
  for (size_t k = 0; k < 3; ++k)
    for (size_t c = 0; c < sig.size(); ++c) EXPECT_NEAR(locked.rows[k][c], plain.rows[k][c], 1e-9);

  auto apart = LoadModel(Model("  World world;\n"
                               "  Revolute j1(axis = {0, 0, 1});\n"
                               "  Rod rod(L = 1, m = 1);\n"
                               "  Revolute j2(axis = {0, 0, 1});\n"
                               "equation\n"
                               "  connect(world.frame_b, j1.frame_a);\n"
                               "  connect(j1.frame_b, rod.frame_a);\n"
                               "  connect(rod.frame_a, j2.frame_a);\n"
                               "  connect(j2.frame_b, rod.frame_b);\n"),
                         {}, {}, true);
  ASSERT_TRUE(apart);
  const rt::CompileMessage* e = Find(apart->errors, "K310", "joint 'j2' cannot move (both its frames are fixed to body");
  ASSERT_TRUE(e) << Messages(apart->errors);
  EXPECT_NE(e->message.find("translation along x off by 1"), std::string::npos) << e->message;
}

const char* kWeldBehindRevolute =
    "  World world(g = {0, -9.81, 0});\n"
    "  Rod rod(L = 1, m = 1);\n"
    "  Revolute j1(axis = {0, 0, 1});\n"
    "  Weld w;\n"
    "equation\n"
    "  connect(world.frame_b, j1.frame_a);\n"
    "  connect(j1.frame_b, rod.frame_a);\n"
    "  connect(rod.frame_a, w.frame_a);\n"
    "  connect(w.frame_b, world.frame_b);\n";

// If this fails, a body welded to the world behind a revolute (an easy mistake, and the
// way to hold a joint on purpose) crashes, or its held rod moves: 0 degrees of freedom,
// the weld named in the warning, the energy that of the rod fixed to the world directly.
TEST(LockedJoint, WeldBehindARevoluteHoldsTheRod) {
  auto l = LoadModel(Model(kWeldBehindRevolute), {}, {}, true);
  ASSERT_TRUE(l && l->prog) << Messages(l->errors);
  EXPECT_EQ(SummaryOf(*l).dof, 0);
  const auto w = rt::LockedJointWarnings(*l->prog);
  ASSERT_EQ(w.size(), 1u);
  ASSERT_EQ(w[0].notes.size(), 1u);
  EXPECT_NE(w[0].notes[0].second.find("weld 'w'"), std::string::npos);
  EXPECT_EQ(w[0].notes[0].first.line, 5);
  RunsEverywhere(*l->prog, {"kinetic_energy", "potential_energy", "rod.body.r[1]"});
  sim::SimResult r;
  sim::MemorySink s = RunWith(*l->prog, AllIntegrators()[0], 1.0, 0.5, {"kinetic_energy", "rod.body.r[1]"}, &r);
  ASSERT_EQ(s.rows.size(), 3u);
  for (const auto& row : s.rows) {
    EXPECT_EQ(row[0], 0.0);
    EXPECT_EQ(row[1], 0.5);  // the rod's mass centre, half its length along x
  }
}

// If this fails, two welds of one body to the world (a rigid loop of welds) crash or,
// when they disagree on where the body is, the first silently wins.
TEST(LockedJoint, RigidLoopsOfWelds) {
  auto twice = LoadModel(Model("  World world;\n"
                               "  Body b(m = 1, I = identity(3));\n"
                               "  Weld w1;\n"
                               "  Weld w2;\n"
                               "equation\n"
                               "  connect(world.frame_b, w1.frame_a);\n"
                               "  connect(w1.frame_b, b.frame_a);\n"
                               "  connect(world.frame_b, w2.frame_a);\n"
                               "  connect(w2.frame_b, b.frame_a);\n"),
                         {}, {}, true);
  ASSERT_TRUE(twice && twice->prog) << Messages(twice->errors);
  RunsEverywhere(*twice->prog, {"kinetic_energy"});

  auto apart = LoadModel(Model("  World world;\n"
                               "  Body b(m = 1, I = identity(3));\n"
                               "  FixedTranslation ft(r = {1, 0, 0});\n"
                               "  Weld w;\n"
                               "equation\n"
                               "  connect(world.frame_b, ft.frame_a);\n"
                               "  connect(ft.frame_b, b.frame_a);\n"
                               "  connect(world.frame_b, w.frame_a);\n"
                               "  connect(w.frame_b, b.frame_a);\n"),
                         {}, {}, true);
  ASSERT_TRUE(apart);
  EXPECT_FALSE(apart->prog);
  const rt::CompileMessage* e = Find(apart->errors, "K310", "closes a rigid loop");
  ASSERT_TRUE(e) << Messages(apart->errors);
  EXPECT_NE(e->message.find("positions 1 apart"), std::string::npos) << e->message;
  EXPECT_EQ(std::count_if(apart->errors.begin(), apart->errors.end(),
                          [](const rt::CompileMessage& m) { return m.message.find("rigid loop") != std::string::npos; }),
            1);
}

// If this fails, a loop of fixed elements closed through two revolutes (no body anywhere)
// crashes or fails at t = 0 with a singular mass matrix. world -j1- a -b- j2 -world with
// a and b going out 1 m and back: j1 and j2 coaxial at the origin, a degree of freedom
// that moves no mass (K309 at j1). With b ending 1 m out, j2's frames must meet at (1, 0, 0):
// the loop holds j1 at q = 0, 0 degrees of freedom, and it runs; 3 m out it cannot close.
TEST(LockedJoint, LoopThroughAMasslessChain) {
  auto loop = [](const char* back, const char* world_end) {
    return Model(std::string("  World world;\n"
                             "  Revolute j1(axis = {0, 0, 1});\n"
                             "  FixedTranslation a(r = {1, 0, 0});\n"
                             "  FixedTranslation b(r = ") + back + ");\n"
                 "  FixedTranslation c(r = " + world_end + ");\n"
                 "  Revolute j2(axis = {0, 0, 1});\n"
                 "equation\n"
                 "  connect(world.frame_b, j1.frame_a);\n"
                 "  connect(j1.frame_b, a.frame_a);\n"
                 "  connect(a.frame_b, b.frame_a);\n"
                 "  connect(b.frame_b, j2.frame_a);\n"
                 "  connect(world.frame_b, c.frame_a);\n"
                 "  connect(j2.frame_b, c.frame_b);\n");
  };
  auto massless = LoadModel(loop("{-1, 0, 0}", "{0, 0, 0}"), {}, {}, true);
  ASSERT_TRUE(massless);
  const rt::CompileMessage* e = Find(massless->errors, "K309", "joint 'j1' moves no mass");
  ASSERT_TRUE(e) << Messages(massless->errors);
  EXPECT_EQ(e->loc.line, 3);

  auto held = LoadModel(loop("{0, 0, 0}", "{1, 0, 0}"), {}, {}, true);
  ASSERT_TRUE(held && held->prog) << Messages(held->errors);
  EXPECT_EQ(SummaryOf(*held).dof, 0);
  RunsEverywhere(*held->prog, {"j1.q"});

  auto apart = LoadModel(loop("{0, 0, 0}", "{3, 0, 0}"), {}, {}, true);
  ASSERT_TRUE(apart);
  EXPECT_TRUE(Find(apart->errors, "K310", "joint 'j2'")) << Messages(apart->errors);
}

// If this fails, a fixed element whose R is no rotation (a user's own fixed primitive;
// FixedRotation about a zero axis is E213 already, its R is NaN) shears every pose
// downstream instead of being K306 at the element.
TEST(LockedJoint, FixedElementWhoseRIsNoRotationIsK306) {
  auto l = LoadModel("model Shear\n"
                     "  parameter Real[3] r = {0, 0, 0};\n"
                     "  parameter Real[3, 3] R = {{1, 0.5, 0}, {0, 1, 0}, {0, 0, 1}};\n"
                     "  Frame frame_a, frame_b;\n"
                     "  annotation(__kanesim(primitive = \"fixed\"));\n"
                     "end Shear;\n" +
                         Model("  World world;\n"
                               "  Shear sh;\n"
                               "  Revolute j(axis = {0, 0, 1});\n"
                               "  Body b(m = 1, I = identity(3), r_CM = {1, 0, 0});\n"
                               "equation\n"
                               "  connect(world.frame_b, sh.frame_a);\n"
                               "  connect(sh.frame_b, j.frame_a);\n"
                               "  connect(j.frame_b, b.frame_a);\n"),
                     {}, {}, true);
  ASSERT_TRUE(l);
  const rt::CompileMessage* e = Find(l->errors, "K306", "fixed element 'sh': its rotation R is not a rotation");
  ASSERT_TRUE(e) << Messages(l->errors);
  EXPECT_EQ(e->loc.line, 9);
}

}  // namespace
}  // namespace kanesim::test
