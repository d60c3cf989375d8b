// Exact friction's laws at rest decided as one problem (sim/stick_slip_laws.cpp (6)): more
// joints at rest than the enumeration takes (kMaxEnumerated = 6), each case checked against a
// second method, the same chain with regularized friction (tau = -C tanh(u / v)), whose
// motion tends to the exact one as v -> 0, and against the energy, which friction only takes.
// Before (6) every case here stopped with exit 2 ("neither sticking nor sliding is consistent
// (Painleve-type)"): 40 of 40 random chains of 8-10 joints released from rest, and Talos in
// 16 runs of a random sweep (docs/benchmarks/2026-12-01_talos_sweep.md).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "run_kanesim.h"

namespace kanesim::stress {
namespace {

// bench search, seed 1 trial 0: N = 8 rods, constant friction 0.5 N m on every joint (mu = 0),
// stops at +-0.363 rad with e = 0.3, released from rest bent. At t = 0 the joints' own
// decisions (five slip, three stick) leave j1 stuck against its acceleration; the 8 laws
// are solved together and j1 slides backwards.
const std::vector<std::string> kChainOfEight = {
    "--set", "N=8", "--set", "bend=0.363062", "--set", "tq=0.5", "--set", "mu=0", "--set", "e=0.3",
    "--set", "j[1].q.start=-0.277438", "--set", "j[2].q.start=0.189491", "--set", "j[3].q.start=-0.020153",
    "--set", "j[4].q.start=-0.087414", "--set", "j[5].q.start=-0.210609", "--set", "j[6].q.start=-0.008818",
    "--set", "j[7].q.start=0.285597"};
constexpr const char* kModel = "tests/stress/models/friction_stop_chain.mech";

std::vector<std::string> With(std::vector<std::string> a, const std::vector<std::string>& more) {
  a.insert(a.end(), more.begin(), more.end());
  return a;
}

// The joints' angles at the last row.
std::vector<double> LastAngles(const RunResult& r, int N) {
  std::vector<double> q;
  q.push_back(r.Column("j1.q").back());
  for (int k = 1; k < N; ++k) q.push_back(r.Column("j[" + std::to_string(k) + "].q").back());
  return q;
}

TEST(RestLaws, EightJointsAtRestAreTheLimitOfRegularizedFriction) {
  const std::vector<std::string> common = {"--stop-time", "0.5", "--interval", "0.005", "--rtol", "1e-10",
                                           "--atol", "1e-10"};
  RunResult exact = RunKanesim(kModel, With(With(kChainOfEight, common),
                                            {"--stats", "--output", "kinetic_energy", "--output", "potential_energy",
                                             "--output", "j*.q"}));
  ASSERT_EQ(exact.exit_code, 0) << exact.stderr_text;
  EXPECT_NE(exact.stderr_text.find("the laws at rest of 8 joints solved together"), std::string::npos)
      << exact.stderr_text;
  // Friction and plastic-ish stops only take energy: T + V never rises (beyond the
  // integration's error between rows, 1e-9 relative across an instant).
  const std::vector<double> t = exact.Column("time"), T = exact.Column("kinetic_energy"),
                            V = exact.Column("potential_energy");
  for (size_t i = 1; i < t.size(); ++i)
    EXPECT_LE(T[i] + V[i] - T[i - 1] - V[i - 1], (t[i] == t[i - 1] ? 1e-9 : 1e-7) * std::max(1.0, std::abs(V[i])))
        << "t = " << t[i];
  const std::vector<double> q = LastAngles(exact, 8);
  // The regularized friction at v = 1e-2 and 1e-3 rad/s: its angles at 0.5 s within O(v) of
  // the exact ones, the distance shrinking with v (measured: 1.8e-3, 2.3e-4, 2.8e-5 rad at
  // v = 1e-2, 1e-3, 1e-4). Laws chosen wrongly at t = 0 (a joint stuck that slides) leave an
  // O(1) distance that does not shrink.
  std::vector<double> distance;
  for (const char* v : {"1e-2", "1e-3"}) {
    std::vector<std::string> reg = With(kChainOfEight, common);
    for (const std::string j : {"j1", "j[1]", "j[2]", "j[3]", "j[4]", "j[5]", "j[6]", "j[7]"})
      reg = With(reg, {"--set", j + ".friction_exact=false", "--set", j + ".friction_v=" + v});
    RunResult r = RunKanesim(kModel, With(reg, {"--integrator", "cvode", "--output", "j*.q"}));
    ASSERT_EQ(r.exit_code, 0) << r.stderr_text;
    const std::vector<double> qr = LastAngles(r, 8);
    double d = 0.0;
    for (size_t k = 0; k < q.size(); ++k) d = std::max(d, std::abs(qr[k] - q[k]));
    distance.push_back(d);
  }
  EXPECT_LT(distance[0], 5e-3);
  EXPECT_LT(distance[1], 5e-4);
  EXPECT_LT(distance[1], 0.2 * distance[0]);  // first order in v
}

// bench search, seed 2 trial 37: N = 8 rods between tight stops (+-0.0358 rad, e = 0.3),
// friction torque 2 N m, started moving. At t = 0.0495 a cascade of impacts at one instant
// keeps striking neighbours (j[1]..j[5] at q_max, each rebound striking the next) and did
// not end within Settle's 16 n + 16 steps: exit 2 in every integrator. Its second round is
// plastic (sim/end_stops.cpp Settle): what must hold is that the run goes on, says so, never
// raises T + V across an instant, and no row has a joint past a stop.
TEST(RestLaws, ACascadeOfImpactsThatDoesNotEndGoesOnPlastic) {
  const std::vector<std::string> args = {
      "--set", "N=8", "--set", "bend=0.035761", "--set", "tq=2", "--set", "mu=0", "--set", "e=0.3",
      "--set", "j[1].q.start=-0.001915", "--set", "j[1].u.start=1.777616", "--set", "j[2].q.start=-0.010358",
      "--set", "j[2].u.start=-0.639730", "--set", "j[3].q.start=0.030224", "--set", "j[3].u.start=0.423894",
      "--set", "j[4].q.start=-0.028105", "--set", "j[4].u.start=1.136823", "--set", "j[5].q.start=-0.009769",
      "--set", "j[5].u.start=1.789932", "--set", "j[6].q.start=0.009718", "--set", "j[6].u.start=1.219610",
      "--set", "j[7].q.start=0.028320", "--set", "j[7].u.start=0.037335", "--stop-time", "0.2", "--rtol", "1e-8",
      "--stats", "--output", "kinetic_energy", "--output", "potential_energy", "--output", "j*.q"};
  RunResult r = RunKanesim(kModel, args);
  ASSERT_EQ(r.exit_code, 0) << r.stderr_text;
  EXPECT_NE(r.stderr_text.find("goes on plastic (restitution 0)"), std::string::npos) << r.stderr_text;
  const std::vector<double> t = r.Column("time"), T = r.Column("kinetic_energy"), V = r.Column("potential_energy");
  ASSERT_GT(t.back(), 0.199);
  for (size_t i = 1; i < t.size(); ++i) {
    if (t[i] != t[i - 1]) continue;  // (across an instant)
    EXPECT_LE(T[i] + V[i] - T[i - 1] - V[i - 1], 1e-9 * std::max(1.0, std::abs(T[i - 1] + V[i - 1]))) << "t = " << t[i];
  }
  for (int k = 1; k < 8; ++k)
    for (double q : r.Column("j[" + std::to_string(k) + "].q")) EXPECT_LE(std::abs(q), 0.035761 + 1e-9) << "j[" << k << "]";
}

}  // namespace
}  // namespace kanesim::stress
