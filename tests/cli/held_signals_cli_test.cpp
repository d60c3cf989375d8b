// `kanesim run` of held rows (docs/events.md "Outputs"): the CSV's acceleration and reaction
// columns of a joint resting on its stop read the held motion (a = 0, the stop's static
// torque), under the default solver path and --solver sparse alike, with the same events.
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "tests/support/cli_util.h"

namespace kanesim::clitest {
namespace {

// A rod (L = 1, m = 1) on its stop q_min = 0.2 from the start, driven by tau = 10 t: it leaves
// at t* = m g (L/2) cos 0.2 / 10 = 0.4807...; before, the stop carries m g (L/2) cos 0.2.
constexpr char kRod[] = R"(model P
  World world(g = {0, -9.81, 0});
  Revolute j1(axis = {0, 0, 1}, q(start = 0.2), q_min = 0.2, tau = 10 * time);
  Rod rod(L = 1, m = 1);
equation
  connect(world.frame_b, j1.frame_a);
  connect(j1.frame_b, rod.frame_a);
end P;
)";

// Rows of a CSV with columns time, j1.a, j1.reaction_torque[3].
std::vector<std::vector<double>> Rows(const std::string& path) {
  std::istringstream in(Slurp(path));
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "time,j1.a,j1.reaction_torque[3]");
  std::vector<std::vector<double>> rows;
  while (std::getline(in, line)) {
    std::vector<double> row;
    std::istringstream f(line);
    for (std::string x; std::getline(f, x, ',');) row.push_back(std::stod(x));
    rows.push_back(row);
  }
  return rows;
}

// If this fails, the CSV writes the free pendulum's acceleration (-14.4 rad/s^2 rising with
// tau) and no stop torque (0) while the joint rests on its stop, or --solver sparse differs.
TEST(HeldSignalsCli, ARestingJointWritesZeroAccelerationAndTheStopTorque) {
  const std::string d = Work("held_signals");
  Write(d + "/p.mech", kRod);
  const double statics = 9.81 * 0.5 * std::cos(0.2), t_leave = statics / 10;
  std::vector<std::vector<double>> first;
  for (const std::string solver : {"auto", "sparse"}) {
    Result r = Kanesim("run p.mech --solver " + solver +
                           " --stop-time 0.45 --interval 0.05 --rtol 1e-10 --atol 1e-10 -o " + solver +
                           ".csv --output j1.a --output 'j1.reaction_torque[3]'",
                       d);
    ASSERT_EQ(r.rc, 0) << r.err;
    const std::vector<std::vector<double>> rows = Rows(d + "/" + solver + ".csv");
    ASSERT_EQ(rows.size(), 10u) << solver;
    for (const std::vector<double>& row : rows) {
      ASSERT_LT(row[0], t_leave);
      EXPECT_EQ(row[1], 0.0) << solver << " t = " << row[0];
      EXPECT_NEAR(row[2], statics, 1e-12) << solver << " t = " << row[0];
    }
  }
}

}  // namespace
}  // namespace kanesim::clitest
