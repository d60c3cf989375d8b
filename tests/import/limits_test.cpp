// URDF <limit lower upper> as end stops (stdlib q_min, q_max; docs/import.md), `--limits
// ignore`, and <mimic> elements on fixed joints (ignored, as Pinocchio and MuJoCo do). If
// these fail, an imported joint passes through its limits, a <mimic> follower passes its
// limit, `ignore` changes the motion, or Talos's grippers are refused again.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

#include "import/import.h"
#include "pipeline/pipeline.h"
#include "sim/csv.h"

namespace kanesim {
namespace {

const std::string kData = std::string(KANESIM_SOURCE_DIR) + "/tests/import/data";
constexpr double kG = 9.81;  // the importer's gravity, -z

std::string ReadText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// A robot of one link on `joint` (type, axis, <limit> and the link's centre of mass).
std::string OneLink(const std::string& type, const std::string& axis, const std::string& limit,
                    const std::string& com = "0 0 0") {
  return "<robot name=\"one\">\n  <link name=\"base\"/>\n"
         "  <link name=\"arm\"><inertial><origin xyz=\"" + com + "\"/><mass value=\"2\"/>"
         "<inertia ixx=\"0.01\" iyy=\"0.01\" izz=\"0.01\"/></inertial></link>\n"
         "  <joint name=\"j\" type=\"" + type + "\"><parent link=\"base\"/><child link=\"arm\"/><axis xyz=\"" + axis +
         "\"/>" + limit + "</joint>\n</robot>\n";
}

// The URDF text run in memory as `kanesim run x.urdf [--limits ignore]` does.
sim::MemorySink RunUrdf(const std::string& urdf, bool stops, double stop_time = 1.0) {
  pipeline::RunSpec spec;
  spec.stop_time = stop_time;
  spec.interval = 0.01;
  spec.rtol = spec.atol = 1e-10;
  pipeline::LoadOptions lo;
  lo.urdf.stops = stops;
  lo.urdf.use_ros_package_path = false;
  sim::MemorySink rows;
  pipeline::LoadResult lr = pipeline::LoadModel(pipeline::Source::Text("x.urdf", urdf), lo, spec);
  EXPECT_TRUE(lr.model) << lr.diagnostics;
  if (!lr.model) return rows;
  sim::SimResult res = pipeline::Run(*lr.model, spec, rows);
  EXPECT_EQ(res.status, sim::SimResult::Status::kOk) << res.message;
  return rows;
}

std::size_t Col(const sim::MemorySink& s, const std::string& name) {
  const auto it = std::find(s.names.begin(), s.names.end(), name);
  EXPECT_NE(it, s.names.end()) << name;
  return static_cast<std::size_t>(it - s.names.begin());
}

// A slider falling from q = 0 under gravity reaches its lower limit -h at t = sqrt(2h/g)
// (the event: that time twice in the rows) and rests there; no row is below the limit.
TEST(UrdfLimits, PrismaticFallsOntoItsLowerLimitAtTheClosedFormTimeAndRests) {
  const double h = 0.5;
  const std::string urdf = OneLink("prismatic", "0 0 1", "<limit lower=\"-0.5\" upper=\"1\" effort=\"1\" velocity=\"1\"/>");
  const sim::MemorySink rows = RunUrdf(urdf, true);
  ASSERT_GT(rows.rows.size(), 100u);
  const std::size_t q = Col(rows, "j.q"), u = Col(rows, "j.u");
  double hit = -1;
  for (std::size_t i = 0; i < rows.rows.size(); ++i) {
    EXPECT_GE(rows.rows[i][q], -h) << "row " << i << " at t = " << rows.times[i];
    if (i > 0 && rows.times[i] == rows.times[i - 1] && hit < 0) hit = rows.times[i];
  }
  EXPECT_NEAR(hit, std::sqrt(2 * h / kG), 1e-8);
  EXPECT_EQ(rows.rows.back()[q], -h);
  EXPECT_EQ(rows.rows.back()[u], 0.0);
  // --limits ignore: free fall through the limit, q = -g t^2 / 2.
  const sim::MemorySink free = RunUrdf(urdf, false);
  EXPECT_NEAR(free.rows.back()[Col(free, "j.q")], -kG / 2, 1e-8);
}

// A pendulum (axis y, centre of mass along x) released inside [-0.3, 0.4] swings onto a limit
// and stays in the range in every row; a start of q = 0 outside the range starts on the nearer
// limit, which the note says.
TEST(UrdfLimits, RevoluteStaysWithinItsLimits) {
  const std::string urdf =
      OneLink("revolute", "0 1 0", "<limit lower=\"-0.3\" upper=\"0.4\" effort=\"1\" velocity=\"1\"/>", "0.5 0 0");
  const sim::MemorySink rows = RunUrdf(urdf, true);
  const std::size_t q = Col(rows, "j.q");
  for (const auto& r : rows.rows) {
    EXPECT_GE(r[q], -0.3);
    EXPECT_LE(r[q], 0.4);
  }
  // Gravity -z on a centre of mass at +x turns it positively about y: it rests on the upper stop.
  EXPECT_EQ(rows.rows.back()[q], 0.4);
  const sim::MemorySink free = RunUrdf(urdf, false);
  EXPECT_GT(free.rows.back()[Col(free, "j.q")], 0.4);  // without stops it swings past

  const std::string outside = OneLink("revolute", "0 1 0", "<limit lower=\"0.1\" upper=\"0.4\"/>", "-0.5 0 0");
  import::Options o;
  o.use_ros_package_path = false;
  const import::Result r = import::UrdfToMech("x.urdf", outside, o);
  ASSERT_TRUE(r.ok) << r.diagnostics;
  EXPECT_NE(r.mech.find("Revolute j(axis = {0, 1, 0}, q_min = 0.1, q_max = 0.4, q(start = 0.1))"), std::string::npos)
      << r.mech;
  EXPECT_NE(r.diagnostics.find("q = 0 is outside its <limit> [0.1, 0.4]: it starts at 0.1"), std::string::npos)
      << r.diagnostics;
  const sim::MemorySink on = RunUrdf(outside, true, 0.2);
  ASSERT_FALSE(on.rows.empty());
  for (const auto& row : on.rows) EXPECT_EQ(row[Col(on, "j.q")], 0.1);  // pushed onto the stop it rests on
}

// --limits ignore gives the same rows, bit for bit, as the file without its <limit>s (the
// importer's output before limits became stops), for UR5 (whose +-2 pi limits it does not reach
// from rest) and for the slider above (which falls through its limit).
TEST(UrdfLimits, IgnoreEqualsTheFileWithoutLimits) {
  const std::string slider =
      OneLink("prismatic", "0 0 1", "<limit lower=\"-0.5\" upper=\"1\" effort=\"1\" velocity=\"1\"/>");
  for (const std::string& urdf : {ReadText(kData + "/ur5_robot.urdf"), slider}) {
    std::string stripped = urdf;
    for (std::size_t at; (at = stripped.find("<limit ")) != std::string::npos;)
      stripped.erase(at, stripped.find("/>", at) + 2 - at);
    const sim::MemorySink ignored = RunUrdf(urdf, false), plain = RunUrdf(stripped, true);
    ASSERT_FALSE(ignored.rows.empty());
    EXPECT_EQ(ignored.names, plain.names);
    EXPECT_EQ(ignored.times, plain.times);
    EXPECT_EQ(ignored.rows, plain.rows);
  }
  EXPECT_NE(RunUrdf(slider, false).rows, RunUrdf(slider, true).rows);
}

// A robot whose <mimic>s are kept as couplings: its limits become end stops of each group's
// root leader, the intersection of the members' ranges mapped through q = m q_l + c (stops
// on the follower too would be rows dependent on the leader's). every_joint.urdf: 'slide'
// in [0, 0.2], 'follow' = -slide + 0.01 in [-0.2, 0], so slide in [0.01, 0.2].
TEST(UrdfLimits, CoupledRobotGetsItsLimitsAsTheLeadersStops) {
  import::Options o;
  o.use_ros_package_path = false;
  const std::string path = kData + "/every_joint.urdf";
  const import::Result r = import::UrdfToMech(path, ReadText(path), o);
  ASSERT_TRUE(r.ok) << r.diagnostics;
  EXPECT_NE(r.mech.find("q_min = 0.01, q_max = 0.2, q(start = 0.01)"), std::string::npos) << r.mech;
  EXPECT_NE(r.mech.find("limit lower -0.2 upper 0 effort 100 velocity 1 (held by the end stops of 'slide' through the <mimic>)"),
            std::string::npos)
      << r.mech;
  EXPECT_EQ(r.mech.find("recorded: no end stops"), std::string::npos) << r.mech;
  pipeline::LoadResult lr = pipeline::LoadModel(pipeline::Source::Text("every_joint.urdf.mech", r.mech), {}, {});
  EXPECT_TRUE(lr.model) << lr.diagnostics;
}

void CheckLiftFallsOntoTheFingersLimit(const sim::MemorySink& rows, double accel);

// A lift (prismatic, z) carrying a finger (prismatic, x) that mimics it, q_f = 2 q_l + 0.1;
// the finger's lower limit -0.7 is the binding one (q_l = -0.4; the lift's own is -0.5).
// Equal masses m: T = (m + m + 4 m) u_l^2 / 2 against the weight 2 m g, so the lift falls
// with g / 3 from rest and meets q_l = -0.4 at t = sqrt(2 0.4 / (g / 3)), then rests. If this
// fails, a follower's limit was not a stop (the finger passes -0.7), the stop let the
// coupling go (q_f != 2 q_l + 0.1), or the impact is not at the closed-form time.
TEST(UrdfLimits, MimicFollowerDrivenIntoItsLimitStopsThere) {
  const std::string link = "><inertial><mass value=\"1\"/><inertia ixx=\"0.01\" iyy=\"0.01\" izz=\"0.01\"/></inertial></link>\n";
  const std::string urdf =
      "<robot name=\"grip\">\n  <link name=\"base\"/>\n  <link name=\"a\"" + link + "  <link name=\"b\"" + link +
      "  <joint name=\"lift\" type=\"prismatic\"><parent link=\"base\"/><child link=\"a\"/><axis xyz=\"0 0 1\"/>"
      "<limit lower=\"-0.5\" upper=\"0.5\" effort=\"1\" velocity=\"1\"/></joint>\n"
      "  <joint name=\"finger\" type=\"prismatic\"><parent link=\"a\"/><child link=\"b\"/><axis xyz=\"1 0 0\"/>"
      "<limit lower=\"-0.7\" upper=\"0.5\" effort=\"1\" velocity=\"1\"/>"
      "<mimic joint=\"lift\" multiplier=\"2\" offset=\"0.1\"/></joint>\n</robot>\n";
  const sim::MemorySink rows = RunUrdf(urdf, true);
  ASSERT_GT(rows.rows.size(), 100u);
  CheckLiftFallsOntoTheFingersLimit(rows, kG / 3);
}

// The lift and finger of MimicFollowerDrivenIntoItsLimitStopsThere with <dynamics friction>:
// 2 N on the lift, c_f on the finger. The importer puts the group's friction on the lift as
// exact friction, 2 + |2| c_f (virtual work through q_f = 2 q_l + 0.1). c_f = 10: 22 N holds the
// weight 2 m g = 19.62 N, stuck for good; c_f = 5: 12 N, it slides down with (2 m g - 12) / 6 m
// onto the finger's limit. If this fails, the follower's friction was not reflected through the
// ratio (or was kept as the stiff tanh law), or exact friction beside the coupling misbehaves.
TEST(UrdfLimits, MimicGroupFrictionIsExactOnTheLeader) {
  auto urdf = [](const std::string& finger_friction) {
    const std::string link = "><inertial><mass value=\"1\"/><inertia ixx=\"0.01\" iyy=\"0.01\" izz=\"0.01\"/></inertial></link>\n";
    return "<robot name=\"grip\">\n  <link name=\"base\"/>\n  <link name=\"a\"" + link + "  <link name=\"b\"" + link +
           "  <joint name=\"lift\" type=\"prismatic\"><parent link=\"base\"/><child link=\"a\"/><axis xyz=\"0 0 1\"/>"
           "<limit lower=\"-0.5\" upper=\"0.5\" effort=\"1\" velocity=\"1\"/><dynamics friction=\"2\"/></joint>\n"
           "  <joint name=\"finger\" type=\"prismatic\"><parent link=\"a\"/><child link=\"b\"/><axis xyz=\"1 0 0\"/>"
           "<limit lower=\"-0.7\" upper=\"0.5\" effort=\"1\" velocity=\"1\"/><dynamics friction=\"" + finger_friction +
           "\"/><mimic joint=\"lift\" multiplier=\"2\" offset=\"0.1\"/></joint>\n</robot>\n";
  };
  import::Options o;
  o.use_ros_package_path = false;
  const import::Result r = import::UrdfToMech("grip.urdf", urdf("5"), o);
  ASSERT_TRUE(r.ok) << r.diagnostics;
  EXPECT_NE(r.mech.find("friction_force = 12, friction_exact = true"), std::string::npos) << r.mech;
  EXPECT_NE(r.mech.find("<dynamics friction 5> on the exact friction of 'lift' through the <mimic>"), std::string::npos)
      << r.mech;
  EXPECT_EQ(r.mech.find("tanh"), std::string::npos) << r.mech;
  const sim::MemorySink held = RunUrdf(urdf("10"), true);
  ASSERT_GT(held.rows.size(), 100u);
  for (const std::vector<double>& y : held.rows) EXPECT_EQ(y[Col(held, "lift.q")], 0.0);
  CheckLiftFallsOntoTheFingersLimit(RunUrdf(urdf("5"), true), (2 * kG - 12) / 6);
}

// The lift falls from rest with `accel` onto q_l = -0.4 (the finger's limit -0.7 through the
// coupling) at t = sqrt(0.8 / accel) and rests there; q_f = 2 q_l + 0.1 in every row.
void CheckLiftFallsOntoTheFingersLimit(const sim::MemorySink& rows, double accel) {
  ASSERT_GT(rows.rows.size(), 100u);
  const std::size_t ql = Col(rows, "lift.q"), qf = Col(rows, "finger.q"), ul = Col(rows, "lift.u");
  double hit = -1;
  for (std::size_t i = 0; i < rows.rows.size(); ++i) {
    const std::vector<double>& y = rows.rows[i];
    EXPECT_GE(y[qf], -0.7 - 1e-12) << "row " << i << " at t = " << rows.times[i];
    EXPECT_NEAR(y[qf], 2 * y[ql] + 0.1, 1e-12) << "row " << i << " at t = " << rows.times[i];
    if (i > 0 && rows.times[i] == rows.times[i - 1] && hit < 0) hit = rows.times[i];
  }
  EXPECT_NEAR(hit, std::sqrt(2 * 0.4 / accel), 1e-8);
  EXPECT_NEAR(rows.rows.back()[ql], -0.4, 1e-12);
  EXPECT_NEAR(rows.rows.back()[qf], -0.7, 1e-12);
  EXPECT_EQ(rows.rows.back()[ul], 0.0);
}

// <mimic> on a fixed joint, or naming a fixed leader (Talos's grippers): nothing to couple,
// ignored with a comment and one note; a fixed joint mimicking itself stays U412.
TEST(UrdfMimic, OnOrOfAFixedJointIsIgnoredWithANote) {
  const std::string urdf =
      "<robot name=\"g\">\n  <link name=\"palm\"/>\n"
      "  <link name=\"a\"><inertial><mass value=\"1\"/><inertia ixx=\"1\" iyy=\"1\" izz=\"1\"/></inertial></link>\n"
      "  <link name=\"b\"><inertial><mass value=\"1\"/><inertia ixx=\"1\" iyy=\"1\" izz=\"1\"/></inertial></link>\n"
      "  <link name=\"c\"><inertial><mass value=\"1\"/><inertia ixx=\"1\" iyy=\"1\" izz=\"1\"/></inertial></link>\n"
      "  <joint name=\"drive\" type=\"revolute\"><parent link=\"palm\"/><child link=\"a\"/></joint>\n"
      "  <joint name=\"pad\" type=\"fixed\"><parent link=\"a\"/><child link=\"b\"/><mimic joint=\"drive\"/></joint>\n"
      "  <joint name=\"tip\" type=\"revolute\"><parent link=\"b\"/><child link=\"c\"/><mimic joint=\"pad\" multiplier=\"2\"/></joint>\n"
      "</robot>\n";
  import::Options o;
  o.use_ros_package_path = false;
  const import::Result r = import::UrdfToMech("g.urdf", urdf, o);
  ASSERT_TRUE(r.ok) << r.diagnostics;
  EXPECT_EQ(r.mech.find("JointCoupling"), std::string::npos) << r.mech;
  EXPECT_NE(r.mech.find("// joint 'pad' (g.urdf:7): fixed; <mimic joint=\"drive\"> ignored"), std::string::npos) << r.mech;
  EXPECT_NE(r.mech.find("// joint 'tip' (g.urdf:8): revolute; <mimic joint=\"pad\"> ignored"), std::string::npos) << r.mech;
  EXPECT_NE(r.diagnostics.find("note: 2 <mimic> elements on or of fixed joints ignored"), std::string::npos)
      << r.diagnostics;
  // The follower 'tip' moves on its own: two coordinates.
  pipeline::LoadResult lr = pipeline::LoadModel(pipeline::Source::Text("g.urdf.mech", r.mech), {}, {});
  ASSERT_TRUE(lr.model) << lr.diagnostics;

  std::string self = urdf;
  self.replace(self.find("<mimic joint=\"drive\"/>"), 22, "<mimic joint=\"pad\"/>");
  const import::Result bad = import::UrdfToMech("g.urdf", self, o);
  EXPECT_FALSE(bad.ok);
  EXPECT_NE(bad.diagnostics.find("g.urdf:7:69: error[U412]: joint 'pad' cannot mimic 'pad': itself"), std::string::npos)
      << bad.diagnostics;
}

}  // namespace
}  // namespace kanesim
