// A folded chain striking its stops together (bench/models/stop_chain.mech: N = 5 rods on
// revolute joints, the inner four with end stops at +-bend, restitution e), from a run of a
// random sweep that stopped (issue 41, exit 2 at t = 1.62885 in all five integrators:
// "joint 'j[2]' is past its stop q_min ... an impact was missed"). At t = 1.6276945 and
// 1.6278387 the inner joints j[1]..j[4] reach q_min at nearly one instant; they were struck
// one at a time at that instant (sequential impulses: each rebound pressed its neighbours,
// rebounding already, back into their stops, since a side separating from its stop was no
// companion of the impact), 287 impacts at t = 1.6278387 until Settle's pivot limit ended
// the cascade silently with j[2] closing on its stop from a gap <= 0, whose event function
// then never crossed. Now the sides on their stops that the impulse would press through join
// it (EndStopEvents::Complementary): one simultaneous Newton impact, no side left closing.
// What must hold, in every integrator: the run completes; no joint past its stops beyond
// the tolerance's reach; the energy (e = 0.3) never rises from one row to the next beyond
// the integration's error; at most 20 impacts at one instant.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <regex>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "run_kanesim.h"

namespace kanesim::stress {
namespace {

TEST(StopChain, AFoldedChainStrikesItsStopsTogether) {
  const double bend = 0.378415;
  for (const char* how : {"dop853", "cvode", "cvode-bdf", "ida", "arkode"}) {
    std::vector<std::string> args = {"--integrator", how, "--stop-time", "3", "--rtol", "1e-8", "--stats",
                                     "--output", "kinetic_energy", "--output", "potential_energy",
                                     "--set", "N=5", "--set", "e=0.3", "--set", "bend=0.378415",
                                     "--set", "j1.q.start=0.5305456195499234"};
    for (int k = 1; k <= 4; ++k) args.insert(args.end(), {"--output", "j[" + std::to_string(k) + "].q"});
    const RunResult r = RunKanesim("bench/models/stop_chain.mech", args);
    ASSERT_EQ(r.exit_code, 0) << how << ": " << r.stderr_text;
    for (int k = 1; k <= 4; ++k)
      for (double q : r.Column("j[" + std::to_string(k) + "].q")) {
        EXPECT_GE(q, -bend - 2e-7) << how << " j[" << k << "] past q_min";
        EXPECT_LE(q, bend + 2e-7) << how << " j[" << k << "] past q_max";
      }
    const std::vector<double> T = r.Column("kinetic_energy"), V = r.Column("potential_energy");
    ASSERT_GT(T.size(), 100u) << how;
    for (size_t i = 1; i < T.size(); ++i) EXPECT_LE(T[i] + V[i] - T[i - 1] - V[i - 1], 1e-5) << how << " row " << i;
    std::map<std::string, int> at;  // impacts per instant (--stats's event log: "  t = 1.62...  j[2]: impact ...")
    const std::regex line("t = ([0-9.eE+-]+)\\s+\\S+: impact");
    for (auto it = std::sregex_iterator(r.stderr_text.begin(), r.stderr_text.end(), line); it != std::sregex_iterator();
         ++it)
      ++at[(*it)[1]];
    int most = 0;
    for (const auto& [t, n] : at) most = std::max(most, n);
    EXPECT_GT(at.size(), 10u) << how << ": no impacts logged?";
    EXPECT_LT(most, 20) << how << ": a cascade of sequential impulses at one instant";
  }
}

// The same chain's simultaneous strikes, from another run of that sweep (N = 5, e = 0.7): an
// impulse that strikes j[2] at q_max with Newton's law also presses j[1], separating from its
// stop at 0.2 rad/s, back into it; held at gap rate 0 beside j[2]'s rebound, that impact
// would add kinetic energy (t = 0.6754). Every restitution of such an impact is scaled by the
// largest common factor that adds none (here 0.81; plastic would be 0). And a joint coming
// to rest short of its stop by the tolerance's reach (9e-8 rad, t = 2.1950) rests there:
// moved onto the stop it gained 2.3e-6 J of potential energy. What must hold, in every
// integrator: across every event instant (the two rows at one time) the energy does not
// rise beyond round-off; j[2]'s first rebound at t = 0.6754 is neither Newton's nor 0.
TEST(StopChain, SimultaneousStrikesAddNoEnergy) {
  for (const char* how : {"dop853", "cvode", "cvode-bdf", "ida", "arkode"}) {
    const RunResult r = RunKanesim("bench/models/stop_chain.mech",
                                   {"--integrator", how, "--stop-time", "3", "--rtol", "1e-8", "--stats", "--output",
                                    "kinetic_energy", "--output", "potential_energy", "--set", "N=5", "--set", "e=0.7",
                                    "--set", "bend=0.319951", "--set", "j1.q.start=1.420354214664079"});
    ASSERT_EQ(r.exit_code, 0) << how << ": " << r.stderr_text;
    const std::vector<double> t = r.Column("time"), T = r.Column("kinetic_energy"), V = r.Column("potential_energy");
    int instants = 0;
    for (size_t i = 1; i < t.size(); ++i) {
      if (t[i] != t[i - 1]) continue;
      ++instants;
      const double E0 = T[i - 1] + V[i - 1], E1 = T[i] + V[i];
      EXPECT_LE(E1 - E0, 1e-12 * std::abs(E0)) << how << " at t = " << t[i];
    }
    EXPECT_GT(instants, 50) << how;
    // j[2]'s rebounds in the log: "j[2]: impact at q_max, speed a -> b"; the scaled one near
    // t = 0.6754 (where j[1] joins at rest) has -b / a strictly between 0 and e = 0.7 (the
    // ones joined at rest 0, the others 0.7).
    const std::regex line("t = (0\\.6754[0-9]*)\\s+j\\[2\\]: impact at q_max, speed ([0-9.eE+-]+) -> ([0-9.eE+-]+)");
    int scaled = 0;
    for (auto it = std::sregex_iterator(r.stderr_text.begin(), r.stderr_text.end(), line); it != std::sregex_iterator();
         ++it) {
      const double ratio = -std::stod((*it)[3]) / std::stod((*it)[2]);
      EXPECT_GE(ratio, 0.0) << how;
      EXPECT_LE(ratio, 0.7 * (1.0 + 1e-9)) << how;
      if (ratio > 1e-3 && ratio < 0.7 * (1.0 - 1e-6)) ++scaled;
    }
    EXPECT_GE(scaled, 1) << how << ": no impact with its restitution scaled";
  }
}

// A chain of 4 rods with exact Coulomb friction on every joint (mu = 0.05 on 5 cm pins) and
// stops on the inner ones (models/friction_stop_chain.mech), from a random sweep of stops
// with friction. At t = 1.77861 j[3], stuck, needed a friction torque that grew past its
// bound (by 6e-15 N m at the slip: its acceleration after it ~0) and slipped forwards. Four
// integrators agreed on that instant to 4e-7 s and went on. CVODE-BDF found the slip again
// and again, every 4e-14 s: 23 875 events over 6.7e-10 s in 5 s of a run that never ended;
// then 1000 events within rtol max(1, |t|) of one another stopped the run (exit 2,
// sim/integrator.cpp). The error was the right-hand side's: the stuck joints' forces one
// Newton step from their last values (sim/stick_slip.cpp SolveNewton) and CVODE's
// difference quotients over increments far below the mu N iteration's noise, so BDF's
// Jacobian was garbage. (That run's laws were not all consistent either: at 1.0651 j[1]
// sticks and j[2], stuck, then needs more than its bound; decided together, j[2] slides
// and the slip at 1.7786 is gone.) What must hold: all five complete with the same events
// (34, the same joints in the same order) at the same times, end with one T + V, and T + V
// never rises from one row to the next (e = 0.3, friction).
TEST(StopChain, EventsWithoutProgressStopTheRunNeverHangIt) {
  // Measured: event times within 3.3e-6 s of DOP853's (CVODE, IDA), 4.3e-6 (CVODE-BDF); T + V
  // at 3 s within 6e-8 of |E| (39 J); no row's T + V above the last by more than 2e-16 of |E|.
  constexpr double kEventTimes = 2e-5, kAgree = 1e-6, kEnergyRise = 1e-12;
  double E_ref = NAN;
  std::vector<std::pair<double, std::string>> reference;
  for (const char* how : {"dop853", "cvode", "ida", "arkode", "cvode-bdf"}) {
    const RunResult r = RunKanesim("tests/stress/models/friction_stop_chain.mech",
                                   {"--integrator", how, "--stop-time", "3", "--rtol", "1e-8", "--stats", "--output",
                                    "kinetic_energy", "--output", "potential_energy"});
    ASSERT_EQ(r.exit_code, 0) << how << ": " << r.stderr_text;
    const std::vector<std::pair<double, std::string>> events = r.Events();
    if (reference.empty()) reference = events;
    ASSERT_EQ(events.size(), reference.size()) << how << ": " << r.stderr_text;
    for (size_t k = 0; k < events.size(); ++k) {
      EXPECT_EQ(events[k].second, reference[k].second) << how << " event " << k;
      EXPECT_NEAR(events[k].first, reference[k].first, kEventTimes) << how << " event " << k;
    }
    ASSERT_FALSE(r.rows.empty()) << how;
    EXPECT_NEAR(r.rows.back()[0], 3.0, 1e-12) << how;
    const std::vector<double> T = r.Column("kinetic_energy"), V = r.Column("potential_energy");
    for (size_t i = 1; i < T.size(); ++i)
      EXPECT_LE(T[i] + V[i] - (T[i - 1] + V[i - 1]), kEnergyRise * std::abs(T[i - 1] + V[i - 1])) << how << " row " << i;
    const double E = T.back() + V.back();
    if (std::isnan(E_ref)) E_ref = E;
    EXPECT_NEAR(E, E_ref, kAgree * std::abs(E_ref)) << how << ": T + V at t = 3";
  }
}

// The friction chain (models/friction_stop_chain.mech) with N = 6 rods, e = 1, mu = 0.2 on
// 1 cm pins, from a random sweep of stops with friction (/work/wt/fchain.py, issue 41: "Energy
// never rises at an impact with e <= 1"). j[1] strikes q_max alone at t = 0.66179, 15.3869 ->
// -15.3869 rad/s: Newton's law beside the other joints' friction impulses added 0.045 J
// (0.016 J at t = 0.60867, j[4]), the energy gain of Newton's kinematic restitution with
// friction (Kane & Levinson; sim/end_stops.cpp (4)). Now its restitution is scaled by the
// largest factor that adds none, as where sides strike together. What must hold, in every
// integrator: the run completes; across every impact's instant (the two rows at one time)
// the energy does not rise beyond round-off, 1e-12 relative (at the other event instants,
// reversals of a sliding joint, its speed set to 0 from the event location's residual moves
// T by up to 5e-12 relative through M's cross terms: 1e-9 there); no rebound is faster than
// its approach (e = 1), and some are slower (the scaled ones).
TEST(StopChain, ImpactsBesideFrictionImpulsesAddNoEnergy) {
#ifdef KANESIM_STRESS_SHORT  // sanitizers (~30x slower): the first second, 47 impacts (t = 0.4727, 0.6087, 0.6618 among them)
  const char* stop = "1";
  const int least = 15;
#else
  const char* stop = "3";
  const int least = 50;
#endif
#ifdef KANESIM_STRESS_SHORT  // sanitizers: two integrators here, the other three in the next test
  for (const char* how : {"cvode", "arkode"}) {
#else
  for (const char* how : {"dop853", "cvode", "cvode-bdf", "ida", "arkode"}) {
#endif
    const RunResult r = RunKanesim("tests/stress/models/friction_stop_chain.mech",
                                   {"--integrator", how, "--stop-time", stop, "--rtol", "1e-8", "--stats", "--output",
                                    "kinetic_energy", "--output", "potential_energy", "--set", "N=6", "--set", "e=1.0",
                                    "--set", "bend=0.427278", "--set", "mu=0.2", "--set", "r=0.01", "--set", "tq=0.0",
                                    "--set", "j1.q.start=1.10413592142989"});
    ASSERT_EQ(r.exit_code, 0) << how << ": " << r.stderr_text;
    const std::vector<double> t = r.Column("time"), T = r.Column("kinetic_energy"), V = r.Column("potential_energy");
    std::set<double> struck;  // the impacts' instants (--stats's event log: "  t = 0.66...  j[1]: impact ...")
    const std::regex at("t = ([0-9.eE+-]+)\\s+\\S+: impact");
    for (auto it = std::sregex_iterator(r.stderr_text.begin(), r.stderr_text.end(), at); it != std::sregex_iterator();
         ++it)
      struck.insert(std::stod((*it)[1]));
    int instants = 0;
    for (size_t i = 1; i < t.size(); ++i) {
      if (t[i] != t[i - 1]) continue;
      const bool impact = struck.count(t[i]) > 0;
      instants += impact;
      const double E0 = T[i - 1] + V[i - 1], E1 = T[i] + V[i];
      EXPECT_LE(E1 - E0, (impact ? 1e-12 : 1e-9) * std::abs(E0)) << how << " at t = " << t[i];
    }
    EXPECT_GT(instants, least) << how << " impact instants";
    const std::regex line("t = [0-9.eE+-]+\\s+j\\[[0-9]\\]: impact at q_m[a-z]+, speed ([0-9.eE+-]+) -> ([0-9.eE+-]+)");
    int impacts = 0, scaled = 0;
    for (auto it = std::sregex_iterator(r.stderr_text.begin(), r.stderr_text.end(), line); it != std::sregex_iterator();
         ++it) {
      const double ratio = -std::stod((*it)[2]) / std::stod((*it)[1]);
      ++impacts;
      EXPECT_GE(ratio, 0.0) << how;
      EXPECT_LE(ratio, 1.0 + 1e-9) << how;
      if (ratio < 1.0 - 1e-6) ++scaled;
    }
    EXPECT_GT(impacts, least) << how;
    EXPECT_GE(scaled, 1) << how << ": no impact with its restitution scaled";
  }
}

// The same chain of six with mu = 1 on pins of r = 0.2 m (mu r = 0.2 m on 0.5 m links),
// released at rest with j1 at -0.0593: at the start j1 and j[1] slip and the friction
// forces, which follow the normal forces, solve the normal-force fixed point
// (runtime/kane/friction.cpp (3)) with a contraction of 0.65 per iteration: ~75 iterations
// from zero. The iteration stopped at 60 and the start was refused ("did not converge",
// exit 1: four integrators; DOP853 passed from another warm start). Then j[1], decided
// sliding forwards before the others' laws were, accelerated backwards under its own
// friction (the energy rose 0.7 J in 0.2 s): the start now decides such a joint again
// (StickSlipEvents::CheckSlides). What must hold, up to the first event after the start
// (j[3] slips at 0.058 s): every integrator starts, the five agree at 0.05 s, and the
// energy does not rise (friction takes energy out, none in).
TEST(StopChain, SlowlyConvergingFrictionAtTheStartIsSolvedByEveryIntegrator) {
  const std::vector<std::string> params{"--set", "N=6", "--set", "e=1.0", "--set", "bend=0.853888", "--set", "mu=1.0",
                                        "--set", "r=0.2", "--set", "tq=0.0", "--set", "j1.q.start=-0.059319080947191516"};
  // Five integrators at rtol 1e-8 over 0.05 s: measured spread 5e-5 J in the energies
  // (more than rtol would give; the friction solve's tolerance? not explained yet).
  constexpr double kAgree = 2e-4;
  // The energy's round-off and integration error at rtol 1e-8 (|E| ~ 5 J).
  constexpr double kEnergyRise = 1e-6;
  std::vector<double> reference;
#ifdef KANESIM_STRESS_SHORT  // sanitizers: three integrators here, the other two in the test above
  for (const char* how : {"dop853", "cvode-bdf", "ida"}) {
#else
  for (const char* how : {"dop853", "cvode", "cvode-bdf", "ida", "arkode"}) {
#endif
    std::vector<std::string> args{"--integrator", how, "--stop-time", "0.05", "--rtol", "1e-8",
                                  "--output", "kinetic_energy", "--output", "potential_energy"};
    args.insert(args.end(), params.begin(), params.end());
    const RunResult r = RunKanesim("tests/stress/models/friction_stop_chain.mech", args);
    ASSERT_EQ(r.exit_code, 0) << how << ": " << r.stderr_text;
    ASSERT_FALSE(r.rows.empty()) << how;
    EXPECT_NEAR(r.rows.back()[0], 0.05, 1e-12) << how;
    const std::vector<double> T = r.Column("kinetic_energy"), V = r.Column("potential_energy");
    for (size_t i = 1; i < T.size(); ++i) EXPECT_LE(T[i] + V[i], T[i - 1] + V[i - 1] + kEnergyRise) << how << " row " << i;
    if (reference.empty()) {
      reference = r.rows.back();
      continue;
    }
    ASSERT_EQ(r.rows.back().size(), reference.size()) << how;
    for (size_t k = 1; k < reference.size(); ++k) EXPECT_NEAR(r.rows.back()[k], reference[k], kAgree) << how << " column " << r.header[k];
  }
}

}  // namespace
}  // namespace kanesim::stress
