// Issue 42: a model's `input`, given by `kanesim run --input-file` or `--set`. If these fail,
// a table does not drive the model as the same function written in the file does, its
// interpolation is not the one asked for, a time outside it is extrapolated, or an input
// left without a value runs (or is not named where it is declared).
#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <vector>

#include "tests/support/cli_util.h"

namespace kanesim::clitest {
namespace {

// A rod on a revolute joint, its torque `torque`, with the declarations `decls`.
std::string Pendulum(const std::string& decls, const std::string& torque, const std::string& extra = "") {
  return "model P\n" + decls +
         "  World world(g = {0, -9.81, 0});\n"
         "  Revolute j(axis = {0, 0, 1}, q(start = 0.5), u(start = 0));\n"
         "  Rod rod(L = 1, m = 1);\n"
         "  Revolute k(axis = {0, 0, 1});\n"
         "  Rod tip(L = 0.5, m = 0.5);\n"
         "equation\n"
         "  connect(world.frame_b, j.frame_a);\n"
         "  connect(j.frame_b, rod.frame_a);\n"
         "  connect(rod.frame_b, k.frame_a);\n"
         "  connect(k.frame_b, tip.frame_a);\n"
         "  j.tau = " + torque + ";\n" + extra +
         "  annotation(experiment(StopTime = 3, Interval = 0.25));\n"
         "end P;\n";
}

// The numbers of the last row of a CSV.
std::vector<double> LastRow(const std::string& csv) {
  std::istringstream in(csv);
  std::string line, last;
  while (std::getline(in, line))
    if (!line.empty()) last = line;
  std::vector<double> v;
  std::istringstream row(last);
  std::string cell;
  while (std::getline(row, cell, ',')) v.push_back(std::stod(cell));
  return v;
}

void ExpectNear(const std::vector<double>& a, const std::vector<double>& b, double tol, const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (size_t i = 0; i < a.size(); ++i) EXPECT_NEAR(a[i], b[i], tol) << what << " column " << i;
}

const char* kRun = " --integrator dop853 --rtol 1e-10 --atol 1e-10";

// The table's rows (0, 0), (1, 2), (2, 0), (3, 1): linearly interpolated, the triangle written
// as an equation; held, the staircase. Both also drive a prescribed motion (k.q = the input
// / 4: its speed from the table's slope) the same as the written function does.
TEST(InputFile, TableEqualsTheSameFunctionWrittenInTheModel) {
  const std::string d = Work("input_file_equal");
  Write(d + "/linear.csv", "time,tau\n0,0\n1,2\n2,0\n3,1\n");
  Write(d + "/hold.csv", "# interpolation = hold\ntime,tau\n0,0\n1,2\n2,0\n3,1\n");
  Write(d + "/m.mech", Pendulum("  input Real tau;\n", "tau", "  k.q = tau / 4;\n"));
  const std::string tri = "(if time < 1 then 2 * time elseif time < 2 then 2 - 2 * (time - 1) else time - 2)";
  const std::string stair = "(if time < 1 then 0 elseif time < 2 then 2 elseif time < 3 then 0 else 1)";
  Write(d + "/linear.mech", Pendulum("", tri, "  k.q = " + tri + " / 4;\n"));
  Write(d + "/hold.mech", Pendulum("", stair, "  k.q = " + stair + " / 4;\n"));
  for (const std::string mode : {"linear", "hold"}) {
    Result want = Kanesim("run " + mode + ".mech -o want_" + mode + ".csv" + kRun, d);
    ASSERT_EQ(want.rc, 0) << want.err;
    Result got = Kanesim("run m.mech --input-file " + mode + ".csv -o got_" + mode + ".csv" + kRun, d);
    ASSERT_EQ(got.rc, 0) << got.err;
    // The same function, differently rounded: the runs agree to the tolerance's reach.
    ExpectNear(LastRow(Slurp(d + "/got_" + mode + ".csv")), LastRow(Slurp(d + "/want_" + mode + ".csv")), 1e-7, mode);
  }
  // The two interpolations differ (the table is read as asked).
  const std::vector<double> a = LastRow(Slurp(d + "/got_linear.csv")), b = LastRow(Slurp(d + "/got_hold.csv"));
  EXPECT_GT(std::abs(a[1] - b[1]), 1e-2);
  // A column's own ":hold" overrides the file's default.
  Write(d + "/hold_col.csv", "time,tau:hold\n0,0\n1,2\n2,0\n3,1\n");
  Result col = Kanesim("run m.mech --input-file hold_col.csv -o got_col.csv" + std::string(kRun), d);
  ASSERT_EQ(col.rc, 0) << col.err;
  EXPECT_EQ(Slurp(d + "/got_col.csv"), Slurp(d + "/got_hold.csv"));
}

// If this fails, --set does not give an input its value, or an array input's columns are
// not its elements.
TEST(InputFile, SetAndArrayInputs) {
  const std::string d = Work("input_file_set");
  Write(d + "/m.mech", Pendulum("  input Real tau;\n", "tau"));
  Write(d + "/const.mech", Pendulum("", "0.75"));
  Result want = Kanesim("run const.mech -o want.csv", d);
  ASSERT_EQ(want.rc, 0) << want.err;
  Result got = Kanesim("run m.mech --set tau=0.75 -o got.csv", d);
  ASSERT_EQ(got.rc, 0) << got.err;
  EXPECT_EQ(Slurp(d + "/got.csv"), Slurp(d + "/want.csv"));
  Write(d + "/arr.mech", Pendulum("  input Real f[2];\n", "f[1] - f[2]"));
  Write(d + "/f.csv", "time,f[2],f[1]\n0,0.25,1\n3,0.25,1\n");
  Result arr = Kanesim("run arr.mech --input-file f.csv -o arr.csv", d);
  ASSERT_EQ(arr.rc, 0) << arr.err;
  EXPECT_EQ(Slurp(d + "/arr.csv"), Slurp(d + "/want.csv"));
}

// If this fails, a run reads a table outside its rows or runs with an input nobody gives.
TEST(InputFile, OutOfRangeAndUnconnectedAreErrors) {
  const std::string d = Work("input_file_errors");
  Write(d + "/m.mech", Pendulum("  input Real tau;\n", "tau"));
  Write(d + "/short.csv", "time,tau\n0,0\n2,1\n");
  Result r = Kanesim("run m.mech --input-file short.csv -o out.csv", d);
  EXPECT_EQ(r.rc, 1) << r.err;
  EXPECT_TRUE(Has(r.err, "short.csv covers 0 to 2, not the run's 0 to 3")) << r.err;
  Result u = Kanesim("run m.mech -o out.csv", d);
  EXPECT_EQ(u.rc, 1) << u.err;
  EXPECT_TRUE(Has(u.err, "m.mech:2:14: error[E239]: input 'tau' is not connected")) << u.err;
  Write(d + "/other.csv", "time,torque\n0,0\n3,1\n");
  Result n = Kanesim("run m.mech --input-file other.csv -o out.csv", d);
  EXPECT_EQ(n.rc, 1) << n.err;
  EXPECT_TRUE(Has(n.err, "other.csv:1:6: 'torque' is not an input of the model (its inputs: tau)")) << n.err;
}


// If this fails, a sweep's --resume or a golden test does not see an edited input table: the
// rows would mix (or pass against) two different drives of the model.
TEST(InputFile, SweepsAndGoldenTestsRecordTheTable) {
  const std::string d = Work("input_file_hash");
  Write(d + "/m.mech", Pendulum("  parameter Real gain = 1;\n  input Real tau;\n", "gain * tau"));
  Write(d + "/u.csv", "time,tau\n0,0\n3,1\n");
  const std::string sweep = "sweep m.mech --input-file u.csv --grid gain=1,2 --metric final:j.q --no-progress -o out";
  Result first = Kanesim(sweep, d);
  ASSERT_EQ(first.rc, 0) << first.err;
  Result same = Kanesim(sweep + " --resume", d);
  EXPECT_EQ(same.rc, 0) << same.err;
  Write(d + "/u.csv", "time,tau\n0,0\n3,2\n");
  Result edited = Kanesim(sweep + " --resume", d);
  EXPECT_EQ(edited.rc, 1) << edited.err;
  EXPECT_TRUE(Has(edited.err, "cannot resume") && Has(edited.err, "u.csv")) << edited.err;

  Write(d + "/g.toml", "model = \"m.mech\"\ninput_files = [\"u.csv\"]\n[run]\nstop_time = 1\n");
  Result update = Kanesim("test g.toml --update", d);
  ASSERT_EQ(update.rc, 0) << update.err << update.out;
  Result pass = Kanesim("test g.toml", d);
  EXPECT_EQ(pass.rc, 0) << pass.err << pass.out;
  Write(d + "/u.csv", "time,tau\n0,0\n3,5\n");
  Result changed = Kanesim("test g.toml", d);
  EXPECT_NE(changed.rc, 0) << changed.out;
  EXPECT_TRUE(Has(changed.out + changed.err, "settings")) << changed.out << changed.err;
}

}  // namespace
}  // namespace kanesim::clitest
