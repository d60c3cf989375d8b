// URDF robots imported (import/import.h) against Pinocchio's reading of the same files
// (bench/reference/urdf_robots.py wrote tests/import/data/*_ref.txt): the accelerations at
// random states against its articulated-body algorithm, every link's world pose against its
// framesForwardKinematics. If these fail, the importer maps a joint, an origin, an inertia or
// a <dynamics> element differently from URDF's definition (or the engine got it wrong).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "import/import.h"
#include "pipeline/pipeline.h"
#include "runtime/program/program.h"
#include "runtime/runtime.h"
#include "sim/csv.h"
#include "tests/support/csv_table.h"

namespace kanesim {
namespace {

namespace fs = std::filesystem;
const std::string kData = std::string(KANESIM_SOURCE_DIR) + "/tests/import/data";

// Two double-precision evaluations of one model by different algorithms (Kane's equations,
// the articulated-body algorithm): round-off of a few hundred operations at most.
constexpr double kAccelTol = 1e-12;  // relative to the largest |acceleration| (at least 1)
constexpr double kPoseTol = 1e-12;   // metres and rotation-matrix entries, robots of ~1 m

struct State {
  std::map<std::string, std::vector<double>> q, u, a;
  std::map<std::string, std::vector<double>> pose;  // link -> p (3), then R row by row (9)
};

struct Reference {
  std::string robot, urdf;
  bool floating = false;
  std::vector<State> states;
};

Reference ReadReference(const std::string& path) {
  Reference r;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::string key, name;
    ls >> key;
    if (key == "robot") ls >> r.robot;
    else if (key == "urdf") ls >> r.urdf;
    else if (key == "floating") ls >> r.floating;
    else if (key == "state") r.states.emplace_back();
    else if (key == "q" || key == "u" || key == "a" || key == "pose") {
      ls >> name;
      std::vector<double> v;
      for (double x; ls >> x;) v.push_back(x);
      State& s = r.states.back();
      (key == "q" ? s.q : key == "u" ? s.u : key == "a" ? s.a : s.pose)[name] = v;
    }
  }
  return r;
}

std::string ReadText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The URDF named by the reference: the copy in tests/import/data, else example-robot-data's
// in bench/.venv (Talos, whose licence forbids a copy); "" when neither is there.
std::string FindUrdf(const std::string& name) {
  if (fs::exists(kData + "/" + name)) return kData + "/" + name;
  const fs::path venv = fs::path(KANESIM_SOURCE_DIR) / "bench" / ".venv" / "lib";
  std::error_code ec;
  if (fs::exists(venv, ec))
    for (const auto& py : fs::directory_iterator(venv, ec)) {
      fs::path p = py.path() / "site-packages/cmeel.prefix/share/example-robot-data/robots/talos_data/robots" / name;
      if (fs::exists(p, ec)) return p.string();
    }
  return "";
}

class ImportedRobot : public ::testing::TestWithParam<const char*> {};

TEST_P(ImportedRobot, AccelerationsAndLinkPosesMatchPinocchio) {
  const Reference ref = ReadReference(kData + "/" + GetParam() + "_ref.txt");
  ASSERT_FALSE(ref.states.empty()) << GetParam();
  const std::string urdf = FindUrdf(ref.urdf);
  if (urdf.empty()) GTEST_SKIP() << ref.urdf << " is not installed (sh bench/setup_venv.sh installs it)";

  import::Options o;
  o.floating = ref.floating;
  o.use_ros_package_path = false;
  o.mimic = false;  // Pinocchio's reading (urdf_robots.py) leaves mimic joints independent
  import::Result imp = import::UrdfToMech(urdf, ReadText(urdf), o);
  ASSERT_TRUE(imp.ok) << imp.diagnostics;
  // Every link's frame as declared outputs: position and orientation in the world.
  std::string outputs;
  std::vector<std::string> links;
  for (const auto& [link, frame] : imp.link_frames) {
    const std::string i = std::to_string(links.size());
    outputs += "  output Real[3] p_" + i + " = " + frame + ".r;\n  output Real[3, 3] R_" + i + " = " + frame + ".R;\n";
    links.push_back(link);
  }
  std::string mech = imp.mech;
  mech.insert(mech.find("equation\n"), outputs);
  pipeline::LoadResult lr = pipeline::LoadModel(pipeline::Source::Text(urdf + ".mech", mech), {}, {});
  ASSERT_TRUE(lr.model) << lr.diagnostics;
  const rt::Program& p = *lr.model->program;
  std::map<std::string, std::string> component(imp.joints.begin(), imp.joints.end());
  component["root_joint"] = "root_joint";
  std::map<std::string, const rt::TreeJoint*> joint;
  for (const rt::TreeJoint& j : p.joints) joint[j.name] = &j;

  std::vector<std::string> names;
  for (std::size_t i = 0; i < links.size(); ++i) {
    for (int k = 1; k <= 3; ++k) names.push_back("p_" + std::to_string(i) + "[" + std::to_string(k) + "]");
    for (int k = 1; k <= 9; ++k)  // a matrix output's columns: its elements row by row
      names.push_back("R_" + std::to_string(i) + "[" + std::to_string(k) + "]");
  }
  std::string err;
  auto plan = rt::PlanSignals(p, names, &err);
  ASSERT_TRUE(plan) << err;
  auto ws = rt::MakeWorkspace(p);
  const int n = rt::StateSize(p);
  for (const State& s : ref.states) {
    std::vector<double> y(static_cast<std::size_t>(n), 0.0), ydot(y.size(), 0.0);
    for (const auto& [name, q] : s.q) {
      ASSERT_TRUE(component.count(name) && joint.count(component[name])) << "joint " << name;
      const rt::TreeJoint& j = *joint[component[name]];
      ASSERT_EQ(static_cast<int>(q.size()), j.nq) << name;
      for (int k = 0; k < j.nq; ++k) y[static_cast<std::size_t>(j.q0 + k)] = q[static_cast<std::size_t>(k)];
      for (int k = 0; k < j.nu; ++k) y[static_cast<std::size_t>(p.nq + j.u0 + k)] = s.u.at(name)[static_cast<std::size_t>(k)];
    }
    ASSERT_EQ(rt::Derivative(p, *ws, 0.0, y.data(), ydot.data()), 0) << rt::ErrorMessage(*ws);
    double scale = 1.0, worst = 0.0;
    std::string worst_at;
    for (const auto& [name, a] : s.a)
      for (double x : a) scale = std::max(scale, std::fabs(x));
    for (const auto& [name, a] : s.a) {
      const rt::TreeJoint& j = *joint[component[name]];
      for (int k = 0; k < j.nu; ++k) {
        const double d = std::fabs(ydot[static_cast<std::size_t>(p.nq + j.u0 + k)] - a[static_cast<std::size_t>(k)]);
        if (d > worst) worst = d, worst_at = name + "[" + std::to_string(k) + "]";
      }
    }
    EXPECT_LE(worst / scale, kAccelTol) << GetParam() << ": acceleration of " << worst_at;

    std::vector<double> out(names.size());
    ASSERT_EQ(rt::EvalSignals(p, *plan, *ws, 0.0, y.data(), out.data()), 0);
    for (std::size_t i = 0; i < links.size(); ++i) {
      ASSERT_TRUE(s.pose.count(links[i])) << "no Pinocchio frame for link " << links[i];
      const std::vector<double>& want = s.pose.at(links[i]);
      for (std::size_t k = 0; k < 12; ++k)
        EXPECT_NEAR(out[12 * i + k], want[k], kPoseTol) << GetParam() << ": link " << links[i] << " entry " << k;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(ExampleRobotData, ImportedRobot,
                         ::testing::Values("ur5", "panda", "solo12", "talos", "every_joint"));

}  // namespace
}  // namespace kanesim

namespace kanesim {
namespace {

// One second of motion of a fixed-base arm (with its <dynamics> damping) from a random state
// against SciPy's DOP853 on Pinocchio's aba at rtol = atol = 1e-13 (urdf_robots.py; its run at
// 1e-12 differs by 7.6e-12 for UR5 and 4.6e-8 for Panda, whose light fingers make it stiffer).
// If this fails, the imported model's motion drifts from URDF's although single evaluations
// agree (a start value, the force law of <dynamics> over time, the integrator).
class ImportedTrajectory : public ::testing::TestWithParam<std::pair<const char*, double>> {};

TEST_P(ImportedTrajectory, FollowsPinocchioAndScipyOverOneSecond) {
  const auto [robot, tol] = GetParam();
  const std::string urdf = kData + "/" + (std::string(robot) == "ur5" ? "ur5_robot" : robot) + ".urdf";
  const test::CsvTable table = test::ReadCsvTable(kData + "/" + robot + "_traj.csv");
  const std::vector<std::string>& cols = table.names;
  const std::vector<std::vector<double>>& ref = table.rows;
  ASSERT_EQ(ref.size(), 11u);

  import::Options o;
  o.use_ros_package_path = false;
  o.mimic = false;  // as Pinocchio reads the file: Panda's second finger moves on its own
  import::Result imp = import::UrdfToMech(urdf, ReadText(urdf), o);
  ASSERT_TRUE(imp.ok) << imp.diagnostics;
  // The start state as start values of each joint (the URDF names are identifiers here).
  std::string mech = imp.mech;
  for (std::size_t c = 1; c < cols.size(); ++c) {
    const std::string joint = cols[c].substr(0, cols[c].size() - 2);
    if (cols[c].back() != 'q') continue;
    const std::size_t u = std::find(cols.begin(), cols.end(), joint + ".u") - cols.begin();
    std::size_t at = mech.find(" " + joint + "(axis");
    ASSERT_NE(at, std::string::npos) << joint;
    at = mech.find('(', at) + 1;
    char buf[96];
    std::snprintf(buf, sizeof buf, "q(start = %.17g), u(start = %.17g), ", ref[0][c], ref[0][u]);
    mech.insert(at, buf);
  }
  pipeline::RunSpec spec;
  spec.stop_time = 1.0;
  spec.interval = 0.1;
  spec.rtol = spec.atol = 1e-12;
  spec.energy_check = sim::EnergyCheck::kOff;
  pipeline::LoadResult lr = pipeline::LoadModel(pipeline::Source::Text(urdf + ".mech", mech), {}, spec);
  ASSERT_TRUE(lr.model) << lr.diagnostics;
  sim::MemorySink rows;
  sim::SimResult res = pipeline::Run(*lr.model, spec, rows);
  ASSERT_EQ(res.status, sim::SimResult::Status::kOk) << res.message;
  ASSERT_EQ(rows.rows.size(), ref.size());
  double worst = 0;
  for (std::size_t r = 0; r < ref.size(); ++r)
    for (std::size_t c = 1; c < cols.size(); ++c) {
      const auto k = std::find(rows.names.begin(), rows.names.end(), cols[c]) - rows.names.begin();
      ASSERT_LT(k, static_cast<long>(rows.names.size())) << cols[c];
      worst = std::max(worst, std::fabs(rows.rows[r][static_cast<std::size_t>(k)] - ref[r][c]));
    }
  EXPECT_LE(worst, tol) << robot;
  std::printf("%s: largest difference over 1 s %.2e\n", robot, worst);
}

INSTANTIATE_TEST_SUITE_P(FixedBaseArms, ImportedTrajectory,
                         ::testing::Values(std::make_pair("ur5", 1e-9), std::make_pair("panda", 5e-7)));

}  // namespace
}  // namespace kanesim
