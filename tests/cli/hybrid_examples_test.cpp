// The hybrid examples (examples/bouncing_ball.mech, stick_slip.mech, pendulum_stop.mech) run
// by the command as their headers say, in all five integrators, against the closed forms
// their headers quote: the ball's impact times t1 + 2 t1 (e + ... + e^(k-1)) and its rest at
// t1 (1 + e) / (1 - e); the Coulomb oscillator's reversals at k pi / w and its stick at
// 6 pi / w at x0 - 12 F / k; the stop's Newton law. If these fail, an example no longer runs
// (a missed impact: exit 2, as the ball on a plane offset from the origin before the fix of
// EndStopEvents' Side::shift), or it runs to other numbers than its header promises.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include "tests/support/cli_util.h"

namespace kanesim::clitest {
namespace {

const char* const kIntegrators[] = {"dop853", "cvode", "cvode-bdf", "ida", "arkode"};

struct Event {
  double time = 0.0;
  std::string element, kind;
};

// The events CSV's distinct (time, element, kind) rows, in order.
std::vector<Event> Events(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  std::vector<Event> out;
  while (std::getline(in, line)) {
    const std::vector<std::string> f = CsvFields(line);
    if (f.size() < 3) continue;
    Event e{std::stod(f[0]), f[1], f[2]};
    if (out.empty() || out.back().time != e.time || out.back().kind != e.kind || out.back().element != e.element)
      out.push_back(e);
  }
  return out;
}

// The rows of a CSV file as numbers, with the columns `names` in that order (time first).
std::vector<std::vector<double>> Rows(const std::string& path, const std::vector<std::string>& names) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  const std::vector<std::string> header = CsvFields(line);
  std::vector<size_t> cols = {0};
  for (const std::string& n : names) {
    const auto it = std::find(header.begin(), header.end(), n);
    EXPECT_NE(it, header.end()) << "no column " << n << " in " << path;
    cols.push_back(it == header.end() ? 0 : static_cast<size_t>(it - header.begin()));
  }
  std::vector<std::vector<double>> out;
  while (std::getline(in, line)) {
    std::vector<double> row;
    size_t at = 0;
    while (at <= line.size()) {
      size_t comma = line.find(',', at);
      if (comma == std::string::npos) comma = line.size();
      row.push_back(std::stod(line.substr(at, comma - at)));
      at = comma + 1;
    }
    std::vector<double> picked;
    for (size_t c : cols) picked.push_back(c < row.size() ? row[c] : NAN);
    out.push_back(picked);
  }
  return out;
}

TEST(HybridExamples, BouncingBallBouncesToRestAtTheClosedFormTimes) {
  const std::string d = Work("hybrid_examples_ball");
  const double g = 9.81, h = 1.0, e = 0.8, t1 = std::sqrt(2 * h / g), t_inf = t1 * (1 + e) / (1 - e);
  for (const char* how : kIntegrators) {
    Result r = Kanesim("run " + kSrc + "/examples/bouncing_ball.mech --integrator " + how +
                           " --output height --output free.q[1] -o ball.csv --events ball_ev.csv",
                       d);
    ASSERT_EQ(r.rc, 0) << how << ": " << r.err;
    const std::vector<Event> ev = Events(d + "/ball_ev.csv");
    double want = t1, speed = std::sqrt(2 * g * h);
    int impacts = 0;
    for (const Event& x : ev) {
      if (x.kind.rfind("impact", 0) != 0 || impacts >= 12) continue;
      // CVODE's free fall is about atol off (it is not exact for a parabola): 1e-7 there.
      EXPECT_NEAR(x.time, want, 1e-7) << how << " impact " << impacts + 1;
      want += 2 * e * speed / g, speed *= e, ++impacts;
    }
    EXPECT_EQ(impacts, 12) << how;
    ASSERT_FALSE(ev.empty());
    EXPECT_EQ(ev.back().kind, "rests on the plane (accumulation point of the bounces)") << how;
    EXPECT_NEAR(ev.back().time, t_inf, 1e-5 * t_inf) << how;
    const std::vector<std::vector<double>> rows = Rows(d + "/ball.csv", {"height", "free.q[1]"});
    ASSERT_FALSE(rows.empty());
    for (const std::vector<double>& row : rows) {
      EXPECT_GE(row[1], -1e-9) << how << " t = " << row[0] << ": below the floor";
      EXPECT_NEAR(row[2], 0.5 * row[0], 1e-9) << how << ": the frictionless floor keeps the sideways speed";
    }
    EXPECT_EQ(rows.back()[0], 5.0) << how;
    EXPECT_NEAR(rows.back()[1], 0.0, 1e-9) << how << ": at rest on the floor";
  }
}

TEST(HybridExamples, StickSlipReversesEveryHalfPeriodAndSticksForGood) {
  const std::string d = Work("hybrid_examples_stick");
  const double k = 100, m = 1, F = 0.2 * m * 9.81, w = std::sqrt(k / m), x0 = 0.25;
  for (const char* how : kIntegrators) {
    Result r = Kanesim("run " + kSrc + "/examples/stick_slip.mech --integrator " + how +
                           " --output slide.q --output slide.u -o stick.csv --events stick_ev.csv",
                       d);
    ASSERT_EQ(r.rc, 0) << how << ": " << r.err;
    const std::vector<Event> ev = Events(d + "/stick_ev.csv");
    ASSERT_EQ(ev.size(), 7u) << how;  // slips at 0, reverses 5 times, sticks
    for (int j = 1; j <= 5; ++j) {
      EXPECT_NEAR(ev[static_cast<size_t>(j)].time, j * M_PI / w, 1e-8) << how;
      EXPECT_EQ(ev[static_cast<size_t>(j)].kind.rfind("reverses", 0), 0u) << ev[static_cast<size_t>(j)].kind;
    }
    EXPECT_NEAR(ev[6].time, 6 * M_PI / w, 1e-8) << how;
    EXPECT_EQ(ev[6].kind.rfind("sticks", 0), 0u) << ev[6].kind;
    const std::vector<std::vector<double>> rows = Rows(d + "/stick.csv", {"slide.q", "slide.u"});
    ASSERT_FALSE(rows.empty());
    EXPECT_NEAR(rows.back()[1], x0 - 12 * F / k, 1e-8) << how;
    EXPECT_EQ(rows.back()[2], 0.0) << how << ": stuck for good";
  }
}

TEST(HybridExamples, PendulumStopKeepsNewtonsLawAndItsStop) {
  const std::string d = Work("hybrid_examples_stop");
  std::vector<double> first;
  for (const char* how : kIntegrators) {
    Result r = Kanesim("run " + kSrc + "/examples/pendulum_stop.mech --integrator " + how +
                           " --output j1.q -o stop.csv --events stop_ev.csv --stats",
                       d);
    ASSERT_EQ(r.rc, 0) << how << ": " << r.err;
    // Newton's law at each impact of the stats' log (stderr): "speed A -> B" with B = -0.5 A,
    // or 0 at the accumulation point.
    int impacts = 0;
    size_t at = 0;
    while ((at = r.err.find("impact at q_min, speed ", at)) != std::string::npos) {
      at += 23;
      const double before = std::stod(r.err.substr(at));
      const double after = std::stod(r.err.substr(r.err.find("-> ", at) + 3));
      if (after != 0.0) {
        EXPECT_NEAR(after, -0.5 * before, 1e-15 * std::abs(before)) << how;
      }
      ++impacts;
    }
    EXPECT_GE(impacts, 10) << how;
    EXPECT_TRUE(Has(r.err, "when (pendulum_stop.mech:20): fires")) << how;
    for (const std::vector<double>& row : Rows(d + "/stop.csv", {"j1.q"})) EXPECT_GE(row[1], -0.6 - 1e-12) << how << " t = " << row[0];
    const std::vector<Event> ev = Events(d + "/stop_ev.csv");
    std::vector<double> times;
    for (const Event& x : ev)
      if (x.time < 1.2) times.push_back(x.time);
    if (first.empty()) first = times;
    ASSERT_EQ(times.size(), first.size()) << how;
    for (size_t i = 0; i < times.size(); ++i) EXPECT_NEAR(times[i], first[i], 1e-6) << how << " event " << i;
  }
}

}  // namespace
}  // namespace kanesim::clitest
