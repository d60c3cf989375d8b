// The right-hand side allocates nothing: a global operator new counter (this binary
// replaces operator new, so it is built apart from the other runtime tests).
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>
#include <random>

#include "compiler/compiler.h"
#include "runtime/program/program.h"
#include "tests/support/alloc_counter.h"
#include "tests/support/alloc_free_check.h"
#include "tests/support/builders.h"
#include "tests/support/random_state.h"

namespace kanesim {
namespace {

using flat::Op;

// A scene that exercises every stage: mixed joints, a weld, a prescribed coordinate,
// time- and state-dependent joint force, a spring-damper and a wrench.
flat::Mechanism BusyScene(std::mt19937& rng) {
  auto m = test::RandomTree(rng, {9, true, true, true});
  // j1 is revolute: prescribe it.
  m.joints[0].prescribed[0] = m.exprs.Unary(Op::Sin, m.exprs.Binary(Op::Mul, m.exprs.Constant(2.0), m.exprs.Time()));
  test::AddBusyForces(m);
  return m;
}

TEST(AllocFree, DenseDerivativeAllocatesNothing) {
  // If this fails, the dense right-hand side (or signal evaluation) allocates memory.
  std::mt19937 rng(1);
  test::ExpectNoAllocation(BusyScene(rng), rt::SolverPath::Dense, rng);
  test::ExpectNoAllocation(test::Chain(30), rt::SolverPath::Dense, rng);
}

TEST(AllocFree, SparseDerivativeAllocatesNothing) {
  // If this fails, the sparse right-hand side allocates (e.g. KLU factors afresh
  // instead of refactoring, or a temporary escapes to the heap).
  std::mt19937 rng(2);
  test::ExpectNoAllocation(BusyScene(rng), rt::SolverPath::Sparse, rng);
  test::ExpectNoAllocation(test::Chain(80), rt::SolverPath::Sparse, rng);
}

TEST(AllocFree, PlanningARunsSignalsNamesOnlyThem) {
  // If this fails, a run's start names every signal of the model (hundreds per body: frames,
  // reactions, rotations) to plan the few it writes: the default signals, their plan and the
  // energy guard's plan must cost allocations in proportion to the names asked for.
  std::mt19937 rng(3);
  auto r = rt::Compile(test::RandomTree(rng, {40, true, true, true}), {});
  ASSERT_TRUE(r.errors.empty()) << r.errors[0].message;
  const rt::Program& p = *r.program;
  const long before = g_allocations.load();
  const auto names = rt::DefaultSignals(p);
  auto plan = rt::PlanSignals(p, names, nullptr);
  auto energy = rt::PlanSignals(p, {"kinetic_energy", "potential_energy"}, nullptr);
  const long used = g_allocations.load() - before;
  ASSERT_TRUE(plan && energy);
  EXPECT_LE(used, static_cast<long>(2 * names.size()) + 24)
      << names.size() << " names asked for, " << rt::AvailableSignals(p).size() << " signals in all";
}

TEST(AllocFree, CounterSeesAllocations) {
  // If this fails, the counter is not wired and the two tests above prove nothing.
  const long before = g_allocations.load();
  auto* v = new std::vector<int>(100);
  delete v;
  EXPECT_GT(g_allocations.load() - before, 0);
}

TEST(AllocFree, TapeBuilderGivenNoRootAllocatesNothing) {
  // If this fails, a tape builder clears per-node tables of the whole expression pool
  // though it is given no root: compile pays for a model's empty output and when tapes.
  flat::ExprPool pool;
  flat::ExprId last_sum = flat::kNoExpr;
  for (int i = 0; i < 1000; ++i) last_sum = pool.Binary(Op::Add, pool.Constant(i), pool.Time());
  const std::vector<double> params;
  const long before = g_allocations.load();
  {
    rt::TapeBuilder builder(pool, params);
    const rt::Tape tape = builder.Finish();
    EXPECT_TRUE(tape.code.empty());
  }
  EXPECT_EQ(g_allocations.load() - before, 0);
  // Given a root, it still folds and records that root's sub-DAG.
  const flat::ExprId product = pool.Binary(Op::Mul, pool.Constant(3), pool.Constant(4));
  rt::TapeBuilder builder(pool, params);
  double v = 0;
  EXPECT_TRUE(builder.Fold(product, &v));
  EXPECT_EQ(v, 12.0);
  builder.AddRoot(last_sum, "last sum", "999 + time");
  const rt::Tape tape = builder.Finish();
  std::vector<double> regs = tape.init;
  regs[static_cast<size_t>(tape.time_reg)] = 0.5;
  tape.Eval(regs.data());
  EXPECT_EQ(regs[static_cast<size_t>(tape.roots[0])], 999.5);
}

TEST(AllocFree, TapeBuilderSharingFoldsReusesThemAndBuildsTheSameTape) {
  // If this fails, the compiler's tapes (forces, outputs, whens, prescribed motions) each
  // clear and fill per-node fold tables of the whole pool again, or a tape built with
  // shared folds differs from one built alone.
  flat::ExprPool pool;
  const std::vector<double> params = {2.5};
  const flat::ExprId k = pool.Binary(Op::Mul, pool.Parameter(0), pool.Constant(4));  // folds to 10
  const flat::ExprId force = pool.Binary(Op::Add, pool.Binary(Op::Mul, k, pool.Time()), pool.Constant(1));
  rt::TapeBuilder first(pool, params);
  double v = 0;
  ASSERT_TRUE(first.Fold(k, &v));
  EXPECT_EQ(v, 10.0);
  EXPECT_FALSE(first.Fold(force, &v));  // reads time; every node of the pool is now folded
  rt::TapeBuilder shared = rt::TapeBuilder::SharingFolds(first);
  const long before = g_allocations.load();
  EXPECT_FALSE(shared.Fold(force, &v));
  ASSERT_TRUE(shared.Fold(k, &v));
  EXPECT_EQ(v, 10.0);
  EXPECT_EQ(g_allocations.load() - before, 0);
  shared.AddRoot(force, "force", "k*time + 1");
  rt::TapeBuilder alone(pool, params);
  alone.AddRoot(force, "force", "k*time + 1");
  const rt::Tape a = shared.Finish(), b = alone.Finish();
  ASSERT_EQ(a.code.size(), b.code.size());
  for (size_t i = 0; i < a.code.size(); ++i) {
    EXPECT_EQ(a.code[i].op, b.code[i].op);
    EXPECT_EQ(a.code[i].dst, b.code[i].dst);
    EXPECT_EQ(a.code[i].a, b.code[i].a);
    EXPECT_EQ(a.code[i].b, b.code[i].b);
  }
  EXPECT_EQ(a.init, b.init);
  EXPECT_EQ(a.time_reg, b.time_reg);
  std::vector<double> regs = a.init;
  regs[static_cast<size_t>(a.time_reg)] = 0.5;
  a.Eval(regs.data());
  EXPECT_EQ(regs[static_cast<size_t>(a.roots[0])], 6.0);  // 10 * 0.5 + 1
}

}  // namespace
}  // namespace kanesim
