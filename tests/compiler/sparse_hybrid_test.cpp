// Exact stick-slip friction and resting stops on the sparse solver path (issue 41; --solver
// sparse: the K-vector system solved by KLU, and with constraint rows the multiplier form):
// the same events (kinds and times) and the same rows as the default path, in all five
// integrators, and the path taken is the sparse one (never another path in silence).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "tests/compiler/compile_test_util.h"
#include "tests/support/model_texts.h"

namespace kanesim::test {
namespace {

// `text` compiled for the default path and for --solver sparse; both runs' events and rows
// agree to `tol` (times absolute; rows, accelerations among them, to 100 tol relative to 1 + |value|), and the sparse program takes
// the sparse path. At least `min_events` events.
void ExpectSparseLikeDefault(const std::string& text, double stop, const std::vector<std::string>& signals,
                             double rtol, double tol, size_t min_events) {
  auto dflt = LoadModel(text, {}, {}, true);
  rt::CompileOptions o;
  o.solver = rt::SolverPath::Sparse;
  auto sparse = LoadModel(text, {}, o, true);
  ASSERT_TRUE(dflt && dflt->prog && sparse && sparse->prog);
  EXPECT_NE(SummaryOf(*dflt).solver, rt::SolverPath::Sparse);
  ASSERT_EQ(SummaryOf(*sparse).solver, rt::SolverPath::Sparse) << SummaryOf(*sparse).solver_reason;
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult a, b;
    const sim::MemorySink ra = RunWith(*dflt->prog, how, stop, 0.1, signals, &a, rtol);
    const sim::MemorySink rb = RunWith(*sparse->prog, how, stop, 0.1, signals, &b, rtol);
    ASSERT_EQ(a.status, sim::SimResult::Status::kOk) << how.name << ": " << a.message;
    ASSERT_EQ(b.status, sim::SimResult::Status::kOk) << how.name << " sparse: " << b.message;
    ASSERT_GE(a.stats.events.size(), min_events) << how.name;
    ASSERT_EQ(a.stats.events.size(), b.stats.events.size()) << how.name;
    for (size_t k = 0; k < a.stats.events.size(); ++k) {
      const sim::EventRecord &ea = a.stats.events[k], &eb = b.stats.events[k];
      EXPECT_EQ(ea.element, eb.element) << how.name;
      EXPECT_EQ(ea.kind.substr(0, ea.kind.find_first_of(",(")), eb.kind.substr(0, eb.kind.find_first_of(",("))) << how.name;
      EXPECT_NEAR(ea.time, eb.time, tol) << how.name << " " << ea.kind;
    }
    ASSERT_EQ(ra.times.size(), rb.times.size()) << how.name;
    for (size_t i = 0; i < ra.rows.size(); ++i) {
      EXPECT_NEAR(ra.times[i], rb.times[i], tol) << how.name;
      for (size_t c = 0; c < ra.rows[i].size(); ++c)
        EXPECT_NEAR(ra.rows[i][c], rb.rows[i][c], 100 * tol * (1 + std::abs(ra.rows[i][c])))
            << how.name << " " << signals[c] << " t = " << ra.times[i];
    }
  }
}

// A block (m = 2) on a spring (k = 20) with exact Coulomb friction mu N (mu = 0.1, mu_s = 0.15),
// released at x = 1: it reverses at each half-cycle and sticks for good (the Coulomb oscillator
// of stick_slip_test.cpp). If this fails, the sparse path's normal force, friction law or stick
// decisions differ from the default path's.
TEST(SparseHybrid, CoulombOscillatorWithMuFrictionAsOnTheDefaultPath) {
  const std::string text =
      "model Coulomb\n  World world(g = {0, -9.81, 0});\n"
      "  Prismatic slide(axis = {1, 0, 0}, q(start = 1), mu = 0.1, mu_s = 0.15, friction_exact = true);\n"
      "  Body box(m = 2);\nequation\n  connect(world.frame_b, slide.frame_a);\n"
      "  connect(slide.frame_b, box.frame_a);\n  slide.tau = -20 * slide.q;\nend Coulomb;\n";
  ExpectSparseLikeDefault(text, 3.0, {"slide.q", "slide.u", "slide.a"}, 1e-10, 1e-9, 3);
}

// Two rods whose first rests on its stop q_min = -0.6 (restitution 0) after striking it while
// the second, with exact friction mu N at its pin, swings, sticks and slips: impacts, rests,
// leaves, stick and slip events. If this fails, the sparse path's stops or friction beside
// them differ from the default path's.
TEST(SparseHybrid, RestingStopBesideExactFrictionAsOnTheDefaultPath) {
  const std::string text = TwoRodText(", q(start = -0.3), q_min = -0.6",
                                      ", q(start = 0.3), u(start = 0.5), mu = 0.4, friction_radius = 0.3, friction_exact = true");
  ExpectSparseLikeDefault(text, 1.0, {"j1.q", "j1.u", "j1.a", "j2.q", "j2.u", "j2.a", "j1.reaction_torque[3]"}, 1e-10,
                          1e-9, 3);
}

}  // namespace
}  // namespace kanesim::test
