// `kanesim run --events FILE.csv` (docs/events.md "Outputs"): every end-stop row carries the
// state entries its event changed, and a rest or a leave its joint's speed, against the
// impulse's closed form (Kane's impulsive form on a double pendulum). Before, stops' rows had
// their signal, before and after columns empty (the state names were read for when clauses only).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "tests/support/cli_util.h"

namespace kanesim::clitest {
namespace {

struct EventRow {
  double time = 0.0;
  std::string element, kind, signal, before, after;
};

std::vector<EventRow> ReadEvents(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "time,element,kind,signal,before,after");
  std::vector<EventRow> rows;
  while (std::getline(in, line)) {
    std::vector<std::string> f = CsvFields(line);
    if (f.size() != 6) {
      ADD_FAILURE() << "bad row: " << line;
      continue;
    }
    rows.push_back({std::stod(f[0]), f[1], f[2], f[3], f[4], f[5]});
  }
  return rows;
}

// Two rods (L1 = 1, m1 = 1; L2 = 0.8, m2 = 0.7), j1 stopping at q_min = -0.6: plastic, it rests
// there until the swinging second rod pulls it off (t = 0.347).
std::string DoublePendulum(double e) {
  std::ostringstream s;
  s << "model D\n  World world(g = {0, -9.81, 0});\n"
    << "  Revolute j1(axis = {0, 0, 1}, q_min = -0.6, restitution = " << e << ");\n"
    << "  Revolute j2(axis = {0, 0, 1}, q(start = 0.3), u(start = 0.5));\n"
    << "  Rod rod1(L = 1, m = 1);\n  Rod rod2(L = 0.8, m = 0.7);\nequation\n"
    << "  connect(world.frame_b, j1.frame_a);\n  connect(j1.frame_b, rod1.frame_a);\n"
    << "  connect(rod1.frame_b, j2.frame_a);\n  connect(j2.frame_b, rod2.frame_a);\n"
    << "  annotation(experiment(StopTime = 0.6, Interval = 0.01, Tolerance = 1e-10));\nend D;\n";
  return s.str();
}

// If this fails, an impact's rows do not list the speeds it changed with their values (j1's
// speed reversed by Newton's law, j2's following through the mass matrix: du2 = -(M12 / M22)
// du1, M12 = m2 (L2^2/3 + L1 L2 cos(q2)/2), M22 = m2 L2^2/3), or a rest or a leave has no
// speed entry.
TEST(EventsCsv, EndStopRowsCarryTheSpeedsTheyChanged) {
  const std::string d = Work("events_csv");
  const double L1 = 1, L2 = 0.8, m2 = 0.7;
  for (double e : {0.5, 0.0}) {
    Write(d + "/d.mech", DoublePendulum(e));
    Result r = Kanesim("run d.mech --output j2.q -o rows.csv --events ev.csv", d);
    ASSERT_EQ(r.rc, 0) << r.err;
    const std::vector<EventRow> ev = ReadEvents(d + "/ev.csv");
    ASSERT_GE(ev.size(), 2u);
    std::map<std::string, const EventRow*> first;  // of the first impact: signal -> row
    for (const EventRow& row : ev) {
      EXPECT_FALSE(row.signal.empty()) << row.time << " " << row.element << " " << row.kind << ": no signal";
      if (row.time == ev[0].time && row.kind == ev[0].kind) first[row.signal] = &row;
    }
    ASSERT_EQ(ev[0].kind.rfind("impact at q_min", 0), 0u) << ev[0].kind;
    ASSERT_TRUE(first.count("j1.u") && first.count("j2.u"));
    const double u1 = std::stod(first["j1.u"]->before), u1p = std::stod(first["j1.u"]->after);
    const double u2 = std::stod(first["j2.u"]->before), u2p = std::stod(first["j2.u"]->after);
    EXPECT_EQ(u1p, -e * u1);
    // j2.q at the impact: the row at its time in the output (its left limit).
    std::ifstream rows(d + "/rows.csv");
    std::string line;
    double q2 = NAN;
    std::getline(rows, line);
    while (std::getline(rows, line))
      if (std::stod(CsvFields(line)[0]) == ev[0].time) q2 = std::stod(CsvFields(line)[1]);
    ASSERT_FALSE(std::isnan(q2));
    const double M12 = m2 * (L2 * L2 / 3 + L1 * L2 * std::cos(q2) / 2), M22 = m2 * L2 * L2 / 3;
    EXPECT_NEAR(u2p - u2, -M12 / M22 * (u1p - u1), 1e-9 * (std::abs(u1) + std::abs(u2)));
    if (e == 0.0) {  // rests on the stop (j1.u -> 0), then leaves it (0 -> 0)
      bool rests = false, leaves = false;
      for (const EventRow& row : ev) {
        if (row.kind == "rests on q_min" && row.signal == "j1.u") rests = std::stod(row.after) == 0.0;
        if (row.kind == "leaves q_min") {
          leaves = true;
          EXPECT_EQ(row.signal, "j1.u");
          EXPECT_EQ(row.before, "0");
          EXPECT_EQ(row.after, "0");
        }
      }
      EXPECT_TRUE(rests);
      EXPECT_TRUE(leaves);
    }
  }
}

// A jump that cannot be applied names its cause. A when clause setting a joint past its stop
// (where no impact law says what follows) stops the run with exit 2 at the event's time, the
// rows before kept. If this fails, the cause is empty or generic ("the equations of motion
// could not be evaluated", as before), or the run goes on with the joint through its stop.
// Two plane contacts at one point (dependent rows) share the load
// (PlaneContact.TwoCoincidentPlanesShareTheLoadAndLeaveTogether) unless their impact laws
// contradict each other: then exit 2 at the landing, naming both. (A reinit of a resting
// joint is handled: tests/compiler/when_rest_test.cpp.)
TEST(EventsCsv, SingularImpulsesNameTheirCause) {
  const std::string d = Work("singular_impulse");
  Write(d + "/rw.mech",
        "model RW\n  World world(g = {0, -9.81, 0});\n"
        "  Revolute j1(axis = {0, 0, 1}, q(start = -1.0), q_min = -1.0);\n  Rod rod(L = 1, m = 1);\nequation\n"
        "  connect(world.frame_b, j1.frame_a);\n  connect(j1.frame_b, rod.frame_a);\n"
        "  when time > 1 then\n    reinit(j1.q, -1.3);\n  end when;\n"
        "  annotation(experiment(StopTime = 2, Interval = 0.1));\nend RW;\n");
  Result r = Kanesim("run rw.mech -o rw.csv", d);
  EXPECT_EQ(r.rc, 2) << r.err;
  EXPECT_TRUE(Has(r.err, "numerical failure at t = 1:")) << r.err;
  EXPECT_TRUE(Has(r.err, "when (rw.mech:8) sets joint 'j1' past q_min by 0.3")) << r.err;
  EXPECT_EQ(CsvRows(d + "/rw.csv"), 11);  // t = 0, 0.1, ..., 1
  // Two coincident plane contacts (dependent rows) with different restitutions: at the
  // landing (t = sqrt(2 0.2 / g) = 0.2019 s) Newton's laws contradict each other.
  Write(d + "/mixed.mech",
        "model Mixed\n  World world(g = {0, -9.81, 0});\n  Prismatic p(axis = {0, 1, 0}, q(start = 0.2));\n"
        "  Body b(m = 1, I = diagonal({1, 1, 1}));\n  PlaneContact c1(restitution = 0.5);\n  PlaneContact c2(n = {0, 2, 0});\n"
        "equation\n  connect(world.frame_b, p.frame_a);\n  connect(p.frame_b, b.frame_a);\n"
        "  connect(p.frame_b, c1.frame_a);\n  connect(p.frame_b, c2.frame_a);\n"
        "  annotation(experiment(StopTime = 1, Interval = 0.1));\nend Mixed;\n");
  r = Kanesim("run mixed.mech -o mixed.csv", d);
  EXPECT_EQ(r.rc, 2) << r.err;
  EXPECT_TRUE(Has(r.err, "numerical failure at t = 0.2019")) << r.err;
  EXPECT_TRUE(Has(r.err, "contact 'c1'") && Has(r.err, "contact 'c2'") && Has(r.err, "targets disagree")) << r.err;
  EXPECT_EQ(CsvRows(d + "/mixed.csv"), 4);  // t = 0, 0.1, 0.2 and the landing's left limit
}

// `--stats` lists the run's events (issue 41: "an events log (time, element, kind) in
// --stats"): the same records, in the same order, as the --events file (whose rows repeat a
// record once per state entry it changed). If this fails, one of the two logs misses,
// reorders or misnames an event (the double pendulum's impact, rest and leave).
TEST(EventsCsv, StatsListTheSameEventsAsTheFile) {
  const std::string d = Work("events_stats");
  Write(d + "/d.mech", DoublePendulum(0.0));
  Result r = Kanesim("run d.mech -o rows.csv --events ev.csv --stats", d);
  ASSERT_EQ(r.rc, 0) << r.err;
  std::vector<std::string> file;  // "time|element|kind", one per record
  for (const EventRow& row : ReadEvents(d + "/ev.csv")) {
    std::ostringstream key;
    key.precision(17);
    key << row.time << "|" << row.element << "|" << row.kind;
    if (file.empty() || file.back() != key.str()) file.push_back(key.str());
  }
  const std::string all = r.out + r.err;
  const size_t head = all.find("\nevents ");
  ASSERT_NE(head, std::string::npos) << all;
  std::istringstream lines(all.substr(all.find('\n', head + 1) + 1));
  std::vector<std::string> stats;
  std::string line;
  while (std::getline(lines, line) && line.rfind("  t = ", 0) == 0) {
    std::istringstream in(line.substr(6));
    double t = 0.0;
    std::string rest;
    in >> t >> std::ws;
    std::getline(in, rest);
    const size_t colon = rest.find(": ");
    std::ostringstream key;
    key.precision(17);
    key << t << "|" << rest.substr(0, colon) << "|" << rest.substr(colon + 2);
    stats.push_back(key.str());
  }
  std::string word;
  size_t count = 0;
  std::istringstream(all.substr(head + 1)) >> word >> count;
  EXPECT_EQ(count, stats.size()) << "the count line";
  EXPECT_GE(stats.size(), 3u);
  EXPECT_EQ(stats, file);
}

// `kanesim run` of a rod resting on its stop that a when clause flings off it (docs/events.md
// "A joint resting on its end stop"; tests/data/resting_reinit.mech): exit 0, the clause fires
// and the joint leaves q_max at t = 1 (j1.u 0 -> -2), then strikes it again at the free
// pendulum's return time (closed form in tests/compiler/when_rest_test.cpp) at speed 2.
// Before, the run stopped there (exit 2, "not handled yet").
TEST(EventsCsv, AReinitFlingsAJointOffItsStop) {
  const std::string d = Work("resting_reinit");
  Result r = Kanesim("run " + kSrc + "/tests/data/resting_reinit.mech -o rows.csv --events ev.csv", d);
  ASSERT_EQ(r.rc, 0) << r.err;
  const std::vector<EventRow> ev = ReadEvents(d + "/ev.csv");
  ASSERT_GE(ev.size(), 4u);
  EXPECT_EQ(ev[0].kind, "rests on q_max");  // the start
  EXPECT_NEAR(ev[1].time, 1.0, 1e-12);
  EXPECT_EQ(ev[1].kind, "fires");
  EXPECT_EQ(ev[2].kind, "leaves q_max");
  EXPECT_EQ(ev[2].signal + " " + ev[2].before + " " + ev[2].after, "j1.u 0 -2");
  const EventRow* hit = nullptr;  // the impact's row of j1.u (one of q may come first)
  for (const EventRow& row : ev)
    if (!hit && row.kind.rfind("impact at q_max", 0) == 0 && row.signal == "j1.u") hit = &row;
  ASSERT_NE(hit, nullptr);
  EXPECT_NEAR(std::stod(hit->before), 2.0, 1e-8);  // the energy kept in flight
  EXPECT_NEAR(std::stod(hit->after), -1.0, 1e-8);  // restitution 1/2
}

// `kanesim run` of a ball written by hand (when p.q < 0 then reinit(p.u, -e pre(p.u))): its
// bounces accumulate at t_inf = t1 (1 + e) / (1 - e), t1 = sqrt(2 h / g). If this fails, the
// run ends in a step-size underflow (DOP853) or falls through the floor (the others) instead
// of exit 2 naming the clause and t_inf, with the rows up to it on disk.
TEST(EventsCsv, AccumulatingWhenEventsExitTwoAtTheirAccumulationPoint) {
  const std::string d = Work("when_zeno");
  Write(d + "/ball.mech",
        "model Ball\n  parameter Real e = 0.8;\n  World world(g = {0, -9.81, 0});\n"
        "  Prismatic p(axis = {0, 1, 0}, q(start = 1));\n  Body b(m = 1);\nequation\n"
        "  connect(world.frame_b, p.frame_a);\n  connect(p.frame_b, b.frame_a);\n"
        "  when p.q < 0 then\n    reinit(p.u, -e * pre(p.u));\n  end when;\n"
        "  annotation(experiment(StopTime = 10, Interval = 0.1, Tolerance = 1e-12));\nend Ball;\n");
  const double t_inf = std::sqrt(2 / 9.81) * 1.8 / 0.2;
  for (const char* integrator : {"dop853", "cvode", "ida"}) {
    Result r = Kanesim(std::string("run ball.mech --integrator ") + integrator + " -o rows.csv", d);
    EXPECT_EQ(r.rc, 2) << integrator << ": " << r.err;
    EXPECT_TRUE(Has(r.err, "when (ball.mech:9)")) << r.err;
    EXPECT_TRUE(Has(r.err, "PlaneContact")) << r.err;
    const size_t at = r.err.find("accumulation point at t = ");
    ASSERT_NE(at, std::string::npos) << r.err;
    EXPECT_NEAR(std::stod(r.err.substr(at + 26)), t_inf, 1e-6 * t_inf) << integrator;
    EXPECT_GE(CsvRows(d + "/rows.csv"), 41) << integrator << ": the grid's rows up to t_inf (0, 0.1, ..., 4.0)";
  }
}

// `kanesim run --events` of a reinit in a mechanism with Coulomb friction mu (docs/events.md
// "Friction in a jump"): a slider on an axis at 0.6 rad on a carrier whose speed is set from
// 0 to 3 slides on with u+ = 1 - 3 cos 0.6 + 0.4 (3 sin 0.6) (its normal impulse m_s 3 sin 0.6).
// If this fails, the reinit is refused (K321, before) or the row lacks the slider's speed.
TEST(EventsCsv, AReinitWithMuFrictionTakesTheFrictionImpulse) {
  const std::string d = Work("when_mu");
  Write(d + "/s.mech",
        "model S\n  World world(g = {0, 0, 0});\n  Prismatic cx(axis = {1, 0, 0});\n  Body carrier(m = 2);\n"
        "  Prismatic s(axis = {cos(0.6), sin(0.6), 0}, u(start = 1), mu = 0.4);\n  Body slider(m = 0.5);\n"
        "equation\n  connect(world.frame_b, cx.frame_a);\n  connect(cx.frame_b, carrier.frame_a);\n"
        "  connect(carrier.frame_a, s.frame_a);\n  connect(s.frame_b, slider.frame_a);\n"
        "  when time > 0.1 then\n    reinit(cx.u, 3);\n  end when;\n"
        "  annotation(experiment(StopTime = 0.2, Interval = 0.1, Tolerance = 1e-10));\nend S;\n");
  Result r = Kanesim("run s.mech -o rows.csv --events ev.csv", d);
  ASSERT_EQ(r.rc, 0) << r.err;
  const double want = 1 - 3 * std::cos(0.6) + 0.4 * 3 * std::sin(0.6);
  bool seen = false;
  for (const EventRow& row : ReadEvents(d + "/ev.csv"))
    if (row.signal == "s.u") {
      seen = true;
      EXPECT_EQ(std::stod(row.before), 1.0);
      EXPECT_NEAR(std::stod(row.after), want, 1e-12);
    }
  EXPECT_TRUE(seen);
}

// `kanesim run --events` of a carriage on a rail with mu whose leg rests on the floor
// (docs/stdlib.md "PlaneContact"): the floor carries the leg's weight, so the rail's normal
// force is the carriage's m_c g alone and the drive 8 sin 3t slips it where
// 8 sin 3t = mu m_c g (tests/compiler/plane_friction_test.cpp has the rest of the motion).
// If this fails, the contact beside mu is refused (K311, before) or its force is left out of N.
TEST(EventsCsv, ACarriageWhoseLegRestsOnTheFloorSlipsAtTheHandTime) {
  const std::string d = Work("plane_mu");
  Write(d + "/l.mech",
        "model L\n  World world(g = {0, -9.81, 0});\n"
        "  Prismatic cx(axis = {1, 0, 0}, mu = 0.3, friction_exact = true);\n  Body carriage(m = 2);\n"
        "  Revolute leg(axis = {0, 0, 1}, q(start = 0.600000000001));\n  FixedTranslation rod(r = {0, -1, 0});\n"
        "  Body tip(m = 0.5);\n  PlaneContact foot(n = {0, 1, 0}, d = -cos(0.6));\nequation\n"
        "  connect(world.frame_b, cx.frame_a);\n  connect(cx.frame_b, carriage.frame_a);\n"
        "  connect(carriage.frame_a, leg.frame_a);\n  connect(leg.frame_b, rod.frame_a);\n"
        "  connect(rod.frame_b, tip.frame_a);\n  connect(rod.frame_b, foot.frame_a);\n"
        "  cx.tau = 8 * sin(3 * time);\n"
        "  annotation(experiment(StopTime = 0.5, Interval = 0.1, Tolerance = 1e-11));\nend L;\n");
  Result r = Kanesim("run l.mech -o rows.csv --events ev.csv", d);
  ASSERT_EQ(r.rc, 0) << r.err;
  std::vector<double> slips;
  for (const EventRow& row : ReadEvents(d + "/ev.csv"))
    if (row.element == "cx" && row.kind.rfind("slips", 0) == 0) slips.push_back(row.time);
  ASSERT_EQ(slips.size(), 1u);
  EXPECT_NEAR(slips[0], std::asin(0.3 * 2 * 9.81 / 8) / 3, 1e-8);
}

}  // namespace
}  // namespace kanesim::clitest
