// Issue 40: start values set from outside (`--set j.q.start=X`, `--grid j.q.start=...`)
// run exactly what the file edited to start = X runs (before: E201 "no member 'start'").
#include <gtest/gtest.h>

#include <sstream>

#include "tests/support/cli_util.h"

namespace kanesim::clitest {
namespace {

// The pendulum of examples/double_pendulum.mech with the shoulder's start written as `q0`.
std::string Pendulum(const std::string& q0) {
  std::string text = Slurp(kSrc + "/examples/double_pendulum.mech");
  const std::string from = "shoulder(axis = {0, 0, 1}, q(start = pi / 2)";
  const size_t at = text.find(from);
  if (at == std::string::npos) return "";
  return text.replace(at, from.size(), "shoulder(axis = {0, 0, 1}, q(start = " + q0 + ")");
}

// The last line of a CSV.
std::string LastRow(const std::string& csv) {
  std::istringstream in(csv);
  std::string line, last;
  while (std::getline(in, line))
    if (!line.empty()) last = line;
  return last;
}

// If this fails, a start set from outside differs from the same start written in the file.
TEST(SetStart, RunEqualsTheEditedFileBitForBit) {
  const std::string d = Work("set_start_run");
  Write(d + "/m.mech", Pendulum("pi / 2"));
  for (const std::string x : {"0.3", "-1.25", "2.0000000000000004"}) {
    Write(d + "/edited.mech", Pendulum(x));
    Result want = Kanesim("run edited.mech --stop-time 2 -o want.csv", d);
    ASSERT_EQ(want.rc, 0) << want.err;
    Result got = Kanesim("run m.mech --stop-time 2 --set shoulder.q.start=" + x + " -o got.csv", d);
    ASSERT_EQ(got.rc, 0) << got.err;
    EXPECT_EQ(Slurp(d + "/got.csv"), Slurp(d + "/want.csv")) << x;
    // The first row starts there (not at the file's pi / 2).
    const std::string csv = Slurp(d + "/got.csv");
    const size_t row = csv.find("\n0,");
    ASSERT_NE(row, std::string::npos) << csv.substr(0, 200);
    EXPECT_EQ(std::stod(csv.substr(row + 3)), std::stod(x)) << x;
  }
}

// If this fails, a sweep over a start value is refused or its summary disagrees with the
// individual runs (each row's final state is the last row of `run --set`).
TEST(SetStart, SweepSummaryEqualsIndividualRuns) {
  const std::string d = Work("set_start_sweep");
  Write(d + "/m.mech", Pendulum("pi / 2"));
  Result sw = Kanesim("sweep m.mech --stop-time 1 --grid shoulder.q.start=0.25:0.25:0.75 --grid elbow.u.start=-1:2:1"
                      " --metric final:shoulder.q --metric final:elbow.u --no-progress -o out",
                      d);
  ASSERT_EQ(sw.rc, 0) << sw.err;
  std::istringstream rows(Slurp(d + "/out/summary.csv"));
  std::string line;
  std::getline(rows, line);
  ASSERT_EQ(line.rfind("id,shoulder.q.start,elbow.u.start,", 0), 0u) << line;
  int n = 0;
  while (std::getline(rows, line)) {
    std::vector<std::string> f;
    std::istringstream cells(line);
    for (std::string c; std::getline(cells, c, ',');) f.push_back(c);
    ASSERT_GE(f.size(), 11u) << line;
    EXPECT_EQ(f[6], "ok") << line;
    Result one = Kanesim("run m.mech --stop-time 1 --set shoulder.q.start=" + f[1] + " --set elbow.u.start=" + f[2] +
                             " --output shoulder.q --output elbow.u",
                         d);
    ASSERT_EQ(one.rc, 0) << one.err;
    EXPECT_EQ(LastRow(one.out), "1," + f[9] + "," + f[10]) << line;
    ++n;
  }
  EXPECT_EQ(n, 6);
}

}  // namespace
}  // namespace kanesim::clitest
