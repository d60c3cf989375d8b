// URDF <dynamics friction> (a constant torque or force) imported as the joint's exact Coulomb
// friction (stdlib friction_torque / friction_force with friction_exact; docs/import.md), damping
// kept as the joint's force law. If these fail, the importer writes the stiff regularized law
// again, or an imported joint does not stick where its friction holds it, or does not come to
// rest where the energy balance says.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "import/import.h"
#include "pipeline/pipeline.h"

namespace kanesim {
namespace {

constexpr double kG = 9.81;  // the importer's gravity, -z

// A pendulum of one link (m = 2, centre of mass 0.5 along x, axis y: gravity turns it
// positively with torque m g 0.5 cos q) on a `type` joint with <dynamics>.
std::string Pendulum(const std::string& type, const std::string& dynamics) {
  return "<robot name=\"one\">\n  <link name=\"base\"/>\n"
         "  <link name=\"arm\"><inertial><origin xyz=\"0.5 0 0\"/><mass value=\"2\"/>"
         "<inertia ixx=\"0.01\" iyy=\"0.01\" izz=\"0.01\"/></inertial></link>\n"
         "  <joint name=\"j\" type=\"" + type + "\"><parent link=\"base\"/><child link=\"arm\"/><axis xyz=\"0 1 0\"/>" +
         dynamics + "</joint>\n</robot>\n";
}

import::Result Import(const std::string& urdf) {
  import::Options o;
  o.use_ros_package_path = false;
  return import::UrdfToMech("x.urdf", urdf, o);
}

sim::MemorySink RunUrdf(const std::string& urdf, double stop, sim::SimResult* res) {
  pipeline::RunSpec spec;
  spec.stop_time = stop;
  spec.interval = 0.01;
  spec.rtol = spec.atol = 1e-10;
  pipeline::LoadOptions lo;
  lo.urdf.use_ros_package_path = false;
  sim::MemorySink rows;
  pipeline::LoadResult lr = pipeline::LoadModel(pipeline::Source::Text("x.urdf", urdf), lo, spec);
  EXPECT_TRUE(lr.model) << lr.diagnostics;
  if (!lr.model) return rows;
  *res = pipeline::Run(*lr.model, spec, rows);
  EXPECT_EQ(res->status, sim::SimResult::Status::kOk) << res->message;
  return rows;
}

TEST(UrdfFriction, WrittenAsExactFrictionWithDampingAsTheLaw) {
  const import::Result r = Import(Pendulum("continuous", "<dynamics damping=\"0.3\" friction=\"0.7\"/>"));
  ASSERT_TRUE(r.ok) << r.diagnostics;
  EXPECT_NE(r.mech.find("Revolute j(axis = {0, 1, 0}, friction_torque = 0.7, friction_exact = true)"), std::string::npos)
      << r.mech;
  EXPECT_NE(r.mech.find("j.tau = -(0.3 * j.u);"), std::string::npos) << r.mech;
  EXPECT_EQ(r.mech.find("tanh"), std::string::npos) << r.mech;
  // A prismatic joint's friction is a force; friction alone writes no force law.
  const import::Result p = Import(Pendulum("prismatic", "<limit lower=\"-1\" upper=\"1\"/><dynamics friction=\"2\"/>"));
  ASSERT_TRUE(p.ok) << p.diagnostics;
  EXPECT_NE(p.mech.find("q_min = -1, q_max = 1, friction_force = 2, friction_exact = true)"), std::string::npos) << p.mech;
  EXPECT_EQ(p.mech.find("j.tau ="), std::string::npos) << p.mech;
}

// Friction 12 N m above the gravity torque m g 0.5 = 9.81 N m at q = 0: stuck for good, q = 0
// exactly. Friction 5: it slips, swings up to the first q1 with m g 0.5 sin q1 = 5 q1 (energy
// lost = friction times path) and sticks there, where |m g 0.5 cos q1| <= 5.
TEST(UrdfFriction, ImportedPendulumSticksOrRestsWhereTheEnergyBalanceSays) {
  sim::SimResult held;
  const sim::MemorySink still = RunUrdf(Pendulum("continuous", "<dynamics friction=\"12\"/>"), 1.0, &held);
  ASSERT_FALSE(still.rows.empty());
  const std::size_t q = static_cast<std::size_t>(std::find(still.names.begin(), still.names.end(), "j.q") - still.names.begin());
  ASSERT_LT(q, still.names.size());
  for (const auto& row : still.rows) EXPECT_EQ(row[q], 0.0);
  ASSERT_EQ(held.stats.events.size(), 1u);
  EXPECT_EQ(held.stats.events[0].kind.find("sticks"), 0u) << held.stats.events[0].kind;

  const double mgr = 2 * kG * 0.5, F = 5;
  double a = 1.0, b = 3.0;  // mgr sin(x) - F x: positive at 1, negative at 3
  for (int it = 0; it < 200; ++it) {
    const double m = 0.5 * (a + b);
    (mgr * std::sin(m) - F * m > 0 ? a : b) = m;
  }
  ASSERT_LT(std::abs(mgr * std::cos(a)), F);  // statics holds it there
  sim::SimResult swung;
  const sim::MemorySink rows = RunUrdf(Pendulum("continuous", "<dynamics friction=\"5\"/>"), 3.0, &swung);
  ASSERT_FALSE(rows.rows.empty());
  ASSERT_EQ(swung.stats.events.size(), 2u);  // slips at the start, sticks at the top
  EXPECT_EQ(swung.stats.events[1].kind.find("sticks"), 0u) << swung.stats.events[1].kind;
  EXPECT_NEAR(rows.rows.back()[q], a, 1e-8);
}

}  // namespace
}  // namespace kanesim
