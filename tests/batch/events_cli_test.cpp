// Sweeps and golden tests of a model with events, through the binary (issue 41): a ball
// bouncing by a when clause (reinit(p.u, -e pre(p.u)), dropped from h). Its position at T
// has a closed form: impacts at t1 = sqrt(2h/g), then every 2 e^k t1 later, each leaving at
// e^k g t1.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "batch/csv_util.h"
#include "batch/summary.h"

namespace kanesim::batch {
namespace {

const std::string kBin = KANESIM_BIN;
constexpr double kG = 9.81;

std::string Work(const std::string& name) {
  std::string d = std::string(KANESIM_WORK_DIR) + "/" + name;
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  return d;
}

// The exit code of `cmd` run in `dir`, its output in dir/out.txt.
int Sh(const std::string& dir, const std::string& cmd) {
  int rc = std::system(("cd " + dir + " && " + cmd + " >out.txt 2>&1").c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

std::string Slurp(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void WriteBall(const std::string& dir) {
  std::ofstream(dir + "/ball.mech") << "model Ball\n  parameter Real e = 0.8;\n  parameter Real h = 1;\n"
                                       "  World world(g = {0, -9.81, 0});\n"
                                       "  Prismatic p(axis = {0, 1, 0}, q(start = h));\n"
                                       "  Body b(m = 1, I = diagonal({1, 1, 1}));\nequation\n"
                                       "  connect(world.frame_b, p.frame_a);\n  connect(p.frame_b, b.frame_a);\n"
                                       "  when p.q < 0 then\n    reinit(p.u, -e * pre(p.u));\n  end when;\n"
                                       "  annotation(experiment(StopTime = 1.5, Interval = 0.1, Tolerance = 1e-12));\n"
                                       "end Ball;\n";
}

// The ball's height at time T (closed form above).
double Height(double h, double e, double T) {
  const double t1 = std::sqrt(2 * h / kG);
  if (T <= t1) return h - kG * T * T / 2;
  double t = t1, v = kG * t1;
  while (t + 2 * e * v / kG < T) t += 2 * e * v / kG, v *= e;
  v *= e;
  return v * (T - t) - kG * (T - t) * (T - t) / 2;
}

// If this fails, a sweep over a model with events loses them (the final heights differ
// from the bounces' closed form) or its trajectories lack the events' two rows.
TEST(EventsCli, SweepFinalHeightsFollowTheBounces) {
  const std::string d = Work("events_sweep");
  WriteBall(d);
  ASSERT_EQ(Sh(d, kBin + " sweep ball.mech --grid h=1,2 --grid e=0.6,0.8 --metric final:p.q -o sw --trajectories "
                         "--no-progress -j1"),
            0)
      << Slurp(d + "/out.txt");
  SummaryTable t;
  std::string err;
  ASSERT_TRUE(ReadSummary(d + "/sw/summary.csv", &t, &err)) << err;
  const std::vector<std::string> head = SplitCsvLine(t.header);
  auto col = [&](const std::string& n) { return static_cast<size_t>(std::find(head.begin(), head.end(), n) - head.begin()); };
  ASSERT_EQ(t.rows.size(), 4u);
  for (const auto& [id, line] : t.rows) {
    const std::vector<std::string> f = SplitCsvLine(line);
    const double h = std::stod(f[col("h")]), e = std::stod(f[col("e")]);
    EXPECT_EQ(f[col("status")], "ok") << line;
    EXPECT_NEAR(std::stod(f[col("final:p.q")]), Height(h, e, 1.5), 1e-9) << "h " << h << " e " << e;
    std::ifstream tr(d + "/sw/trajectories/scenario_" + std::to_string(id) + ".csv");
    std::string row;
    std::vector<double> times;
    std::getline(tr, row);
    while (std::getline(tr, row)) times.push_back(std::stod(row));
    std::vector<double> events;  // the times written twice
    for (size_t k = 1; k < times.size(); ++k)
      if (times[k] == times[k - 1]) events.push_back(times[k]);
    ASSERT_FALSE(events.empty()) << "h " << h;
    EXPECT_NEAR(events[0], std::sqrt(2 * h / kG), 1e-9) << "h " << h << ": the first impact's two rows";
  }
}

// If this fails, `kanesim test` cannot keep a golden of a model with events (before: the
// golden it recorded was refused as corrupt), or a changed restitution passes.
TEST(EventsCli, GoldenOfABouncingBall) {
  const std::string d = Work("events_golden");
  WriteBall(d);
  std::ofstream(d + "/ball.toml") << "model = \"ball.mech\"\n[tolerance]\ndefault = { abs = 1e-9, rel = 1e-8 }\n";
  ASSERT_EQ(Sh(d, kBin + " test ball.toml --update"), 0) << Slurp(d + "/out.txt");
  EXPECT_EQ(Sh(d, kBin + " test ball.toml"), 0) << Slurp(d + "/out.txt");
  EXPECT_NE(Slurp(d + "/out.txt").find("PASS  ball"), std::string::npos) << Slurp(d + "/out.txt");
  EXPECT_EQ(Sh(d, kBin + " test ball.toml --set e=0.799999"), 3) << Slurp(d + "/out.txt");
}

}  // namespace
}  // namespace kanesim::batch
