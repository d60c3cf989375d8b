// Failures of the random sweep of stops with exact friction (bench/event_sweeps.py friction,
// issue 41), each reduced to one run of its model (models/friction_stop_chain.mech: a chain
// of N rods on revolute joints with exact Coulomb friction mu r N + tq, the inner joints with
// end stops at +-bend, restitution e) and checked for what must hold whatever the integrator:
// no output row with a joint past its stop, the energy never rising across an event instant,
// the integrators agreeing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <regex>
#include <string>
#include <vector>

#include "run_kanesim.h"

namespace kanesim::stress {
namespace {

// T + V never rises across an event instant (two rows at one time) beyond 1e-9 nor between
// rows beyond the integration's error (1e-6), relative to max(1 J, |T + V|) as
// bench/event_sweeps.py (T + V passes near zero in some runs: seed 21 trial 3 rose 3.7e-12 J
// across an event at E = -7.4e-4 J, round-off).
void ExpectNoEnergyRise(const std::vector<double>& t, const std::vector<double>& T, const std::vector<double>& V,
                        const char* how) {
  for (size_t i = 1; i < t.size(); ++i) {
    const double E0 = T[i - 1] + V[i - 1], E1 = T[i] + V[i];
    EXPECT_LE(E1 - E0, (t[i] == t[i - 1] ? 1e-9 : 1e-6) * std::max(1.0, std::abs(E0))) << how << " at t = " << t[i];
  }
}

// Sweep seed 6, trial 3: N = 6, e = 0, bend = 0.852068, mu = 0.5 on 1 cm pins, tq = 0.1 N m.
// At t = 1.8165815 j1 reverses (slides forwards) while j[4] rests on q_max, held there by the
// stop with its friction, and j[5] is stuck by its friction. The stop's reaction was solved
// again after the reversal with j[5]'s friction torque from before it (its stuck force not
// solved under j1's new law): a pull of -1.878 N m beyond the static friction 0.128 N m, so
// j[4] was let go to slide away from q_max; it accelerated into the stop instead (+1.67
// rad/s^2, its sliding friction pushing it there), from a gap of exactly 0 whose event
// function never crossed: in all five integrators the run stopped at t = 1.818 (exit 2, "past
// its stop q_max by 1.67e-06 ... an impact was missed"). With j[5]'s force solved under the
// new law the stop holds j[4] (its margin +0.59 N m). What must hold: every integrator runs
// past the instant; j[4] stays on q_max after it; no row has a joint past a stop by more than
// 1e-9 rad; across every event instant (two rows at one time) T + V does not rise beyond
// 1e-9 relative, nor between rows beyond the integration's error; T + V at the end agrees with
// DOP853's to 1e-3 J (CVODE-BDF is 4e-4 J off, the others 3e-6 J).
TEST(FrictionSweep, AJointItsStopHoldsWithFrictionIsNotLetGoIntoIt) {
  const double bend = 0.852068, t_event = 1.8165815;
#ifdef KANESIM_STRESS_SHORT  // sanitizers: three integrators (the five take ~3 s in Release)
  const std::vector<const char*> integrators = {"dop853", "cvode", "ida"};
#else
  const std::vector<const char*> integrators = {"dop853", "cvode", "cvode-bdf", "ida", "arkode"};
#endif
  double E_ref = NAN;
  for (const char* how : integrators) {
    std::vector<std::string> args = {"--integrator", how, "--stop-time", "1.85", "--rtol", "1e-8", "--output",
                                     "kinetic_energy", "--output", "potential_energy", "--set", "N=6", "--set", "e=0",
                                     "--set", "bend=0.852068", "--set", "mu=0.5", "--set", "r=0.01", "--set",
                                     "tq=0.1", "--set", "j1.q.start=0.9008481594162774"};
    for (int k = 1; k <= 5; ++k) args.insert(args.end(), {"--output", "j[" + std::to_string(k) + "].q"});
    const RunResult r = RunKanesim("tests/stress/models/friction_stop_chain.mech", args);
    ASSERT_EQ(r.exit_code, 0) << how << ": " << r.stderr_text;
    const std::vector<double> t = r.Column("time"), T = r.Column("kinetic_energy"), V = r.Column("potential_energy");
    ASSERT_GT(t.size(), 100u) << how;
    EXPECT_GE(t.back(), 1.85 - 1e-12) << how;
    for (int k = 1; k <= 5; ++k) {
      const std::vector<double> q = r.Column("j[" + std::to_string(k) + "].q");
      for (size_t i = 0; i < q.size(); ++i) {
        EXPECT_LE(std::abs(q[i]), bend + 1e-9) << how << " j[" << k << "] past its stop at t = " << t[i];
        if (k == 4 && t[i] > t_event + 1e-6) {
          EXPECT_NEAR(q[i], bend, 1e-9) << how << " j[4] left q_max at t = " << t[i];
        }
      }
    }
    int instants = 0;
    for (size_t i = 1; i < t.size(); ++i) instants += t[i] == t[i - 1];
    ExpectNoEnergyRise(t, T, V, how);
    EXPECT_GT(instants, 50) << how;
    const double E = T.back() + V.back();
    if (std::isnan(E_ref)) E_ref = E;
    EXPECT_NEAR(E, E_ref, 1e-3) << how << " against DOP853 at t = 1.85";
  }
}

// Sweep seed 4, trial 4: N = 4, e = 0, bend = 0.85255, mu = 0.5 on 20 cm pins (mu r = 0.1 m),
// tq = 0.5 N m. From t = 1.9140 a joint rests on its stop with its friction mu N, whose
// reactions the chord iteration of sim/end_stops_friction.cpp (1) solves; it contracts at
// 0.923 per iteration there (~300 iterations), and its cap of 60 stopped DOP853, CVODE, IDA and
// ARKODE at t = 1.91398 (exit 2, "the resting contacts' reactions with Coulomb friction mu N
// did not converge"). It now runs while the residual shrinks. Needs fix/slides' stuck forces
// solved to convergence (before them the run stops at t = 1.2635 in the normal-force
// iteration). What must hold: the four run to t = 2, no row past a stop by more than 1e-9 rad,
// T + V not rising across an event instant beyond 1e-9 relative, T + V at the end within
// 1e-4 J of DOP853's (they agree to 3e-6; CVODE-BDF's slip chatter at t = 0.514 is not this).
TEST(FrictionSweep, ReactionsAtAStopWithSlowlyConvergingFrictionAreSolved) {
  const double bend = 0.85255;
#ifdef KANESIM_STRESS_SHORT  // sanitizers: CVODE alone (1.8 s in Release), against DOP853's end in Release
  const std::vector<const char*> integrators = {"cvode"};
  double E_ref = -24.3203257;  // DOP853 at t = 2 with fix/slides' laws at rest (CVODE: -24.3203246)
#else
  const std::vector<const char*> integrators = {"dop853", "cvode", "ida", "arkode"};
  double E_ref = NAN;
#endif
  for (const char* how : integrators) {
    std::vector<std::string> args = {"--integrator", how, "--stop-time", "2", "--rtol", "1e-8", "--output",
                                     "kinetic_energy", "--output", "potential_energy", "--set", "N=4", "--set", "e=0",
                                     "--set", "bend=0.85255", "--set", "mu=0.5", "--set", "r=0.2", "--set", "tq=0.5",
                                     "--set", "j1.q.start=0.017861327131245996"};
    for (int k = 1; k <= 3; ++k) args.insert(args.end(), {"--output", "j[" + std::to_string(k) + "].q"});
    const RunResult r = RunKanesim("tests/stress/models/friction_stop_chain.mech", args);
    ASSERT_EQ(r.exit_code, 0) << how << ": " << r.stderr_text;
    const std::vector<double> t = r.Column("time"), T = r.Column("kinetic_energy"), V = r.Column("potential_energy");
    ASSERT_GT(t.size(), 100u) << how;
    EXPECT_GE(t.back(), 2.0 - 1e-12) << how;
    for (int k = 1; k <= 3; ++k) {
      const std::vector<double> q = r.Column("j[" + std::to_string(k) + "].q");
      for (size_t i = 0; i < q.size(); ++i) {
        EXPECT_LE(std::abs(q[i]), bend + 1e-9) << how << " j[" << k << "] past its stop at t = " << t[i];
      }
    }
    ExpectNoEnergyRise(t, T, V, how);
    const double E = T.back() + V.back();
    if (std::isnan(E_ref)) E_ref = E;
    EXPECT_NEAR(E, E_ref, 1e-4) << how << " against DOP853 at t = 2";
  }
}

// The checks every run of the chain must pass, whatever happened at its events: exit 0 at
// t_end, no row with a joint past its stop by more than 1e-9 rad, T + V not rising across an
// event instant nor between rows (ExpectNoEnergyRise). Returns T + V at the end (NAN where the
// run failed).
double CheckedEndEnergy(const RunResult& r, const char* how, int N, double bend, double t_end) {
  EXPECT_EQ(r.exit_code, 0) << how << ": " << r.stderr_text;
  if (r.exit_code != 0) return NAN;
  const std::vector<double> t = r.Column("time"), T = r.Column("kinetic_energy"), V = r.Column("potential_energy");
  EXPECT_GE(t.back(), t_end - 1e-12) << how;
  for (int k = 1; k < N; ++k) {
    const std::vector<double> q = r.Column("j[" + std::to_string(k) + "].q");
    for (size_t i = 0; i < q.size(); ++i)
      EXPECT_LE(std::abs(q[i]), bend + 1e-9) << how << " j[" << k << "] past its stop at t = " << t[i];
  }
  ExpectNoEnergyRise(t, T, V, how);
  return T.back() + V.back();
}

std::vector<std::string> ChainArgs(const char* how, const char* rtol, const char* stop, int N,
                                   const std::vector<std::string>& sets, const std::vector<std::string>& outputs) {
  std::vector<std::string> args = {"--integrator", how,     "--stop-time", stop, "--rtol", rtol, "--output",
                                   "kinetic_energy", "--output", "potential_energy"};
  for (int k = 1; k < N; ++k) args.insert(args.end(), {"--output", "j[" + std::to_string(k) + "].q"});
  for (const std::string& o : outputs) args.insert(args.end(), {"--output", o});
  for (const std::string& s : sets) args.insert(args.end(), {"--set", s});
  return args;
}

// One sweep case (`sets` with N links, stops at +-bend) run to `stop` s at rtol 1e-8 by each
// integrator: CheckedEndEnergy's checks, T + V at the end within `tol` of DOP853's at rtol
// 1e-11, then `check` on every run that completed. Under the sanitizers only `short_how` run,
// against `short_E_ref` (DOP853 at rtol 1e-11, measured in Release).
struct SweepCase {
  int N;
  double bend;
  const char* stop;
  std::vector<std::string> sets, outputs;
  double tol;
  std::vector<const char*> short_how;
  double short_E_ref;
};

void RunSweepCase(const SweepCase& c, const std::function<void(const char*, const RunResult&)>& check) {
  const double t_end = std::stod(c.stop);
#ifdef KANESIM_STRESS_SHORT
  const std::vector<const char*> integrators = c.short_how;
  const double E_ref = c.short_E_ref;
#else
  const std::vector<const char*> integrators = {"dop853", "cvode", "cvode-bdf", "ida", "arkode"};
  const double E_ref = CheckedEndEnergy(RunKanesim("tests/stress/models/friction_stop_chain.mech",
                                                   ChainArgs("dop853", "1e-11", c.stop, c.N, c.sets, {})),
                                        "dop853 at rtol 1e-11", c.N, c.bend, t_end);
#endif
  for (const char* how : integrators) {
    const RunResult r =
        RunKanesim("tests/stress/models/friction_stop_chain.mech", ChainArgs(how, "1e-8", c.stop, c.N, c.sets, c.outputs));
    const double E = CheckedEndEnergy(r, how, c.N, c.bend, t_end);
    if (std::isnan(E)) continue;
    EXPECT_NEAR(E, E_ref, c.tol) << how << " against DOP853 at rtol 1e-11, t = " << c.stop;
    check(how, r);
  }
}

// Sweep seed 6, trial 7: N = 6, e = 0, bend = 0.135203, mu = 0.2 on 1 cm pins, tq = 0.1 N m.
// At t = 0.2916333 j[1] strikes q_max plastically beside j[2], which rests on q_max held by the
// stop and its friction. Both were pulled beyond their static friction with the stuck forces
// from before, and Settle let them go one at a time: j[1] first, then j[2] with j[1]'s sliding
// friction but the other stuck forces not solved again; with everything solved for both
// released, j[2] accelerated into its stop (-0.077 rad/s^2): exit 2 ("accelerates into it
// without resting on it") in all five integrators. Decided together (sim/stop_releases.cpp),
// releasing j[1] alone is consistent: it slides away (j[1].a = -8.42 rad/s^2) and j[2] stays
// held (its reaction and friction within their bound). What must hold: the checks above; at
// the instant's right limit j[1] accelerates away from q_max and j[2] is held on it (a = 0,
// q = bend) and stays there to t = 0.4 (the reference's events: j[4] and j[1] strike, j[2]
// none); T + V at t = 0.4 within 1e-6 J of DOP853's at rtol 1e-11 (measured: 5e-8 J, IDA).
TEST(FrictionSweep, JointsHeldAtTheirStopsWithFrictionAreReleasedTogether) {
  const double bend = 0.135203, t_event = 0.2916333;
  // Sanitizers: two integrators (1.9 s in Release for all five).
  const SweepCase c{6, bend, "0.4", {"N=6", "e=0", "bend=0.135203", "mu=0.2", "r=0.01", "tq=0.1",
                    "j1.q.start=-0.5631580192073434"}, {"j[1].a", "j[2].a"}, 1e-6, {"dop853", "cvode"},
                    -48.0841298527};
  RunSweepCase(c, [&](const char* how, const RunResult& r) {
    const std::vector<double> t = r.Column("time"), a1 = r.Column("j[1].a"), a2 = r.Column("j[2].a"),
                              q2 = r.Column("j[2].q");
    size_t right = 0;  // the instant's right limit: the second of its two rows
    for (size_t i = 1; i < t.size(); ++i)
      if (t[i] == t[i - 1] && std::abs(t[i] - t_event) < 1e-6) right = i;
    ASSERT_GT(right, 0u) << how << ": no event rows at t = " << t_event;
    EXPECT_LT(a1[right], -1.0) << how << ": j[1] does not leave q_max";
    EXPECT_EQ(a2[right], 0.0) << how << ": j[2] is not held on q_max";
    for (size_t i = right; i < t.size(); ++i)
      EXPECT_NEAR(q2[i], bend, 1e-12) << how << " j[2] left q_max at t = " << t[i];
  });
}

// Sweep seed 4, trial 6: N = 4, e = 0.7, bend = 0.855642, mu = 0.2 on 5 cm pins, tq = 0.5 N m.
// At t = 2.2468551 j[2] reverses (slides backwards from u = 0 exactly), at 2.2508777 its speed
// is back at 0 and it sticks, at 2.2517429 j[3] reverses. DOP853's step from the reversal's
// restart was 0.0226 s long: j[2]'s event function s u started it at 0, rose, fell through 0
// at the stick and rose again by the step's end, so it was not searched (a function from zero
// was only one negative at the step's end); j[3]'s crossing shortened the step, and the row
// there had j[2] moving forwards under its backwards friction: exit 2 ("its reversal was
// missed") at 2.2517415 in DOP853 alone. A function from zero is now searched where it is
// below zero at the bracket's right end (the earliest crossing so far). What must hold: every
// integrator's checks above; j[2] at rest (u = 0 exactly) on the left limit of j[3]'s reversal
// (stuck since 2.25088); T + V at t = 2.4 within 1e-5 J of DOP853's at rtol 1e-11 (measured:
// 2.3e-6 J, CVODE-BDF; DOP853 at 1e-8 4e-8 J).
TEST(FrictionSweep, Dop853FindsAStickInsideTheStepFromAReversal) {
  const double t_reversal = 2.2517429;
  // Sanitizers: DOP853 alone (0.7 s in Release for all five).
  const SweepCase c{4, 0.855642, "2.4", {"N=4", "e=0.7", "bend=0.855642", "mu=0.2", "r=0.05", "tq=0.5",
                    "j1.q.start=0.2967374165699683"}, {"j[2].u"}, 1e-5, {"dop853"}, -6.2053834057};
  RunSweepCase(c, [&](const char* how, const RunResult& r) {
    const std::vector<double> t = r.Column("time"), u2 = r.Column("j[2].u");
    size_t left = 0;  // the reversal's left limit: the first of its two rows
    for (size_t i = 1; i < t.size() && left == 0; ++i)
      if (t[i] == t[i - 1] && std::abs(t[i] - t_reversal) < 1e-5) left = i - 1;
    ASSERT_GT(left, 0u) << how << ": no event rows at t = " << t_reversal;
    EXPECT_EQ(u2[left], 0.0) << how << ": j[2] is not stuck at j[3]'s reversal";
  });
}

// Sweep seed 8, trial 6: N = 6, e = 0, bend = 0.514233, mu = 0.2 on 1 cm pins, tq = 0.5 N m.
// At t = 0.3201901 j[3] reverses (its friction needed beyond its bound: slides forwards from
// u = 0), and with its new law j[1], resting on q_max with its friction, is pulled beyond its
// bound and released. j[3]'s law had been decided with j[1] held; with j[1] sliding away it
// accelerated backwards, against its slide from u = 0 exactly (no crossing): exit 2 ("its
// reversal was missed") at the row t = 0.324 in all five integrators. The laws at rest are now
// checked together after a release too (StickSlipEvents::Refresh): j[3] sticks there (its
// friction -0.492 within 0.526) and slips at 0.32540. What must hold: the checks above; at the
// instant's right limit j[1] accelerates away from q_max and j[3] is stuck (u = a = 0) and
// stays so to t = 0.325; T + V at t = 0.4 within 1e-5 J of DOP853's at rtol 1e-11 (measured:
// 1.1e-6 J, CVODE-BDF).
TEST(FrictionSweep, AReleaseFromAStopDecidesTheLawsAtRestAgain) {
  const double t_event = 0.3201901;
  // Sanitizers: two integrators (2 s in Release for all five).
  const SweepCase c{6, 0.514233, "0.4", {"N=6", "e=0", "bend=0.514233", "mu=0.2", "r=0.01", "tq=0.5",
                    "j1.q.start=0.6868243795119158"}, {"j[1].a", "j[3].u", "j[3].a"}, 1e-5, {"dop853", "cvode"},
                    54.680264170884};
  RunSweepCase(c, [&](const char* how, const RunResult& r) {
    const std::vector<double> t = r.Column("time"), a1 = r.Column("j[1].a"), u3 = r.Column("j[3].u"),
                              a3 = r.Column("j[3].a");
    size_t right = 0;  // the instant's right limit: the last of its rows
    for (size_t i = 1; i < t.size(); ++i)
      if (t[i] == t[i - 1] && std::abs(t[i] - t_event) < 1e-6) right = i;
    ASSERT_GT(right, 0u) << how << ": no event rows at t = " << t_event;
    EXPECT_LT(a1[right], -1.0) << how << ": j[1] does not leave q_max";
    for (size_t i = right; i < t.size() && t[i] < 0.325; ++i) {
      EXPECT_EQ(u3[i], 0.0) << how << ": j[3] moves at t = " << t[i];
      EXPECT_EQ(a3[i], 0.0) << how << ": j[3] is not held at t = " << t[i];
    }
  });
}

// Sweep seed 9, trial 5: N = 5, e = 0.7, bend = 0.374577, mu = 0.05 on 1 cm pins, tq = 0.
// At t = 1.7957251 (rtol 1e-8) a cascade of impacts at q_min: j[1] bounces, j[2] is stopped
// (0.000117 -> 0), j[3] leaves q_min and strikes it again, j[1] comes to rest. The stops had
// settled under the friction laws from before; decided again after them, j[2] could not stay
// stuck and slid backwards into q_min without resting on it: exit 2 ("accelerates into it
// without resting on it") in four integrators (CVODE-BDF's cascade differs). The stops now
// settle again under the laws the last decision left while such a side remains
// (SettleHeldAtStops): j[2] rests on q_min. What must hold: the checks above in all five;
// T + V at t = 1.8 within 5e-3 J of DOP853's at rtol 1e-11 (measured: 4.1e-3 J, DOP853, CVODE,
// IDA and ARKODE, whose cascade at rtol 1e-8 takes another order of impacts than the
// reference's; 9e-6 J, CVODE-BDF; at rtol 1e-9 all five within 4.5e-6 J).
TEST(FrictionSweep, AJointStoppedInACascadeThatSlidesBackRestsOnItsStop) {
  const SweepCase c{5, 0.374577, "1.8", {"N=5", "e=0.7", "bend=0.374577", "mu=0.05", "r=0.01", "tq=0.0",
                    "j1.q.start=1.1381195652005305"}, {}, 5e-3, {"dop853"}, 43.569387035};
  RunSweepCase(c, [](const char*, const RunResult&) {});
}

// Sweep seed 17, trial 1: N = 6, e = 0.7, bend = 0.154654, mu = 0.05 on 1 cm pins, tq = 0.5.
// At t = 1.8982 j[5] strikes q_max while j[1]..j[4] rest on q_min held by their friction: a
// cascade of impacts in which j[1] was pulled off its stop beyond its static friction
// (released: it slides away), and then j[2]'s plastic impact drove it back in at
// -0.35 rad/s. A released joint was never looked at again in the cascade, so it went through
// its stop unseen: exit 2 at t = 1.9 in all five integrators ("past its stop q_min by 0.00148
// ... an impact was missed"). It now strikes its stop again in the cascade (DOP853: at
// t = 1.9004228, j[1] three times, j[2] five, j[3] four). The same change alters earlier
// cascades of this run (the first at t = 0.398). What must hold: the checks above in all five
// (no row past a stop, no energy rise, exit 0); T + V at t = 2 within 4e-2 J of DOP853's at
// rtol 1e-11. Measured: DOP853, CVODE, IDA and ARKODE 2.9e-3 J, CVODE-BDF 3.5e-2 J. The spread
// is the order of earlier cascades' impacts at rtol 1e-8 in a chaotic chain; the four agree
// with each other to 6e-6 J.
TEST(FrictionSweep, AJointPulledOffItsStopAndDrivenBackInTheSameCascadeStrikesIt) {
  const SweepCase c{6, 0.154654, "2.0", {"N=6", "e=0.7", "bend=0.154654", "mu=0.05", "r=0.01", "tq=0.5",
                    "j1.q.start=0.9455582666336415"}, {}, 4e-2, {"dop853"}, 62.763414747};
  RunSweepCase(c, [](const char*, const RunResult&) {});
}

// Sweep seed 21, trial 3: N = 5, e = 1, bend = 0.082367, mu = 0.5 on 20 cm pins, tq = 0.5.
// Exposed by the change for seed 17 (which moved this run's cascades); it passed before it.
// At t = 1.6555426 j[1] reverses and slides backwards; decided together with it, j[4] slides
// forwards from rest (accelerating 1.36 rad/s^2 that way). Then j[1] comes to rest on q_min,
// which moves the force j[4] needs, and j[4] accelerated backwards: exit 2 at t = 1.6558 in
// four integrators ("a joint sliding forwards ... moves the other way: its reversal was
// missed"). A joint that comes to rest on its stop now has the laws at rest checked again
// (StickSlipEvents::Refresh), as a release from a stop already had. What must hold: the
// checks above in all five; T + V at t = 1.8 within 1e-3 J of DOP853's at rtol 1e-11
// (measured: 6.6e-4 J, IDA; CVODE-BDF 2.2e-4 J).
TEST(FrictionSweep, AJointThatComesToRestOnItsStopHasTheLawsAtRestDecidedAgain) {
  const SweepCase c{5, 0.082367, "1.8", {"N=5", "e=1.0", "bend=0.082367", "mu=0.5", "r=0.2", "tq=0.5",
                    "j1.q.start=0.5817462157266542"}, {}, 1e-3, {"dop853"}, -2.445987810};
  RunSweepCase(c, [](const char*, const RunResult&) {});
}

// Sweep seeds 44 (trial 1: N = 6, e = 0, bend = 0.145171, mu = 0.5 on 20 cm pins, tq = 0.5)
// and 48 (trial 0: N = 6, e = 0.7, bend = 0.175297, mu = 0.5 on 20 cm pins, tq = 0). One joint
// rests on its stop with friction, and the chord iteration for the stop's reaction
// (sim/end_stops_friction.cpp (1)) overshot: its residual flipped sign every iteration, at a
// gain of -1.02 (seed 44, t = 0.1921210) or erratically (seed 48, t = 1.5778865), and never
// shrank: exit 2 in all five integrators ("the resting contacts' reactions with Coulomb
// friction mu N did not converge"). Its step is now relaxed by the secant estimate where the
// residual alternates (seed 44: 0.2 s of simulation in 0.35 s with DOP853, where relaxing by
// halving alone took 3.6 s at ~470 iterations a solve). What must hold: the checks above in
// all five, and T + V of DOP853's at rtol 1e-11 within 5e-6 J at t = 0.2 for seed 44
// (measured: 1.7e-6 J CVODE-BDF, the others 6e-8 J) and within 1e-3 J for seed 48
// at t = 1.6 (impacts at e = 0.7 whose order at rtol 1e-8 differs from the reference's;
// measured 4.2e-4 J DOP853, 7.4e-4 J CVODE-BDF).
TEST(FrictionSweep, AStopReactionWhoseChordOvershootsIsRelaxed) {
  const SweepCase seed44{6, 0.145171, "0.2", {"N=6", "e=0", "bend=0.145171", "mu=0.5", "r=0.2", "tq=0.5",
                         "j1.q.start=0.2729915322001517"}, {}, 5e-6, {"cvode"}, 23.2306089737};
  RunSweepCase(seed44, [](const char*, const RunResult&) {});
  const SweepCase seed48{6, 0.175297, "1.6", {"N=6", "e=0.7", "bend=0.175297", "mu=0.5", "r=0.2", "tq=0.0",
                         "j1.q.start=0.641602764174007"}, {}, 1e-3, {"cvode"}, 6.6757207409};
  RunSweepCase(seed48, [](const char*, const RunResult&) {});
}

// Sweep seed 54, trial 3: N = 4, e = 0.3, bend = 0.141919, mu = 0.5 on 5 cm pins, tq = 0.5.
// At t = 0.2631103 (CVODE-BDF) j[1] sticks and j[3], leaving q_max at 2e-6 rad/s, is brought
// to rest on it; that rest's impulse left the stuck j[1] at 4.4e-7 rad/s, which Refresh then
// zeroed alone: T rose 2.76e-6 J across the instant (j[1]'s momentum, with the base turning at
// -1.87 rad/s, times its speed). Seed 48 trial 0 with CVODE-BDF rose 7.0e-7 J the same way at
// t = 0.5288658. Such a joint is now brought to rest by impulses that keep the other stuck and
// resting joints at rest (StickSlipEvents::BackToRest), which take energy. What must hold: the
// checks above in all five, no rise across an instant beyond 1e-9 relative; T + V at t = 0.3
// within 1e-2 J of DOP853's at rtol 1e-11 (measured: 6.8e-3 J for all five, whose cascades at
// rtol 1e-8 agree with each other to 3e-4 J and take another order than the reference's).
TEST(FrictionSweep, AStuckJointAnImpulseLeftAtARestSpeedIsStoppedWithoutAddingEnergy) {
  const SweepCase c{4, 0.141919, "0.3", {"N=4", "e=0.3", "bend=0.141919", "mu=0.5", "r=0.05", "tq=0.5",
                    "j1.q.start=0.25998361179878726"}, {}, 1e-2, {"cvode-bdf"}, 8.9278637147};
  RunSweepCase(c, [](const char*, const RunResult&) {});
}

// Sweep seed 53, trial 0: N = 6, e = 0.3, bend = 0.483663, mu = 1 on 20 cm pins, tq = 0.1.
// At t = 2.6551854 j[3] sticks (its friction -14.05 within 14.60 N m); under the new laws
// the normal-force iteration contracts at 0.954 per iteration (its residual keeps its sign),
// and converges in ~520 iterations. A transient of the change (four two-iteration ratios of
// 0.99 at the start) halved the relaxation w, which only slows a positive rate 1 + w (g - 1),
// down to 1/64: exit 2 ("no consistent friction force") in all five integrators. w is now
// halved only while the residual flips sign. What must hold: the checks above in all five;
// T + V at t = 2.7 within 1e-4 J of DOP853's at rtol 1e-11 (measured: 1.1e-5 J, CVODE;
// 5.9e-5 J, CVODE-BDF; the others within 1e-7 J).
TEST(FrictionSweep, AFrictionGainBelowOneIsIteratedToItsEndNotRelaxed) {
  const SweepCase c{6, 0.483663, "2.7", {"N=6", "e=0.3", "bend=0.483663", "mu=1.0", "r=0.2", "tq=0.1",
                    "j1.q.start=0.7015205127293336"}, {}, 1e-4, {"cvode"}, -44.10198084845};
  RunSweepCase(c, [](const char*, const RunResult&) {});
}

// Sweep seed 36, trial 3: N = 5, e = 0.3, bend = 0.167284, mu = 1 on 20 cm pins (mu r = 0.2 m
// on 0.5 m links), tq = 0. At t = 0.1910791 j[2] strikes q_max (1.287 -> -0.386 rad/s); after
// it j1, j[1], j[2] and j[3] slide and j[4] is stuck. With those four sliding, each friction
// torque raises the normal forces that set the others: the friction torques of the
// normal-force iteration grow 1.52-fold per iteration once they are large (the linearized
// map's dominant gain; instrumented, the same ratio for all four joints to three digits), and
// the refusal reports that gain. Is there a consistent force the iteration missed? A search
// (a debugging build, 2026-11-30) solved tau = F(tau) by Newton with a finite-difference
// Jacobian from 2000 random starts (torques up to 1000 N m), for each of j[4]'s laws (stuck,
// its force solving udot = 0; sliding either way): no solution. At an earlier state of the same
// run it found the iteration's converged forces from every start. So this is a Painleve-type
// state (Coulomb's law has no answer without an impulsive friction), and exit 2 is the right
// answer. What must hold: exit 2 at the impact's instant in all five integrators (they agree
// on it to 1e-8 s), with the gain, every row up to it kept and none past a stop.
TEST(FrictionSweep, FrictionWhoseGainExceedsOneAfterAnImpactStopsTheRun) {
  const double bend = 0.167284, t_impact = 0.1910791;
  for (const char* how : {"dop853", "cvode", "cvode-bdf", "ida", "arkode"}) {
    std::vector<std::string> args = {"--integrator", how, "--stop-time", "3", "--rtol", "1e-8", "--set", "N=5",
                                     "--set", "e=0.3", "--set", "bend=0.167284", "--set", "mu=1.0", "--set", "r=0.2",
                                     "--set", "tq=0.0", "--set", "j1.q.start=0.0725869304161415"};
    for (int k = 1; k <= 4; ++k) args.insert(args.end(), {"--output", "j[" + std::to_string(k) + "].q"});
    const RunResult r = RunKanesim("tests/stress/models/friction_stop_chain.mech", args);
    EXPECT_EQ(r.exit_code, 2) << how << ": " << r.stderr_text;
    EXPECT_NE(r.stderr_text.find("no consistent friction force"), std::string::npos) << how << ": " << r.stderr_text;
    std::smatch at;
    ASSERT_TRUE(std::regex_search(r.stderr_text, at, std::regex("numerical failure at t = ([0-9.]+)"))) << how;
    EXPECT_NEAR(std::stod(at[1]), t_impact, 1e-7) << how;
    std::smatch gain;
    ASSERT_TRUE(std::regex_search(r.stderr_text, gain, std::regex("gain of about ([0-9.]+)"))) << how;
    EXPECT_NEAR(std::stod(gain[1]), 1.52, 0.01) << how;
    const std::vector<double> t = r.Column("time");
    ASSERT_GT(t.size(), 10u) << how;
    EXPECT_NEAR(t.back(), std::stod(at[1]), 1e-12) << how << ": the rows before the refusal were not kept";
    for (int k = 1; k <= 4; ++k) {
      const std::vector<double> q = r.Column("j[" + std::to_string(k) + "].q");
      for (size_t i = 0; i < q.size(); ++i)
        EXPECT_LE(std::abs(q[i]), bend + 1e-9) << how << " j[" << k << "] past its stop at t = " << t[i];
    }
  }
}

}  // namespace
}  // namespace kanesim::stress
