// URDF <mimic> joints imported as exact couplings (stdlib JointCoupling; docs/import.md),
// run against reduced models derived by hand with the coupling substituted. If these fail,
// the follower moves on its own again (the coupling dropped), the constraint row drifts, or
// its force does work (energy not conserved).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>

#include "import/import.h"
#include "pipeline/pipeline.h"
#include "sim/csv.h"

namespace kanesim {
namespace {

const std::string kData = std::string(KANESIM_SOURCE_DIR) + "/tests/import/data";
constexpr double kG = 9.81;  // the importer's gravity, -z
// The coupling is one linear row kept by Newton to round-off at every evaluation: residual
// at the level of round-off of the coordinates (~1), with a margin.
constexpr double kCouplingTol = 1e-12;

std::string ReadText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The imported URDF with `joint`'s start q and u, run for 1 s at rtol = atol = 1e-12, its
// <limit>s ignored (the reduced models have none; the gripper would reach the right finger's
// lower limit at t = 0.93: tests/import/limits_test.cpp tests limits with <mimic>s).
sim::MemorySink RunImported(const std::string& file, const std::string& joint, double q0, double u0) {
  import::Options o;
  o.use_ros_package_path = false;
  o.stops = false;
  const std::string urdf = kData + "/" + file;
  import::Result imp = import::UrdfToMech(urdf, ReadText(urdf), o);
  EXPECT_TRUE(imp.ok) << imp.diagnostics;
  std::string mech = imp.mech;
  std::size_t at = mech.find(" " + joint + "(axis");
  EXPECT_NE(at, std::string::npos) << mech;
  at = mech.find('(', at) + 1;
  char buf[96];
  std::snprintf(buf, sizeof buf, "q(start = %.17g), u(start = %.17g), ", q0, u0);
  mech.insert(at, buf);
  pipeline::RunSpec spec;
  spec.stop_time = 1.0;
  spec.interval = 0.05;
  spec.rtol = spec.atol = 1e-12;
  sim::MemorySink rows;
  pipeline::LoadResult lr = pipeline::LoadModel(pipeline::Source::Text(urdf + ".mech", mech), {}, spec);
  EXPECT_TRUE(lr.model) << lr.diagnostics << mech;
  if (!lr.model) return rows;
  sim::SimResult res = pipeline::Run(*lr.model, spec, rows);
  EXPECT_EQ(res.status, sim::SimResult::Status::kOk) << res.message;
  EXPECT_EQ(rows.rows.size(), 21u);
  return rows;
}

std::size_t Col(const sim::MemorySink& s, const std::string& name) {
  const auto it = std::find(s.names.begin(), s.names.end(), name);
  EXPECT_NE(it, s.names.end()) << name;
  return static_cast<std::size_t>(it - s.names.begin());
}

// Fingers on separate branches of a fixed palm, q_r = r q_l + c (r = -2): with x = q_l,
// T = (m_l + r^2 m_r) xdot^2 / 2 and V = g (m_l + r m_r) x + const, so
//   x(t) = x0 + v0 t + a t^2 / 2,   a = -g (m_l + r m_r) / (m_l + r^2 m_r).
TEST(MimicJoint, GripperFingersFollowTheLeverAtwoodMachine) {
  const double ml = 0.3, mr = 0.1, r = -2.0, c = 0.01, x0 = 0.02, v0 = 0.1;
  const double a = -kG * (ml + r * mr) / (ml + r * r * mr);
  const sim::MemorySink s = RunImported("mimic_gripper.urdf", "left", x0, v0);
  const std::size_t ql = Col(s, "left.q"), qr = Col(s, "right.q"), ur = Col(s, "right.u");
  double worst = 0.0, residual = 0.0;
  for (std::size_t k = 0; k < s.rows.size(); ++k) {
    const double t = s.times[k], x = x0 + v0 * t + 0.5 * a * t * t;
    worst = std::max(worst, std::fabs(s.rows[k][ql] - x));
    residual = std::max(residual, std::fabs(s.rows[k][qr] - (r * s.rows[k][ql] + c)));
    residual = std::max(residual, std::fabs(s.rows[k][ur] - r * (v0 + a * t)));
  }
  EXPECT_LE(worst, 1e-10);  // a polynomial of degree 2: the integrator's error is round-off
  EXPECT_LE(residual, kCouplingTol);
}

// Two links about y, the elbow mimicking the shoulder: q2 = r q1 + c. With th = q1 and
// s = 1 + r (the lower link turns by s th), link 1 (m1, mass centre at a1, I1 about it),
// link 2 (m2, a2, I2) at L1 along link 1, directions d(phi) = (cos phi, -sin phi) in (x, z):
//   T = J(th) thdot^2 / 2,  J = m1 a1^2 + I1 + m2 (L1^2 + s^2 a2^2 + 2 s L1 a2 cos(r th + c)) + s^2 I2
//   V = -g (m1 a1 sin th + m2 L1 sin th + m2 a2 sin(s th + c))
//   J thddot + J'(th) thdot^2 / 2 + V'(th) = 0
// integrated here by classical RK4 at h = 1e-4 (error ~1e-14 over 1 s).
struct ReducedArm {
  double m1 = 1.5, a1 = 0.2, I1 = 0.02, m2 = 0.8, a2 = 0.15, I2 = 0.01, L1 = 0.4, r = 0.5, c = 0.3;
  double s() const { return 1.0 + r; }
  double J(double th) const {
    return m1 * a1 * a1 + I1 + m2 * (L1 * L1 + s() * s() * a2 * a2 + 2 * s() * L1 * a2 * std::cos(r * th + c)) +
           s() * s() * I2;
  }
  double dJ(double th) const { return -2 * m2 * s() * L1 * a2 * r * std::sin(r * th + c); }
  double V(double th) const { return -kG * ((m1 * a1 + m2 * L1) * std::sin(th) + m2 * a2 * std::sin(s() * th + c)); }
  double dV(double th) const {
    return -kG * ((m1 * a1 + m2 * L1) * std::cos(th) + m2 * a2 * s() * std::cos(s() * th + c));
  }
  double Accel(double th, double w) const { return -(0.5 * dJ(th) * w * w + dV(th)) / J(th); }
  double Energy(double th, double w) const { return 0.5 * J(th) * w * w + V(th); }
};

TEST(MimicJoint, ArmFollowsItsReducedModelAndConservesEnergy) {
  const ReducedArm arm;
  const double th0 = 0.3, w0 = 0.5;
  const sim::MemorySink s = RunImported("mimic_arm.urdf", "shoulder", th0, w0);
  const std::size_t q1 = Col(s, "shoulder.q"), u1 = Col(s, "shoulder.u"), q2 = Col(s, "elbow.q"),
                    u2 = Col(s, "elbow.u");
  double th = th0, w = w0, t = 0.0, worst = 0.0, residual = 0.0, drift = 0.0;
  const double h = 1e-4, e0 = arm.Energy(th0, w0);
  for (std::size_t k = 0; k < s.rows.size(); ++k) {
    while (t < s.times[k] - h / 2) {
      const double k1t = w, k1w = arm.Accel(th, w);
      const double k2t = w + h / 2 * k1w, k2w = arm.Accel(th + h / 2 * k1t, w + h / 2 * k1w);
      const double k3t = w + h / 2 * k2w, k3w = arm.Accel(th + h / 2 * k2t, w + h / 2 * k2w);
      const double k4t = w + h * k3w, k4w = arm.Accel(th + h * k3t, w + h * k3w);
      th += h / 6 * (k1t + 2 * k2t + 2 * k3t + k4t);
      w += h / 6 * (k1w + 2 * k2w + 2 * k3w + k4w);
      t += h;
    }
    const std::vector<double>& row = s.rows[k];
    worst = std::max({worst, std::fabs(row[q1] - th), std::fabs(row[u1] - w)});
    residual = std::max({residual, std::fabs(row[q2] - (arm.r * row[q1] + arm.c)), std::fabs(row[u2] - arm.r * row[u1])});
    drift = std::max(drift, std::fabs(arm.Energy(row[q1], row[u1]) - e0));
  }
  EXPECT_GT(std::fabs(th - th0), 0.5);  // it swings: the comparison is not of a resting arm
  EXPECT_LE(worst, 1e-9);               // two integrations at 1e-12 and ~1e-14 of one ODE
  EXPECT_LE(residual, kCouplingTol);
  EXPECT_LE(drift, 1e-9 * std::fabs(e0 - arm.V(0.0)) + 1e-9);
  std::printf("mimic arm: largest difference from the reduced model %.2e, coupling residual %.2e, energy drift %.2e J\n",
              worst, residual, drift);
}

// The written model says what it keeps: the coupling, readable, with the URDF's numbers.
TEST(MimicJoint, IsWrittenAsAJointCoupling) {
  import::Options o;
  o.use_ros_package_path = false;
  import::Result r = import::UrdfToMech("arm.urdf", ReadText(kData + "/mimic_arm.urdf"), o);
  ASSERT_TRUE(r.ok) << r.diagnostics;
  EXPECT_NE(r.mech.find("JointCoupling elbow_mimic(ratio = 0.5, offset = 0.3)"), std::string::npos) << r.mech;
  EXPECT_NE(r.mech.find("connect(shoulder.drive, elbow_mimic.flange_a);"), std::string::npos);
  EXPECT_NE(r.mech.find("connect(elbow.drive, elbow_mimic.flange_b);"), std::string::npos);
  EXPECT_EQ(r.diagnostics.find("warning"), std::string::npos) << r.diagnostics;
}

}  // namespace
}  // namespace kanesim
