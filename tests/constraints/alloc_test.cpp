// The closed-loop right-hand side allocates nothing (projection by Newton, partition,
// reduced Kane's equations): a global operator-new counter around rt::Derivative and
// rt::EvalSignals (with loop residuals and the drive torque) on the examples.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "runtime/program/program.h"
#include "tests/support/alloc_counter.h"
#include "tests/support/load_util.h"
#include "tests/support/builders.h"
#include "compiler/compiler.h"

namespace kanesim::test {
namespace {

void Check(const std::string& example, const std::vector<std::string>& signals,
           rt::SolverPath solver = rt::SolverPath::Auto) {
  auto l = LoadModel(kRoot + "/examples/" + example);
  ASSERT_TRUE(l && l->prog);
  rt::CompileOptions o;
  o.solver = solver;
  auto cr = rt::Compile(l->mech, o);
  ASSERT_TRUE(cr.program);
  const rt::Program& p = *cr.program;
  auto ws = rt::MakeWorkspace(p);
  std::vector<double> y(static_cast<size_t>(rt::StateSize(p))), yd(y.size()), out(signals.size());
  rt::InitialState(p, y.data());
  std::string err;
  auto plan = rt::PlanSignals(p, signals, &err);
  ASSERT_TRUE(plan) << err;
  ASSERT_EQ(rt::Derivative(p, *ws, 0.0, y.data(), yd.data()), 0);  // first call may size nothing lazily
  for (size_t i = 0; i < y.size(); ++i) y[i] += 1e-4;                // off the manifold: Newton iterates
  const long before = g_allocations.load();
  for (int k = 0; k < 5; ++k) {
    ASSERT_EQ(rt::Derivative(p, *ws, 0.01 * k, y.data(), yd.data()), 0) << rt::ErrorMessage(*ws);
    ASSERT_EQ(rt::EvalSignals(p, *plan, *ws, 0.01 * k, y.data(), out.data()), 0) << rt::ErrorMessage(*ws);
  }
  EXPECT_EQ(g_allocations.load() - before, 0) << example << ": operator new called in the right-hand side";
}

TEST(ConstraintsAlloc, FourBarRightHandSideAllocatesNothing) {
  // If this fails, the projection or the reduced solve allocates on every evaluation.
  Check("fourbar.mech", {"crank_coupler.q", "coupler_rocker.constraint_residual", "coupler_rocker.constraint_drift",
                         "coupler_rocker.constraint_residual_velocity"});
}

TEST(ConstraintsAlloc, ReactionsAndConstraintPowerAllocateNothing) {
  // If this fails, the constraint forces computed on request allocate per output row.
  Check("fourbar.mech", {"crank_pivot.reaction_force[1]", "coupler_rocker.reaction_torque[3]", "constraint_power"});
}

TEST(ConstraintsAlloc, SliderCrankDriveAllocatesNothing) {
  // If this fails, the zero-DOF path or the loop drive torque allocates.
  Check("slider_crank.mech", {"slide.q", "crank_pivot.drive"});
}

TEST(ConstraintsAlloc, RollingContactsAllocateNothing) {
  // If this fails, the contact rows (geometry, Jacobian, bias) or their outputs allocate.
  Check("sphere_incline.mech", {"contact.normal_force", "contact.point[1]", "contact.constraint_residual_velocity"});
  Check("rolling_disk.mech", {"lean", "contact.lateral_force", "constraint_power"});
  Check("sleigh.mech", {"blade.lateral_force", "plane.reaction_force[1]"});
}

TEST(ConstraintsAlloc, MultiplierFormAllocatesNothing) {
  // If this fails, the sparse multiplier path (KLU refactorization, kinetic-metric
  // projection, multipliers as reactions) allocates per evaluation.
  Check("fourbar.mech", {"crank_coupler.q", "coupler_rocker.constraint_residual", "crank_pivot.reaction_force[1]",
                         "constraint_power"},
        rt::SolverPath::Sparse);
  Check("slider_crank.mech", {"slide.q", "crank_pivot.drive"}, rt::SolverPath::Sparse);
  Check("rolling_disk.mech", {"lean", "contact.lateral_force"}, rt::SolverPath::Sparse);
}

TEST(ConstraintsAlloc, BandedPartitionChoiceAllocatesNothing) {
  // If this fails, choosing the partition of a chain of loops (pivoted QR of A, the banded
  // order of the dependent speeds and its symbolic cost, the profile QR) allocates.
  rt::CompileOptions o;
  o.solver = rt::SolverPath::Dense;
  auto l = LoadModel(kRoot + "/tests/stress/models/parallelogram_chain.mech", {{"N", "10"}}, o);
  ASSERT_TRUE(l && l->prog);
  const rt::Program& p = *l->prog;
  ASSERT_GE(p.loop_rank, 16);  // at or above kBandedMinRank (constraints.cpp)
  auto ws = rt::MakeWorkspace(p);
  std::vector<double> y(static_cast<size_t>(rt::StateSize(p))), yd(y.size());
  rt::InitialState(p, y.data());
  ASSERT_EQ(rt::Derivative(p, *ws, 0.0, y.data(), yd.data()), 0) << rt::ErrorMessage(*ws);
  for (size_t i = 0; i < y.size(); ++i) y[i] += 1e-4;
  const long before = g_allocations.load();
  for (int k = 0; k < 5; ++k) {
    ws->partition_valid = false;  // re-choose at every evaluation
    ASSERT_EQ(rt::Derivative(p, *ws, 0.01 * k, y.data(), yd.data()), 0) << rt::ErrorMessage(*ws);
  }
  EXPECT_EQ(g_allocations.load() - before, 0) << "operator new called in the chain's right-hand side";
}

TEST(ConstraintsAlloc, JointFrictionIterationAllocatesNothing) {
  // If this fails, the friction fixed point (reactions inside the right-hand side) allocates.
  MechBuilder b;
  const int world = b.World(Vec3(0, -9.81, 0));
  const int cart = b.Frame("cart.frame"), arm = b.Frame("arm.frame");
  b.Body("cart", cart, 1.0, Vec3::Zero(), Diag(0.01, 0.01, 0.01));
  b.Body("bob", arm, 0.7, Vec3(0, -0.5, 0), Mat3::Zero());
  auto& slide = b.Joint("slide", JointType::Prismatic, world, cart, Vec3::UnitX());
  slide.friction_mu = b.C(0.4);
  slide.friction_v = b.C(1e-3);
  slide.u_start[0] = b.C(0.5);
  b.Joint("hinge", JointType::Revolute, cart, arm, Vec3::UnitZ());
  auto cr = rt::Compile(b.m, {});
  ASSERT_TRUE(cr.program);
  const rt::Program& p = *cr.program;
  auto ws = rt::MakeWorkspace(p);
  std::vector<double> y = {0.0, 0.9, 0.8, -1.5}, yd(4);
  ASSERT_EQ(rt::Derivative(p, *ws, 0.0, y.data(), yd.data()), 0);
  const long before = g_allocations.load();
  for (int k = 0; k < 5; ++k) ASSERT_EQ(rt::Derivative(p, *ws, 0.0, y.data(), yd.data()), 0);
  EXPECT_EQ(g_allocations.load() - before, 0);
}

}  // namespace
}  // namespace kanesim::test
