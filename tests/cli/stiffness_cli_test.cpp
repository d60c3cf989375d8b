// DOP853's stiff hand-over (docs/integrators.md "The automatic choice") through `kanesim run`:
// the `--stats` report names what ran, and `--sensitivity` hands over as a plain run does.
// If these fail, --stats says DOP853 for a run CVODE-BDF finished, or a stiff sensitivity run
// under auto crawls through DOP853 (or its columns differ from DOP853's all the way).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>

#include "tests/support/cli_util.h"
#include "tests/support/csv_table.h"

namespace kanesim::clitest {
namespace {

// A light link held by stiff joint friction: auto picks DOP853, which finds it stiff at t ~ 0.4.
const std::string kModel = kSrc + "/tests/sim/models/stiff_friction.mech";
constexpr double kTol = 1e-8;

// The count on `--stats`' "right-hand sides" line (-1 when there is none).
long RhsEvals(const std::string& stats) {
  const size_t at = stats.find("  right-hand sides ");
  return at == std::string::npos ? -1 : std::strtol(stats.c_str() + at + 19, nullptr, 10);
}

// `run --stats` of the model (auto, or an explicit DOP853): the header names DOP853, then
// CVODE-BDF from the instant of the hand-over; the explicit choice only notes the stiffness.
TEST(StiffnessCli, StatsNameTheMethodsThatRan) {
  const std::string d = Work("stiff_stats");
  Result a = Kanesim("run " + kModel + " --rtol 1e-8 --atol 1e-8 --stats -o out.csv", d);
  ASSERT_EQ(a.rc, 0) << a.err;
  EXPECT_TRUE(Has(a.err, "integrator                 DOP853 \u2192 CVODE-BDF at t = 0.39")) << a.err;
  EXPECT_TRUE(Has(a.err, ", stiffness detected\n")) << a.err;
  EXPECT_TRUE(Has(a.err, "  then                     CVODE: variable-order BDF")) << a.err;
  EXPECT_TRUE(Has(a.err, "past DOP853's stability boundary 6.1\n")) << a.err;
  EXPECT_TRUE(Has(a.err, "(dense LU)")) << a.err;  // CVODE-BDF's linear solver, not "none"

  Result e = Kanesim("run " + kModel + " --rtol 1e-8 --atol 1e-8 --integrator dop853 --stats -o out.csv", d);
  ASSERT_EQ(e.rc, 0) << e.err;
  EXPECT_TRUE(Has(e.err, "integrator                 DOP853\n")) << e.err;
  EXPECT_TRUE(Has(e.err, "(not switched: DOP853 was chosen explicitly)")) << e.err;
  EXPECT_FALSE(Has(e.err, "CVODE")) << e.err;
}

// Under auto, stiffness found with fewer than 100 DOP853 steps to the stop: DOP853 finishes
// (not worth a hand-over), and the report says why, not that DOP853 was chosen explicitly.
TEST(StiffnessCli, StatsSayWhyAutoDidNotSwitch) {
  const std::string d = Work("stiff_late");
  Result a = Kanesim("run " + kModel + " --rtol 1e-8 --atol 1e-8 --stop-time 0.4 --stats -o out.csv", d);
  ASSERT_EQ(a.rc, 0) << a.err;
  EXPECT_TRUE(Has(a.err, "integrator                 DOP853\n")) << a.err;
  EXPECT_TRUE(Has(a.err, "(not switched: fewer than 100 of its steps were left)")) << a.err;
  EXPECT_FALSE(Has(a.err, "chosen explicitly")) << a.err;
}

// `--sensitivity` under auto: handed over (the report says so) at a small fraction of
// DOP853's evaluations, and every column, the derivatives too, equal to DOP853's own run
// (which never switches) to the tolerance's reach.
TEST(StiffnessCli, SensitivitiesHandOverAsARunDoes) {
  const std::string d = Work("stiff_sens");
  const std::string run = "run " + kModel + " --rtol 1e-8 --atol 1e-8 --sensitivity friction,damping --stats";
  Result a = Kanesim(run + " -o auto.csv", d);
  Result e = Kanesim(run + " --integrator dop853 -o dop.csv", d);
  ASSERT_EQ(a.rc, 0) << a.err;
  ASSERT_EQ(e.rc, 0) << e.err;
  EXPECT_TRUE(Has(a.err, "DOP853 \u2192 CVODE-BDF at t = ")) << a.err;
  const long fa = RhsEvals(a.err), fe = RhsEvals(e.err);
  ASSERT_GT(fa, 0);
  EXPECT_LT(fa, 0.1 * static_cast<double>(fe)) << "auto " << fa << " f, DOP853 " << fe;

  const test::CsvTable ta = test::ReadCsvTable(d + "/auto.csv"), te = test::ReadCsvTable(d + "/dop.csv");
  ASSERT_EQ(ta.names, te.names);
  ASSERT_EQ(ta.names.size(), 7u);  // time, q, u and their derivatives by both parameters
  ASSERT_EQ(ta.rows.size(), 101u);
  ASSERT_EQ(te.rows.size(), 101u);
  for (size_t c = 1; c < ta.names.size(); ++c) {
    double diff = 0.0, scale = 0.0;
    for (size_t k = 0; k < ta.rows.size(); ++k) {
      diff = std::max(diff, std::abs(ta.rows[k][c] - te.rows[k][c]));
      scale = std::max(scale, std::abs(te.rows[k][c]));
    }
    EXPECT_LT(diff, 1e3 * kTol * (1.0 + scale)) << ta.names[c];
  }
}

}  // namespace
}  // namespace kanesim::clitest
