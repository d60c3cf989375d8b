// A cube tossed spinning onto a frictionless floor (models/tossed_cube.mech: eight corner
// PlaneContacts, restitution e), from tosses of a random sweep that stopped a run before
// (exit 2, "an impact was missed (two crossings within one step are not handled)": ARKODE,
// stepping one step at a time beside resting corners, took a graze guard's root inside a
// step, no event, and served the rows after it from the step's interpolant without
// searching the rest of the step, where a corner crossed the floor). What must hold, in
// every integrator: the run completes; the floor, pushing only along its normal, keeps the
// speed along it (0 across, vx along) and the vertical spin (the cube's inertia is
// isotropic: the world angular velocity's vertical component) through every impact; no
// corner goes below the floor beyond the tolerance's reach.
// Measured (Release): the spin to 3e-9, the speeds to round-off, corners >= -2e-8.
// Issue 41 (two more failures of the sweep): at tight tolerances the cube rocking on an edge
// (each corner's impact lifting the other off on a flight lower than the tolerance's reach)
// missed a landing, exit 2 (examples/tumbling_cube.mech, 11 of 40 integrator x rtol runs);
// and resting corners kept the gap rate they had when they came to rest, so they sank
// through the floor at that rate (IDA -6.6e-8 m/s, exit 2 at 3.44 s).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <regex>
#include <string>
#include <vector>

#include "run_kanesim.h"
#include "tests/support/sanitizer_cases.h"

namespace kanesim::stress {
namespace {

struct Toss {
  const char* what;
  std::vector<std::string> sets;  // --set NAME=VALUE of the model's parameters
};

// The tosses (parameters of models/tossed_cube.mech) whose ARKODE runs missed an impact. Run
// to 4 s: the first one's e = 0.8 chatter lands a face at 3.365 s, where dependent corners
// strike with Newton's laws that disagree unless they rest together (sim/end_stops.cpp Impact).
const Toss kTosses[] = {
    {"e=0.8 spin", {"e=0.8", "h=0.6029369475335373", "th=2.3630682556196203", "ax=-0.9957878932977786",
                    "ay=-0.10922561189039715", "az=0.44308006468156513", "wx=-4.339804459672758", "wy=7.124331128862757",
                    "wz=6.422839321783737", "vx=-0.9388200339328929"}},
    {"e=0.5 edge pair", {"e=0.5", "h=0.6213922123374678", "th=0.8347663800684059", "ax=0.09599261893249778",
                         "ay=0.9142325629204537", "az=-0.9885817410992142", "wx=4.538483721846237", "wy=5.127774590807711",
                         "wz=6.178873293216132", "vx=0.4810068236663927"}},
    {"e=0.2 low", {"e=0.2", "h=0.6630747984661014", "th=1.740209380812975", "ax=-0.14781864062369965",
                   "ay=-0.8877534049585192", "az=0.7400203103532796", "wx=1.119989342022084", "wy=-4.802569277165711",
                   "wz=0.07552747886181344", "vx=-0.030149775544531687"}},
    // Two landings that stopped a branch joining every corner the impulse would leave closing
    // on the floor (sim/end_stops.cpp Complementary, for a folded chain's stops): a face's
    // fourth corner joined at rate 0 beside three with Newton's laws, rows dependent and
    // targets disagreeing, exit 2 at t = 0.8668 in all five integrators; and e = 0 pivoting
    // that cycled (t = 0.2823). Where joining finds no impulse, it is solved without joins.
    {"e=0 pivots", {"e=0", "h=0.3641093511835515", "th=1.1192781693491825", "ax=-0.6618327686791126",
                    "ay=0.6179240892787337", "az=0.7076687709709473", "wx=-3.9746672384805493", "wy=-4.60449902930239",
                    "wz=-7.428248932218073", "vx=0.3624923699853251"}},
    {"e=0.5 face", {"e=0.5", "h=0.47138238457831183", "th=0.6524847099565041", "ax=0.7611635187325598",
                    "ay=-0.15416470322060793", "az=0.43392219780995056", "wx=-7.490030877972078",
                    "wy=-2.2022894191481495", "wz=-5.249904125988282", "vx=0.34553088282708355"}},
};

// The run's outputs for the checks below: the speeds along the floor, the vertical spin, the
// centre's height and the eight corners' heights.
std::vector<std::string> FloorOutputs() {
  std::vector<std::string> args = {"--output", "free.frame_b.v[1]", "--output", "free.frame_b.v[3]",
                                   "--output", "free.frame_b.w[2]", "--output", "free.q[2]"};
  for (int k = 1; k <= 8; ++k) args.insert(args.end(), {"--output", "c" + std::to_string(k) + ".frame_b.r[2]"});
  return args;
}

// In every row of a run with FloorOutputs(): the speed along the floor vx, 0 across, the
// vertical spin as at the start; no corner below the floor beyond the tolerance's reach.
void ExpectWhatTheFloorCannotChange(const RunResult& r, double vx, const std::string& what) {
  const std::vector<double> v1 = r.Column("free.frame_b.v[1]"), v3 = r.Column("free.frame_b.v[3]"),
                            w2 = r.Column("free.frame_b.w[2]");
  ASSERT_GT(w2.size(), 100u) << what;
  double low = 0.0;
  for (int k = 1; k <= 8; ++k)
    for (double y : r.Column("c" + std::to_string(k) + ".frame_b.r[2]")) low = std::min(low, y);
  for (size_t i = 0; i < w2.size(); ++i) {
    EXPECT_NEAR(v1[i], vx, 1e-9) << what << " row " << i;
    EXPECT_NEAR(v3[i], 0.0, 1e-9) << what << " row " << i;
    EXPECT_NEAR(w2[i], w2[0], 1e-6) << what << " row " << i;
  }
  EXPECT_GE(low, -2e-7) << what << ": a corner below the floor";
}

const char* const kIntegrators[] = {"dop853", "cvode", "cvode-bdf", "ida", "arkode"};

TEST(CubeToss, EveryIntegratorKeepsWhatTheFloorCannotChange) {
  const char* const hows[] = {"dop853", "cvode", "ida", "arkode"};
  const size_t n_toss = std::size(kTosses), n_how = std::size(hows);
  for (size_t ti = 0; ti < n_toss; ++ti) {
    const Toss& toss = kTosses[ti];
    double vx = 0.0;
    for (const std::string& s : toss.sets)
      if (s.rfind("vx=", 0) == 0) vx = std::stod(s.substr(3));
    for (size_t hi = 0; hi < n_how; ++hi) {
      if (!test::RunsCase(ti, n_toss, hi, n_how)) continue;  // sanitizers: each toss and integrator once
      const char* how = hows[hi];
      std::vector<std::string> args = {"--integrator", how, "--stop-time", "4", "--rtol", "1e-8"};
      for (const std::string& o : FloorOutputs()) args.push_back(o);
      for (const std::string& x : toss.sets) args.insert(args.end(), {"--set", x});
      const RunResult r = RunKanesim("tests/stress/models/tossed_cube.mech", args);
      ASSERT_EQ(r.exit_code, 0) << toss.what << " " << how << ": " << r.stderr_text;
      ExpectWhatTheFloorCannotChange(r, vx, std::string(toss.what) + " " + how);
    }
  }
}

// examples/tumbling_cube.mech at tight tolerances: the cube lands on the edge of corners
// p3, p4 and rocks on it, each corner's impact lifting the other off; late in the rocking
// the lifted corner's flight (v^2 / (2 |a|): 6e-19 m at rtol 1e-11) is far below the
// tolerance's reach, and its landing was missed (exit 2 at 0.95 s: DOP853 at 1e-11 and
// 1e-12, CVODE at 1e-10 .. 1e-12, CVODE-BDF at 1e-10 and 1e-12, ARKODE at 1e-11). Such a
// flight now passes to rest with the bounces (Settle). What must hold: every run completes,
// keeps the speed along the floor (0.5, 0 across) and the vertical spin, no corner below the
// floor beyond the tolerance's reach, and it ends at rest flat on a face (centre at a = 0.1,
// four corners on the floor, four at 2 a), the same face for all.
TEST(CubeToss, TightTolerancesResolveTheRockingOnAnEdge) {
  const char* const rtols[] = {"1e-10", "1e-11", "1e-12"};
  for (size_t ri = 0; ri < std::size(rtols); ++ri) {
    const char* rtol = rtols[ri];
    std::vector<int> face;  // the corners on the floor at the end (the first run's)
    for (size_t hi = 0; hi < std::size(kIntegrators); ++hi) {
      // Sanitizers: each rtol and each integrator once (the faces then compared in Release only).
      if (!test::RunsCase(ri, std::size(rtols), hi, std::size(kIntegrators))) continue;
      const char* how = kIntegrators[hi];
      std::vector<std::string> args = {"--integrator", how, "--rtol", rtol};
      for (const std::string& a : FloorOutputs()) args.push_back(a);
      const RunResult r = RunKanesim("examples/tumbling_cube.mech", args);
      const std::string what = std::string(how) + " rtol " + rtol;
      ASSERT_EQ(r.exit_code, 0) << what << ": " << r.stderr_text;
      const std::vector<double> v1 = r.Column("free.frame_b.v[1]"), v3 = r.Column("free.frame_b.v[3]"),
                                w2 = r.Column("free.frame_b.w[2]"), h = r.Column("free.q[2]");
      ASSERT_GT(w2.size(), 100u);
      for (size_t i = 0; i < w2.size(); ++i) {
        EXPECT_NEAR(v1[i], 0.5, 1e-9) << what << " row " << i;
        EXPECT_NEAR(v3[i], 0.0, 1e-9) << what << " row " << i;
        EXPECT_NEAR(w2[i], w2[0], 1e-7) << what << " row " << i;
      }
      EXPECT_NEAR(h.back(), 0.1, 1e-8) << what << ": not at rest on a face";
      std::vector<int> down;
      for (int k = 1; k <= 8; ++k) {
        const std::vector<double> c = r.Column("c" + std::to_string(k) + ".frame_b.r[2]");
        EXPECT_GE(*std::min_element(c.begin(), c.end()), -1e-8) << what << ": corner " << k << " below the floor";
        if (std::abs(c.back()) <= 1e-8) down.push_back(k);
        else EXPECT_NEAR(c.back(), 0.2, 1e-8) << what << ": corner " << k << " neither on the floor nor on top";
      }
      EXPECT_EQ(down.size(), 4u) << what;
      if (face.empty()) face = down;
      EXPECT_EQ(down, face) << what << ": another face than " << kIntegrators[0] << "'s";
    }
  }
}

// A toss (e = 0.2) that comes to rest flat at 0.59 s and then slides and spins on for 3.4 s:
// resting corners kept the gap rate they had when they came to rest (the held rows hold the
// gap accelerations at 0, so the rates the integration left in them stayed), so they sank
// at that rate: IDA at rtol 1e-8 -6.6e-8 m/s (exit 2 'an impact was missed' at 3.44 s),
// CVODE -1e-8 m/s, CVODE-BDF -2e-8 m/s, ARKODE +5e-9 m/s, DOP853 +1.5e-10 m/s. The resting
// rows' rates are now zeroed at every event (sim/end_stops.cpp ZeroRestingRates). What must
// hold: every run completes; a resting corner stays where it rested (its height at 4 s as at
// 1.5 s, to 1e-10 m); no corner below the floor beyond the tolerance's reach; the floor's
// invariants; at rest flat at the end.
TEST(CubeToss, RestingCornersStayOnTheFloor) {
  const std::vector<std::string> sets = {"e=0.2", "h=0.5419902902961267", "th=2.0982304735349206",
                                         "ax=0.5218954750836411", "ay=0.9044889105823875", "az=0.853013247571732",
                                         "wx=-1.341120977690462", "wy=6.660317368084707", "wz=6.755016999518199",
                                         "vx=-0.7999994578077456"};
  const double vx = -0.7999994578077456;
  for (const char* how : kIntegrators) {
    std::vector<std::string> args = {"--integrator", how, "--rtol", "1e-8", "--stop-time", "4"};
    for (const std::string& a : FloorOutputs()) args.push_back(a);
    for (const std::string& s : sets) args.insert(args.end(), {"--set", s});
    const RunResult r = RunKanesim("tests/stress/models/tossed_cube.mech", args);
    ASSERT_EQ(r.exit_code, 0) << how << ": " << r.stderr_text;
    const std::vector<double> v1 = r.Column("free.frame_b.v[1]"), v3 = r.Column("free.frame_b.v[3]"),
                              w2 = r.Column("free.frame_b.w[2]"), h = r.Column("free.q[2]");
    ASSERT_GT(w2.size(), 100u);
    for (size_t i = 0; i < w2.size(); ++i) {
      EXPECT_NEAR(v1[i], vx, 1e-9) << how << " row " << i;
      EXPECT_NEAR(v3[i], 0.0, 1e-9) << how << " row " << i;
      EXPECT_NEAR(w2[i], w2[0], 1e-6) << how << " row " << i;
    }
    EXPECT_NEAR(h.back(), 0.1, 1e-7) << how << ": not at rest on a face";
    const int at = r.Index("c1.frame_b.r[2]");
    int down = 0;
    for (int k = 0; k < 8; ++k) {
      const std::vector<double> c = r.Column("c" + std::to_string(k + 1) + ".frame_b.r[2]");
      EXPECT_GE(*std::min_element(c.begin(), c.end()), -2e-7) << how << ": corner " << k + 1 << " below the floor";
      const double before = r.RowAt(1.5)[static_cast<size_t>(at + k)], after = r.RowAt(4.0)[static_cast<size_t>(at + k)];
      if (std::abs(after) > 1e-6) continue;
      ++down;
      EXPECT_NEAR(after, before, 1e-10) << how << ": resting corner " << k + 1 << " drifts";
    }
    EXPECT_EQ(down, 4) << how;
  }
}

// A count from --stats ("  steps   1240 (...)", "events   149"); -1 when absent.
long StatCount(const std::string& text, const std::string& name) {
  std::smatch m;
  if (!std::regex_search(text, m, std::regex("(^|\\n)\\s*" + name + "\\s+(\\d+)"))) return -1;
  return std::stol(m[2]);
}

// An e = 0.8 toss (issue 41) that rocks onto an edge: corners p5 and p6 strike in turn, p5
// comes to rest, and the impulse lifts p6 off at 7.5e-5 m/s under a gap acceleration of about
// -7 m/s^2: a flight of 4e-10 m, far below the tolerance's reach (rtol 1e-8). Left in
// flight, its gap sat in the solver's error (the restart's first step from an order-1
// interpolant moved it ~1e-4 m/s off J u): its lifted event function crossed again 1e-13 s
// after each restart, and CVODE crept (thousands of events at t = 3.2386237, > 2 min for
// the 4 s). Such a flight now rests at once (EndStopEvents::Settle, Unresolved). What must
// hold, in every integrator: the run completes, with steps and events bounded (measured:
// 155-3956 steps, 120-149 events), the speed along the floor and the vertical spin kept,
// no corner below the floor beyond the tolerance's reach. If this fails by the test's
// timeout (CVODE), the creep is back.
TEST(CubeToss, AnEdgeRockingToRestNeitherCreepsNorChatters) {
  const std::vector<std::string> sets = {"e=0.8", "h=0.7469299366732856", "th=2.491375273774098",
                                         "ax=0.7204882054749064", "ay=0.018134906133941753",
                                         "az=-0.2558794089529359", "wx=6.971386962515615",
                                         "wy=0.03307667592057406", "wz=6.419324759951152", "vx=0.7420659367359408"};
  const double vx = 0.7420659367359408;
  for (const char* how : {"cvode", "dop853", "ida", "arkode"}) {
    std::vector<std::string> args = {"--integrator", how, "--stop-time", "4", "--rtol", "1e-8", "--stats"};
    for (const std::string& o : FloorOutputs()) args.push_back(o);
    for (const std::string& s : sets) args.insert(args.end(), {"--set", s});
    const RunResult r = RunKanesim("tests/stress/models/tossed_cube.mech", args);
    ASSERT_EQ(r.exit_code, 0) << how << ": " << r.stderr_text;
    const long steps = StatCount(r.stderr_text, "steps"), events = StatCount(r.stderr_text, "events");
    ASSERT_GT(steps, 0) << how << ": " << r.stderr_text;
    EXPECT_LT(steps, 20000) << how << ": the steps crept";
    EXPECT_LT(events, 1000) << how << ": events chatter";
    ExpectWhatTheFloorCannotChange(r, vx, how);
  }
}

}  // namespace
}  // namespace kanesim::stress
