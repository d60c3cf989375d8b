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
#include <string>
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

}  // namespace
}  // namespace kanesim::stress
