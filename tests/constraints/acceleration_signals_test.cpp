// Acceleration signals (joint `j.a`, body `b.a[k]`, `b.alpha[k]`; runtime/engine/signals.cpp)
// against closed forms and against a second method.
//
// Physical pendulum (tests/support/builders.h Pendulum): a thin rod of mass m and length L
// hanging along -y of its frame from a revolute joint about z at the origin; mass centre at
// r = (L/2)(sin q, -cos q, 0), I_O = m L^2 / 3. Lagrange:
//   qdd = -(3 g / (2 L)) sin q                                                        (1)
//   a_cm = qdd z x r + qd^2 (-r) ,   alpha = qdd z                                      (2)
//
// Torque-free rigid body on a free joint: Euler's equations in world axes,
//   alpha = I_W^-1 (-(w x I_W w)),   a_cm = 0                                           (3)
//
// Closed loops (four-bar, slider-crank) and the solver paths (dense reduced, multiplier
// form): the accelerations at the output instants against central differences of the
// velocities of a tight-tolerance run (a second method: the integrator's own trajectory).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "sim/signal_select.h"
#include "tests/support/load_util.h"
#include "tests/support/builders.h"
#include "compiler/compiler.h"

namespace kanesim::test {
namespace {

TEST(AccelerationSignals, PendulumMatchesLagrange) {
  // If this fails, j.a is not the solved udot, or the body acceleration misses the
  // centripetal term or is taken at the wrong point (body origin instead of mass centre).
  const double m = 1.3, L = 0.7, g = 9.81;
  auto cr = rt::Compile(Pendulum(m, L, g, 2.0), {});
  ASSERT_TRUE(cr.program);
  auto s = RunModel(*cr.program, 3.0, 0.01, 1e-10,
                    {"pivot.q", "pivot.u", "pivot.a", "rod.a[1]", "rod.a[2]", "rod.a[3]", "rod.alpha[1]",
                     "rod.alpha[2]", "rod.alpha[3]"});
  double err = 0.0, amax = 0.0;
  for (const auto& r : s.rows) {
    const double q = r[0], qd = r[1];
    const double qdd = -(3 * g / (2 * L)) * std::sin(q);  // (1)
    const double rx = L / 2 * std::sin(q), ry = -L / 2 * std::cos(q);
    const double ax = -qdd * ry - qd * qd * rx, ay = qdd * rx - qd * qd * ry;  // (2)
    amax = std::max(amax, std::fabs(qdd));
    err = std::max({err, std::fabs(r[2] - qdd), std::fabs(r[3] - ax), std::fabs(r[4] - ay), std::fabs(r[5]),
                    std::fabs(r[6]), std::fabs(r[7]), std::fabs(r[8] - qdd)});
  }
  EXPECT_GT(amax, 15.0);         // released at 2 rad: |qdd| reaches 3g/(2L) sin 2 = 19 rad/s^2
  EXPECT_LT(err, 1e-11 * amax);  // evaluated at the output state: round-off
}

TEST(AccelerationSignals, TorqueFreeBodyFollowsEuler) {
  // If this fails, the angular acceleration misses the gyroscopic term of a free body or is
  // expressed in the wrong axes.
  const char* model = R"(
model Tumbler
  World world(g = {0, 0, 0});
  FreeMotion free(u(start = {0.1, 0, 0, 0.3, 2.0, -0.7}));
  Body body(m = 2, I = [0.2, 0.01, -0.02; 0.01, 0.3, 0.03; -0.02, 0.03, 0.45]);
equation
  connect(world.frame_b, free.frame_a);
  connect(free.frame_b, body.frame_a);
end Tumbler;
)";
  auto l = LoadModel(model, {}, {}, /*is_text=*/true);
  ASSERT_TRUE(l && l->prog);
  std::vector<std::string> names;
  for (const char* f : {"w", "a", "alpha", "R"})
    for (int k = 1; k <= (f[0] == 'R' ? 9 : 3); ++k)
      names.push_back(std::string("body.") + f + (f[0] == 'R' ? "[" + std::to_string((k - 1) / 3 + 1) + "," +
                                                                    std::to_string((k - 1) % 3 + 1) + "]"
                                                              : "[" + std::to_string(k) + "]"));
  auto s = RunModel(*l->prog, 2.0, 0.05, 1e-10, names);
  const Eigen::Matrix3d I_B{{0.2, 0.01, -0.02}, {0.01, 0.3, 0.03}, {-0.02, 0.03, 0.45}};
  double err = 0.0, amax = 0.0;
  for (const auto& r : s.rows) {
    const Eigen::Vector3d w(r[0], r[1], r[2]), a(r[3], r[4], r[5]), alpha(r[6], r[7], r[8]);
    Eigen::Matrix3d R;
    for (int k = 0; k < 9; ++k) R(k / 3, k % 3) = r[9 + static_cast<size_t>(k)];
    const Eigen::Matrix3d I_W = R * I_B * R.transpose();
    const Eigen::Vector3d expected = I_W.ldlt().solve(-w.cross(I_W * w));  // (3)
    amax = std::max(amax, expected.norm());
    err = std::max({err, (alpha - expected).norm(), a.norm()});
  }
  EXPECT_GT(amax, 0.5);
  EXPECT_LT(err, 1e-10 * amax);
}

// Central differences of a velocity signal at the interior output instants against the
// acceleration signal there: the difference's truncation error is (h^2/6) |dddot v|.
double DifferenceError(const sim::MemorySink& s, size_t v, size_t a, double h, double* scale) {
  double err = 0.0;
  for (size_t i = 1; i + 1 < s.rows.size(); ++i) {
    const double fd = (s.rows[i + 1][v] - s.rows[i - 1][v]) / (2 * h);
    *scale = std::max(*scale, std::fabs(s.rows[i][a]));
    err = std::max(err, std::fabs(fd - s.rows[i][a]));
  }
  return err;
}

TEST(AccelerationSignals, ClosedLoopsMatchDifferencesOfVelocities) {
  // If this fails, the accelerations of a closed loop are not the constrained ones (the
  // dependent speeds' udot or the multiplier form's accelerations are wrong) on one of the
  // solution paths.
  struct Case {
    const char* example;
    const char* joint;
    const char* body;
  };
  for (const Case& c : {Case{"fourbar.mech", "rocker_pivot", "coupler.body"}, Case{"slider_crank.mech", "slide", "rod.body"}}) {
    for (rt::SolverPath path : {rt::SolverPath::Dense, rt::SolverPath::Sparse}) {
      rt::CompileOptions o;
      o.solver = path;
      auto l = LoadModel(kRoot + "/examples/" + c.example, {}, o);
      ASSERT_TRUE(l && l->prog) << c.example;
      const std::string j = c.joint, b = c.body;
      const double h = 1e-4;
      auto s = RunModel(*l->prog, 0.2, h, 1e-12,
                        {j + ".u", j + ".a", b + ".v[1]", b + ".a[1]", b + ".v[2]", b + ".a[2]", b + ".w[3]",
                         b + ".alpha[3]"});
      for (size_t k = 0; k < 4; ++k) {
        double scale = 0.0;
        const double err = DifferenceError(s, 2 * k, 2 * k + 1, h, &scale);
        EXPECT_GT(scale, 1.0) << c.example << " signal " << s.names[2 * k + 1];
        // Truncation ((h w)^2 / 6 ~ 1e-6 relative at w = 20 rad/s) plus the run's own error.
        EXPECT_LT(err, 1e-5 * scale) << c.example << " " << s.names[2 * k + 1] << " path "
                                      << static_cast<int>(path);
      }
    }
  }
}

TEST(AccelerationSignals, DerAliasSelectsTheAccelerations) {
  // If this fails, der(j.u) / der(b.v[k]) / der(b.w[k]) do not select the acceleration
  // signals, or der() of something else is silently accepted.
  const std::vector<std::string> available = {"j.q", "j.u", "j.a", "b.v[1]", "b.a[1]", "b.w[2]", "b.alpha[2]"};
  std::vector<std::string> got;
  std::string error;
  ASSERT_TRUE(sim::SelectSignals(available, {"der(j.u)", "der(b.v[1])", "der(b.w[2])"}, &got, &error)) << error;
  EXPECT_EQ(got, (std::vector<std::string>{"j.a", "b.a[1]", "b.alpha[2]"}));
  EXPECT_FALSE(sim::SelectSignals(available, {"der(j.q)"}, &got, &error));
  EXPECT_NE(error.find("der()"), std::string::npos) << error;
}

}  // namespace
}  // namespace kanesim::test
