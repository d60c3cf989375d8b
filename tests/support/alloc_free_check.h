// The "allocates nothing" check of the right-hand side: a mechanism compiled on one solver
// path, then rt::Derivative and rt::EvalSignals (every available signal) at 20 random states
// with the operator-new counter read around them. Include after tests/support/alloc_counter.h
// (g_allocations), in the one source file of a test binary that replaces operator new.
#pragma once

#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "compiler/compiler.h"
#include "runtime/program/program.h"
#include "tests/support/random_state.h"

namespace kanesim::test {

inline void ExpectNoAllocation(const flat::Mechanism& m, rt::SolverPath path, std::mt19937& rng) {
  rt::CompileOptions o;
  o.solver = path;
  auto r = rt::Compile(m, o);
  ASSERT_TRUE(r.errors.empty()) << r.errors[0].message;
  const rt::Program& p = *r.program;
  auto ws = rt::MakeWorkspace(p);
  auto plan = rt::PlanSignals(p, rt::AvailableSignals(p), nullptr);
  ASSERT_TRUE(plan);
  std::vector<Eigen::VectorXd> ys;
  for (int i = 0; i < 20; ++i) ys.push_back(RandomState(p, rng));
  Eigen::VectorXd ydot(rt::StateSize(p));
  std::vector<double> out(rt::AvailableSignals(p).size());
  const long before = g_allocations.load();
  for (int i = 0; i < 20; ++i) {
    ASSERT_EQ(rt::Derivative(p, *ws, 0.05 * i, ys[static_cast<size_t>(i)].data(), ydot.data()), 0)
        << rt::ErrorMessage(*ws);
    ASSERT_EQ(rt::EvalSignals(p, *plan, *ws, 0.05 * i, ys[static_cast<size_t>(i)].data(), out.data()), 0);
  }
  EXPECT_EQ(g_allocations.load() - before, 0) << "allocations in Derivative/EvalSignals";
}

}  // namespace kanesim::test
