// The hybrid examples (examples/bouncing_ball.mech, stick_slip.mech, pendulum_stop.mech,
// tumbling_cube.mech) run by the command as their headers say, in all five integrators,
// against the closed forms and invariants their headers quote: the ball's impact times
// t1 + 2 t1 (e + ... + e^(k-1)) and its rest at t1 (1 + e) / (1 - e); the Coulomb
// oscillator's reversals at k pi / w and its stick at 6 pi / w at x0 - 12 F / k; the stop's
// Newton law; the cube's speed along the floor and vertical spin. If these fail, an example
// no longer runs (a missed impact: exit 2, as the ball on a plane offset from the origin
// before the fix of EndStopEvents' Side::shift), or it runs to other numbers than its header
// promises.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include "tests/support/cli_util.h"
#include "tests/support/sanitizer_cases.h"

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
    // Under the sanitizers DOP853 and IDA (the others run this model in the goldens and above).
    if (test::kUnderSanitizers && std::string(how) != "dop853" && std::string(how) != "ida") continue;
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

// The tumbling cube: the floor pushes only along its normal (vertical forces at the corners),
// so its impulses and reactions change neither the horizontal momentum nor the angular
// momentum about the vertical through the centre of mass; the cube's inertia is isotropic,
// so the world angular velocity's vertical component stays at its start value, and the speed
// along the floor at 0.5 m/s, in every row, through every impact. Energy
// (1/2 m |v|^2 + 1/2 J |w|^2 + m g y) never rises at an event (e = 0.3 < 1, resting and
// leaving do no work), no corner goes below the floor, and the cube ends flat on a face
// (its centre at a = 0.1 with four corners on the floor, those resting among them).
// If this fails, dependent corner contacts (a face on the floor: four rows of rank three)
// stop the run (exit 2 before redundant contacts were solved), or an impulse acts along the
// floor or turns the cube about the vertical, or an impact gains energy.
TEST(HybridExamples, TumblingCubeKeepsWhatTheFloorCannotChangeAndSettlesOnAFace) {
  const std::string d = Work("hybrid_examples_cube");
  const double m = 1, a = 0.1, J = m * (2 * a) * (2 * a) / 6, g = 9.81;
  std::string corners;
  std::vector<std::string> names = {"height", "free.frame_b.v[1]", "free.frame_b.v[2]", "free.frame_b.v[3]",
                                    "free.frame_b.w[1]", "free.frame_b.w[2]", "free.frame_b.w[3]"};
  for (int k = 1; k <= 8; ++k) {
    names.push_back("c" + std::to_string(k) + ".frame_b.r[2]");
    corners += " --output c" + std::to_string(k) + ".frame_b.r[2]";
  }
  for (const char* how : kIntegrators) {
    std::string outputs;
    for (size_t i = 0; i < 7; ++i) outputs += " --output " + names[i];
    Result r = Kanesim("run " + kSrc + "/examples/tumbling_cube.mech --integrator " + how + outputs + corners +
                           " -o cube.csv --events cube_ev.csv",
                       d);
    ASSERT_EQ(r.rc, 0) << how << ": " << r.err;
    const std::vector<std::vector<double>> rows = Rows(d + "/cube.csv", names);
    ASSERT_GT(rows.size(), 300u) << how;
    const double spin = rows[0][6];
    EXPECT_NEAR(spin, -2.4362436, 1e-7);  // R(q0) (3, -2, 5), the header's value
    double e_prev = INFINITY, t_prev = -1;
    for (const std::vector<double>& row : rows) {
      EXPECT_NEAR(row[2], 0.5, 1e-9) << how << " t = " << row[0];
      EXPECT_NEAR(row[4], 0.0, 1e-9) << how << " t = " << row[0];
      EXPECT_NEAR(row[6], spin, 1e-7) << how << " t = " << row[0];
      for (size_t k = 8; k < 16; ++k) EXPECT_GE(row[k], -1e-8) << how << " t = " << row[0] << " corner " << k - 7;
      double energy = m * g * row[1];
      for (size_t k = 2; k < 8; ++k) energy += 0.5 * (k < 5 ? m : J) * row[k] * row[k];
      if (row[0] == t_prev) {  // an event's right limit after its left: no energy gained
        EXPECT_LE(energy, e_prev + 1e-9 * (1 + std::abs(e_prev))) << how << " t = " << row[0];
      }
      e_prev = energy, t_prev = row[0];
    }
    EXPECT_EQ(rows.back()[0], 3.0) << how;
    EXPECT_NEAR(rows.back()[1], a, 1e-6) << how << ": flat on a face";
    int on_floor = 0;
    for (size_t k = 8; k < 16; ++k) on_floor += std::abs(rows.back()[k]) < 1e-6 ? 1 : 0;
    EXPECT_EQ(on_floor, 4) << how;
    const std::vector<Event> ev = Events(d + "/cube_ev.csv");
    std::vector<std::string> resting;
    for (const Event& x : ev) {
      if (x.kind.rfind("rests on", 0) == 0 && std::find(resting.begin(), resting.end(), x.element) == resting.end())
        resting.push_back(x.element);
      if (x.kind.rfind("leaves", 0) == 0) resting.erase(std::remove(resting.begin(), resting.end(), x.element), resting.end());
    }
    // Three or four rest: a fourth corner touching at zero speed takes no load where three
    // already hold the face (its row dependent, its gap acceleration 0: nothing to join for).
    EXPECT_GE(resting.size(), 3u) << how;
    for (const std::string& c : resting) EXPECT_LT(std::abs(rows.back()[7 + std::stoul(c.substr(1))]), 1e-6) << how << " " << c;
  }
}

}  // namespace
}  // namespace kanesim::clitest
