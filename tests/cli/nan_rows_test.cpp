// Item 12 of issue 24: a model that turns NaN at some time must stop with exit 2 at
// about that time, and every output instant before it must be on disk, whichever the
// integrator and the solver path (a stage of a long DOP853 step probing past the NaN
// used to end the run at the step's start: rows to t = 0.1 for a NaN from t = 0.35), and
// in a sweep's trajectory files too.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

#include "tests/support/cli_util.h"

namespace kanesim::clitest {
namespace {

constexpr double kInterval = 0.1;

// A pendulum whose hinge torque is `tau` (NaN past some time or state).
// `tau` is dimensionless: k (N.m) carries the torque's unit and ts (s) makes times
// dimensionless, so that the model passes the unit check (docs/language.md "Units").
std::string Model(const std::string& tau) {
  return "model NaNPendulum\n  parameter Real c(unit = \"s\") = 0.35;\n"
         "  parameter Real k(unit = \"N.m\") = 1;\n  parameter Real ts(unit = \"s\") = 1;\n  World world;\n"
         "  Revolute hinge(axis = {0, 0, 1}, q(start = 0));\n  Rod rod(L = 1, m = 1);\nequation\n"
         "  connect(world.frame_b, hinge.frame_a);\n  connect(hinge.frame_b, rod.frame_a);\n"
         "  hinge.tau = k * (" + tau + ");\n  annotation(experiment(StopTime = 1, Interval = 0.1));\nend NaNPendulum;\n";
}

// The time in "numerical failure at t = <time>:".
double FailTime(const std::string& err) {
  const std::string key = "numerical failure at t = ";
  size_t at = err.find(key);
  return at == std::string::npos ? std::nan("") : std::stod(err.substr(at + key.size()));
}

// Times of the rows of a CSV.
std::vector<double> Times(const std::string& path) {
  std::vector<double> t;
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  while (std::getline(in, line)) t.push_back(std::stod(line));
  return t;
}

// Every instant k * kInterval before `fail` is a row, and no row is at or past it.
void ExpectRowsBefore(const std::vector<double>& t, double fail, const std::string& what) {
  const int expected = static_cast<int>(std::floor(fail / kInterval - 1e-9)) + 1;
  EXPECT_EQ(static_cast<int>(t.size()), expected) << what << ": failure at " << fail;
  for (size_t k = 0; k < t.size(); ++k) EXPECT_NEAR(t[k], kInterval * static_cast<double>(k), 1e-12) << what;
}

TEST(NaNRows, EveryRowBeforeATimeNaNIsKeptByEveryIntegratorAndPath) {
  std::string d = Work("nan_time");
  Write(d + "/m.mech", Model("sqrt((c - time) / ts)"));
  for (double c : {0.35, 0.55, 0.72})
    for (std::string integrator : {"auto", "dop853", "cvode", "cvode-bdf", "arkode", "ida"})
      for (std::string solver : {"dense", "sparse", "recursive"}) {
        const std::string what = "c=" + std::to_string(c) + " " + integrator + " " + solver;
        Result r = Kanesim("run m.mech --set c=" + std::to_string(c) + " --integrator " + integrator + " --solver " +
                               solver + " -o out.csv",
                           d);
        ASSERT_EQ(r.rc, 2) << what << "\n" << r.err;
        const double fail = FailTime(r.err);
        EXPECT_GE(fail, c) << what;
        EXPECT_LT(fail, c + 1e-3) << what << ": the failure is reported where the NaN begins";
        EXPECT_TRUE(Has(r.err, "NaN")) << what << "\n" << r.err;
        ExpectRowsBefore(Times(d + "/out.csv"), fail, what);
      }
}

// The message names the expression that turned NaN, as the model's text prints it: a
// joint force, an output and a prescribed motion (each tape keeps its roots' texts).
TEST(NaNRows, TheMessageNamesTheExpressionThatTurnedNaN) {
  std::string d = Work("nan_text");
  Write(d + "/force.mech", Model("sqrt((c - time) / ts)"));
  const std::string rest =
      "  parameter Real c(unit = \"s\") = 0.35;\n  parameter Real ts(unit = \"s\") = 1;\n  World world;\n"
      "  Revolute hinge(axis = {0, 0, 1}, q(start = 0));\n  Rod rod(L = 1, m = 1);\n";
  const std::string joints = "  connect(world.frame_b, hinge.frame_a);\n  connect(hinge.frame_b, rod.frame_a);\n";
  const std::string end = "  annotation(experiment(StopTime = 1, Interval = 0.1));\nend M;\n";
  Write(d + "/output.mech", "model M\n" + rest + "  output Real y = sqrt((c - time) / ts);\nequation\n" + joints + end);
  Write(d + "/motion.mech", "model M\n" + rest + "equation\n" + joints + "  hinge.q = sqrt((c - time) / ts);\n" + end);
  const std::pair<const char*, const char*> cases[] = {
      {"force.mech", "NaN from expression: force of joint 'hinge' tau = (k * sqrt(((c - time) / ts))) at time "},
      {"output.mech", "NaN from expression: output 'y' = sqrt(((c - time) / ts)) at time "},
      {"motion.mech", "NaN from expression: prescribed motion hinge.q = sqrt(((c - time) / ts)) at time "}};
  for (const auto& [file, message] : cases) {
    Result r = Kanesim(std::string("run ") + file + " -o out.csv", d);
    EXPECT_EQ(r.rc, 2) << file << "\n" << r.err;
    EXPECT_TRUE(Has(r.err, message)) << file << "\n" << r.err;
  }
}

// A run killed from outside (SIGKILL: no handler, no flush) leaves its rows so far in the
// temporary beside the output (out.csv.tmp.<host>.<pid>: recognizably not a finished output;
// out.csv itself appears only when a run ends, issue 38), and they are whole rows, in order,
// plus at most one last row cut short: the writer gathers rows and writes them in one
// piece per 50 ms (never a row cut by a full stdio buffer), but Linux lets SIGKILL end a
// write(2) to a file between two pages (measured: 1 file in 40 killed at random ended
// inside a row; a reader drops a last line without its '\n', as with a sweep's summary).
// Wrong if a row is missing or cut in the middle of the file, or if out.csv holds a part.
TEST(NaNRows, AKilledRunLeavesWholeRowsOnly) {
  std::string d = Work("killed");
  for (double after : {0.3, 0.7}) {
    for (const auto& e : std::filesystem::directory_iterator(d)) std::filesystem::remove(e.path());
    // Killed `after` seconds once its first row is on disk (however slow the machine).
    std::system(("cd '" + d + "' && { '" + Bin() + "' run '" + kSrc +
                 "/examples/chain.mech' --set N=20 --stop-time 1e4 --interval 1e-3 -o out.csv 2>/dev/null & pid=$!; "
                 "for i in $(seq 600); do [ \"$(cat out.csv.tmp.* 2>/dev/null | wc -l)\" -ge 2 ] && break; sleep 0.05; "
                 "done; sleep " + std::to_string(after) + "; kill -KILL $pid; wait $pid; }")
                    .c_str());
    EXPECT_FALSE(std::filesystem::exists(d + "/out.csv")) << "a killed run left a partial out.csv";
    std::string temp;
    for (const auto& e : std::filesystem::directory_iterator(d))
      if (e.path().filename().string().starts_with("out.csv.tmp.")) temp = e.path().string();
    ASSERT_FALSE(temp.empty()) << "the rows so far are in the temporary";
    std::string text = Slurp(temp);
    ASSERT_FALSE(text.empty()) << "killed " << after << " s after its first row";
    text.erase(text.rfind('\n') + 1);  // a last row cut short by the kill
    std::istringstream in(text);
    std::string line;
    std::getline(in, line);
    const long fields = std::count(line.begin(), line.end(), ',');
    long k = 0;
    while (std::getline(in, line)) {
      ASSERT_EQ(std::count(line.begin(), line.end(), ','), fields) << "row " << k << ": " << line;
      ASSERT_NEAR(std::stod(line), 1e-3 * static_cast<double>(k), 1e-9) << "row " << k;
      ++k;
    }
    EXPECT_GE(k, 1) << "the first row is written at once";
  }
}

// A NaN that depends on the state (the angle passing a value), not on time.
TEST(NaNRows, EveryRowBeforeAStateNaNIsKept) {
  std::string d = Work("nan_state");
  Write(d + "/m.mech", Model("10 + sqrt(0.4 - hinge.q)"));  // driven forward, NaN once q > 0.4 (t ~ 0.23)
  for (std::string integrator : {"dop853", "cvode", "arkode", "ida"}) {
    Result r = Kanesim("run m.mech --integrator " + integrator + " -o out.csv", d);
    ASSERT_EQ(r.rc, 2) << integrator << "\n" << r.err;
    ExpectRowsBefore(Times(d + "/out.csv"), FailTime(r.err), integrator);
  }
}

// In a sweep: the failed scenario's row says when, and its trajectory file keeps every
// row before that time.
TEST(NaNRows, SweepTrajectoriesKeepTheRowsBeforeTheFailure) {
  std::string d = Work("nan_sweep");
  Write(d + "/m.mech", Model("sqrt((c - time) / ts)"));
  Result r = Kanesim("sweep m.mech --grid c=0.35,0.55,2 --metric final:hinge.q --trajectories --no-progress -o out", d);
  ASSERT_EQ(r.rc, 2) << r.err;
  for (int id : {0, 1}) {
    const std::vector<double> t = Times(d + "/out/trajectories/scenario_" + std::to_string(id) + ".csv");
    ExpectRowsBefore(t, id == 0 ? 0.35 + 1e-6 : 0.55 + 1e-6, "scenario " + std::to_string(id));
  }
  EXPECT_EQ(Times(d + "/out/trajectories/scenario_2.csv").size(), 11u);
}

}  // namespace
}  // namespace kanesim::clitest
