// Item 7 of issue 24: the output grid's row count is computed from doubles; a count past
// the limit (kMaxOutputRows) or one that would overflow a conversion must be refused
// with a diagnostic and exit 1 by every command (run, sweep, test), never run as one row.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "sim/csv.h"
#include "sim/integrator.h"
#include "tests/support/cli_util.h"

namespace kanesim::clitest {
namespace {

const std::string kSpring = kSrc + "/examples/spring_mass.mech";  // experiment Interval 0.01, StopTime 10

struct Member {
  std::string args;  // --start-time/--stop-time/--interval options
  double start, stop, interval;  // the same for a golden spec (interval <= 0: not given)
};

// Grids too large, by their count (rows > 1e8, past 2^63, or infinite) or by an
// interval too small for the size of the times.
const std::vector<Member> kTooLarge = {
    {"--stop-time 1e19", 0, 1e19, -1},                         // 1e21 rows: past a long
    {"--interval 1e-19", 0, 10, 1e-19},                        // 1e20 rows
    {"--stop-time 1e9 --interval 0.001", 0, 1e9, 0.001},       // 1e12 rows
    {"--stop-time 1.5e6 --interval 0.01", 0, 1.5e6, 0.01},     // 1.5e8: just past the limit
    {"--start-time -1e19 --stop-time 1e19 --interval 1", -1e19, 1e19, 1},
    {"--start-time -1e308 --stop-time 1e308", -1e308, 1e308, -1},  // the span overflows
    {"--start-time 1e15 --stop-time 1000000000000000.25 --interval 0.001", 1e15, 1000000000000000.25, 0.001},
};

bool Refused(const Result& r) {
  return r.rc == 1 && (Has(r.err + r.out, "more than the limit") || Has(r.err + r.out, "too small for times") ||
                       Has(r.err + r.out, "out of range"));
}

// Wrong if a grid past the limit runs (or exits 0 with the start row only).
TEST(OutputGrid, RunRefusesEveryGridPastTheLimit) {
  std::string d = Work("grid_run");
  for (const Member& m : kTooLarge) {
    Result r = Kanesim("run " + kSpring + " " + m.args + " -o out.csv", d);
    EXPECT_TRUE(Refused(r)) << m.args << "\nrc " << r.rc << "\n" << r.err;
    EXPECT_FALSE(std::filesystem::exists(d + "/out.csv")) << m.args << ": an output was started";
    std::filesystem::remove(d + "/out.csv");
  }
}

// Wrong if a sweep records such a scenario as `ok` with the start value as its final
// metric, or refuses only some of them (the sweep's own times, or a scenario's stop_time).
TEST(OutputGrid, SweepRefusesEveryGridPastTheLimit) {
  std::string d = Work("grid_sweep");
  for (const Member& m : kTooLarge) {
    Result r = Kanesim("sweep " + kSpring + " --grid mass=1,2 --metric final:slider.q --no-progress " + m.args +
                           " -o out",
                       d);
    EXPECT_TRUE(Refused(r)) << m.args << "\nrc " << r.rc << "\n" << r.err;
    EXPECT_FALSE(Has(Slurp(d + "/out/summary.csv"), ",ok,")) << m.args;
    std::filesystem::remove_all(d + "/out");
  }
  for (std::string stop : {"1e19", "2e6"}) {  // one scenario's own stop time, in a list
    Write(d + "/list.csv", "mass,stop_time\n1,1\n2," + stop + "\n");
    Result r = Kanesim("sweep " + kSpring + " --list list.csv --metric final:slider.q --no-progress -o out", d);
    EXPECT_TRUE(Refused(r) && Has(r.err, "scenario 1")) << stop << "\n" << r.err;
  }
}

// Wrong if a golden spec with such times records or compares one instant, or reports
// its own mistake as a regression (exit 3) instead of an error (exit 1).
TEST(OutputGrid, GoldenSpecRefusesEveryGridPastTheLimit) {
  std::string d = Work("grid_golden");
  for (const Member& m : kTooLarge) {
    std::string spec = "model = \"" + kSpring + "\"\n[run]\nstart_time = " + sim::FormatNumber(m.start) +
                       "\nstop_time = " + sim::FormatNumber(m.stop) + "\n";
    if (m.interval > 0) spec += "interval = " + sim::FormatNumber(m.interval) + "\n";
    Write(d + "/g.toml", spec);
    for (std::string update : {"--update ", ""}) {
      Result r = Kanesim("test " + update + "g.toml", d);
      EXPECT_EQ(r.rc, 1) << update << m.args << "\n" << r.out << r.err;
      EXPECT_TRUE(Has(r.out, "ERROR")) << r.out;
      EXPECT_FALSE(std::filesystem::exists(d + "/g.csv")) << m.args << ": a golden was recorded";
    }
  }
}

// The other side of the limit: large times with a sensible interval run to exactly the
// stop time (a body at rest: the solver's steps grow to the span).
TEST(OutputGrid, LargeTimesWithFewRowsRun) {
  std::string d = Work("grid_ok");
  for (std::string stop : {"1e6", "1e19", "1e300"}) {
    Result r = Kanesim("run " + kSpring + " --set k=0 --set c=0 --set F0=0 --stop-time " + stop +
                           " --interval " + sim::FormatNumber(std::stod(stop) / 100) + " -o out.csv",
                       d);
    ASSERT_EQ(r.rc, 0) << stop << "\n" << r.err;
    EXPECT_EQ(CsvRows(d + "/out.csv"), 101) << stop;
    std::string text = Slurp(d + "/out.csv");
    text.pop_back();
    EXPECT_EQ(std::stod(text.substr(text.rfind('\n') + 1)), std::stod(stop)) << "the last row is the stop time";
  }
}

// The grid itself, over a generator of sizes: Count never wraps, and Check refuses
// exactly the grids whose true row count passes the limit.
TEST(OutputGrid, CountNeverOverflowsAndCheckMatchesTheTrueCount) {
  for (double span : {1.0, 1e3, 1e8, 1e12, 1e19, 1e100, 1e300}) {
    for (double interval : {1e-19, 1e-9, 1e-3, 0.01, 1.0, 1e6, 1e17}) {
      sim::OutputGrid g{0.0, span, interval};
      const double rows = span / interval + 1;
      const long count = g.Count();
      EXPECT_GE(count, 1);
      EXPECT_LE(count, sim::kMaxOutputRows + 1);
      const bool too_many = rows > static_cast<double>(sim::kMaxOutputRows);
      EXPECT_EQ(!g.Check().empty(), too_many) << span << " / " << interval << ": " << g.Check();
      if (!too_many) {
        EXPECT_NEAR(static_cast<double>(count), std::ceil(span / interval - 1e-9) + 1, 0.5);
      }
    }
  }
  EXPECT_FALSE((sim::OutputGrid{0.0, std::nan(""), 0.1}.Check().empty()));
  EXPECT_FALSE((sim::OutputGrid{0.0, 1.0, std::nan("")}.Check().empty()));
  EXPECT_FALSE((sim::OutputGrid{1.0, 0.0, 0.1}.Check().empty()));
  EXPECT_TRUE((sim::OutputGrid{2.0, 2.0, 0.0}.Check().empty()));  // one instant
}

}  // namespace
}  // namespace kanesim::clitest
