// Models with nothing to integrate (no free coordinate): the World alone, a body welded to
// it, a joint whose motion is prescribed. They run with every integrator and write their
// outputs at every output instant (sim/integrator.cpp Integrate), as OpenModelica
// does, instead of failing with a different error per integrator (issue 38).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "tests/compiler/compile_test_util.h"

namespace kanesim::test {
namespace {

// Compiles `text` (no errors allowed) and runs it with every integrator from 0 to 1 every
// 0.25; calls check(integrator, sink) on each run.
template <class Check>
void EveryIntegrator(const std::string& text, const std::vector<std::string>& signals, Check check) {
  auto l = LoadModel(text, {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  EXPECT_EQ(rt::StateSize(*l->prog), 0);
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    sim::MemorySink s = RunWith(*l->prog, how, 1.0, 0.25, signals, &r);
    EXPECT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
    EXPECT_EQ(s.times, (std::vector<double>{0.0, 0.25, 0.5, 0.75, 1.0})) << how.name;
    check(how.name, s);
  }
}

// If this fails, the World alone (fail_zero_dof_run.mech) stops with a numerical failure
// ("h = -nan") instead of writing its rows.
TEST(ZeroDof, WorldAloneWritesEveryRow) {
  EveryIntegrator("model M\n  World world;\nend M;\n", {"kinetic_energy", "potential_energy"},
                  [](const char* name, const sim::MemorySink& s) {
                    for (const auto& row : s.rows) EXPECT_EQ(row, (std::vector<double>{0.0, 0.0})) << name;
                  });
}

// If this fails, a body welded to the world does not run, or does not stay where the
// weld holds it: at r = (0.3, 0.4, 0), T = 0 (and V = 0: mass fixed to the world is no
// part of the mechanism's energy, compile.cpp MassProperties).
TEST(ZeroDof, BodyWeldedToTheWorldStaysPut) {
  const std::string text =
      "model M\n"
      "  World world(g = {0, -9.81, 0});\n"
      "  FixedTranslation ft(r = {0.3, 0.4, 0});\n"
      "  Weld w;\n"
      "  Body b(m = 2, I = identity(3));\n"
      "equation\n"
      "  connect(world.frame_b, ft.frame_a);\n"
      "  connect(ft.frame_b, w.frame_a);\n"
      "  connect(w.frame_b, b.frame_a);\n"
      "end M;\n";
  EveryIntegrator(text, {"kinetic_energy", "potential_energy", "b.r[1]", "b.r[2]"},
                  [](const char* name, const sim::MemorySink& s) {
                    for (const auto& row : s.rows) {
                      EXPECT_EQ(row[0], 0.0) << name;
                      EXPECT_EQ(row[1], 0.0) << name;
                      EXPECT_EQ(row[2], 0.3) << name;
                      EXPECT_EQ(row[3], 0.4) << name;
                    }
                  });
}

// If this fails, a mechanism whose only joint is prescribed (no state, but outputs that
// change with time) writes constant rows or fails: j.q must be 2 t at every instant, and
// the rod's kinetic energy (1/2) (m L^2 / 3) (2)^2.
TEST(ZeroDof, PrescribedMotionAloneFollowsTime) {
  const std::string text =
      "model M\n"
      "  World world(g = {0, -9.81, 0});\n"
      "  Revolute j(axis = {0, 0, 1});\n"
      "  Rod rod(L = 1, m = 3);\n"
      "equation\n"
      "  connect(world.frame_b, j.frame_a);\n"
      "  connect(j.frame_b, rod.frame_a);\n"
      "  j.q = 2 * time;\n"
      "end M;\n";
  EveryIntegrator(text, {"j.q", "kinetic_energy"}, [](const char* name, const sim::MemorySink& s) {
    for (size_t k = 0; k < s.rows.size(); ++k) {
      EXPECT_NEAR(s.rows[k][0], 2 * s.times[k], 1e-15) << name;
      EXPECT_NEAR(s.rows[k][1], 0.5 * (3.0 * 1.0 / 3.0) * 4.0, 1e-12) << name;
    }
  });
}

}  // namespace
}  // namespace kanesim::test
