// Closed loops (runtime/constraints/constraints.*, compiler/loops.cpp) against closed forms:
//
// Four-bar (examples/fourbar.mech): crank a from O2 = 0 at angle theta, coupler b,
// rocker c from O4 = (d, 0). With A = a (cos theta, sin theta), the rocker tip B lies on
// the circles |B - A| = b and |B - O4| = c; on the open (upper) branch
//   phi3 = atan2(O4 - A) + acos((b^2 + L^2 - c^2) / (2 b L)),  L = |O4 - A|          (1)
//   B = A + b (cos phi3, sin phi3),  phi4 = atan2(B_y, B_x - d)                     (2)
// (law of cosines); the tree's coordinates are theta, phi3 - theta and phi4.
//
// Slider-crank (examples/slider_crank.mech), theta = omega t prescribed:
//   x = a cos theta + sqrt(b^2 - a^2 sin^2 theta)                                   (3)
// and, with no friction, the drive torque's power is the rate of the total energy:
// tau omega = dE/dt = dE/dtheta omega, so tau = dE/dtheta, E(theta) from the
// closed-form positions and velocities of the three bodies (independent of Kane's
// equations; dE/dtheta by a central difference).                                   (4)
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "runtime/constraints/constraints.h"
#include "runtime/runtime.h"
#include "runtime/kinematics/kinematics.h"
#include "runtime/program/program.h"
#include "tests/support/load_util.h"

namespace kanesim::test {
namespace {

double Wrap(double x) { return std::remainder(x, 2.0 * M_PI); }

// The state indices of the four-bar's coordinates (crank, coupler, rocker).
struct FourBarIndices {
  size_t crank, coupler, rocker;
};
FourBarIndices FourBarCoordinates(const rt::Program& p) {
  FourBarIndices ix{0, 0, 0};
  for (const rt::TreeJoint& j : p.joints) {
    const auto q0 = static_cast<size_t>(j.q0);
    if (j.name == "crank_pivot") ix.crank = q0;
    if (j.name == "crank_coupler") ix.coupler = q0;
    if (j.name == "rocker_pivot") ix.rocker = q0;
  }
  EXPECT_NE(ix.coupler, ix.rocker);
  return ix;
}

struct FourBarAngles {
  double phi3, phi4;
};
FourBarAngles FourBarClosedForm(double a, double b, double c, double d, double theta) {
  const double Ax = a * std::cos(theta), Ay = a * std::sin(theta);
  const double dx = d - Ax, dy = -Ay, L = std::hypot(dx, dy);
  const double phi3 = std::atan2(dy, dx) + std::acos((b * b + L * L - c * c) / (2 * b * L));  // (1)
  const double Bx = Ax + b * std::cos(phi3), By = Ay + b * std::sin(phi3);
  return {phi3, std::atan2(By, Bx - d)};  // (2)
}

TEST(FourBar, CompilesWithOneDofAndNamesTheRedundantConstraints) {
  // If this fails, the DOF is counted instead of computed from the Jacobian's rank, or
  // the planar loop's three redundant rows are not detected and attributed.
  auto l = LoadModel(kRoot + "/examples/fourbar.mech");
  ASSERT_TRUE(l && l->prog);
  const rt::ProgramSummary s = rt::Summarize(*l->prog);
  EXPECT_EQ(s.dof, 1);
  EXPECT_EQ(s.nu, 3);
  ASSERT_EQ(s.cut_joints.size(), 1u);
  EXPECT_EQ(s.cut_joints[0], "coupler_rocker");
  bool named = false;
  for (const auto& n : s.notes)
    named = named || (n.find("redundant") != std::string::npos && n.find("fourbar.mech:") != std::string::npos &&
                      n.find("translation along z") != std::string::npos);
  EXPECT_TRUE(named);
}

TEST(FourBar, AssemblyHoldsTheFixedCrankAndClosesTheLoop) {
  // If this fails, assembly moved a coordinate marked fixed, or left the start state
  // off the constraint manifold.
  auto l = LoadModel(kRoot + "/examples/fourbar.mech");
  ASSERT_TRUE(l && l->prog);
  const rt::Program& p = *l->prog;
  std::vector<double> y(static_cast<size_t>(rt::StateSize(p)));
  rt::InitialState(p, y.data());
  auto q = [&](const char* joint) {
    for (const rt::TreeJoint& j : p.joints)
      if (j.name == joint) return y[static_cast<size_t>(j.q0)];
    ADD_FAILURE() << joint;
    return 0.0;
  };
  auto u = [&](const char* joint) {
    for (const rt::TreeJoint& j : p.joints)
      if (j.name == joint) return y[static_cast<size_t>(p.nq + j.u0)];
    return 0.0;
  };
  EXPECT_EQ(q("crank_pivot"), 0.3);  // theta0, held exactly
  const FourBarAngles cf = FourBarClosedForm(0.2, 0.6, 0.5, 0.6, 0.3);
  EXPECT_NEAR(Wrap(q("crank_pivot") + q("crank_coupler") - cf.phi3), 0.0, 1e-12);
  EXPECT_NEAR(Wrap(q("rocker_pivot") - cf.phi4), 0.0, 1e-12);
  EXPECT_EQ(u("crank_pivot"), 6.0);  // the crank's speed is held with its angle
}

TEST(FourBar, LoopThatCannotCloseIsAClearError) {
  // If this fails, an impossible loop (ground link longer than the other three) is
  // accepted or the error does not point at the cut joint.
  auto l = LoadModel(kRoot + "/examples/fourbar.mech", {{"d", "2.0"}});
  ASSERT_TRUE(l);
  EXPECT_FALSE(l->prog);
  ASSERT_FALSE(l->errors.empty());
  EXPECT_STREQ(flat::DiagCodeString(l->errors[0].code), "K310");
  EXPECT_NE(l->errors[0].message.find("coupler_rocker"), std::string::npos);
  EXPECT_EQ(l->errors[0].loc.line, 25);
}

TEST(FourBar, CoordinatesFollowClosedFormLoopKinematicsAndEnergyIsConserved) {
  // If this fails, the projection or the reduced equations (Lesser eq. 51) are wrong:
  // the coordinates leave the loop, or the motion on it gains or loses energy.
  auto l = LoadModel(kRoot + "/examples/fourbar.mech");
  ASSERT_TRUE(l && l->prog);
  auto s = RunModel(*l->prog, 10.0, 0.01, 1e-10,
               {"crank_pivot.q", "crank_coupler.q", "rocker_pivot.q", "kinetic_energy", "potential_energy"});
  double kin = 0.0, de = 0.0;
  const double E0 = s.rows[0][3] + s.rows[0][4];
  for (const auto& r : s.rows) {
    const FourBarAngles cf = FourBarClosedForm(0.2, 0.6, 0.5, 0.6, r[0]);
    kin = std::max({kin, std::fabs(Wrap(r[0] + r[1] - cf.phi3)), std::fabs(Wrap(r[2] - cf.phi4))});
    de = std::max(de, std::fabs(r[3] + r[4] - E0));
  }
  // Tolerances: the outputs are Newton-projected to round-off (measured 2e-15); the
  // energy drift at rtol 1e-10 measured 5e-8 J of E0 = 5.4 J.
  EXPECT_LT(kin, 1e-12);
  EXPECT_LT(de, 5e-7 * std::fabs(E0));
}

TEST(FourBar, ResidualsStayAtToleranceOverALongRun) {
  // If this fails, the loop drifts: the integrator's state leaves the constraint
  // manifold by more than its tolerance, or the outputs are not projected.
  auto l = LoadModel(kRoot + "/examples/fourbar.mech");
  ASSERT_TRUE(l && l->prog);
  for (auto integ : {rt::Integrator::CvodeAdams, rt::Integrator::IDA}) {
    auto s = RunModel(*l->prog, 100.0, 0.1, 1e-8,
                 {"coupler_rocker.constraint_residual", "coupler_rocker.constraint_residual_velocity",
                  "coupler_rocker.constraint_drift"},
                 integ);
    double pos = 0, vel = 0, drift = 0;
    for (const auto& r : s.rows) {
      pos = std::max(pos, r[0]);
      vel = std::max(vel, r[1]);
      drift = std::max(drift, r[2]);
    }
    EXPECT_LT(pos, 1e-13);  // projected outputs: round-off
    EXPECT_LT(vel, 1e-12);
    // The integrator's own state: its drift from the manifold stays at the tolerance
    // level (measured 3e-8 over 10 s with CVODE), it does not grow without bound.
    EXPECT_LT(drift, 1e-6);
  }
}

TEST(FourBar, StepProjectionKeepsTheLoopClosedOverALongRun) {
  // If this fails, the accepted steps are not projected (the loop then drifts off by the
  // integration error, step after step), or the cheaper right-hand side is wrong (the
  // motion gains or loses energy, or leaves the closed-form loop kinematics).
  auto l = LoadModel(kRoot + "/examples/fourbar.mech");
  ASSERT_TRUE(l && l->prog);
  for (double tol : {1e-6, 1e-9}) {
    // DOP853 with --projection step: the right-hand side takes the positions as they are,
    // the stepper projects each accepted step (runtime/runtime.h SetStepProjection).
    auto s = RunModel(*l->prog, 100.0, 0.1, tol,
                      {"crank_pivot.q", "crank_coupler.q", "rocker_pivot.q", "coupler_rocker.constraint_drift",
                       "kinetic_energy", "potential_energy"},
                      rt::Integrator::Dop853, /*project_steps=*/true);
    const double E0 = s.rows[0][4] + s.rows[0][5];
    double kin = 0.0, drift = 0.0, de = 0.0;
    for (const auto& r : s.rows) {
      const FourBarAngles cf = FourBarClosedForm(0.2, 0.6, 0.5, 0.6, r[0]);
      kin = std::max({kin, std::fabs(Wrap(r[0] + r[1] - cf.phi3)), std::fabs(Wrap(r[2] - cf.phi4))});
      drift = std::max(drift, r[3]);
      de = std::max(de, std::fabs(r[4] + r[5] - E0));
    }
    std::printf("rtol %g: closed-form kinematics %.2g, drift %.2g, energy %.2g J of %.3g J over 100 s\n", tol, kin,
                drift, de, E0);
    EXPECT_LT(kin, 1e-12);  // the outputs are projected: round-off
    // The integrator's own state between projections (output rows are interpolated inside
    // a step) stays below the tolerance: measured 2.3e-7 (1e-6) and 1.1e-10 (1e-9) over
    // 100 s. The last row is the end of an accepted step, hence projected: round-off.
    // (With the projection switched off, the last row's drift was 5.9e-7 and 2e-10.)
    EXPECT_LT(drift, tol);
    EXPECT_LT(s.rows.back()[3], 1e-13);
    // Energy: measured 4.7e-4 J (1e-6) and 9.6e-8 J (1e-9) over 100 s, 87 and 18 times
    // tol of E0: larger than with a projection at every evaluation (docs/constraints.md).
    EXPECT_LT(de, 300 * tol * std::fabs(E0));
  }
}

TEST(FourBar, StepProjectedDerivativeEqualsTheProjectedOneOnTheLoop) {
  // If this fails, the right-hand side for step-projecting solvers differs from the
  // default one on the constraint manifold (where both must be the same function), or
  // ProjectOntoConstraints does not bring a state back onto the loop.
  auto l = LoadModel(kRoot + "/examples/fourbar.mech");
  ASSERT_TRUE(l && l->prog);
  const rt::Program& p = *l->prog;
  ASSERT_TRUE(rt::StepProjectionAvailable(p));
  auto ws = rt::MakeWorkspace(p), ws_step = rt::MakeWorkspace(p);
  rt::SetStepProjection(*ws_step, true);
  const size_t n = static_cast<size_t>(rt::StateSize(p));
  std::vector<double> y(n), y0(n), yd(n), yd_step(n);
  rt::InitialState(p, y0.data());
  const auto [crank, coupler, rocker] = FourBarCoordinates(p);
  for (int k = 0; k < 36; ++k) {
    // Around a crank turn, the dependent coordinates 1e-4 off the closed form, every
    // speed 1e-4 off the start's; then projected.
    y = y0;
    const double th = 0.3 + 2 * M_PI * k / 36.0;
    const FourBarAngles cf = FourBarClosedForm(0.2, 0.6, 0.5, 0.6, th);
    y[crank] = th;
    y[coupler] = cf.phi3 - th + 1e-4;
    y[rocker] = cf.phi4 - 1e-4;
    for (size_t i = static_cast<size_t>(p.nq); i < n; ++i) y[i] += 1e-4;
    const std::vector<double> y_before = y;
    ASSERT_EQ(rt::ProjectOntoConstraints(p, *ws_step, 0.0, y.data()), 0) << rt::ErrorMessage(*ws_step);
    // The projection moves only the dependent coordinates and speeds (revolute joints:
    // coordinate i belongs to speed i); the independent one stays.
    ASSERT_EQ(ws_step->ind.size(), 1u);
    const size_t s = static_cast<size_t>(ws_step->ind[0]);
    EXPECT_EQ(y[s], y_before[s]);
    EXPECT_EQ(y[static_cast<size_t>(p.nq) + s], y_before[static_cast<size_t>(p.nq) + s]);
    // ... and lands on the closed-form loop kinematics of the (projected) crank angle.
    const FourBarAngles on = FourBarClosedForm(0.2, 0.6, 0.5, 0.6, y[crank]);
    EXPECT_LT(std::fabs(Wrap(y[crank] + y[coupler] - on.phi3)), 1e-12) << "k = " << k;
    EXPECT_LT(std::fabs(Wrap(y[rocker] - on.phi4)), 1e-12) << "k = " << k;
    ASSERT_EQ(rt::Derivative(p, *ws, 0.0, y.data(), yd.data()), 0);
    ASSERT_EQ(rt::Derivative(p, *ws_step, 0.0, y.data(), yd_step.data()), 0);
    EXPECT_LT(ws_step->phi.cwiseAbs().maxCoeff(), 1e-13 * p.loop_length) << "k = " << k;
    for (size_t i = 0; i < n; ++i)
      EXPECT_NEAR(yd_step[i], yd[i], 1e-11 * (1.0 + std::fabs(yd[i]))) << "component " << i << ", k = " << k;
  }
}

TEST(FourBar, StepProjectedDerivativeTakesTheSpeedsAsTheyAre) {
  // If this fails, the right-hand side for step-projecting solvers is not the ODE of the
  // reduced equations off the manifold (Hairer, Lubich & Wanner, sec. IV.4): along it the
  // velocity residual psi = A u + b of speeds that are off the loop must stay constant,
  // d psi / dt = A udot + (dA/dt) u = 0, instead of being replaced by the projected speeds'.
  auto l = LoadModel(kRoot + "/examples/fourbar.mech");
  ASSERT_TRUE(l && l->prog);
  const rt::Program& p = *l->prog;
  auto ws = rt::MakeWorkspace(p), ws_step = rt::MakeWorkspace(p), ws_psi = rt::MakeWorkspace(p);
  rt::SetStepProjection(*ws_step, true);
  const size_t n = static_cast<size_t>(rt::StateSize(p));
  std::vector<double> y(n), yd(n), yd_step(n), yp(n), ym(n);
  rt::InitialState(p, y.data());
  const auto [crank, coupler, rocker] = FourBarCoordinates(p);
  // psi at y, from the kinematics alone (no projection, no dynamics).
  auto psi = [&](const std::vector<double>& x) {
    rt::UnpackState(p, *ws_psi, 0.0, x.data());
    rt::PositionKinematics(p, *ws_psi);
    rt::VelocityKinematics(p, *ws_psi);
    rt::ConstraintJacobian(p, *ws_psi);
    return Eigen::VectorXd(ws_psi->psi);
  };
  const double eps = 1e-6;
  auto rate = [&](const std::vector<double>& f) {  // d psi / dt along f: central difference
    for (size_t i = 0; i < n; ++i) {
      yp[i] = y[i] + eps * f[i];
      ym[i] = y[i] - eps * f[i];
    }
    return Eigen::VectorXd((psi(yp) - psi(ym)) / (2 * eps));
  };
  double worst_step = 0.0, least_eval = INFINITY;
  for (int k = 0; k < 12; ++k) {
    const double th = 0.3 + 2 * M_PI * k / 12.0;
    const FourBarAngles cf = FourBarClosedForm(0.2, 0.6, 0.5, 0.6, th);
    y[crank] = th;  // on the loop
    y[coupler] = cf.phi3 - th;
    y[rocker] = cf.phi4;
    y[static_cast<size_t>(p.nq) + crank] = 6.0;  // speeds that do not satisfy A u = 0 (below)
    y[static_cast<size_t>(p.nq) + coupler] = -8.0;
    y[static_cast<size_t>(p.nq) + rocker] = 1.0;
    const Eigen::VectorXd psi0 = psi(y);
    ASSERT_GT(psi0.cwiseAbs().maxCoeff(), 1e-3) << "k = " << k;  // off the velocity constraint
    ASSERT_EQ(rt::Derivative(p, *ws_step, 0.0, y.data(), yd_step.data()), 0) << rt::ErrorMessage(*ws_step);
    ASSERT_EQ(rt::Derivative(p, *ws, 0.0, y.data(), yd.data()), 0) << rt::ErrorMessage(*ws);
    // The speeds enter as they are: qdot = u.
    for (size_t i = 0; i < static_cast<size_t>(p.nq); ++i) EXPECT_EQ(yd_step[i], y[static_cast<size_t>(p.nq) + i]);
    worst_step = std::max(worst_step, rate(yd_step).cwiseAbs().maxCoeff());
    // The default right-hand side projects the speeds and pulls the state toward them:
    // along it psi decays (the pull), so this check can tell the two apart.
    least_eval = std::min(least_eval, rate(yd).cwiseAbs().maxCoeff());
  }
  std::printf("d psi/dt along f: step %.2g, eval at least %.2g\n", worst_step, least_eval);
  EXPECT_LT(worst_step, 1e-6);  // the difference quotient's own error: ~1e-9
  EXPECT_GT(least_eval, 1e-3);
}

TEST(FourBar, ProjectionHoldsAroundAFullCrankTurn) {
  // If this fails, the dependent/independent split is lost at some crank angle (a
  // degraded block not re-chosen) or Newton fails to bring a nearby state back.
  auto l = LoadModel(kRoot + "/examples/fourbar.mech");
  ASSERT_TRUE(l && l->prog);
  const rt::Program& p = *l->prog;
  auto ws = rt::MakeWorkspace(p);
  std::vector<double> y(static_cast<size_t>(rt::StateSize(p))), yd(y.size());
  rt::InitialState(p, y.data());
  const auto [crank, coupler, rocker] = FourBarCoordinates(p);
  // States on the closed form all the way round, each coordinate off by 1e-6 rad: the
  // integrator's state is never further off than that.
  for (int k = 0; k < 720; ++k) {
    const double th = 0.3 + 2 * M_PI * k / 720.0;
    const FourBarAngles cf = FourBarClosedForm(0.2, 0.6, 0.5, 0.6, th);
    y[crank] = th + 1e-6;
    y[coupler] = cf.phi3 - th - 1e-6;
    y[rocker] = cf.phi4 + 1e-6;
    ASSERT_EQ(rt::Derivative(p, *ws, 0.0, y.data(), yd.data()), 0) << rt::ErrorMessage(*ws) << " at k = " << k;
    EXPECT_LT(ws->phi.cwiseAbs().maxCoeff(), 1e-13 * p.loop_length);
  }
  std::printf("partition chosen %ld time(s) around a full turn\n", ws->partition_changes);
  EXPECT_GE(ws->partition_changes, 1);
}

TEST(FourBar, DegradedPartitionIsRechosenByPivoting) {
  // If this fails, a dependent block that has become ill-conditioned is kept (the
  // reduced equations then lose digits or fail near a toggle position).
  auto l = LoadModel(kRoot + "/examples/fourbar.mech");
  ASSERT_TRUE(l && l->prog);
  const rt::Program& p = *l->prog;
  auto ws = rt::MakeWorkspace(p);
  std::vector<double> y(static_cast<size_t>(rt::StateSize(p))), yd(y.size());
  rt::InitialState(p, y.data());
  ASSERT_EQ(rt::Derivative(p, *ws, 0.0, y.data(), yd.data()), 0);
  ASSERT_EQ(ws->partition_changes, 1);
  const int d0 = ws->dep[0], d1 = ws->dep[1], i0 = ws->ind[0];
  // A Jacobian whose current dependent columns are nearly parallel (conditioning 1e-4,
  // below the re-choice threshold 1e-2) while the independent column is not.
  ws->A.setZero();
  ws->A(0, d0) = 1.0;
  ws->A(0, d1) = 1.0;
  ws->A(1, d1) = 1e-4;
  ws->A(1, i0) = 1.0;
  ASSERT_EQ(rt::FactorDependent(p, *ws), 0);
  EXPECT_EQ(ws->partition_changes, 2);
  const bool i0_now_dependent = ws->dep[0] == i0 || ws->dep[1] == i0;
  EXPECT_TRUE(i0_now_dependent);
}

double SliderCrankEnergy(double theta, double* x_out) {
  const double a = 0.1, b = 0.35, w = 20, m1 = 0.4, m2 = 0.6, m3 = 1.5, g = 9.81;
  const double s = std::sin(theta), c = std::cos(theta), R = std::sqrt(b * b - a * a * s * s);
  const double x = a * c + R, xd = -a * s * w - a * a * s * c * w / R;
  const double ph = std::asin(-a * s / b), phd = -a * c * w / (b * std::cos(ph));
  const double T1 = 0.5 * m1 * a * a / 3 * w * w, V1 = m1 * g * a / 2 * s;
  const double vgx = (-a * s * w + xd) / 2, vgy = a * c * w / 2;
  const double T2 = 0.5 * m2 * (vgx * vgx + vgy * vgy) + 0.5 * m2 * b * b / 12 * phd * phd, V2 = m2 * g * a * s / 2;
  const double T3 = 0.5 * m3 * xd * xd;
  if (x_out) *x_out = x;
  return T1 + T2 + T3 + V1 + V2;
}

TEST(SliderCrank, SliderPositionAndDriveTorqueMatchIndependentDerivations) {
  // If this fails, a zero-DOF loop with a prescribed coordinate is not solved by
  // kinematics, or the drive torque misses the loop's dependent speeds.
  auto l = LoadModel(kRoot + "/examples/slider_crank.mech");
  ASSERT_TRUE(l && l->prog);
  EXPECT_EQ(rt::Summarize(*l->prog).dof, 0);
  auto s = RunModel(*l->prog, 1.0, 0.002, 1e-8, {"crank_pivot.q", "slide.q", "crank_pivot.drive"});
  double ex = 0, et = 0, tmax = 0;
  for (const auto& r : s.rows) {
    double x = 0;
    SliderCrankEnergy(r[0], &x);  // (3)
    const double h = 1e-5;
    const double tau = (SliderCrankEnergy(r[0] + h, nullptr) - SliderCrankEnergy(r[0] - h, nullptr)) / (2 * h);  // (4)
    ex = std::max(ex, std::fabs(x - r[1]));
    et = std::max(et, std::fabs(tau - r[2]));
    tmax = std::max(tmax, std::fabs(r[2]));
  }
  EXPECT_LT(ex, 1e-13);          // measured 2e-16
  EXPECT_GT(tmax, 1.0);          // the torque is not trivially zero (max 5.3 N m)
  EXPECT_LT(et, 1e-8 * tmax);    // central difference error ~h^2 E''' (measured 7e-10)
}

}  // namespace
}  // namespace kanesim::test
